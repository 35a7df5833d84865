// TLS with certificates made at test time by the openssl command: a job completes over TLS with
// tokens (client and worker), bit for bit; a plaintext client to a TLS coordinator fails with
// UNAVAILABLE; with --tls-client-ca (mutual TLS for workers) a worker without a client
// certificate is refused, one with a certificate of another CA cannot connect, one with a
// certificate of the CA works, while clients still need none.
#if __has_include("penumbra/v1/farm.pb.h")
#include <gtest/gtest.h>

#include "penumbra/version.h"
#include "security_test_support.h"

namespace penumbra::farm {
namespace {

using namespace std::chrono_literals;
using grpc::StatusCode;
using testing::code_of;
using testing::connection_to;
using testing::CoordinatorProcess;

class FarmTls : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::filesystem::path(testing::fresh_directory("tls"));
    certificates_ = new testing::TestCertificates(testing::make_test_certificates(*dir_ / "certs"));
    tokens_ = new std::filesystem::path(testing::write_tokens_file(*dir_));
    scene_ = new std::string(testing::write_scene(*dir_, 32, 24));
  }
  static void TearDownTestSuite() {
    delete scene_;
    delete tokens_;
    delete certificates_;
    delete dir_;
  }
  static std::vector<std::string> tls_arguments(bool mutual) {
    std::vector<std::string> arguments = {"--tokens-file", tokens_->string(),
                                          "--tls-cert",    certificates_->server_cert.string(),
                                          "--tls-key",     certificates_->server_key.string()};
    if (mutual) {
      arguments.push_back("--tls-client-ca");
      arguments.push_back(certificates_->ca.string());
    }
    return arguments;
  }
  static StatusCode register_code(const FarmConnection& connection) {
    v1::RegisterRequest request;
    request.set_name("probe");
    request.set_threads(1);
    request.set_version(kVersion);
    request.set_build_flavour(kBuildFlavour);
    request.set_protocol_version(v1::PROTOCOL_VERSION_CURRENT);
    v1::RegisterResponse response;
    return v1::Workers::NewStub(make_farm_channel(connection))
        ->Register(testing::short_context().get(), request, &response)
        .error_code();
  }

  static std::filesystem::path* dir_;
  static testing::TestCertificates* certificates_;
  static std::filesystem::path* tokens_;
  static std::string* scene_;
};
std::filesystem::path* FarmTls::dir_ = nullptr;
testing::TestCertificates* FarmTls::certificates_ = nullptr;
std::filesystem::path* FarmTls::tokens_ = nullptr;
std::string* FarmTls::scene_ = nullptr;

