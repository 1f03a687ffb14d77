#include "support/paced_writer.hpp"

#include <csignal>

#include <sys/wait.h>
#include <unistd.h>

namespace crackvis::testing {

PacedWriter::PacedWriter(const std::function<bool(const Pause& pause)>& write) {
  if (pipe(m_paused) != 0 || pipe(m_go) != 0) {
    return;
  }
  m_child = fork();
  if (m_child == 0) {
    close(m_paused[0]);
    close(m_go[1]);
    const Pause pause = [this] {
      char byte = 0;
      return ::write(m_paused[1], "p", 1) == 1 && read(m_go[0], &byte, 1) == 1;
    };
    _exit(write(pause) ? 0 : 1);
  }
  close(m_paused[1]);
  close(m_go[0]);
  m_paused[1] = m_go[0] = -1;
}

PacedWriter::~PacedWriter() {
  for (int fd : {m_paused[0], m_paused[1], m_go[0], m_go[1]}) {
    if (fd >= 0) {
      close(fd);
    }
  }
  if (m_child > 0) {
    kill(m_child, SIGKILL);
    waitpid(m_child, nullptr, 0);
  }
}

bool PacedWriter::waitForPause() {
  char byte = 0;
  return m_child > 0 && read(m_paused[0], &byte, 1) == 1;
}

bool PacedWriter::resume() {
  return m_child > 0 && ::write(m_go[1], "g", 1) == 1;
}

bool PacedWriter::finish() {
  if (m_child <= 0) {
    return false;
  }
  int status = 0;
  const bool waited = waitpid(m_child, &status, 0) == m_child;
  m_child = -1;
  return waited && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

}  // namespace crackvis::testing
