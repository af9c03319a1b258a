#!/usr/bin/env bash
# Agglo test driver: runs every test program and test script, prints their PASS/FAIL lines,
# and closes with one line "N passed, N failed". Exit status 0 only if nothing failed.
#  - build/tests/test_*: Fortran test programs; a line "! ranks: N" in the source runs it on N ranks.
#  - tests/**/test_*.sh: shell tests (decks, restart, MPI comparisons); they print PASS/FAIL lines.
#  - tests/python: pytest for the tools, reported line by line.
# TESTS=pattern runs only the tests whose name matches the pattern.
# BUILD = the build directory (default build), relative to the repository or absolute.
#
# Declared checks. Every test program carries in its source (tests/**/test_*.f90) a line
#     ! checks: N
# and every shell test (tests/**/test_*.sh) a line
#     # checks: N
# (at the start of the line, near the top; the first such line counts): N is the number of lines
# starting "PASS " or "FAIL " the test prints on a normal run. A test whose count depends on its
# environment (e.g. EXTREMES=long) also prints, before its checks, a line "CHECKS N" with this
# run's count, which then replaces the declaration. The driver reports
#     FAIL <name>: ran K of N declared checks
# when the test printed K != N such lines (fewer: checks were lost, e.g. an embedded script
# crashed; more: the declaration is stale), and FAIL <name>: no declared checks when the line is
# missing. The pytest suite (tests/python) is exempt: pytest counts its own tests and exits
# non-zero when a file cannot be collected.
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

tally() { # name, log file, exit status, declared checks (empty: none declared; "-": exempt)
  local name=$1 log=$2 status=$3 declared=$4 p f ran runtime why
  p=$(grep -c '^PASS ' "$log"); f=$(grep -c '^FAIL ' "$log")
  grep -E '^(PASS|FAIL) ' "$log"
  ran=$((p + f))
  if [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
    echo "FAIL $name: exited with status $status without a failed check (see $log)"; f=$((f + 1))
    tail -n 5 "$log" | sed 's/^/    /'
  fi
  if [ "$declared" != - ]; then
    runtime=$(sed -n 's/^CHECKS \([0-9][0-9]*\) *$/\1/p' "$log" | head -n 1)
    declared=${runtime:-$declared}
    if [ "$declared" = twice ]; then
      echo "FAIL $name: declares its checks more than once (keep one line '# checks: N' or" \
           "'! checks: N'; tests/run_tests.sh)"; f=$((f + 1))
    elif [ -z "$declared" ]; then
      echo "FAIL $name: no declared checks (a line '# checks: N' in the script, '! checks: N' in the" \
           "program's source; tests/run_tests.sh)"; f=$((f + 1))
    elif [ "$ran" -ne "$declared" ]; then
      if [ "$ran" -lt "$declared" ]; then why="checks lost: see $log"; else why="the declaration is stale"; fi
      echo "FAIL $name: ran $ran of $declared declared checks ($why)"; f=$((f + 1))
    fi
  fi
  passed=$((passed + p)); failed=$((failed + f))
}

# The N of the line "<comment> checks: N" of a file (empty without one or without the file; "twice"
# when the file has more than one such line: a merge or an edit left a stale one beside the new).
declared_checks() { # file, comment character
  [ -f "$1" ] || return 0
  local counts
  counts=$(sed -n "s/^$2 *checks: *\([0-9][0-9]*\) *\$/\1/p" "$1")
  if [ "$(printf '%s' "$counts" | grep -c .)" -gt 1 ]; then echo twice; else printf '%s\n' "$counts"; fi
}

for exe in "$BUILD"/tests/test_*; do   # glob order is sorted
  [ -x "$exe" ] || continue
  name=$(basename "$exe")
  [[ $name =~ $pattern ]] || continue
  src=$(find tests -name "$name.f90" | head -n 1)
  ranks=; [ -n "$src" ] && ranks=$(sed -n 's/^! *ranks: *\([0-9]*\).*/\1/p' "$src" | head -n 1)
  ranks=${ranks:-1}
  t0=$(date +%s)
  (cd "$log_dir" && mpirun -np "$ranks" "$exe") > "$log_dir/$name.log" 2>&1; status=$?
  tally "$name" "$log_dir/$name.log" $status "$(declared_checks "$src" '!')"
  echo "  ($name: $ranks rank(s), $(( $(date +%s) - t0 )) s)"
done

for script in $(find tests -name 'test_*.sh' | sort); do
  name=$(basename "$script" .sh)
  [[ $name =~ $pattern ]] || continue
  t0=$(date +%s)
  bash "$script" > "$log_dir/$name.log" 2>&1; status=$?
  tally "$name" "$log_dir/$name.log" $status "$(declared_checks "$script" '#')"
  echo "  ($name: $(( $(date +%s) - t0 )) s)"
done

if [ -x tests/python/run_pytest.sh ] && [[ python =~ $pattern || $pattern == . ]]; then
  tests/python/run_pytest.sh > "$log_dir/python.log" 2>&1; status=$?
  tally python "$log_dir/python.log" $status -
fi

echo "suite time: $(( $(date +%s) - start )) s"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
