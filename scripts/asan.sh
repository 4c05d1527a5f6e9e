#!/usr/bin/env bash
# The whole test suite (malformed inputs included) under AddressSanitizer + UBSan. Out of CI since
# session 55: on the 2-core CI machine its build (675 s) and run (457 s) took CI past 30 minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset asan >/dev/null
cmake --build --preset asan >/tmp/lodkit-asan-build.log 2>&1 || { cat /tmp/lodkit-asan-build.log >&2; exit 1; }
ctest --preset asan --output-on-failure
