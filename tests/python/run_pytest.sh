#!/usr/bin/env bash
# Runs the tools' pytest suite with the repository's venv (make tools-deps) and prints one line per
# test, "PASS name" or "FAIL name: reason" (tests/run_tests.sh tallies them); pytest's own output
# follows, indented. Exit status: pytest's (0 = every test passed).
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
repo=$(cd "$here/../.." && pwd -P)
python=$repo/.venv/bin/python
if [ ! -x "$python" ]; then
  echo "FAIL python: no venv at .venv: run 'make tools-deps' first"
  exit 1
fi
report=$(mktemp "${TMPDIR:-/tmp}/agglo-pytest.XXXXXX") || exit 1
trap 'rm -f "$report"' EXIT
# Arguments (test files, -k expressions) replace the default: the whole of tests/python.
[ "$#" -gt 0 ] || set -- "$here"
output=$(cd "$repo" && AGGLO_PYTEST_REPORT=$report "$python" -m pytest -q -p no:cacheprovider "$@" 2>&1)
status=$?
cat "$report"
if [ "$status" -ne 0 ] && ! grep -q '^FAIL ' "$report"; then
  echo "FAIL python: pytest exited with status $status without a failed test"
fi
printf '%s\n' "$output" | sed 's/^/    /'
exit "$status"
