# Sourced, not run: asks glibc's malloc for transparent huge pages in the
# processes this shell starts next, where the kernel gives them only on
# request (THP mode "madvise", Debian's default). crackvis-data and
# crackvis-render do the same for themselves (common/huge_pages.hpp); this is
# for ParaView's pvbatch, pvpython and pvserver with the crackvis plugin,
# whose first update at 1e6 particles took half the time with it
# (docs/deploy.md, "Huge pages"; docs/benchmarks.md, "Huge pages for pvbatch").
#
#   source deploy/huge-pages.sh
#   crackvis_huge_pages          # exports GLIBC_TUNABLES when it applies
#   mpiexec ... "${crackvis_huge_pages_mpi[@]}" pvbatch ...   # passes it to every rank
#
# (Under `set -u` in bash before 4.4, an empty array must be written
# ${crackvis_huge_pages_mpi[@]+"${crackvis_huge_pages_mpi[@]}"}, as the
# scripts here do.)
#
# CRACKVIS_HUGE_PAGES=0 leaves it off; a GLIBC_TUNABLES that already names
# hugetlb is kept as it is, and other tunables in it are kept.
crackvis_huge_pages() {
  crackvis_huge_pages_mpi=()
  if [[ ${CRACKVIS_HUGE_PAGES:-1} != 0 && ${GLIBC_TUNABLES:-} != *hugetlb* ]] &&
    grep -q '\[madvise\]' "${CRACKVIS_THP_ENABLED:-/sys/kernel/mm/transparent_hugepage/enabled}" \
      2>/dev/null; then
    export GLIBC_TUNABLES=${GLIBC_TUNABLES:+$GLIBC_TUNABLES:}glibc.malloc.hugetlb=1
  fi
  [[ -n ${GLIBC_TUNABLES:-} ]] && crackvis_huge_pages_mpi=(-x GLIBC_TUNABLES)
  return 0
}
