#!/usr/bin/env bash
# deploy/huge-pages.sh against fake THP modes: the tunable is exported only
# where THP is "madvise", never with CRACKVIS_HUGE_PAGES=0, other tunables are
# kept, and the mpiexec arguments pass whatever GLIBC_TUNABLES holds.
#
#   tests/deploy/huge-pages.sh SOURCE_DIR
set -uo pipefail
helper=${1:?usage: huge-pages.sh SOURCE_DIR}/deploy/huge-pages.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf 'always [madvise] never\n' >"$work/madvise"
printf '[always] madvise never\n' >"$work/always"
printf 'always madvise [never]\n' >"$work/never"
failed=0

# case NAME MODE EXPECTED_TUNABLES EXPECTED_MPI_ARGS [VAR=VALUE...]: runs the
# helper in a clean shell with the given environment.
case_() {
  local name=$1 mode=$2 want=$3 want_mpi=$4
  shift 4
  local got
  got=$(env -i PATH="$PATH" CRACKVIS_THP_ENABLED="$work/$mode" "$@" bash -c '
    set -euo pipefail
    source "$0"
    crackvis_huge_pages
    echo "${GLIBC_TUNABLES:-}|${crackvis_huge_pages_mpi[*]}"
    # exported, so a child sees it
    bash -c "echo \"child:\${GLIBC_TUNABLES:-}\""' "$helper")
  local expected="$want|$want_mpi"$'\n'"child:$want"
  if [[ $got == "$expected" ]]; then
    echo "ok   $name"
  else
    echo "FAIL $name: expected [$expected], got [$got]"
    failed=1
  fi
}

case_ "madvise: set" madvise "glibc.malloc.hugetlb=1" "-x GLIBC_TUNABLES"
case_ "always: the kernel gives them anyway" always "" ""
case_ "never: not asked for" never "" ""
case_ "CRACKVIS_HUGE_PAGES=0: off" madvise "" "" CRACKVIS_HUGE_PAGES=0
case_ "other tunables kept" madvise "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1" \
  "-x GLIBC_TUNABLES" GLIBC_TUNABLES=glibc.malloc.arena_max=2
case_ "a hugetlb already chosen is kept" madvise "glibc.malloc.hugetlb=0" "-x GLIBC_TUNABLES" \
  GLIBC_TUNABLES=glibc.malloc.hugetlb=0
case_ "no THP file: not asked for" missing "" ""
exit "$failed"
