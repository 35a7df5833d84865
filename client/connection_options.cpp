// The farm commands' connection options (client/connection_options.h).
#include "client/connection_options.h"

#include <cstdlib>

namespace penumbra {

namespace {

std::string environment(const char* name, const std::string& fallback = "") {
  const char* value = std::getenv(name);
  return value && *value ? value : fallback;
}

}  // namespace

ConnectionArguments::ConnectionArguments()
    : coordinator(environment("PENUMBRA_COORDINATOR", "127.0.0.1:7420")),
      tls_ca(environment("PENUMBRA_TLS_CA")) {}

void add_connection_options(CLI::App* command, ConnectionArguments& connection) {
  command->add_option("--coordinator", connection.coordinator,
                      "host:port of the coordinator (default: PENUMBRA_COORDINATOR or "
                      "127.0.0.1:7420)");
  command->add_option("--tls-ca", connection.tls_ca,
                      "PEM file of the CA that signed the coordinator's certificate: connect "
                      "with TLS (default: PENUMBRA_TLS_CA)");
  command->add_option("--tls-cert", connection.tls_cert,
                      "PEM client certificate, for mutual TLS (with --tls-key)");
  command->add_option("--tls-key", connection.tls_key, "PEM private key of --tls-cert");
  command->add_option("--token", connection.token,
                      "bearer token (visible in ps: prefer --token-file or PENUMBRA_TOKEN)");
  command->add_option("--token-file", connection.token_file, "file whose first line is the token");
}

farm::FarmConnection connection_of(const ConnectionArguments& arguments) {
  farm::FarmConnection connection;
  connection.address = arguments.coordinator;
  connection.tls_ca = arguments.tls_ca;
  connection.tls_cert = arguments.tls_cert;
  connection.tls_key = arguments.tls_key;
  connection.token = farm::resolve_token(arguments.token, arguments.token_file);
  return connection;
}

}  // namespace penumbra