TEST_F(FarmTls, JobCompletesOverTlsWithTokens) {
  CoordinatorProcess coordinator(*dir_ / "data-tls", 0, tls_arguments(false));
  auto worker = testing::start_worker_with(
      coordinator.address(), *dir_, "tls-worker",
      {"--tls-ca", certificates_->ca.string(), "--token", testing::kWorkerToken});
  FarmClient client(connection_to(coordinator.address(), testing::kAliceToken, certificates_->ca));
  std::string job = client.submit(testing::job_spec(*scene_, "sa", 8, 11)).job_id();
  v1::JobStatus final_status = client.wait(job, 60s);
  ASSERT_EQ(final_status.state(), v1::JOB_STATE_DONE) << final_status.error();
  EXPECT_EQ(final_status.owner(), "alice");
  testing::expect_bit_identical(client, job, *scene_, "sa", 8, 11);
  // Roles hold over TLS too.
  FarmClient worker_token(
      connection_to(coordinator.address(), testing::kWorkerToken, certificates_->ca));
  EXPECT_EQ(code_of([&] { worker_token.fetch(job); }), StatusCode::PERMISSION_DENIED);
  FarmClient no_token(connection_to(coordinator.address(), "", certificates_->ca));
  EXPECT_EQ(code_of([&] { no_token.list(); }), StatusCode::UNAUTHENTICATED);
  // Health is open over TLS.
  auto [status, bytes] = testing::health_check(
      make_farm_channel(connection_to(coordinator.address(), "", certificates_->ca)));
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(bytes, std::string("\x08\x01", 2));

  // The command-line client: --tls-ca with a token file works; without a token it is refused.
  auto token_file = *dir_ / "alice.token";
  std::ofstream(token_file) << testing::kAliceToken << "\n";
  auto run_client = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> arguments = {testing::binary("client/penumbra"),
                                          "list",
                                          "--coordinator",
                                          coordinator.address(),
                                          "--tls-ca",
                                          certificates_->ca.string()};
    arguments.insert(arguments.end(), extra.begin(), extra.end());
    auto log = *dir_ / (name + ".log");
    testing::ChildProcess process(arguments, log.string());
    int code = process.wait_exit(60s);
    std::ifstream in(log);
    return std::make_pair(
        code, std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()));
  };
  auto [listed, list_output] = run_client("client-list", {"--token-file", token_file.string()});
  EXPECT_EQ(listed, 0) << list_output;
  EXPECT_NE(list_output.find(job), std::string::npos) << list_output;
  auto [refused, refused_output] = run_client("client-refused", {});
  EXPECT_NE(refused, 0) << refused_output;
  EXPECT_NE(refused_output.find("UNAUTHENTICATED"), std::string::npos) << refused_output;

  // A plaintext client cannot talk to the TLS coordinator.
  FarmClient plaintext(connection_to(coordinator.address(), testing::kAliceToken));
  EXPECT_EQ(code_of([&] { plaintext.list(); }), StatusCode::UNAVAILABLE);
  // Nor a client that does not trust the coordinator's CA.
  FarmClient distrustful(
      connection_to(coordinator.address(), testing::kAliceToken, *dir_ / "certs" / "rogue-ca.pem"));
  EXPECT_EQ(code_of([&] { distrustful.list(); }), StatusCode::UNAVAILABLE);
}

TEST_F(FarmTls, MutualTlsRequiresAWorkerCertificate) {
  CoordinatorProcess coordinator(*dir_ / "data-mtls", 0, tls_arguments(true));
  const auto& certs = *certificates_;
  // Probes of the workers API: no client certificate is refused by the coordinator, a
  // certificate of another CA fails the handshake, the CA's certificate passes.
  EXPECT_EQ(register_code(connection_to(coordinator.address(), testing::kWorkerToken, certs.ca)),
            StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(register_code(connection_to(coordinator.address(), testing::kWorkerToken, certs.ca,
                                        certs.rogue_cert, certs.rogue_key)),
            StatusCode::UNAVAILABLE);
  EXPECT_EQ(register_code(connection_to(coordinator.address(), testing::kWorkerToken, certs.ca,
                                        certs.client_cert, certs.client_key)),
            StatusCode::OK);
  // The certificate does not stand in for the token.
  EXPECT_EQ(register_code(connection_to(coordinator.address(), "", certs.ca, certs.client_cert,
                                        certs.client_key)),
            StatusCode::UNAUTHENTICATED);

  // A worker process without a certificate is refused (exit code 2) and renders nothing.
  FarmClient client(connection_to(coordinator.address(), testing::kAliceToken, certs.ca));
  std::string job = client.submit(testing::job_spec(*scene_, "sa", 8, 12)).job_id();
  auto refused =
      testing::start_worker_with(coordinator.address(), *dir_, "no-cert",
                                 {"--tls-ca", certs.ca.string(), "--token", testing::kWorkerToken});
  EXPECT_EQ(refused->wait_exit(30s), 2);
  EXPECT_EQ(client.status(job).tasks_complete(), 0u);
  // With the certificate it works.
  auto worker = testing::start_worker_with(
      coordinator.address(), *dir_, "with-cert",
      {"--tls-ca", certs.ca.string(), "--tls-cert", certs.client_cert.string(), "--tls-key",
       certs.client_key.string(), "--token", testing::kWorkerToken});
  v1::JobStatus final_status = client.wait(job, 60s);
  ASSERT_EQ(final_status.state(), v1::JOB_STATE_DONE) << final_status.error();
  testing::expect_bit_identical(client, job, *scene_, "sa", 8, 12);
}

}  // namespace
}  // namespace penumbra::farm
#else
#include <gtest/gtest.h>
TEST(FarmNotBuilt, Skipped) {
  GTEST_SKIP() << "configured with PENUMBRA_FARM=OFF";
}
#endif
