// install_stop_signals in a child process: while starting a signal ends it at once with its
// message and 128 + the signal; once running the flag gives the loop its clean stop; a second
// signal, or a clean stop over its time, ends it anyway.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <string>

#include "realtime/stop_signal.h"

namespace {

using pcisim::realtime::install_stop_signals;
using pcisim::realtime::mark_running;
using pcisim::realtime::mark_starting;
using pcisim::realtime::stop_flag;

void sleep_s(double s) {
  timespec t{static_cast<time_t>(s), static_cast<long>((s - static_cast<time_t>(s)) * 1e9)};
  while (nanosleep(&t, &t) != 0) {}
}

struct Child {
  int status = 0;
  std::string stderr_text;
  double exit_after_signal_s = 0;  // from the (last) signal to the child's exit
};

// runs `body` in a forked child (its stderr captured); each time it writes a byte on the `ready`
// pipe the parent sends one SIGTERM (`signals` in all: a second one only after the child said it
// saw the first, so the kernel cannot merge the two), and times the child's exit
Child run_child(const std::function<void(int ready_fd)>& body, int signals = 1) {
  int err[2], ready[2];
  EXPECT_EQ(pipe(err), 0);
  EXPECT_EQ(pipe(ready), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(err[1], STDERR_FILENO);
    close(err[0]);
    close(ready[0]);
    body(ready[1]);
    _exit(0);
  }
  close(err[1]);
  close(ready[1]);
  for (int i = 0; i < signals; ++i) {
    char c = 0;
    EXPECT_EQ(read(ready[0], &c, 1), 1) << "the child never got ready for signal " << i + 1;
    kill(pid, SIGTERM);
  }
  close(ready[0]);
  const auto t0 = std::chrono::steady_clock::now();
  Child r;
  waitpid(pid, &r.status, 0);
  r.exit_after_signal_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  char buf[512];
  ssize_t n = 0;
  while ((n = read(err[0], buf, sizeof buf)) > 0) r.stderr_text.append(buf, static_cast<size_t>(n));
  close(err[0]);
  return r;
}

void say_ready(int fd) {
  const ssize_t n = write(fd, "r", 1);
  (void)n;
}

TEST(StopSignal, WhileStartingTheProcessEndsAtOnceSayingSo) {
  const Child c = run_child([](int ready) {
    install_stop_signals("stop-test");
    say_ready(ready);
    sleep_s(30);  // a long case load no loop watches
  });
  ASSERT_TRUE(WIFEXITED(c.status)) << "ended by the signal itself, not by the handler";
  EXPECT_EQ(WEXITSTATUS(c.status), 128 + SIGTERM);
  EXPECT_EQ(c.stderr_text, "stop-test: stopped by SIGTERM while starting\n");
  EXPECT_LT(c.exit_after_signal_s, 1.0);
}

TEST(StopSignal, OnceRunningTheFlagGivesTheLoopItsCleanStop) {
  const Child c = run_child([](int ready) {
    install_stop_signals("stop-test");
    mark_running();
    say_ready(ready);
    for (int i = 0; i < 3000 && !stop_flag().load(); ++i) sleep_s(0.01);
    std::fputs(stop_flag().load() ? "clean stop\n" : "no flag\n", stderr);
    _exit(stop_flag().load() ? 0 : 1);
  });
  ASSERT_TRUE(WIFEXITED(c.status));
  EXPECT_EQ(WEXITSTATUS(c.status), 0) << c.stderr_text;
  EXPECT_EQ(c.stderr_text, "clean stop\n");
  EXPECT_EQ(pcisim::realtime::stop_signal_number(), 0) << "the parent saw no signal";
}

TEST(StopSignal, BackToStartingASignalEndsItAgain) {
  const Child c = run_child([](int ready) {
    install_stop_signals("stop-test", "building the scene");
    mark_running();
    mark_starting();
    say_ready(ready);
    sleep_s(30);
  });
  ASSERT_TRUE(WIFEXITED(c.status));
  EXPECT_EQ(WEXITSTATUS(c.status), 128 + SIGTERM);
  EXPECT_EQ(c.stderr_text, "stop-test: stopped by SIGTERM while building the scene\n");
}

TEST(StopSignal, ASecondSignalEndsARunThatDoesNotStop) {
  const Child c = run_child(
      [](int ready) {
        install_stop_signals("stop-test");
        mark_running();
        say_ready(ready);
        while (!stop_flag().load()) sleep_s(0.001);
        say_ready(ready);  // the first signal arrived; the second may come
        sleep_s(30);       // and the run does not stop
      },
      2);
  ASSERT_TRUE(WIFEXITED(c.status));
  EXPECT_EQ(WEXITSTATUS(c.status), 128 + SIGTERM);
  EXPECT_NE(c.stderr_text.find("stop-test: stopped by SIGTERM (a second signal"), std::string::npos) << c.stderr_text;
}

TEST(StopSignal, ACleanStopOverItsTimeIsEndedAnyway) {
  const Child c = run_child([](int ready) {
    install_stop_signals("stop-test");
    mark_running(0.2);
    say_ready(ready);
    sleep_s(30);  // building a scene: the flag is not read
  });
  ASSERT_TRUE(WIFEXITED(c.status));
  EXPECT_EQ(WEXITSTATUS(c.status), 128 + SIGTERM);
  EXPECT_EQ(c.stderr_text, "stop-test: stopped by SIGTERM: not stopped within 0.2 s (still starting, or stuck)\n");
  EXPECT_GT(c.exit_after_signal_s, 0.15);
  EXPECT_LT(c.exit_after_signal_s, 1.0);
}

}  // namespace

TEST(StopSignal, AStopThatFinishedInTimeIsLeftToWriteItsFigures) {
  const Child c = run_child([](int ready) {
    install_stop_signals("stop-test");
    mark_running(0.2);
    say_ready(ready);
    while (!stop_flag().load()) sleep_s(0.001);
    pcisim::realtime::mark_stopped();  // the loop has stopped; writing stats takes a while
    sleep_s(0.5);
    std::fputs("figures written\n", stderr);
    _exit(0);
  });
  ASSERT_TRUE(WIFEXITED(c.status));
  EXPECT_EQ(WEXITSTATUS(c.status), 0) << c.stderr_text;
  EXPECT_EQ(c.stderr_text, "figures written\n");
}
