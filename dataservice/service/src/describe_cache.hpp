// Describe's answers for files that have not changed since they were
// walked. Walking a crackvis-dem file's tree opens every step's group and
// datasets (about 1,000 objects for 200 steps: tens of milliseconds), while
// every view of the file asks for the same answer; a file is walked once
// per change instead of once per view. A change is a new size, modification
// time, status-change time, inode or device; least recently used answers go first when the
// cache is full.
#pragma once

#include <cstdint>
#include <list>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

namespace crackvis::dataservice {

// What identifies one version of a file on disk.
struct FileStamp {
  std::uint64_t device = 0;
  std::uint64_t inode = 0;
  std::uint64_t size = 0;
  std::int64_t modifiedNanoseconds = 0;
  // The inode's last change: a rewrite that restores the size and the
  // modification time (cp -p, rsync --inplace, utimensat) still sets it.
  std::int64_t changedNanoseconds = 0;
  friend bool operator==(const FileStamp&, const FileStamp&) = default;
};

// The file's stamp now; nullopt when it cannot be read.
std::optional<FileStamp> stampOf(const std::string& path);
// Whether the file was last modified at least two seconds ago. The file
// system's clock is coarse (a few milliseconds): a write in the same tick
// after the stamp was taken leaves the stamp as it was, so answers are kept
// only for files that have settled. A live file being written is walked
// afresh for every Describe, which therefore sees every committed step.
bool settled(const FileStamp& stamp);
// DescribeResponse.revision for a settled file: an opaque 32-digit hex name
// of its stamp (a hash, so that inode numbers are not handed out).
std::string revisionOf(const FileStamp& stamp);

class DescribeCache {
 public:
  explicit DescribeCache(std::uint64_t maxBytes) : m_maxBytes(maxBytes) {}

  // The answer stored under `key` for this stamp of the file, if any.
  std::optional<std::string> find(const std::string& key, const FileStamp& stamp);
  // Stores an answer made from the file as `stamp` saw it (taken before
  // the walk, so a change during the walk is a miss next time). Answers
  // larger than the whole cache are not kept.
  void store(const std::string& key, const FileStamp& stamp, std::string answer);

  std::uint64_t bytes() const;
  std::size_t entries() const;

 private:
  struct Entry {
    std::string key;
    FileStamp stamp;
    std::string answer;
  };
  void evictTo(std::uint64_t bytes);

  const std::uint64_t m_maxBytes;
  mutable std::mutex m_mutex;
  std::list<Entry> m_recent;  // most recently used first
  std::unordered_map<std::string, std::list<Entry>::iterator> m_byKey;
  std::uint64_t m_bytes = 0;
};

}  // namespace crackvis::dataservice
