// Transparent huge pages for the services' large arrays. A step of 10^7
// particles is hundreds of MB of fresh memory, and on kernels whose THP mode
// is "madvise" (Debian's default) each 4 KiB page of it costs a page fault:
// on a virtual machine a quarter of a first picture's time at 10^7 went to
// faults (docs/benchmarks.md, "Huge pages"). glibc's malloc asks the kernel
// for huge pages (madvise(MADV_HUGEPAGE) on its heap and mappings) when the
// tunable glibc.malloc.hugetlb=1 is set, and tunables are read only when a
// process starts: so a service re-executes itself once with it.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace crackvis {

// The environment variable that turns the re-execution off ("0").
inline constexpr const char* kHugePagesVariable = "CRACKVIS_HUGE_PAGES";

// What GLIBC_TUNABLES should become, or nothing when the process should go
// on as it is: THP's mode (/sys/kernel/mm/transparent_hugepage/enabled,
// "always [madvise] never") is not madvise (always: every process has them;
// never: nobody does), GLIBC_TUNABLES (`tunables`, null when unset) already
// names glibc.malloc.hugetlb, or CRACKVIS_HUGE_PAGES (`setting`) is "0".
std::optional<std::string> hugePageTunables(std::string_view thpMode, const char* tunables,
                                            const char* setting);

// The GLIBC_TUNABLES for a helper program a service starts with an
// environment of its own (crackvis-data's HDF5 workers, which get nothing of
// the service's environment): huge pages, a 16 MiB heap padding, and blocks
// under 32 MiB from the heap. Only the THP mode and CRACKVIS_HUGE_PAGES
// (`setting`) decide, not the service's own GLIBC_TUNABLES. A worker's first
// Describe of a file of a thousand objects took 1,500 page faults on small
// pages (docs/benchmarks.md, "The HDF5 workers on huge pages"). The services
// themselves keep glibc's adaptive mmap threshold, which a padding would fix
// at 128 KiB.
std::optional<std::string> helperTunables(std::string_view thpMode, const char* setting);

// helperTunables for this machine and process, as "GLIBC_TUNABLES=..."
// ready for an environment, or empty.
std::string helperTunablesEntry();

// Call first in main, before any thread starts: re-executes the program
// (its own file, the same arguments and process id) with GLIBC_TUNABLES
// from hugePageTunables, once. Returns when there is nothing to do, when the
// process is run by another program (ld.so, valgrind) or is set-user-id,
// or when the re-execution fails: the process then runs on small pages, as
// before.
void reexecWithHugePages(char** argv);

}  // namespace crackvis
