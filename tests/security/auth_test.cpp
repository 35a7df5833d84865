// The pieces of authentication without a server: the tokens file, the role of each method, the
// decision for a call, bearer headers, loopback addresses, where a client's token comes from, and
// the client refusing to send a token in plaintext to a remote host. Then the HTTP side in
// process (a coordinator and its HttpFrontend, no gRPC): every route without a token, with
// another client's, its own, a viewer's, a worker's; tokens in the address carried on by the
// pages; /metrics open only when asked; HTTPS with the coordinator's certificate.
#if __has_include("penumbra/v1/farm.pb.h")
#include "server/auth.h"

#include <gtest/gtest.h>
#include <httplib.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>

#include "proto/support/batch_client.h"
#include "proto/support/farm_client.h"
#include "proto/support/scene_packing.h"
#include "security_test_support.h"
#include "server/batch_manager.h"
#include "server/http_frontend.h"

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

TEST(Roles, ViewerHasNoGrpcMethod) {
  TokenTable table = TokenTable::parse("viewer wall wall-token-0123456789\n", "t");
  ASSERT_EQ(table.find("wall-token-0123456789")->role, Role::viewer);
  for (Role required : {Role::client, Role::worker, Role::admin})
    EXPECT_FALSE(role_allows(Role::viewer, required));
  AuthPolicy policy;
  policy.tokens = std::make_shared<const TokenTable>(table);
  grpc::Status status =
      authorize_call(policy, "/penumbra.v1.Jobs/ListJobs", "Bearer wall-token-0123456789", false)
          .status;
  EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(status.error_message().find("has role viewer"), std::string::npos);
}

TEST(HttpAuth, DecisionForEveryRole) {
  TokenTable table =
      TokenTable::parse(std::string(kTokens) + "viewer wall wall-token-0123456789\n", "t");
  auto decide = [&](std::optional<std::string_view> header,
                    std::optional<std::string_view> parameter) {
    return authorize_http(&table, header, parameter);
  };
  EXPECT_EQ(decide(std::nullopt, std::nullopt).status, 401);
  EXPECT_EQ(decide("Basic alice-token-0123456789", std::nullopt).status, 401);
  EXPECT_EQ(decide("Bearer nobody-0123456789abcdef", std::nullopt).status, 401);
  EXPECT_EQ(decide(std::nullopt, "").status, 401);
  HttpAuthorization alice = decide("Bearer alice-token-0123456789", std::nullopt);
  EXPECT_EQ(alice.status, 200);
  EXPECT_FALSE(alice.caller.sees_every_job);
  EXPECT_EQ(alice.caller.client, "alice");
  EXPECT_FALSE(alice.sees_farm);
  EXPECT_FALSE(alice.token_from_query);
  HttpAuthorization from_query = decide(std::nullopt, "alice-token-0123456789");
  EXPECT_EQ(from_query.status, 200);
  EXPECT_TRUE(from_query.token_from_query);
  // The header wins over the parameter, even when it is malformed.
  EXPECT_EQ(decide("Bearer nobody-0123456789abcdef", "alice-token-0123456789").status, 401);
  HttpAuthorization viewer = decide("Bearer wall-token-0123456789", std::nullopt);
  EXPECT_EQ(viewer.status, 200);
  EXPECT_TRUE(viewer.caller.sees_every_job);
  EXPECT_TRUE(viewer.sees_farm);
  EXPECT_TRUE(decide("Bearer root-token-0123456789", std::nullopt).sees_farm);
  HttpAuthorization worker = decide("Bearer worker-token-0123456789", std::nullopt);
  EXPECT_EQ(worker.status, 403);
  EXPECT_NE(worker.message.find("w1"), std::string::npos);
  EXPECT_EQ(worker.message.find("worker-token"), std::string::npos);
  // Authentication off: everything is open.
  HttpAuthorization open = authorize_http(nullptr, std::nullopt, std::nullopt);
  EXPECT_EQ(open.status, 200);
  EXPECT_TRUE(open.caller.sees_every_job);
  EXPECT_TRUE(open.sees_farm);
}

// A coordinator with a job and a batch of alice's and a job of bob's, its HTTP side with tokens.
class HttpRoutes : public ::testing::Test {
 protected:
  static constexpr const char* kViewerToken = "viewer-wall-0a1b2c3d4e5f6789";

