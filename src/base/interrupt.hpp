// Stop requests: SIGINT and SIGTERM set a flag that long procedures poll
// between chunks of cycling (never per step); they then write a checkpoint
// and throw Interrupted. A second signal of the same kind at least a second
// after the first kills the process the default way (an impatient Ctrl-C
// still works); one within the second is taken as the same request (Ctrl-C
// reaches forked jobs both from the terminal and from the parent).
#pragma once

namespace centridem {

// Installs the handlers (idempotent). Commands that checkpoint call it.
void install_stop_handlers();
// The signal that asked to stop, 0 when none.
int stop_signal();
// For tests: sets or clears the flag as if `signal` had arrived.
void set_stop_signal(int signal);

} // namespace centridem
