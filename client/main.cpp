// penumbra: the command-line client. Local commands live in client/local_commands.cpp; farm
// commands (submit, watch, ...) in client/farm_commands.cpp when the farm is built.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "client/commands.h"
#include "penumbra/version.h"

int main(int argc, char** argv) {
  CLI::App app{"Penumbra: direct illumination with point and line samples, on a render farm"};
  app.set_version_flag("--version", std::string(penumbra::kVersion));
  app.require_subcommand(1);
  penumbra::add_local_commands(app);
  penumbra::add_exact_commands(app);
  penumbra::add_verify_command(app);
#ifdef PENUMBRA_WITH_FARM
  penumbra::add_farm_commands(app);
  penumbra::add_batch_commands(app);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "penumbra: error: %s\n", e.what());
    return 1;
  }
  return penumbra::command_exit_code();
}
