#pragma once
// Helpers for the security tests: certificates made at test time with the openssl command (a
// self-signed CA, a server certificate for 127.0.0.1 and localhost, a client certificate, and a
// second CA nobody trusts), a tokens file with one name per role, and connections to a coordinator
// with a given token. Processes and scenes come from tests/farm/farm_test_support.h.

#include <grpcpp/generic/generic_stub.h>

#include <condition_variable>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <string>

#include "../farm/farm_test_support.h"

namespace penumbra::farm::testing {

struct TestCertificates {
  std::filesystem::path ca;                       // the CA both sides trust
  std::filesystem::path server_cert, server_key;  // CN=localhost, SAN DNS:localhost, IP:127.0.0.1
  std::filesystem::path client_cert, client_key;  // CN=worker-1, signed by `ca`
  std::filesystem::path rogue_cert, rogue_key;    // a client certificate of another CA
};

// Runs a shell command; throws with its output when it fails.
inline void run_shell(const std::string& command, const std::filesystem::path& log) {
  std::string line = "(" + command + ") > '" + log.string() + "' 2>&1";
  if (std::system(line.c_str()) != 0) {
    std::ifstream in(log);
    std::string output((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    throw std::runtime_error("failed: " + command + "\n" + output);
  }
}

inline TestCertificates make_test_certificates(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  const std::string d = dir.string();
  auto path = [&](const std::string& name) { return dir / name; };
  // EC P-256 keys: quick to make. Leaf certificates carry the extensions TLS checks.
  std::ofstream(path("server.ext")) << "basicConstraints=CA:FALSE\n"
                                       "keyUsage=critical,digitalSignature,keyEncipherment\n"
                                       "extendedKeyUsage=serverAuth\n"
                                       "subjectAltName=DNS:localhost,IP:127.0.0.1\n";
  std::ofstream(path("client.ext")) << "basicConstraints=CA:FALSE\n"
                                       "keyUsage=critical,digitalSignature,keyEncipherment\n"
                                       "extendedKeyUsage=clientAuth\n";
  const std::string key = "-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes";
  auto make_ca = [&](const std::string& name, const std::string& subject) {
    run_shell("openssl req -x509 " + key + " -keyout '" + d + "/" + name + ".key' -out '" + d +
                  "/" + name + ".pem' -days 2 -subj '" + subject +
                  "' -addext basicConstraints=critical,CA:TRUE"
                  " -addext keyUsage=critical,keyCertSign,cRLSign",
              path(name + "-openssl.log"));
  };
  auto make_leaf = [&](const std::string& name, const std::string& ca, const std::string& subject,
                       const std::string& extensions) {
    run_shell("openssl req " + key + " -keyout '" + d + "/" + name + ".key' -out '" + d + "/" +
                  name + ".csr' -subj '" + subject + "' && openssl x509 -req -in '" + d + "/" +
                  name + ".csr' -CA '" + d + "/" + ca + ".pem' -CAkey '" + d + "/" + ca +
                  ".key' -CAcreateserial -days 2 -out '" + d + "/" + name + ".pem' -extfile '" + d +
                  "/" + extensions + "'",
              path(name + "-openssl.log"));
  };
  make_ca("ca", "/CN=penumbra-test-ca");
  make_ca("rogue-ca", "/CN=penumbra-rogue-ca");
  make_leaf("server", "ca", "/CN=localhost", "server.ext");
  make_leaf("client", "ca", "/CN=worker-1", "client.ext");
  make_leaf("rogue", "rogue-ca", "/CN=rogue-worker", "client.ext");
  return {path("ca.pem"),     path("server.pem"), path("server.key"), path("client.pem"),
          path("client.key"), path("rogue.pem"),  path("rogue.key")};
}

// One name per role, tokens long enough for the coordinator.
inline constexpr const char* kAliceToken = "client-alice-7f3a9c2e5b1d4086";
inline constexpr const char* kBobToken = "client-bob-2c8e41f09a7b6d35";
inline constexpr const char* kWorkerToken = "worker-w1-93b0e7d45a2c18f6";
inline constexpr const char* kAdminToken = "admin-root-5d17a2c9e84f3b60";

inline std::filesystem::path write_tokens_file(const std::filesystem::path& dir) {
  auto path = dir / "tokens.txt";
  std::ofstream(path) << "# role name token\n"
                      << "client alice " << kAliceToken << "\n"
                      << "client bob   " << kBobToken << "   # a second client\n\n"
                      << "worker w1 " << kWorkerToken << "\n"
                      << "admin root " << kAdminToken << "\n";
  return path;
}

inline FarmConnection connection_to(const std::string& address, const std::string& token,
                                    const std::filesystem::path& ca = {},
                                    const std::filesystem::path& cert = {},
                                    const std::filesystem::path& key = {}) {
  FarmConnection connection;
  connection.address = address;
  connection.token = token;
  connection.tls_ca = ca.string();
  connection.tls_cert = cert.string();
  connection.tls_key = key.string();
  return connection;
}

// grpc.health.v1.Health/Check for the whole server ("" service), as raw bytes: the status and the
// serialized HealthCheckResponse ("\x08\x01" is SERVING).
inline std::pair<grpc::Status, std::string> health_check(
    const std::shared_ptr<grpc::Channel>& channel) {
  grpc::GenericStub generic(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  grpc::Slice empty("", 0);
  grpc::ByteBuffer request(&empty, 1), response;
  std::mutex mutex;
  std::condition_variable done;
  bool finished = false;
  grpc::Status status;
  generic.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request,
                    &response, [&](grpc::Status result) {
                      std::lock_guard lock(mutex);
                      status = result;
                      finished = true;
                      done.notify_all();
                    });
  std::unique_lock lock(mutex);
  done.wait(lock, [&] { return finished; });
  std::string bytes;
  std::vector<grpc::Slice> slices;
  if (status.ok() && response.Dump(&slices).ok())
    for (const grpc::Slice& slice : slices)
      bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
  return {status, bytes};
}

// A call's status code, or OK; for checks like EXPECT_EQ(code_of([&] { ... }), ...).
template <typename Call>
grpc::StatusCode code_of(Call&& call) {
  try {
    call();
  } catch (const FarmCallError& error) {
    return error.code();
  }
  return grpc::StatusCode::OK;
}

inline std::unique_ptr<grpc::ClientContext> short_context() {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  return context;
}

}  // namespace penumbra::farm::testing
