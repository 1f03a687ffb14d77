// How the services stop: SIGINT and SIGTERM are blocked in the main thread
// before any server thread starts (threads inherit the mask, so the signals
// reach no gRPC thread) and taken by sigwait, which runs the shutdown in
// ordinary code rather than in a signal handler. SIGPIPE is ignored: a
// client that vanishes must not kill the server through a write.
#pragma once

#include <csignal>

namespace crackvis {

class TerminationSignals {
 public:
  // Call first in main, before starting threads.
  TerminationSignals();
  // Blocks until SIGINT or SIGTERM arrives; returns which.
  int wait() const;

 private:
  sigset_t m_signals;
};

}  // namespace crackvis
