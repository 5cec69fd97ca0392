#!/usr/bin/env bash
# The whole test suite: the C++ unit tests (ctest) and the Python tests (pytest).
# Tests that need ../shared skip cleanly when it is absent.
set -uo pipefail
cd "$(dirname "$0")/.."
status=0
( cd build && ctest --output-on-failure --parallel "$(nproc)" ) || status=1
.venv/bin/python -m pytest -q tests "$@" || status=1
exit $status
