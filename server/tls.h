#pragma once
// The coordinator's TLS credentials from PEM files: its certificate and key, and optionally the
// CA of client certificates (mutual TLS: certificates are verified when presented; the auth
// interceptor, server/auth.h, then requires one for the Workers service).

#include <grpcpp/security/server_credentials.h>

#include <memory>
#include <string>

namespace penumbra::farm {

struct ServerTlsFiles {
  std::string cert;       // PEM certificate chain of the coordinator
  std::string key;        // PEM private key
  std::string client_ca;  // PEM CA of client certificates; empty: none requested
};

// Throws std::runtime_error naming the file that cannot be read, or when cert or key is missing.
std::shared_ptr<grpc::ServerCredentials> make_server_tls_credentials(const ServerTlsFiles& files);

}  // namespace penumbra::farm
