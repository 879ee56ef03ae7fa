#!/usr/bin/env bash
# Runs every test suite and prints one closing line "N passed, N failed[, N skipped]".
#   layers: tests/check_layers.sh over the checkout (one test: no #include crosses a layer) and
#         tests/check_layers_selftest.sh (one test: the checker rejects fake violations).
#   unit: each build/tests/unit/<area>/test_* cmocka binary (its "[  PASSED  ] N test(s)." lines
#         are summed; a binary that dies without a FAILED line counts as one failure).
#   integration: /usr/bin/python3 -m pytest tests/integration (when it holds test_*.py files).
#   fuzz: each build/fuzz/fuzz_* libFuzzer binary, two tests each, failed on any crash, leak or UB
#         report: (1) replay: every checked-in seed (tests/fuzz/corpus/<name>) runs once, no
#         mutation; (2) a short deterministic run: -seed=1 -runs=FUZZ_TEST_RUNS mutations from those
#         seeds (a few seconds). Long random runs are `make fuzz`.
# Under CI=true every skipped test counts as failed, and so does a requested suite that finds
# nothing to run (unit or fuzz binaries not built): a CI run is never thinned out silently.
# Environment: BUILD (build dir), MESHES (../shared/meshes), PYTHON, SUITES ("layers unit integration fuzz"),
# FUZZ_TEST_RUNS (default 10000), CI, PYTEST_ARGS (extra pytest arguments, e.g. make tsan's
# --deselect of a cost-dependent test).
set -u
BUILD=${BUILD:-build}
PYTHON=${PYTHON:-/usr/bin/python3}
SUITES=${SUITES:-layers unit integration fuzz}
FUZZ_TEST_RUNS=${FUZZ_TEST_RUNS:-10000}
CI=${CI:-}
export MESHES=${MESHES:-$(cd "$(dirname "$0")/.." && pwd)/../shared/meshes}
passed=0; failed=0; skipped=0
log=$(mktemp); trap 'rm -f "$log"' EXIT

count() { # $1 = regex with one capture group of the count; reads $log
  sed -n -E "s/$1/\\1/p" "$log" | awk '{s+=$1} END {print s+0}'
}

if [[ " $SUITES " == *" layers "* ]]; then
  here=$(cd "$(dirname "$0")" && pwd)
  for t in check_layers.sh check_layers_selftest.sh; do
    echo "== tests/$t"
    if bash "$here/$t"; then passed=$((passed + 1)); else failed=$((failed + 1)); echo "!! tests/$t failed"; fi
  done
fi
nothing_to_run() { # $1 = suite, $2 = what is missing: a failure under CI=true, else one skip
  if [ "$CI" = true ]; then failed=$((failed + 1)); echo "!! $1: $2 (CI=true: counted as a failure)"
  else skipped=$((skipped + 1)); echo "!! $1: $2 (skipped)"; fi
}

if [[ " $SUITES " == *" unit "* ]]; then
  units=$(find "$BUILD/tests/unit" -type f -name 'test_*' -perm -u+x 2>/dev/null | sort)
  [ -n "$units" ] || nothing_to_run unit "no test binaries under $BUILD/tests/unit (make all builds them)"
  for t in $units; do
    echo "== $t"
    "$t" >"$log" 2>&1; rc=$?
    cat "$log"
    p=$(count '^\[  PASSED  \] ([0-9]+) test.*')
    f=$(count '^\[  FAILED  \] ([0-9]+) test.*')
    s=$(count '^\[  SKIPPED \] ([0-9]+) test.*')
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then f=1; echo "!! $t exited with status $rc"; fi
    passed=$((passed + p)); failed=$((failed + f)); skipped=$((skipped + s))
  done
fi

if [[ " $SUITES " == *" integration "* ]] && ls tests/integration/test_*.py >/dev/null 2>&1; then
  echo "== pytest tests/integration"
  # shellcheck disable=SC2086  # PYTEST_ARGS is a word list
  BUILD=$BUILD "$PYTHON" -m pytest tests/integration -q -rs -p no:cacheprovider ${PYTEST_ARGS:-} \
    >"$log" 2>&1; rc=$?
  cat "$log"
  last=$(grep -E '[0-9]+ (passed|failed|error)' "$log" | tail -n 1)
  pick() { echo "$last" | grep -oE "[0-9]+ $1" | head -n 1 | awk '{print $1+0}'; }
  p=$(pick passed); f=$(pick failed); e=$(pick error); s=$(pick skipped)
  p=${p:-0}; f=${f:-0}; e=${e:-0}; s=${s:-0}
  f=$((f + e))
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 5 ] && [ "$f" -eq 0 ]; then f=1; echo "!! pytest exited with status $rc"; fi
  passed=$((passed + p)); failed=$((failed + f)); skipped=$((skipped + s))
fi

if [[ " $SUITES " == *" fuzz "* ]]; then
  fuzzers=$(find "$BUILD/fuzz" -maxdepth 1 -type f -name 'fuzz_*' -perm -u+x 2>/dev/null | sort)
  [ -n "$fuzzers" ] || nothing_to_run fuzz "no fuzz binaries under $BUILD/fuzz (make fuzz-build builds them)"
  for b in $fuzzers; do
    n=$(basename "$b"); seeds="tests/fuzz/corpus/${n#fuzz_}"
    mapfile -t files < <(find "$seeds" -type f 2>/dev/null | sort)
    echo "== $b: replay of the ${#files[@]} seeds in $seeds"
    if [ "${#files[@]}" -eq 0 ]; then
      nothing_to_run fuzz "no seeds in $seeds"
    elif "$b" -runs=1 "${files[@]}" >"$log" 2>&1; then
      passed=$((passed + 1)); echo "replayed ${#files[@]} seeds"
    else
      failed=$((failed + 1)); tail -n 40 "$log"
    fi
    scratch=$(mktemp -d)
    echo "== $b: -seed=1 -runs=$FUZZ_TEST_RUNS from $seeds"
    if "$b" -seed=1 -runs="$FUZZ_TEST_RUNS" -print_final_stats=1 "$scratch" "$seeds" >"$log" 2>&1; then
      passed=$((passed + 1)); grep -E '^stat::number_of_executed_units' "$log"
    else
      failed=$((failed + 1)); tail -n 40 "$log"
    fi
    rm -rf "$scratch"
  done
fi

if [ "$CI" = true ] && [ "$skipped" -gt 0 ]; then
  echo "!! CI=true: $skipped skipped test(s) count as failed (a missing prerequisite fails CI)"
  failed=$((failed + skipped)); skipped=0
fi

if [ "$skipped" -gt 0 ]; then
  echo "$passed passed, $failed failed, $skipped skipped"
else
  echo "$passed passed, $failed failed"
fi
[ "$failed" -eq 0 ] && [ "$passed" -gt 0 ]
