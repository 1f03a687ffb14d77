// Memory a service keeps touched while idle, so that a user's first picture
// does not wait for the kernel to hand it fresh pages.
//
// Every page a process touches for the first time is zeroed by the kernel
// (a huge page 2 MiB at once), and on a virtual machine a fresh page can be
// slower still, as the host backs it only when first touched: in a cold
// first picture of cuboid A, page faults took 116-121 ms of crackvis-render's
// 325-380 ms of CPU, nearly all of it zeroing (docs/benchmarks.md, "A heap
// kept touched for the first picture"). A service that frees its memory and
// trims its heap after each session (HeapTrimmer) pays this again for each
// session after a quiet spell.
//
// The reserve: `bytes` of the heap written once at start-up, kept back from
// every trim, then freed back to malloc, which hands the same, already resident,
// pages to the next session's arrays. With crackvis-render's 160 MiB the
// cold first picture of cuboid A fell from 265 to 143-183 ms (medians of
// alternating runs). The cost is resident memory while idle: crackvis-render
// 310 MB against 185 at start (start-up's own blocks reuse part of the
// reserve), 361 against 196 MB after sessions and a trim.
#pragma once

#include <cstddef>

namespace crackvis {

// Sets malloc's thresholds for a reserve of `bytes` (process-wide; a no-op
// for 0): blocks under 32 MiB come from the heap (glibc's adaptive mmap
// threshold stops adapting once any threshold is set, and 32 MiB is where it
// would end), and free() trims the heap's top only once it exceeds `bytes` +
// 32 MiB, so that the reserve freed is not trimmed away at once. (Past that,
// free() trims the whole top, reserve included, until the next refill; and
// malloc_trim returns everything free.) False, and nothing to rely on, when
// malloc refuses either threshold (a heap of a few MiB under
// glibc.malloc.hugetlb=2, say) or `bytes` is 1 GiB or more.
bool setHeapReserveThresholds(std::size_t bytes);

// Writes each page of `bytes` of heap (blocks of 1 MiB, under the mmap
// threshold) and frees it, leaving it resident in malloc's free space: pages
// not yet resident are faulted in, the others cost next to nothing. Call
// after setHeapReserveThresholds, and after each trim. The blocks come from
// the arena of the calling thread: the main heap where a service runs with
// one arena (glibc.malloc.arena_max=1, set with huge pages: huge_pages.hpp),
// which every thread then allocates from.
void touchHeapReserve(std::size_t bytes);

// malloc_trim(0) but for `bytes` of free heap kept back (taken from malloc
// while it trims, then freed): what sessions freed beyond the reserve goes
// back to the system, the reserve's pages stay resident. A plain
// malloc_trim(0) gave the reserve back too, and writing it again after each
// trim took 57-306 ms of CPU against 10-22 ms now (docs/benchmarks.md, "The
// trim keeps the reserve"). Where less than `bytes` is free (sessions still
// open), the heap grows to keep it.
void trimHeapKeepingReserve(std::size_t bytes);

// Whether a new thread allocates from the main heap (the one the program's
// break grows): true where malloc has one arena. Where threads have heaps of
// their own, a reserve written on one thread is of no use to another, so a
// service keeps none.
bool threadsShareMainHeap();

// The heap's free bytes that malloc holds (mallinfo2's fordblks): at least
// the reserve after touchHeapReserve, on one arena. For tests and logs.
std::size_t heapFreeBytes();

}  // namespace crackvis
