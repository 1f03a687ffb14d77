#!/usr/bin/env bash
# Installs what is missing, builds crackvis (release preset) and its ParaView
# plugin (paraview-plugin/build.sh), makes a short
# fuzzing run (tests/fuzz/run-short.sh: each libFuzzer target for
# FUZZ_SECONDS, default 60; FUZZ_SECONDS=0 skips it), then runs the whole
# test suite.
# Used by .ci/run.
#
#   deploy/run-tests.sh            # release build + short fuzzing + tests
#   PRESET=asan deploy/run-tests.sh  # the same under ASan + UBSan
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${PRESET:-release}"

bash deploy/install-deps.sh
cmake --preset "$preset"
cmake --build --preset "$preset"
# The ParaView plugin, in its own tree against ParaView's VTK (its test in
# ctest loads it into pvbatch).
bash paraview-plugin/build.sh >/dev/null
# Fuzzing before ctest, so that the run ends with ctest's summary line.
if [[ "${FUZZ_SECONDS:-60}" != 0 ]]; then
  bash tests/fuzz/run-short.sh
fi
ctest --preset "$preset"
