#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (the `asan` preset: -O1 with
# assertions on, as the sanitizers' authors advise for speed; CGAL's own debug checks off; SPHERECHAIN_SANITIZE=ON,
# no CUDA, no bench; at -O0 the baker's Eigen and CGAL code ran 10-50 times slower and the suite took over an
# hour). Debug information -g1: line tables and function names, which is what the sanitizers' stack traces print
# (inlined frames included); full -g made each file 25-40 % slower to compile under ASan. Any finding fails its
# test (UBSan does not recover; LeakSanitizer runs at exit). Third-party suppressions, if any, live in
# scripts/sanitizer/.
set -euo pipefail
cd "$(dirname "$0")/.."
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
if [ -f scripts/sanitizer/lsan.supp ]; then
  export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$(pwd)/scripts/sanitizer/lsan.supp:print_suppressions=0}"
fi
cmake --preset asan >/dev/null
cmake --build --preset asan -j"$(nproc)"
# Heavy checks (exact ground truth over many frames, names containing "heavy") ran in the normal suite.
ctest --preset asan -j"$(nproc)" -E heavy
