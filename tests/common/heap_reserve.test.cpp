// The heap a service keeps touched while idle (common/heap_reserve.hpp):
// written and freed, it stays in malloc's free space and resident, a trim
// gives it back, and writing it again brings it back; a trim keeping it
// gives back only the rest. Whether threads share the main heap is checked
// here in a process with several arenas (glibc's default); the render server
// started as a program, which runs on one, reports its reserve in
// tests/deploy/deploy.test.cpp.
#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <malloc.h>
#include <unistd.h>

#include <crackvis/common/heap_reserve.hpp>

namespace {

constexpr std::size_t kMiB = std::size_t{1} << 20;

// This process's resident memory, from /proc/self/statm.
std::size_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  std::size_t size = 0;
  std::size_t resident = 0;
  statm >> size >> resident;
  return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

#ifndef __SANITIZE_ADDRESS__
// AddressSanitizer replaces malloc: glibc's free space and trim do not see its
// blocks, so these cases are of glibc's malloc only.
TEST_CASE("a heap reserve stays resident in malloc's free space until a trim",
          "[common][heap-reserve]") {
  constexpr std::size_t kReserve = 64 * kMiB;
  REQUIRE(crackvis::setHeapReserveThresholds(kReserve));
  malloc_trim(0);
  const std::size_t freeBefore = crackvis::heapFreeBytes();
  const std::size_t residentBefore = residentBytes();

  crackvis::touchHeapReserve(kReserve);
  // Freed, yet held by malloc and resident: free() did not give it back.
  CHECK(crackvis::heapFreeBytes() >= freeBefore + kReserve - kMiB);
  CHECK(residentBytes() >= residentBefore + kReserve - 4 * kMiB);

  // The next blocks of that size come from it, without growing the process.
  const std::size_t residentKept = residentBytes();
  void* reused = std::malloc(32 * kMiB - kMiB);  // under the mmap threshold: from the heap
  REQUIRE(reused != nullptr);
  CHECK(crackvis::heapFreeBytes() + 31 * kMiB <= freeBefore + kReserve + kMiB);
  std::free(reused);
  CHECK(residentBytes() <= residentKept + kMiB);

  // A trim gives it back; writing it again brings it back.
  malloc_trim(0);
  CHECK(residentBytes() + kReserve / 2 <= residentKept);
  crackvis::touchHeapReserve(kReserve);
  CHECK(residentBytes() + 4 * kMiB >= residentKept);
  malloc_trim(0);
}

TEST_CASE("a trim keeping the reserve gives back only what lies beyond it",
          "[common][heap-reserve]") {
  constexpr std::size_t kReserve = 64 * kMiB;
  constexpr std::size_t kFreed = 2 * kReserve;
  REQUIRE(crackvis::setHeapReserveThresholds(kReserve));
  malloc_trim(0);
  // A session's arrays, written and freed, below a block still in use, so
  // that free() cannot trim them as the heap's top: all free and resident.
  std::vector<void*> arrays;
  for (std::size_t taken = 0; taken < kFreed; taken += kMiB) {
    arrays.push_back(std::malloc(kMiB));
    REQUIRE(arrays.back() != nullptr);
    std::memset(arrays.back(), 0x33, kMiB);
    // Written though nothing reads it before the free (no dead-store removal).
    asm volatile("" : : "r"(arrays.back()) : "memory");
  }
  void* pin = std::malloc(kMiB);  // from the top: the arrays took any free space below
  REQUIRE(pin != nullptr);
  for (void* array : arrays) {
    std::free(array);
  }
  const std::size_t residentFreed = residentBytes();

  // malloc_trim(0) would give back all 128 MiB; the reserve's 64 stay.
  crackvis::trimHeapKeepingReserve(kReserve);
  const std::size_t given = residentFreed - std::min(residentFreed, residentBytes());
  CHECK(given >= kFreed - kReserve - 8 * kMiB);
  CHECK(given <= kFreed - kReserve + 8 * kMiB);
  CHECK(crackvis::heapFreeBytes() >= kReserve);

  // Writing the reserve now faults in next to nothing: its pages are resident.
  const std::size_t residentKept = residentBytes();
  crackvis::touchHeapReserve(kReserve);
  CHECK(residentBytes() <= residentKept + 4 * kMiB);

  std::free(pin);
  malloc_trim(0);
}

TEST_CASE("a reserve of nothing writes nothing", "[common][heap-reserve]") {
  malloc_trim(0);
  const std::size_t before = crackvis::heapFreeBytes();
  crackvis::touchHeapReserve(0);
  CHECK(crackvis::heapFreeBytes() <= before + kMiB);
}
#endif

TEST_CASE("a reserve too large for malloc's thresholds is refused", "[common][heap-reserve]") {
  CHECK(crackvis::setHeapReserveThresholds(0));
  CHECK_FALSE(crackvis::setHeapReserveThresholds(std::size_t{1} << 30));
  CHECK_FALSE(crackvis::setHeapReserveThresholds(std::size_t{64} << 30));
}

TEST_CASE("threads have heaps of their own under glibc's default arenas",
          "[common][heap-reserve]") {
  // This test program runs without glibc.malloc.arena_max (the services set
  // it where THP is "madvise"): a new thread gets an arena of its own.
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::string(tunables).find("arena_max") != std::string::npos) {
    WARN("GLIBC_TUNABLES names an arena count: not checked");
    return;
  }
  CHECK_FALSE(crackvis::threadsShareMainHeap());
}

}  // namespace
