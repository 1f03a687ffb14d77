// A writer in a child process that the test paces, as a simulation beside a
// reader would run. It must be another process: HDF5 shares one open file
// between the opens of a process, so a writer in the test's own process would
// not show what a reader elsewhere sees of a file being written.
#pragma once

#include <csignal>
#include <functional>

#include <sys/types.h>

namespace crackvis::testing {

class PacedWriter {
 public:
  // In the child: tells the test a point is reached and waits until it says
  // go on; false when the test has gone.
  using Pause = std::function<bool()>;

  // Forks; the child runs `write` and exits 0 when it returns true, 1 else.
  explicit PacedWriter(const std::function<bool(const Pause& pause)>& write);
  // A child still running is killed and reaped.
  ~PacedWriter();
  PacedWriter(const PacedWriter&) = delete;
  PacedWriter& operator=(const PacedWriter&) = delete;

  // Whether the child was started.
  bool started() const { return m_child > 0; }
  // Until the child pauses; false when it ended instead.
  bool waitForPause();
  // Lets the paused child go on.
  bool resume();
  // Waits for the child to end: true when it exited 0.
  bool finish();

 private:
  pid_t m_child = -1;
  void (*m_sigpipe)(int) = SIG_ERR;  // the handler before: SIGPIPE is ignored while a writer lives
  int m_paused[2] = {-1, -1};        // child -> test: "I paused"
  int m_go[2] = {-1, -1};            // test -> child: "go on"
};

}  // namespace crackvis::testing
