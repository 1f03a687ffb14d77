// A small disk that is full: a tmpfs mounted on a fresh folder and filled up
// to a few bytes of slack, for tests that a writer fails without destroying
// an existing file (issue 29 point 7). Where this process may not mount one,
// `mounted()` is false: the folder is plain, and a test makes writes fail
// another way instead (a file size limit: limitedCommand() for a child
// process, FileSizeLimit for this one).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "support/temp_dir.hpp"

namespace crackvis::testing {

class FullDisk {
 public:
  FullDisk(std::size_t size, std::size_t slack);
  FullDisk(const FullDisk&) = delete;
  FullDisk& operator=(const FullDisk&) = delete;
  ~FullDisk();

  std::string path() const;
  std::string file(const std::string& name) const { return path() + "/" + name; }
  bool mounted() const { return m_mounted; }
  std::size_t slack() const { return m_slack; }
  // Fills the disk, keeping the slack free; call after placing the files
  // that must survive. Nothing without a mount.
  void fill() const;
  // `argv` run as a writer on this disk: as it is on a mounted one, else
  // under a file size limit of the slack (SIGXFSZ ignored: writes fail with
  // EFBIG).
  std::vector<std::string> limitedCommand(const std::vector<std::string>& argv) const;

 private:
  TempDir m_dir;
  std::size_t m_slack;
  bool m_mounted = false;
};

// Writes of this process beyond `bytes` fail (EFBIG) while it lives.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(std::size_t bytes);
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;
  ~FileSizeLimit();

 private:
  rlimit m_before{};
  void (*m_handler)(int) = nullptr;
};

}  // namespace crackvis::testing
