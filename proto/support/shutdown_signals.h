#pragma once
// SIGINT and SIGTERM for the farm's daemons: the handler only counts them (async-signal-safe);
// a daemon polls the count to drain on the first and give up on the second.

namespace penumbra::farm {

void install_shutdown_signals();
int shutdown_signal_count();

}  // namespace penumbra::farm
