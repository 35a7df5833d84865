// Local commands: render, probe and demo run in this process with penumbra_core.
#include <atomic>

#include "client/commands.h"

namespace penumbra {

namespace {
std::atomic<int> exit_code{0};
}  // namespace

int command_exit_code() { return exit_code.load(); }
void set_command_exit_code(int code) { exit_code.store(code); }

void add_local_commands(CLI::App& app) { (void)app; }

}  // namespace penumbra
