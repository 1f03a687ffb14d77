// An output file that replaces its target only when complete: the writer
// writes to `path()` (the target's name with ".partial" added, in the same
// folder so the final rename is atomic) and calls commit() when done. Until
// then an existing target is untouched; a writer that fails (a full disk, a
// bad input, an exception) leaves the target as it was and, unless told to
// keep it, no partial file either. Every crackvis writer goes through this
// (issue 29: `generate -o EXISTING.h5` on a full disk destroyed the old file).
#pragma once

#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>

namespace crackvis {

class PendingFile {
 public:
  // Removes a stale partial file of an earlier run of the same output.
  explicit PendingFile(std::string target);
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;
  ~PendingFile();  // removes the partial file unless committed or kept

  const std::string& path() const { return m_partial; }
  const std::string& target() const { return m_target; }

  // Flushes the partial file to disk and renames it over the target.
  Status commit();
  // Leaves the partial file in place when this object goes (an interrupted
  // simulation's complete steps stay readable there).
  void keep() { m_keep = true; }
  // `status` with the partial file's name replaced by the target's: a
  // writer's message names the file the user asked for.
  Status named(const Status& status) const;

 private:
  std::string m_target;
  std::string m_partial;
  bool m_done = false;
  bool m_keep = false;
};

// Writes `bytes` to `path` through a PendingFile: FAILED_PRECONDITION
// naming `path` when it cannot be written (a full disk), the old file kept.
Status replaceFile(const std::string& path, std::string_view bytes);

}  // namespace crackvis
