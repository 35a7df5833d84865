#include "server/tls.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace penumbra::farm {

namespace {

std::string read_pem(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  if (!in || text.str().empty()) throw std::runtime_error("cannot read the " + what + " " + path);
  return text.str();
}

}  // namespace

std::shared_ptr<grpc::ServerCredentials> make_server_tls_credentials(const ServerTlsFiles& files) {
  if (files.cert.empty() || files.key.empty())
    throw std::runtime_error("TLS needs both --tls-cert and --tls-key");
  grpc::SslServerCredentialsOptions options(files.client_ca.empty()
                                                ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                                : GRPC_SSL_REQUEST_CLIENT_CERTIFICATE_AND_VERIFY);
  options.pem_key_cert_pairs.push_back(
      {read_pem(files.key, "TLS key"), read_pem(files.cert, "TLS certificate")});
  if (!files.client_ca.empty())
    options.pem_root_certs = read_pem(files.client_ca, "client CA file");
  return grpc::SslServerCredentials(options);
}

}  // namespace penumbra::farm
