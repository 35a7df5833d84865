#pragma once
// Subcommand registration for the penumbra CLI.
#include <CLI/CLI.hpp>

namespace penumbra {
// render, probe, demo: core only.
void add_local_commands(CLI::App& app);
void add_reproduce_command(CLI::App& app);
// exact, exact-reference: closed-form direct illumination (core/exact).
void add_exact_commands(CLI::App& app);
// verify: a method's runs z-tested per pixel block against an exact reference.
void add_verify_command(CLI::App& app);
// submit, watch, list, status, cancel, fetch, workers: the farm's client (client/farm_*.cpp).
void add_farm_commands(CLI::App& app);
// batch submit/watch/status/list/cancel/fetch/run and report (client/batch_commands.cpp).
void add_batch_commands(CLI::App& app);
// The exit code the command that ran asked for (0 unless it reported a failure itself).
int command_exit_code();
void set_command_exit_code(int code);
}  // namespace penumbra
