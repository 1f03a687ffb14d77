#include "describe_cache.hpp"

#include <array>
#include <chrono>

#include <fmt/format.h>
#include <sys/stat.h>

namespace crackvis::dataservice {

std::optional<FileStamp> stampOf(const std::string& path) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) {
    return std::nullopt;
  }
  return FileStamp{
      static_cast<std::uint64_t>(status.st_dev), static_cast<std::uint64_t>(status.st_ino),
      static_cast<std::uint64_t>(status.st_size),
      static_cast<std::int64_t>(status.st_mtim.tv_sec) * 1'000'000'000 + status.st_mtim.tv_nsec,
      static_cast<std::int64_t>(status.st_ctim.tv_sec) * 1'000'000'000 + status.st_ctim.tv_nsec};
}

bool settled(const FileStamp& stamp) {
  constexpr std::int64_t kSettledNanoseconds = 2'000'000'000;
  const std::int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count();
  return now - stamp.modifiedNanoseconds >= kSettledNanoseconds;
}

std::string revisionOf(const FileStamp& stamp) {
  // FNV-1a over the stamp's bytes, twice with different bases: 128 bits, so
  // that two versions of one file never share a name in practice.
  const std::array<std::uint64_t, 5> fields{stamp.device, stamp.inode, stamp.size,
                                            static_cast<std::uint64_t>(stamp.modifiedNanoseconds),
                                            static_cast<std::uint64_t>(stamp.changedNanoseconds)};
  auto fnv = [&](std::uint64_t hash) {
    constexpr std::uint64_t kPrime = 0x100000001b3;
    for (const std::uint64_t field : fields) {
      for (int byte = 0; byte < 8; ++byte) {
        hash = (hash ^ ((field >> (8 * byte)) & 0xff)) * kPrime;
      }
    }
    return hash;
  };
  return fmt::format("{:016x}{:016x}", fnv(0xcbf29ce484222325), fnv(0x84222325cbf29ce4));
}

std::optional<std::string> DescribeCache::find(const std::string& key, const FileStamp& stamp) {
  std::lock_guard lock(m_mutex);
  const auto found = m_byKey.find(key);
  if (found == m_byKey.end()) {
    return std::nullopt;
  }
  if (!(found->second->stamp == stamp)) {
    // The file changed: its old answer is of no use to anyone.
    m_bytes -= found->second->answer.size();
    m_recent.erase(found->second);
    m_byKey.erase(found);
    return std::nullopt;
  }
  m_recent.splice(m_recent.begin(), m_recent, found->second);
  return found->second->answer;
}

void DescribeCache::store(const std::string& key, const FileStamp& stamp, std::string answer) {
  if (answer.size() > m_maxBytes) {
    return;
  }
  std::lock_guard lock(m_mutex);
  if (const auto found = m_byKey.find(key); found != m_byKey.end()) {
    m_bytes -= found->second->answer.size();
    m_recent.erase(found->second);
    m_byKey.erase(found);
  }
  evictTo(m_maxBytes - answer.size());
  m_bytes += answer.size();
  m_recent.push_front({key, stamp, std::move(answer)});
  m_byKey.emplace(key, m_recent.begin());
}

void DescribeCache::evictTo(std::uint64_t bytes) {
  while (m_bytes > bytes && !m_recent.empty()) {
    m_bytes -= m_recent.back().answer.size();
    m_byKey.erase(m_recent.back().key);
    m_recent.pop_back();
  }
}

std::uint64_t DescribeCache::bytes() const {
  std::lock_guard lock(m_mutex);
  return m_bytes;
}

std::size_t DescribeCache::entries() const {
  std::lock_guard lock(m_mutex);
  return m_recent.size();
}

}  // namespace crackvis::dataservice
