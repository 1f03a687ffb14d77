#include <array>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <sys/auxv.h>
#include <unistd.h>

#include <crackvis/common/huge_pages.hpp>

namespace crackvis {
namespace {

constexpr std::string_view kHugetlbTunable = "glibc.malloc.hugetlb";
// glibc (2.36) asks for huge pages on its main heap and on its own mappings
// of 2 MiB and more, but not on the heaps ("arenas") it makes for other
// threads; below its mmap threshold (which grows to 32 MiB as large blocks
// are freed) a session thread's arrays landed there, on small pages. With
// one arena every thread allocates from the main heap, which also reuses
// what another thread freed instead of faulting in fresh pages.
constexpr std::string_view kArenaTunable = "glibc.malloc.arena_max";
// A helper's heap grows by this much beyond each request (and is trimmed
// back only to it). Measured on a worker's first Describe of cuboid A: with
// huge pages alone 530-930 page faults and 32-46 ms, with this padding too
// 120-470 faults and 25-33 ms (docs/benchmarks.md, "The HDF5 workers on huge
// pages"). The memory is only reserved until touched; a worker may keep up
// to this much resident after a large request.
constexpr std::string_view kTopPadTunable = "glibc.malloc.top_pad";
constexpr std::size_t kTopPad = std::size_t{16} << 20;
// Setting the padding fixes glibc's mmap threshold at 128 KiB (it grows
// with the blocks freed otherwise, up to 32 MiB): a larger block that the
// heap's free space cannot hold, a decompressed chunk for one, would be a
// fresh mapping, faulted in page by page at each use. Blocks under 32 MiB
// (the adaptive threshold's largest) come from the heap.
constexpr std::string_view kMmapThresholdTunable = "glibc.malloc.mmap_threshold";
constexpr std::size_t kMmapThreshold = std::size_t{32} << 20;
// Set before the re-execution: the re-executed program never tries again,
// even where glibc drops the tunable from GLIBC_TUNABLES.
constexpr const char* kReexecutedVariable = "CRACKVIS_HUGE_PAGES_REEXECUTED";

std::string readThpMode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string_view baseName(std::string_view path) {
  const auto slash = path.rfind('/');
  return slash == std::string_view::npos ? path : path.substr(slash + 1);
}

// The running program's own file, when it is the program argv[0] names:
// not a loader (ld.so, valgrind) that runs it, whose re-execution with
// these arguments would fail. Its real path, not /proc/self/exe, so that
// the process keeps its name in ps and the logs.
std::string programFile(const char* argv0) {
  std::array<char, 4096> path{};
  const ssize_t length = readlink("/proc/self/exe", path.data(), path.size() - 1);
  if (length <= 0) {
    return {};
  }
  const std::string file(path.data(), static_cast<std::size_t>(length));
  if (baseName(file) != baseName(argv0) || access(file.c_str(), X_OK) != 0) {
    return {};  // another program, a renamed link, or a file replaced since
  }
  return file;
}

}  // namespace

std::optional<std::string> hugePageTunables(std::string_view thpMode, const char* tunables,
                                            const char* setting) {
  if (setting != nullptr && std::string_view(setting) == "0") {
    return std::nullopt;
  }
  if (thpMode.find("[madvise]") == std::string_view::npos) {
    return std::nullopt;
  }
  const std::string_view present = tunables != nullptr ? tunables : "";
  if (present.find(kHugetlbTunable) != std::string_view::npos) {
    return std::nullopt;  // the user's choice
  }
  std::string wanted = std::string(kHugetlbTunable) + "=1";
  if (present.find(kArenaTunable) == std::string_view::npos) {
    wanted += ":" + std::string(kArenaTunable) + "=1";
  }
  return present.empty() ? wanted : std::string(present) + ":" + wanted;
}

std::optional<std::string> helperTunables(std::string_view thpMode, const char* setting) {
  if (!hugePageTunables(thpMode, nullptr, setting)) {
    return std::nullopt;
  }
  return fmt::format("{}=1:{}={}:{}={}", kHugetlbTunable, kTopPadTunable, kTopPad,
                     kMmapThresholdTunable, kMmapThreshold);
}

std::string helperTunablesEntry() {
  const auto tunables = helperTunables(readThpMode(), std::getenv(kHugePagesVariable));
  return tunables ? "GLIBC_TUNABLES=" + *tunables : std::string();
}

void reexecWithHugePages(char** argv) {
  // A set-user-id or capability-raised program gets no tunables from the
  // environment (glibc drops them): nothing to gain.
  if (argv == nullptr || argv[0] == nullptr || std::getenv(kReexecutedVariable) != nullptr ||
      getauxval(AT_SECURE) != 0) {
    return;
  }
  const auto tunables = hugePageTunables(readThpMode(), std::getenv("GLIBC_TUNABLES"),
                                         std::getenv(kHugePagesVariable));
  if (!tunables) {
    return;
  }
  const std::string file = programFile(argv[0]);
  if (file.empty() || setenv(kReexecutedVariable, "1", 1) != 0 ||
      setenv("GLIBC_TUNABLES", tunables->c_str(), 1) != 0) {
    return;
  }
  execv(file.c_str(), argv);
  // Only a failed exec returns: run on, on small pages.
}

}  // namespace crackvis
