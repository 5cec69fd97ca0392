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
# One pytest worker per core, a test file per worker (module fixtures are built once): 11
# minutes instead of 19 on two cores.
.venv/bin/python -m pytest -q -n "$(nproc)" --dist loadfile tests "$@" || status=1
if [ "${SANITIZE:-1}" != 0 ]; then
  bash scripts/fuzz.sh --ctest "${FUZZ_SECONDS:-30}" || status=1
fi
exit $status
