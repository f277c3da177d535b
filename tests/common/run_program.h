#pragma once
// Runs one of the real programs as a user would, for the tests that judge how it ends: its
// output (stdout and stderr together), how it ended, how long it took, and, when asked, how long
// it took to end after a SIGTERM. The SIGTERM is sent only once the program has installed its
// handler (read from /proc/<pid>/status), so a slow start under a sanitizer cannot turn the test
// into a test of the kernel's default action.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace pcisim::test {

struct ProgramRun {
  bool exited = false;       // by exit(), not by a signal
  int code = -1;             // the exit code, or the signal's number
  double seconds = 0;        // from start to end
  double after_term_s = -1;  // from the SIGTERM to the end; -1 when none was sent
  std::string output;
};

// whether `pid` catches `sig` (its handler is installed): the SigCgt mask of /proc/<pid>/status
inline bool catches_signal(pid_t pid, int sig) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("SigCgt:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> (sig - 1)) & 1u;
  return false;
}

// runs argv[0] with argv; SIGTERM once term_after_s have passed and its handler is in place (when
// term_after_s >= 0); SIGKILL after limit_s
inline ProgramRun run_program(const std::vector<std::string>& argv, double term_after_s = -1, double limit_s = 60) {
  using Clock = std::chrono::steady_clock;
  ProgramRun r;
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return r;
  const auto start = Clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(fds[1], 1);
    ::dup2(fds[1], 2);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  ::fcntl(fds[0], F_SETFL, O_NONBLOCK);
  bool termed = false;
  Clock::time_point term_at;
  int status = 0;
  for (;;) {
    char buf[4096];
    for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) r.output.append(buf, static_cast<size_t>(n));
    if (::waitpid(pid, &status, WNOHANG) == pid) break;
    const double t = std::chrono::duration<double>(Clock::now() - start).count();
    if (term_after_s >= 0 && !termed && t >= term_after_s && catches_signal(pid, SIGTERM)) {
      ::kill(pid, SIGTERM);
      termed = true;
      term_at = Clock::now();
    }
    if (t > limit_s) ::kill(pid, SIGKILL);
    pollfd p{fds[0], POLLIN, 0};
    ::poll(&p, 1, 5);
  }
  const auto end = Clock::now();
  char rest[4096];
  for (ssize_t n; (n = ::read(fds[0], rest, sizeof rest)) > 0;) r.output.append(rest, static_cast<size_t>(n));
  ::close(fds[0]);
  r.exited = WIFEXITED(status);
  r.code = r.exited ? WEXITSTATUS(status) : WTERMSIG(status);
  r.seconds = std::chrono::duration<double>(end - start).count();
  if (termed) r.after_term_s = std::chrono::duration<double>(end - term_at).count();
  return r;
}

}  // namespace pcisim::test
