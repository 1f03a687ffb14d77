#include "support/paced_writer.hpp"

#include <cerrno>
#include <csignal>

#include <sys/wait.h>
#include <unistd.h>

namespace crackvis::testing {
namespace {

// One byte through a pipe, again when a signal interrupts.
bool sendByte(int fd) {
  ssize_t sent = 0;
  do {
    sent = ::write(fd, "x", 1);
  } while (sent < 0 && errno == EINTR);
  return sent == 1;
}

bool receiveByte(int fd) {
  char byte = 0;
  ssize_t got = 0;
  do {
    got = ::read(fd, &byte, 1);
  } while (got < 0 && errno == EINTR);
  return got == 1;
}

}  // namespace

PacedWriter::PacedWriter(const std::function<bool(const Pause& pause)>& write) {
  if (pipe(m_paused) != 0 || pipe(m_go) != 0) {
    return;
  }
  // A child that died makes the test's next write fail with EPIPE instead
  // of killing the test binary.
  m_sigpipe = std::signal(SIGPIPE, SIG_IGN);
  m_child = fork();
  if (m_child == 0) {
    close(m_paused[0]);
    close(m_go[1]);
    const Pause pause = [this] { return sendByte(m_paused[1]) && receiveByte(m_go[0]); };
    // Whatever `write` throws (a REQUIRE, bad_alloc) ends the child here,
    // never in the test framework's copy of the test run.
    try {
      _exit(write(pause) ? 0 : 1);
    } catch (...) {
      _exit(2);
    }
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
    while (waitpid(m_child, nullptr, 0) < 0 && errno == EINTR) {
    }
  }
  if (m_sigpipe != SIG_ERR) {
    std::signal(SIGPIPE, m_sigpipe);
  }
}

bool PacedWriter::waitForPause() {
  return m_child > 0 && receiveByte(m_paused[0]);
}

bool PacedWriter::resume() {
  return m_child > 0 && sendByte(m_go[1]);
}

bool PacedWriter::finish() {
  if (m_child <= 0) {
    return false;
  }
  int status = 0;
  pid_t waited = 0;
  do {
    waited = waitpid(m_child, &status, 0);
  } while (waited < 0 && errno == EINTR);
  m_child = -1;
  return waited > 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

}  // namespace crackvis::testing
