// When a service re-executes itself to get transparent huge pages from
// glibc's malloc (common/huge_pages.hpp): the decision, case by case. The
// re-execution itself is tested on crackvis-data (tests/dataservice/app.test.cpp).
#include <string>

#include <catch2/catch.hpp>

#include <crackvis/common/huge_pages.hpp>

using crackvis::helperTunables;
using crackvis::hugePageTunables;

TEST_CASE("huge pages are asked for only where the kernel gives them on request",
          "[common][huge-pages]") {
  constexpr const char* kMadvise = "always [madvise] never\n";
  // THP on request: ask, with one malloc arena (so that every thread's
  // memory comes from the heap that gets them), keeping what GLIBC_TUNABLES
  // already says, an arena count among it.
  constexpr const char* kBoth = "glibc.malloc.hugetlb=1:glibc.malloc.arena_max=1";
  CHECK(hugePageTunables(kMadvise, nullptr, nullptr) == kBoth);
  CHECK(hugePageTunables(kMadvise, "", nullptr) == kBoth);
  CHECK(hugePageTunables(kMadvise, "glibc.malloc.arena_max=2", nullptr) ==
        "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1");
  CHECK(hugePageTunables(kMadvise, "glibc.malloc.tcache_count=0", nullptr) ==
        std::string("glibc.malloc.tcache_count=0:") + kBoth);
  CHECK(hugePageTunables(kMadvise, nullptr, "1") == kBoth);
  // Nothing to do: every process has them, or nobody does.
  CHECK_FALSE(hugePageTunables("[always] madvise never\n", nullptr, nullptr));
  CHECK_FALSE(hugePageTunables("always madvise [never]\n", nullptr, nullptr));
  CHECK_FALSE(hugePageTunables("", nullptr, nullptr));  // no THP in this kernel
  // Already decided by the user, either way.
  CHECK_FALSE(hugePageTunables(kMadvise, "glibc.malloc.hugetlb=0", nullptr));
  CHECK_FALSE(hugePageTunables(kMadvise, "glibc.malloc.hugetlb=1", nullptr));
  // Turned off.
  CHECK_FALSE(hugePageTunables(kMadvise, nullptr, "0"));
}

TEST_CASE("a helper program gets huge pages and a heap grown in 16 MiB steps",
          "[common][huge-pages]") {
  constexpr const char* kMadvise = "always [madvise] never\n";
  CHECK(
      helperTunables(kMadvise, nullptr) ==
      "glibc.malloc.hugetlb=1:glibc.malloc.top_pad=16777216:glibc.malloc.mmap_threshold=33554432");
  CHECK(helperTunables(kMadvise, "1") == helperTunables(kMadvise, nullptr));
  CHECK_FALSE(helperTunables(kMadvise, "0"));
  CHECK_FALSE(helperTunables("[always] madvise never\n", nullptr));
  CHECK_FALSE(helperTunables("always madvise [never]\n", nullptr));
}
