#include "realtime/stop_signal.h"

#include <semaphore.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <thread>

namespace pcisim::realtime {
namespace {

enum Phase : int { kStarting = 1, kRunning = 2, kStopped = 3 };

// everything the handler reads: lock-free atomics and pointers set before it is installed
std::atomic<int> g_phase{kStarting};
std::atomic<bool> g_installed{false};
std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};
std::atomic<int> g_signals_running{0};  // signals seen while running
std::atomic<const char*> g_program{"pcisim"};
std::atomic<const char*> g_doing{"starting"};
// the watchdog that ends a clean stop taking too long (mark_running's stop_within_s)
std::atomic<int64_t> g_stop_within_ns{0};
std::atomic<bool> g_watchdog_started{false};
char g_watchdog_says[96];  // written before the watchdog starts, read by it alone
sem_t g_watchdog_wake;     // posted by the handler; never destroyed (the thread outlives main)

static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free &&
                  std::atomic<const char*>::is_always_lock_free && std::atomic<int64_t>::is_always_lock_free,
              "the handler may only touch lock-free atomics");

// async-signal-safe string building: appends `s` to buf[*n], truncating at the end
void append(char* buf, size_t size, size_t* n, const char* s) {
  while (s && *s && *n + 1 < size) buf[(*n)++] = *s++;
}

const char* signal_name(int sig) {
  return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "a signal";
}

// one line on stderr, written with one write(2), then _exit: no stdio, no destructors, no locks
[[noreturn]] void end_now(int sig, const char* why_a, const char* why_b) {
  char buf[512];
  size_t n = 0;
  append(buf, sizeof buf, &n, g_program.load());
  append(buf, sizeof buf, &n, ": stopped by ");
  append(buf, sizeof buf, &n, signal_name(sig));
  append(buf, sizeof buf, &n, why_a);
  append(buf, sizeof buf, &n, why_b);
  buf[n++] = '\n';
  const ssize_t ignored = ::write(STDERR_FILENO, buf, n);
  (void)ignored;
  ::_exit(128 + sig);
}

extern "C" void on_stop_signal(int sig) {
  const int saved_errno = errno;
  g_signal.store(sig);
  if (g_phase.load() == kStarting) end_now(sig, " while ", g_doing.load());
  if (g_signals_running.fetch_add(1) > 0) end_now(sig, " (a second signal: the first asked for a clean stop)", "");
  g_stop.store(true);
  if (g_watchdog_started.load()) sem_post(&g_watchdog_wake);
  errno = saved_errno;
}

// waits for the handler's post, then gives the clean stop stop_within_s before ending the process
void watchdog() {
  while (sem_wait(&g_watchdog_wake) != 0) {}
  const int64_t ns = g_stop_within_ns.load();
  timespec t{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, 0, &t, &t) == EINTR) {}
  // a clean stop that finished in time (mark_stopped) is left to write its figures
  if (g_phase.load() == kStopped) return;
  end_now(g_signal.load(), g_watchdog_says, "");
}

}  // namespace

void install_stop_signals(const char* program, const char* doing) {
  g_program.store(program);
  g_doing.store(doing);
  if (g_installed.exchange(true)) return;
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  // SA_RESTART as std::signal gives on glibc: blocking calls of the loops are not cut short
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

void mark_running(double stop_within_s) {
  if (stop_within_s > 0 && std::isfinite(stop_within_s) && !g_watchdog_started.load()) {
    g_stop_within_ns.store(static_cast<int64_t>(stop_within_s * 1e9));
    std::snprintf(g_watchdog_says, sizeof g_watchdog_says, ": not stopped within %.1f s (still starting, or stuck)",
                  stop_within_s);
    sem_init(&g_watchdog_wake, 0, 0);
    // set before the thread starts: a signal in between must still wake it (the semaphore counts)
    g_watchdog_started.store(true);
    std::thread(watchdog).detach();
  }
  g_phase.store(kRunning);
}

void mark_stopped() {
  g_phase.store(kStopped);
}

void mark_starting() {
  if (g_phase.load() == kRunning) g_phase.store(kStarting);
}

const std::atomic<bool>& stop_flag() {
  return g_stop;
}

int stop_signal_number() {
  return g_signal.load();
}

}  // namespace pcisim::realtime
