// libFuzzer target: the crackvis-dem reader (dem/) on mutated files. The
// input is written to a file and read the way `crackvis info --steps` and a
// render session read one: open (structure), the spatial index's summary,
// lattice, break steps, every step. Each call must return a value or a
// Status, never crash. Uses only the public header; HDF5 itself is not
// instrumented, so coverage counts the reader's own checks.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include <unistd.h>

#include <crackvis/dem/dem_file.hpp>

namespace {

// One file per process in memory-backed /dev/shm when there is one.
const std::string& scratchPath() {
  static const std::string path = [] {
    const char* folder = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    return std::string(folder) + "/crackvis-fuzz-dem-" + std::to_string(getpid()) + ".h5";
  }();
  return path;
}

bool writeFile(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* out = std::fopen(path.c_str(), "wb");
  if (out == nullptr) {
    return false;
  }
  const bool written = std::fwrite(data, 1, size, out) == size;
  return std::fclose(out) == 0 && written;
}

// Steps read per input: enough to reach the per-step checks, few enough to
// keep executions fast on files that declare many steps.
constexpr int kMaxSteps = 4;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using crackvis::dem::DemFileReader;
  if (!writeFile(scratchPath(), data, size)) {
    return 0;
  }
  auto reader = DemFileReader::open(scratchPath());
  if (!reader) {
    return 0;
  }
  (void)reader->readSpatialIndexInfo();
  (void)reader->readLattice();
  (void)reader->readBreakSteps();
  for (int step = 0; step < reader->stepCount() && step < kMaxSteps; ++step) {
    (void)reader->readStep(step);
    (void)reader->readBondState(step);
  }
  // Out-of-range indices must be refused, not read.
  (void)reader->readStep(-1);
  (void)reader->readStep(reader->stepCount());
  return 0;
}
