#include <cstdint>
#include <cstdlib>
#include <thread>
#include <vector>

#include <malloc.h>
#include <unistd.h>

#include <crackvis/common/heap_reserve.hpp>

namespace crackvis {
namespace {

// glibc's largest adaptive mmap threshold (DEFAULT_MMAP_THRESHOLD_MAX on
// 64-bit): blocks under it come from the heap, larger ones are mappings of
// their own (with huge pages where asked), as before.
constexpr std::size_t kMmapThreshold = std::size_t{32} << 20;
// Well under the mmap threshold, so each block comes from the heap; large
// enough that the blocks' headers are a negligible part.
constexpr std::size_t kBlock = std::size_t{1} << 20;

// mallopt takes an int: a trim threshold of a reserve this large or larger
// would not fit.
constexpr std::size_t kLargestReserve = std::size_t{1} << 30;

}  // namespace

bool setHeapReserveThresholds(std::size_t bytes) {
  if (bytes == 0) {
    return true;
  }
  if (bytes >= kLargestReserve) {
    return false;
  }
  return mallopt(M_MMAP_THRESHOLD, static_cast<int>(kMmapThreshold)) == 1 &&
         mallopt(M_TRIM_THRESHOLD, static_cast<int>(bytes + kMmapThreshold)) == 1;
}

namespace {

// Blocks of kBlock from malloc summing to `bytes`, fewer where malloc has no
// more to give.
std::vector<void*> takeBlocks(std::size_t bytes) {
  std::vector<void*> blocks;
  blocks.reserve(bytes / kBlock + 1);
  for (std::size_t taken = 0; taken < bytes; taken += kBlock) {
    void* block = std::malloc(kBlock);
    if (block == nullptr) {
      break;  // no memory for a reserve: nothing is lost by its absence
    }
    blocks.push_back(block);
  }
  return blocks;
}

// Newest first, so that the blocks merge into one free region (the heap's
// top when nothing was allocated above them meanwhile).
void giveBack(const std::vector<void*>& blocks) {
  for (auto it = blocks.rbegin(); it != blocks.rend(); ++it) {
    std::free(*it);
  }
}

// One byte written in each page: a page not resident is faulted in (the
// kernel zeroes it, a huge page at once), one already resident costs a store,
// so a reserve mostly resident is rewritten in well under a millisecond
// where a memset of it took tens.
void touchPages(void* block) {
  static const auto kPage = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
  auto* bytes = static_cast<volatile unsigned char*>(block);
  for (std::size_t at = 0; at < kBlock; at += kPage) {
    bytes[at] = 0x5a;
  }
}

}  // namespace

void touchHeapReserve(std::size_t bytes) {
  const std::vector<void*> blocks = takeBlocks(bytes);
  for (void* block : blocks) {
    touchPages(block);
  }
  giveBack(blocks);
}

void trimHeapKeepingReserve(std::size_t bytes) {
  // Held while malloc_trim runs, the reserve's blocks are not free and so not
  // given back; the rest of the free space is.
  const std::vector<void*> blocks = takeBlocks(bytes);
  malloc_trim(0);
  giveBack(blocks);
}

bool threadsShareMainHeap() {
  void* theirs = nullptr;
  std::thread([&theirs] { theirs = std::malloc(64); }).join();
  // The main heap lies below the program's break; other arenas' heaps are
  // mappings of their own, far above it.
  const auto top = reinterpret_cast<std::uintptr_t>(sbrk(0));
  const bool shared = theirs != nullptr && reinterpret_cast<std::uintptr_t>(theirs) < top;
  std::free(theirs);
  return shared;
}

std::size_t heapFreeBytes() {
  return mallinfo2().fordblks;
}

}  // namespace crackvis
