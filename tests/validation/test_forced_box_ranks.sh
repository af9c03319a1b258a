#!/usr/bin/env bash
# checks: 1
# The forced box (fluid solver + Eswaran-Pope forcing, 40 steps from rest on 16^3) gives the same
# velocity on 1 and 2 ranks to 1e-12 relative (docs/studies/validation.md, Forcing): the forcing itself is identical bit for
# bit on any slab layout (test_eswaran_pope_forcing), the solver's FFT and sums differ by round-off.
set -u
exe=${BUILD:-build}/tests/test_forced_box
[[ $exe = /* ]] || exe=$PWD/$exe    # BUILD may be absolute (tests/run_tests.sh passes it so)
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
for np in 1 2; do
  if ! mpirun --oversubscribe -np $np "$exe" fields ranks_$np.h5 > run_$np.log 2>&1; then
    echo "FAIL forced_box_ranks: the $np-rank run failed: $(tail -n 3 run_$np.log)"; exit 0
  fi
done
# |u_1 - u_2| <= 1e-12 max|u|: the absolute tolerance from the largest velocity of the 1-rank run.
umax=$(h5dump -y -d u ranks_1.h5 | sed -n '/DATA {/,/}/p' | grep -oE '[-]?[0-9]+\.[0-9]+(e[-+]?[0-9]+)?' \
       | awk '{ v = ($1 < 0) ? -$1 : $1; if (v > m) m = v } END { printf "%.6e", m }')
tol=$(awk -v m="$umax" 'BEGIN { printf "%.3e", 1e-12 * m }')
if out=$(h5diff -d "$tol" ranks_1.h5 ranks_2.h5 2>&1); then
  echo "PASS forced_box_1_vs_2_ranks  (max|u| = $umax m/s, all of u, v, w within $tol m/s)"
else
  echo "FAIL forced_box_1_vs_2_ranks: differences above $tol m/s: $(echo "$out" | head -n 8)"
fi
