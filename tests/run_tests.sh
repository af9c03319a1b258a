#!/usr/bin/env bash
# Agglo test driver: runs every test program and test script, prints their PASS/FAIL lines,
# and closes with one line "N passed, N failed". Exit status 0 only if nothing failed.
#  - build/tests/test_*: Fortran test programs; a line "! ranks: N" in the source runs it on N ranks.
#  - tests/**/test_*.sh: shell tests (decks, restart, MPI comparisons); they print PASS/FAIL lines.
#  - tests/python: pytest for the tools, reported line by line.
# TESTS=pattern runs only the tests whose name matches the pattern.
# BUILD = the build directory (default build), relative to the repository or absolute.
set -u
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
if [ ! -d "$BUILD" ]; then
  echo "run_tests: no build directory '$BUILD': run 'make test' (or 'make build' with the same BUILD=)" >&2
  exit 1
fi
BUILD=$(cd "$BUILD" && pwd -P)   # absolute from here on: the programs run from the log directory
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export AGGLO=$BUILD/agglo BUILD
pattern=${TESTS:-.}
passed=0; failed=0
log_dir=$BUILD/test-logs; mkdir -p "$log_dir"
start=$(date +%s)

tally() { # name, log file, exit status
  local name=$1 log=$2 status=$3 p f
  p=$(grep -c '^PASS ' "$log"); f=$(grep -c '^FAIL ' "$log")
  grep -E '^(PASS|FAIL) ' "$log"
  if [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
    echo "FAIL $name: exited with status $status without a failed check (see $log)"; f=1
    tail -n 5 "$log" | sed 's/^/    /'
  fi
  passed=$((passed + p)); failed=$((failed + f))
}

for exe in "$BUILD"/tests/test_*; do   # glob order is sorted
  [ -x "$exe" ] || continue
  name=$(basename "$exe")
  [[ $name =~ $pattern ]] || continue
  src=$(find tests -name "$name.f90" | head -n 1)
  ranks=$(sed -n 's/^! *ranks: *\([0-9]*\).*/\1/p' "$src" | head -n 1); ranks=${ranks:-1}
  t0=$(date +%s)
  (cd "$log_dir" && mpirun -np "$ranks" "$exe") > "$log_dir/$name.log" 2>&1; status=$?
  tally "$name" "$log_dir/$name.log" $status
  echo "  ($name: $ranks rank(s), $(( $(date +%s) - t0 )) s)"
done

for script in $(find tests -name 'test_*.sh' | sort); do
  name=$(basename "$script" .sh)
  [[ $name =~ $pattern ]] || continue
  t0=$(date +%s)
  bash "$script" > "$log_dir/$name.log" 2>&1; status=$?
  tally "$name" "$log_dir/$name.log" $status
  echo "  ($name: $(( $(date +%s) - t0 )) s)"
done

if [ -x tests/python/run_pytest.sh ] && [[ python =~ $pattern || $pattern == . ]]; then
  tests/python/run_pytest.sh > "$log_dir/python.log" 2>&1; status=$?
  tally python "$log_dir/python.log" $status
fi

echo "suite time: $(( $(date +%s) - start )) s"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
