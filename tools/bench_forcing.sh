#!/usr/bin/env bash
# Forcing benchmark (issue 3): the Eswaran-Pope forcing's cost per step (evaluation on the u, v, w
# faces + OU update; the fluid step's arrays written in place, no zeroing pass) as a fraction of a
# fluid step (Crank-Nicolson AB2 + FFT projection, as input/hit_box.nml), at 64^3 and 128^3.
# Target <= 10%. Usage: BUILD=build NP=2 tools/bench_forcing.sh  (results: docs/performance.md)
set -u
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}; NP=${NP:-2}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
exe=$PWD/$BUILD/tests/test_forced_box
[ -x "$exe" ] || { echo "bench_forcing: build $exe first (make build $BUILD/tests/test_forced_box)" >&2; exit 1; }
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
for n in 64 128; do
  mpirun -np "$NP" "$exe" bench $n 2>&1 | grep -E '^(bench|PASS|FAIL)'
done