  static void SetUpTestSuite() {
    dir_ = new std::filesystem::path(testing::fresh_directory("http-auth"));
    std::ofstream(*dir_ / "tokens.txt")
        << "client alice " << testing::kAliceToken << "\nclient bob " << testing::kBobToken
        << "\nworker w1 " << testing::kWorkerToken << "\nadmin root " << testing::kAdminToken
        << "\nviewer wall " << kViewerToken << "\n";
    tokens_ = new std::shared_ptr<const TokenTable>(
        std::make_shared<const TokenTable>(TokenTable::load((*dir_ / "tokens.txt").string())));
    CoordinatorOptions options;
    options.data_dir = (*dir_ / "data").string();
    coordinator_ = new Coordinator(options, parse_wire_package);
    BatchManagerOptions batch_options;
    batch_options.data_dir = options.data_dir;
    batch_options.max_spp = options.max_spp;
    batches_ = new BatchManager(*coordinator_, parse_wire_package, batch_options);
    std::string scene = testing::write_scene(*dir_, 32, 24);
    alice_job_ = new std::string(
        coordinator_->submit(CallContext::of_client("alice"), testing::job_spec(scene, "sa", 4, 1))
            .job_id());
    bob_job_ = new std::string(
        coordinator_->submit(CallContext::of_client("bob"), testing::job_spec(scene, "sa", 4, 2))
            .job_id());
    const std::string spec = R"({"format": "penumbra/batch@1", "name": "owned", "scene": ")" +
                             scene + R"(", "methods": ["sa"], "budget": {"seconds": 1},
        "reference": {"method": "sa", "spp": 2}, "repeats": 1})";
    auto request = make_batch_request_from_text(spec, "owned.json", dir_->string(),
                                                [](const std::string& name) { return name; });
    alice_batch_ =
        new std::string(batches_->submit(request, CallContext::of_client("alice")).batch_id());
    HttpFrontendOptions http_options;
    http_options.batches = batches_;
    http_options.tokens = *tokens_;
    http_ = new HttpFrontend(*coordinator_, http_options);
  }
  static void TearDownTestSuite() {
    delete http_;
    delete batches_;
    delete coordinator_;
    delete tokens_;
    std::filesystem::remove_all(*dir_);
    delete dir_;
    delete alice_job_;
    delete bob_job_;
    delete alice_batch_;
  }
  // GET `path` with "Authorization: Bearer <token>" (none for an empty token).
  static httplib::Result get(const std::string& path, const std::string& token = "") {
    httplib::Client client(http_->host(), http_->port());
    httplib::Headers headers;
    if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
    return client.Get(path, headers);
  }
  static int status(const std::string& path, const std::string& token = "") {
    auto result = get(path, token);
    return result ? result->status : 0;
  }

  static std::filesystem::path* dir_;
  static std::shared_ptr<const TokenTable>* tokens_;
  static Coordinator* coordinator_;
  static BatchManager* batches_;
  static HttpFrontend* http_;
  static std::string *alice_job_, *bob_job_, *alice_batch_;
};
std::filesystem::path* HttpRoutes::dir_ = nullptr;
std::shared_ptr<const TokenTable>* HttpRoutes::tokens_ = nullptr;
Coordinator* HttpRoutes::coordinator_ = nullptr;
BatchManager* HttpRoutes::batches_ = nullptr;
HttpFrontend* HttpRoutes::http_ = nullptr;
std::string* HttpRoutes::alice_job_ = nullptr;
std::string* HttpRoutes::bob_job_ = nullptr;
std::string* HttpRoutes::alice_batch_ = nullptr;

