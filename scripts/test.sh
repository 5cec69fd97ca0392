#!/usr/bin/env bash
# The whole test suite: the C++ unit tests (ctest), the Python tests (pytest), then the C++
# tests again under AddressSanitizer + UndefinedBehaviorSanitizer and a short run of each
# fuzz target (scripts/fuzz.sh, build-fuzz/; FUZZ_SECONDS per target, default 30; 0 skips
# the fuzzing, SANITIZE=0 skips the sanitizer build and the fuzzing).
# Tests that need ../shared skip cleanly when it is absent.
set -uo pipefail
cd "$(dirname "$0")/.."
status=0
( cd build && ctest --output-on-failure --parallel "$(nproc)" ) || status=1
.venv/bin/python -m pytest -q tests "$@" || status=1
if [ "${SANITIZE:-1}" != 0 ]; then
  bash scripts/fuzz.sh --ctest "${FUZZ_SECONDS:-30}" || status=1
fi
exit $status
