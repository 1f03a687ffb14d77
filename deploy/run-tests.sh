#!/usr/bin/env bash
# Installs what is missing, builds crackvis (release preset) and runs the
# whole test suite; ends with ctest's summary line. Used by .ci/run.
#
#   deploy/run-tests.sh            # release build + tests
#   PRESET=asan deploy/run-tests.sh  # the same under ASan + UBSan
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${PRESET:-release}"

bash deploy/install-deps.sh
cmake --preset "$preset"
cmake --build --preset "$preset"
ctest --preset "$preset"
