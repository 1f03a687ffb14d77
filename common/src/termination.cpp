#include <pthread.h>

#include <crackvis/common/termination.hpp>

namespace crackvis {

TerminationSignals::TerminationSignals() {
  sigemptyset(&m_signals);
  sigaddset(&m_signals, SIGINT);
  sigaddset(&m_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &m_signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

int TerminationSignals::wait() const {
  int signal = 0;
  sigwait(&m_signals, &signal);
  return signal;
}

}  // namespace crackvis