TEST_F(HttpRoutes, EveryRouteButHealthNeedsAToken) {
  const std::string job = *alice_job_;
  for (const std::string& path :
       {std::string("/"), std::string("/api/summary"), std::string("/api/jobs"), "/api/jobs/" + job,
        "/api/jobs/" + job + "/preview.png", std::string("/api/workers"), "/jobs/" + job,
        "/batches/" + *alice_batch_, std::string("/metrics"), std::string("/no-such-route")}) {
    SCOPED_TRACE(path);
    auto result = get(path);
    ASSERT_TRUE(result);
    EXPECT_EQ(result->status, 401);
    EXPECT_EQ(result->get_header_value("WWW-Authenticate"), "Bearer realm=\"penumbra\"");
    EXPECT_EQ(result->body.find(job + "\""), std::string::npos);  // no job's data
    EXPECT_EQ(status(path, "nobody-0123456789abcdef"), 401);
    EXPECT_EQ(status(path, testing::kWorkerToken), 403);
    // A token in the wrong scheme is no token.
    httplib::Client client(http_->host(), http_->port());
    auto basic = client.Get(path, {{"Authorization", std::string("Basic ") + kViewerToken}});
    ASSERT_TRUE(basic);
    EXPECT_EQ(basic->status, 401);
  }
  auto health = get("/healthz");
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  EXPECT_EQ(health->get_header_value("Referrer-Policy"), "no-referrer");
}

TEST_F(HttpRoutes, AClientSeesItsOwnJobsAndBatchesOnlyAViewerSeesAll) {
  const std::string job = *alice_job_, bobs = *bob_job_, batch = *alice_batch_;
  // One job's and one batch's routes: 404 for bob (the words of an unknown id), 200 for alice,
  // the viewer and the admin.
  for (const std::string& path : {"/api/jobs/" + job, "/api/jobs/" + job + "/preview.png",
                                  "/jobs/" + job, "/batches/" + batch}) {
    SCOPED_TRACE(path);
    auto other = get(path, testing::kBobToken);
    ASSERT_TRUE(other);
    EXPECT_EQ(other->status, 404);
    std::string unknown_path = path;
    for (const std::string& id : {job, batch})
      if (size_t at = unknown_path.find(id); at != std::string::npos)
        unknown_path.replace(at, id.size(), id.substr(0, id.find('-')) + "-987654");
    auto unknown = get(unknown_path, testing::kBobToken);
    ASSERT_TRUE(unknown);
    EXPECT_EQ(unknown->status, 404);
    EXPECT_EQ(other->body.find("alice"), std::string::npos);
    EXPECT_EQ(status(path, testing::kAliceToken), 200);
    EXPECT_EQ(status(path, kViewerToken), 200);
    EXPECT_EQ(status(path, testing::kAdminToken), 200);
  }
  // Lists: alice's jobs only for alice, both for the viewer; the dashboard likewise.
  auto alice_list = get("/api/jobs", testing::kAliceToken);
  ASSERT_TRUE(alice_list);
  EXPECT_EQ(alice_list->status, 200);
  EXPECT_NE(alice_list->body.find("\"" + job + "\""), std::string::npos);
  EXPECT_EQ(alice_list->body.find("\"" + bobs + "\""), std::string::npos);
  EXPECT_EQ(alice_list->body.find("\"bob\""), std::string::npos);
  auto viewer_list = get("/api/jobs", kViewerToken);
  ASSERT_TRUE(viewer_list);
  EXPECT_NE(viewer_list->body.find("\"" + job + "\""), std::string::npos);
  EXPECT_NE(viewer_list->body.find("\"" + bobs + "\""), std::string::npos);
  auto bob_page = get("/", testing::kBobToken);
  ASSERT_TRUE(bob_page);
  EXPECT_EQ(bob_page->status, 200);
  EXPECT_NE(bob_page->body.find("data-job-id=\"" + bobs + "\""), std::string::npos);
  EXPECT_EQ(bob_page->body.find("data-job-id=\"" + job + "\""), std::string::npos);
  auto wall = get("/", kViewerToken);
  ASSERT_TRUE(wall);
  EXPECT_NE(wall->body.find("data-job-id=\"" + job + "\""), std::string::npos);
  EXPECT_NE(wall->body.find("data-job-id=\"" + bobs + "\""), std::string::npos);
  // The farm's aggregate figures are any client's; /metrics (every job by id) is not.
  EXPECT_EQ(status("/api/summary", testing::kBobToken), 200);
  EXPECT_EQ(status("/api/workers", testing::kBobToken), 200);
  EXPECT_EQ(status("/metrics", testing::kBobToken), 403);
  EXPECT_EQ(status("/metrics", kViewerToken), 200);
  EXPECT_EQ(status("/metrics", testing::kAdminToken), 200);
}

