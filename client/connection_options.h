#pragma once
// How a farm command reaches its coordinator: the address (--coordinator, else
// PENUMBRA_COORDINATOR, else 127.0.0.1:7420), TLS (--tls-ca or PENUMBRA_TLS_CA; mutual with
// --tls-cert and --tls-key) and a bearer token (--token, --token-file or PENUMBRA_TOKEN). Shared
// by the job commands (client/farm_commands.cpp) and the batch commands
// (client/batch_commands.cpp). Built only with the farm.

#include <CLI/CLI.hpp>
#include <string>

#include "proto/support/farm_client.h"

namespace penumbra {

// The connection options as given on the command line; the defaults come from the environment.
struct ConnectionArguments {
  ConnectionArguments();
  std::string coordinator;  // host:port
  std::string tls_ca;       // PEM file
  std::string tls_cert, tls_key, token, token_file;
};

// Adds --coordinator, --tls-ca, --tls-cert, --tls-key, --token and --token-file to `command`.
void add_connection_options(CLI::App* command, ConnectionArguments& connection);

// The connection the arguments describe, with the token resolved (--token, else the first line
// of --token-file, else PENUMBRA_TOKEN; throws when --token-file cannot be read).
farm::FarmConnection connection_of(const ConnectionArguments& arguments);

}  // namespace penumbra
