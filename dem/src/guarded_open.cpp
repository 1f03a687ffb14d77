// DemFileReader::openGuarded: the structure read in a child first.
#include <charconv>

#include <fmt/format.h>

#include <crackvis/common/child_process.hpp>
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::dem {
namespace {

// What reading a file's structure may map beyond what the process maps:
// libhdf5's metadata cache needs megabytes.
constexpr std::uint64_t kStructureHeadroom = std::uint64_t{4} << 30;

// The child's answer: "<code> <message>".
std::string encode(const Status& status) {
  return fmt::format("{} {}", static_cast<int>(status.code()), status.message());
}

Status decode(const std::string& answer, const std::string& path) {
  int code = -1;
  const auto [end, error] = std::from_chars(answer.data(), answer.data() + answer.size(), code);
  if (error != std::errc() || code < 0 || code > static_cast<int>(StatusCode::kDeadlineExceeded) ||
      end == answer.data() + answer.size() || *end != ' ') {
    return internalError(fmt::format("{}: the structure check sent an unreadable answer", path));
  }
  return {static_cast<StatusCode>(code),
          answer.substr(static_cast<std::size_t>(end - answer.data()) + 1)};
}

}  // namespace

Result<DemFileReader> DemFileReader::openGuarded(const std::string& path,
                                                 std::chrono::milliseconds limit) {
  auto outcome = runInChild(
      [&] {
        // A corrupt size makes libhdf5 allocate and fill what it says (20
        // GB for one the fuzzer kept): the child's allocation fails instead.
        if (const Status capped = capAddressSpace(kStructureHeadroom); !capped) {
          return encode(capped);
        }
        auto reader = open(path);
        if (reader) {
          // The spatial index's headers too: a local step source reads its
          // summary right after the open (the decomposition the file
          // records), and a fault there must end the child, not the caller.
          // Its refusal is the caller's to ignore, as the source does.
          (void)reader->readSpatialIndexInfo();
        }
        return encode(reader.status());
      },
      limit);
  if (!outcome) {
    return outcome.status();
  }
  if (outcome->timedOut) {
    return failedPrecondition(fmt::format(
        "{}: libhdf5 did not finish reading the file's structure in {} s (the file may be corrupt)",
        path, std::chrono::duration_cast<std::chrono::seconds>(limit).count()));
  }
  if (!outcome->finished()) {
    return failedPrecondition(
        fmt::format("{}: libhdf5 faulted reading the file's structure ({}); the file is probably "
                    "corrupt",
                    path, describeExit(outcome->waitStatus)));
  }
  CRACKVIS_RETURN_IF_ERROR(decode(outcome->output, path));
  return open(path);
}

}  // namespace crackvis::dem