TEST_F(HttpRoutes, ATokenInTheAddressIsCarriedOnByThePages) {
  const std::string job = *alice_job_;
  httplib::Client client(http_->host(), http_->port());
  const std::string query = std::string("?token=") + testing::kAliceToken;
  auto page = client.Get("/jobs/" + job + query);
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("src=\"/api/jobs/" + job + "/preview.png" + query + "\""),
            std::string::npos);
  EXPECT_NE(page->body.find("<a href=\"/" + query + "\">dashboard</a>"), std::string::npos);
  EXPECT_EQ(page->get_header_value("Referrer-Policy"), "no-referrer");
  auto image = client.Get("/api/jobs/" + job + "/preview.png" + query);
  ASSERT_TRUE(image);
  EXPECT_EQ(image->status, 200);
  EXPECT_EQ(image->get_header_value("Content-Type"), "image/png");
  auto dashboard = client.Get("/" + query);
  ASSERT_TRUE(dashboard);
  EXPECT_EQ(dashboard->status, 200);
  EXPECT_NE(
      dashboard->body.find("/preview.png?passes=0&amp;token=" + std::string(testing::kAliceToken)),
      std::string::npos);
  auto batch = client.Get("/batches/" + *alice_batch_ + query);
  ASSERT_TRUE(batch);
  EXPECT_EQ(batch->status, 200);
  EXPECT_NE(batch->body.find("<a href=\"/" + query + "\">dashboard</a>"), std::string::npos);
  // Without one the links stay bare; another client's token in the address is 404.
  auto bare = get("/jobs/" + job, testing::kAliceToken);
  ASSERT_TRUE(bare);
  EXPECT_EQ(bare->body.find("token="), std::string::npos);
  auto other = client.Get("/jobs/" + job + "?token=" + testing::kBobToken);
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 404);
  // Nothing but GET is served (the side changes nothing).
  auto post = client.Post("/api/jobs" + query, "", "application/json");
  ASSERT_TRUE(post);
  EXPECT_NE(post->status, 200);
}

TEST(HttpAuth, OpenMetricsAndHttpsWithTheCoordinatorsCertificate) {
  auto dir = testing::fresh_directory("http-tls");
  auto certificates = testing::make_test_certificates(dir / "certs");
  auto tokens = std::make_shared<const TokenTable>(TokenTable::parse(kTokens, "t"));
  CoordinatorOptions options;
  options.data_dir = (dir / "data").string();
  Coordinator coordinator(options, parse_wire_package);
  HttpFrontendOptions http_options;
  http_options.tokens = tokens;
  http_options.open_metrics = true;
  http_options.tls_cert = certificates.server_cert.string();
  http_options.tls_key = certificates.server_key.string();
  HttpFrontend http(coordinator, http_options);
  httplib::SSLClient client(http.host(), http.port());
  client.set_ca_cert_path(certificates.ca.string().c_str());
  client.enable_server_certificate_verification(true);
  auto metrics = client.Get("/metrics");  // open: no token
  ASSERT_TRUE(metrics) << httplib::to_string(metrics.error());
  EXPECT_EQ(metrics->status, 200);
  EXPECT_NE(metrics->body.find("penumbra_queue_depth"), std::string::npos);
  auto jobs = client.Get("/api/jobs");
  ASSERT_TRUE(jobs);
  EXPECT_EQ(jobs->status, 401);
  auto with_token = client.Get("/api/jobs", {{"Authorization", "Bearer alice-token-0123456789"}});
  ASSERT_TRUE(with_token);
  EXPECT_EQ(with_token->status, 200);
  // Plain HTTP to the HTTPS port gets no answer.
  httplib::Client plain(http.host(), http.port());
  plain.set_read_timeout(std::chrono::seconds(2));
  auto refused = plain.Get("/healthz");
  EXPECT_TRUE(!refused || refused->status != 200);
  // A certificate the client does not trust is refused by the client.
  httplib::SSLClient untrusting(http.host(), http.port());
  untrusting.set_ca_cert_path((dir / "certs" / "rogue-ca.pem").string().c_str());
  untrusting.enable_server_certificate_verification(true);
  EXPECT_FALSE(untrusting.Get("/healthz"));
  http.stop();
  // A certificate without its key is refused at start-up.
  HttpFrontendOptions half;
  half.tls_cert = certificates.server_cert.string();
  EXPECT_THROW(HttpFrontend(coordinator, half), std::runtime_error);
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
