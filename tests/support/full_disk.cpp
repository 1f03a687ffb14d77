#include "support/full_disk.hpp"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mount.h>
#include <unistd.h>

namespace crackvis::testing {

FullDisk::FullDisk(std::size_t size, std::size_t slack) : m_slack(slack) {
  std::filesystem::create_directories(path());
  m_mounted = ::mount("tmpfs", path().c_str(), "tmpfs", MS_NOSUID | MS_NODEV,
                      fmt::format("size={}", size).c_str()) == 0;
}

FullDisk::~FullDisk() {
  if (m_mounted) {
    ::umount2(path().c_str(), MNT_DETACH);
  }
}

std::string FullDisk::path() const {
  return (m_dir.path() / "disk").string();
}

void FullDisk::fill() const {
  if (!m_mounted) {
    return;
  }
  const std::string slack = file("slack");
  std::ofstream(slack, std::ios::binary) << std::string(m_slack, 's');
  const int fd = ::open(file("filler").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  REQUIRE(fd >= 0);
  const std::string block(4096, 'f');
  while (::write(fd, block.data(), block.size()) > 0) {
  }
  CHECK(errno == ENOSPC);
  ::close(fd);
  std::filesystem::remove(slack);
}

std::vector<std::string> FullDisk::limitedCommand(const std::vector<std::string>& argv) const {
  if (m_mounted) {
    return argv;
  }
  std::vector<std::string> limited{"/bin/bash", "-c",
                                   fmt::format("trap '' XFSZ; ulimit -f {}; exec \"$@\"",
                                               std::max<std::size_t>(1, m_slack / 1024)),
                                   "writer"};
  limited.insert(limited.end(), argv.begin(), argv.end());
  return limited;
}

FileSizeLimit::FileSizeLimit(std::size_t bytes) {
  ::getrlimit(RLIMIT_FSIZE, &m_before);
  m_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit limit = m_before;
  limit.rlim_cur = bytes;
  ::setrlimit(RLIMIT_FSIZE, &limit);
}

FileSizeLimit::~FileSizeLimit() {
  ::setrlimit(RLIMIT_FSIZE, &m_before);
  std::signal(SIGXFSZ, m_handler);
}

}  // namespace crackvis::testing
