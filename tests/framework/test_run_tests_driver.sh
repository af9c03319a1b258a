#!/usr/bin/env bash
# checks: 10
# The test driver itself (tests/run_tests.sh, "Declared checks" in its header; docs/tools.md,
# "Tests"), run on a fake repository in a temporary directory: a copy of the driver, one fake test
# program (an executable shell script standing in for build/tests/test_*, its declaration in a
# tests/unit/*.f90 source) and fake shell tests:
#  - a script printing as many checks as it declares passes, and adds its lines to the tally;
#  - a script whose embedded Python check crashes after one of its three declared checks, and which
#    then exits 0 (the crash is silent but for the count), is reported "FAIL <name>: ran 1 of 3 declared checks", and the closing line counts the failure;
#  - a script printing more checks than declared (a stale declaration) fails;
#  - a script without a declaration fails, naming the missing line;
#  - a script with two declarations (a stale one left beside the new) fails;
#  - a script printing "CHECKS N" (a count that depends on its environment) is held to that N;
#  - a program with "! checks: N" in its source that prints fewer lines fails by name;
#  - the driver exits non-zero when anything failed, and zero on a good test alone (TESTS=pattern).
# Prints PASS/FAIL lines (only its own: the fake suite's output stays in files).
set -u
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
driver=$here/../run_tests.sh
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
mkdir -p "$work/repo/tests/fake" "$work/repo/tests/unit" "$work/repo/build/tests"
cp "$driver" "$work/repo/tests/run_tests.sh"
cd "$work/repo"

script() { # name, body (the declaration, if any, is part of the body)
  printf '#!/usr/bin/env bash\n%s\n' "$2" > "tests/fake/$1.sh"
}
script test_good $'# checks: 2\necho "PASS good/one"\necho "FAIL good/two: a failing check still counts as run"'
script test_crash $'# checks: 3\necho "PASS crash/first"\npython3 - <<\'EOF\'\nraise RuntimeError("the check crashed")\nprint("PASS crash/second")\nprint("PASS crash/third")\nEOF\necho "the script goes on and exits 0"'
script test_stale $'# checks: 1\necho "PASS stale/one"\necho "PASS stale/two"'
script test_pure $'# checks: 1\necho "PASS pure/one"'
script test_undeclared $'echo "PASS undeclared/one"'
script test_twice $'# checks: 1\n# checks: 2\necho "PASS twice/one"'
script test_runtime $'# checks: 1\necho "CHECKS 2"\necho "PASS runtime/one"'
printf '! ranks: 1\n! checks: 2\nprogram test_prog\nend program test_prog\n' > tests/unit/test_prog.f90
printf '#!/usr/bin/env bash\necho "PASS prog/one"\n' > build/tests/test_prog
chmod +x build/tests/test_prog

BUILD=build TESTS=. bash tests/run_tests.sh > all.out 2>&1; all_status=$?
BUILD=build TESTS='^test_pure$' bash tests/run_tests.sh > pure.out 2>&1; pure_status=$?

report() { # name, condition status (0 = holds), detail
  if [ "$2" -eq 0 ]; then echo "PASS run_tests_driver/$1  ($3)"; else echo "FAIL run_tests_driver/$1: $3"; fi
}
has() { grep -qxF -- "$1" all.out; }
has "PASS good/one" && has "FAIL good/two: a failing check still counts as run" && ! grep -q '^FAIL test_good' all.out
report declared_count_met $? "test_good's two lines pass through, no driver FAIL for it"
has "FAIL test_crash: ran 1 of 3 declared checks (checks lost: see $PWD/build/test-logs/test_crash.log)"
report crashed_check_is_a_failure_by_name $? "$(grep 'test_crash' all.out | head -n 2 | tr '\n' ' ')"
has "FAIL test_stale: ran 2 of 1 declared checks (the declaration is stale)"
report more_than_declared_fails $? "$(grep 'test_stale' all.out | head -n 1)"
grep -q "^FAIL test_undeclared: no declared checks (a line '# checks: N'" all.out
report missing_declaration_fails $? "$(grep 'test_undeclared' all.out | head -n 1)"
grep -q "^FAIL test_twice: declares its checks more than once" all.out
report double_declaration_fails $? "$(grep 'test_twice' all.out | head -n 1)"
has "FAIL test_runtime: ran 1 of 2 declared checks (checks lost: see $PWD/build/test-logs/test_runtime.log)"
report printed_count_replaces_declaration $? "$(grep 'test_runtime' all.out | head -n 1)"
has "FAIL test_prog: ran 1 of 2 declared checks (checks lost: see $PWD/build/test-logs/test_prog.log)"
report program_declaration_from_source $? "$(grep 'test_prog' all.out | head -n 1)"
# PASS lines: good, crash, stale x2, pure, undeclared, twice, runtime, prog = 9; failed: good/two and
# the six driver failures (crash, stale, undeclared, twice, runtime, prog) = 7.
has "9 passed, 7 failed"
report closing_line_counts_driver_failures $? "$(tail -n 1 all.out)"
[ "$all_status" -ne 0 ]
report exit_status_on_failures $? "exit status $all_status with failures"
grep -qxF "1 passed, 0 failed" pure.out && [ "$pure_status" -eq 0 ] && ! grep -q '^FAIL ' pure.out
report good_tests_only_exit_zero $? "TESTS='^test_pure\$': $(tail -n 1 pure.out), status $pure_status"
