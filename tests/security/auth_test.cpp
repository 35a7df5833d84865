// The pieces of authentication without a server: the tokens file, the role of each method, the
// decision for a call, bearer headers, loopback addresses, where a client's token comes from, and
// the client refusing to send a token in plaintext to a remote host.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/auth.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

#include "proto/support/farm_client.h"

namespace penumbra::farm {
namespace {

const char* kTokens = R"(# role name token
client alice alice-token-0123456789
client bob   bob-token-0123456789abc   # trailing comment

worker w1    worker-token-0123456789
admin  root  root-token-0123456789
)";

TEST(TokenTable, ParsesRolesNamesAndComments) {
  TokenTable table = TokenTable::parse(kTokens, "tokens.txt");
  EXPECT_EQ(table.size(), 4u);
  auto alice = table.find("alice-token-0123456789");
  ASSERT_TRUE(alice);
  EXPECT_EQ(alice->name, "alice");
  EXPECT_EQ(alice->role, Role::client);
  EXPECT_EQ(table.find("bob-token-0123456789abc")->name, "bob");
  EXPECT_EQ(table.find("worker-token-0123456789")->role, Role::worker);
  EXPECT_EQ(table.find("root-token-0123456789")->role, Role::admin);
  // A prefix, an extension or a case change of a token is another token.
  EXPECT_FALSE(table.find("alice-token-012345678"));
  EXPECT_FALSE(table.find("alice-token-01234567890"));
  EXPECT_FALSE(table.find("ALICE-token-0123456789"));
  EXPECT_FALSE(table.find(""));
}

TEST(TokenTable, RefusesMalformedFilesWithoutEchoingTokens) {
  auto message = [](const std::string& text) {
    try {
      TokenTable::parse(text, "t.txt");
    } catch (const std::runtime_error& error) {
      return std::string(error.what());
    }
    return std::string("accepted");
  };
  std::string unknown_role = message("superuser eve eve-token-0123456789\n");
  EXPECT_NE(unknown_role.find("t.txt:1"), std::string::npos) << unknown_role;
  EXPECT_NE(unknown_role.find("unknown role"), std::string::npos) << unknown_role;
  EXPECT_EQ(unknown_role.find("eve-token"), std::string::npos) << unknown_role;
  std::string short_token = message("# c\nclient eve short\n");
  EXPECT_NE(short_token.find("t.txt:2"), std::string::npos) << short_token;
  EXPECT_EQ(short_token.find("short\""), std::string::npos) << short_token;
  EXPECT_NE(message("client eve\n").find("expected \"role name token\""), std::string::npos);
  EXPECT_NE(message("client eve eve-token-0123456789 extra\n").find("expected"), std::string::npos);
  std::string duplicate = message(
      "client eve same-token-0123456789\n"
      "worker mallory same-token-0123456789\n");
  EXPECT_NE(duplicate.find("t.txt:2"), std::string::npos) << duplicate;
  EXPECT_EQ(duplicate.find("same-token"), std::string::npos) << duplicate;
  // One name may hold tokens of two roles.
  EXPECT_EQ(message("client eve eve-client-0123456789\nadmin eve eve-admin-0123456789\n"),
            "accepted");
}

TEST(TokenTable, LoadRefusesMissingOrEmptyFiles) {
  auto dir = std::filesystem::temp_directory_path() / ("penumbra-auth-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  EXPECT_THROW(TokenTable::load((dir / "missing.txt").string()), std::runtime_error);
  std::ofstream(dir / "empty.txt") << "# nothing but comments\n\n";
  EXPECT_THROW(TokenTable::load((dir / "empty.txt").string()), std::runtime_error);
  std::ofstream(dir / "good.txt") << kTokens;
  EXPECT_EQ(TokenTable::load((dir / "good.txt").string()).size(), 4u);
  std::filesystem::remove_all(dir);
}

TEST(Roles, EachMethodNeedsItsRole) {
  EXPECT_EQ(required_role("/penumbra.v1.Jobs/SubmitJob"), Role::client);
  EXPECT_EQ(required_role("/penumbra.v1.Jobs/FetchResult"), Role::client);
  EXPECT_EQ(required_role("/penumbra.v1.Batches/SubmitBatch"), Role::client);
  EXPECT_EQ(required_role("/penumbra.v1.Workers/LeaseTasks"), Role::worker);
  EXPECT_EQ(required_role("/grpc.health.v1.Health/Check"), std::nullopt);
  EXPECT_EQ(required_role("/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo"),
            std::nullopt);
  // Anything unknown needs admin, including look-alike prefixes.
  EXPECT_EQ(required_role("/penumbra.v1.JobsAdmin/Drop"), Role::admin);
  EXPECT_EQ(required_role("/penumbra.v2.Jobs/SubmitJob"), Role::admin);
  EXPECT_EQ(required_role(""), Role::admin);
  EXPECT_TRUE(role_allows(Role::admin, Role::client));
  EXPECT_TRUE(role_allows(Role::admin, Role::worker));
  EXPECT_TRUE(role_allows(Role::admin, Role::admin));
  EXPECT_TRUE(role_allows(Role::client, Role::client));
  EXPECT_FALSE(role_allows(Role::client, Role::worker));
  EXPECT_FALSE(role_allows(Role::worker, Role::client));
  EXPECT_FALSE(role_allows(Role::client, Role::admin));
}

TEST(Roles, BearerHeader) {
  EXPECT_EQ(bearer_token("Bearer abc"), "abc");
  EXPECT_EQ(bearer_token("bearer   abc  "), "abc");
  EXPECT_EQ(bearer_token("BEARER abc"), "abc");
  EXPECT_EQ(bearer_token("Bearerabc"), std::nullopt);
  EXPECT_EQ(bearer_token("Basic abc"), std::nullopt);
  EXPECT_EQ(bearer_token("Bearer "), std::nullopt);
  EXPECT_EQ(bearer_token(""), std::nullopt);
}

TEST(Roles, DecisionForEveryRoleAndMethod) {
  AuthPolicy policy;
  policy.tokens = std::make_shared<const TokenTable>(TokenTable::parse(kTokens, "t"));
  auto code = [&](const char* method, std::optional<std::string_view> header) {
    return authorize_call(policy, method, header, false).status.error_code();
  };
  using grpc::StatusCode;
  const char* submit = "/penumbra.v1.Jobs/SubmitJob";
  const char* lease = "/penumbra.v1.Workers/LeaseTasks";
  EXPECT_EQ(code(submit, "Bearer alice-token-0123456789"), StatusCode::OK);
  EXPECT_EQ(code(lease, "Bearer alice-token-0123456789"), StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code(lease, "Bearer worker-token-0123456789"), StatusCode::OK);
  EXPECT_EQ(code(submit, "Bearer worker-token-0123456789"), StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code(submit, "Bearer root-token-0123456789"), StatusCode::OK);
  EXPECT_EQ(code(lease, "Bearer root-token-0123456789"), StatusCode::OK);
  EXPECT_EQ(code(submit, std::nullopt), StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code(submit, "Bearer nobody-0123456789abcdef"), StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code(submit, "alice-token-0123456789"), StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code("/grpc.health.v1.Health/Check", std::nullopt), StatusCode::OK);
  EXPECT_EQ(code("/penumbra.v1.Other/Do", "Bearer alice-token-0123456789"),
            StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code("/penumbra.v1.Other/Do", "Bearer root-token-0123456789"), StatusCode::OK);
  CallAuthorization alice = authorize_call(policy, submit, "Bearer alice-token-0123456789", false);
  ASSERT_TRUE(alice.principal);
  EXPECT_EQ(alice.principal->name, "alice");
  // The refusal names the caller and the role needed, never the token.
  grpc::Status denied =
      authorize_call(policy, lease, "Bearer alice-token-0123456789", false).status;
  EXPECT_NE(denied.error_message().find("alice"), std::string::npos);
  EXPECT_NE(denied.error_message().find("worker"), std::string::npos);
  EXPECT_EQ(denied.error_message().find("alice-token"), std::string::npos);
}

TEST(Roles, MutualTlsForWorkersOnly) {
  AuthPolicy policy;  // tokens off
  policy.workers_need_client_certificate = true;
  auto code = [&](const char* method, bool certificate) {
    return authorize_call(policy, method, std::nullopt, certificate).status.error_code();
  };
  EXPECT_EQ(code("/penumbra.v1.Workers/Register", false), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code("/penumbra.v1.Workers/Register", true), grpc::StatusCode::OK);
  EXPECT_EQ(code("/penumbra.v1.Jobs/ListJobs", false), grpc::StatusCode::OK);
  EXPECT_EQ(code("/grpc.health.v1.Health/Check", false), grpc::StatusCode::OK);
  // With tokens on, the certificate does not replace the token.
  policy.tokens = std::make_shared<const TokenTable>(TokenTable::parse(kTokens, "t"));
  EXPECT_EQ(code("/penumbra.v1.Workers/Register", true), grpc::StatusCode::UNAUTHENTICATED);
}

TEST(ClientConnection, LoopbackAddresses) {
  for (const char* address :
       {"127.0.0.1:7420", "localhost:7420", "LOCALHOST:1", "[::1]:7420", "::1", "127.1.2.3:80",
        "ipv4:127.0.0.1:7420", "dns:///localhost:7420", "unix:/tmp/penumbra.sock"})
    EXPECT_TRUE(is_loopback_address(address)) << address;
  for (const char* address :
       {"0.0.0.0:7420", "10.0.0.1:7420", "farm.example.com:7420", "127.0.0.1.example.com:7420",
        "localhost.example.com:1", "[::]:7420", "[2001:db8::1]:7420", "128.0.0.1:7420", ""})
    EXPECT_FALSE(is_loopback_address(address)) << address;
}

TEST(ClientConnection, RefusesTokensInPlaintextToRemoteHosts) {
  FarmConnection remote{"192.0.2.1:7420", "", "", "", "alice-token-0123456789"};
  try {
    make_farm_channel(remote);
    ADD_FAILURE() << "a token in plaintext to a remote host was accepted";
  } catch (const std::runtime_error& error) {
    std::string message = error.what();
    EXPECT_NE(message.find("plaintext"), std::string::npos) << message;
    EXPECT_NE(message.find("--tls-ca"), std::string::npos) << message;
    EXPECT_EQ(message.find("alice-token"), std::string::npos) << message;
  }
  // Loopback, or no token, or TLS: a channel.
  EXPECT_TRUE(make_farm_channel(FarmConnection{"127.0.0.1:7420", "", "", "", "t"}));
  EXPECT_TRUE(make_farm_channel(FarmConnection{"192.0.2.1:7420", "", "", "", ""}));
  FarmConnection tls{"192.0.2.1:7420", "", "", "", "t"};
  tls.tls = true;
  EXPECT_TRUE(make_farm_channel(tls));
  // Mutual TLS needs both halves; PEM files must exist.
  EXPECT_THROW(make_farm_channel(FarmConnection{"192.0.2.1:7420", "", "cert.pem", "", ""}),
               std::runtime_error);
  EXPECT_THROW(
      make_farm_channel(FarmConnection{"192.0.2.1:7420", "/nonexistent/ca.pem", "", "", ""}),
      std::runtime_error);
}

TEST(ClientConnection, TokenFromFlagFileOrEnvironment) {
  auto dir =
      std::filesystem::temp_directory_path() / ("penumbra-token-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "token") << "  file-token-0123456789 \nsecond line\n";
  std::ofstream(dir / "blank") << "\n";
  ::setenv("PENUMBRA_TOKEN", "env-token-0123456789", 1);
  EXPECT_EQ(resolve_token("flag-token", (dir / "token").string()), "flag-token");
  EXPECT_EQ(resolve_token("", (dir / "token").string()), "file-token-0123456789");
  EXPECT_EQ(resolve_token("", ""), "env-token-0123456789");
  EXPECT_THROW(resolve_token("", (dir / "blank").string()), std::runtime_error);
  EXPECT_THROW(resolve_token("", (dir / "missing").string()), std::runtime_error);
  ::unsetenv("PENUMBRA_TOKEN");
  EXPECT_EQ(resolve_token("", ""), "");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
