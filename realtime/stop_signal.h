#pragma once
// SIGINT and SIGTERM for the long-running programs (server, dataset, model, clients). A program
// that is still starting (reading a case, building a scene: seconds of work no loop watches)
// ends at once, saying so: "<program>: stopped by SIGTERM while starting" on stderr and exit
// status 128 + the signal. Once it calls mark_running(), a signal only sets stop_flag(), which
// its loop reads for a clean shutdown; a second signal then ends it at once. The handler does
// only what is async-signal-safe (write, _exit, lock-free atomics, sem_post).
#include <atomic>

namespace pcisim::realtime {

// installs the handlers (once per process; a later call changes the program name and what it is
// doing). `program` and `doing` must outlive the process (string literals): the handler reads them
void install_stop_signals(const char* program, const char* doing = "starting");

// from now on a signal sets stop_flag(); with stop_within_s > 0 the process is ended anyway when
// it has not exited that long after the signal (a loop that does not look at the flag while it
// builds a scene still answers within that time)
void mark_running(double stop_within_s = 0);

// back to the start (a long rebuild no loop watches): a signal ends the process at once again
void mark_starting();

// the loop has stopped (cleanly, after the flag, or at its end): the watchdog mark_running armed
// no longer ends the process, which now writes its figures; a signal still sets the flag, a
// second one ends it at once
void mark_stopped();

// set by the first signal once running; the loops' stop flag
const std::atomic<bool>& stop_flag();

// the signal that set the flag or ended the start (SIGINT, SIGTERM), 0 while none came
int stop_signal_number();

}  // namespace pcisim::realtime
