#!/usr/bin/env bash
# checks: 3
# Two bodies far closer than a cell with explicit diffusion (docs/theory.md, "Two bodies closer than
# half a cell"): the quiescent needle pair of input/quiescent_needle_resolved.nml at seed 1013 with
# &pair hydrodynamics_from = 'first_contact' and without the squeeze film (&collision lubrication =
# .false., the saturated rows alone carry the gap; the needles, tilted at random, close at 0.875 mm/s
# without feeling the fluid, so their surfaces meet with relative normal and tangential motion at the
# gap; 48^3, explicit diffusion, nu dt/dx^2 = 0.079), run to step 360, about 0.01 cell apart.
# Before the saturated Couette rows the ghost rows next to the gap extrapolated with
# kappa = d_G/(s/2): from step 331 (about 0.06 cell apart) the loads on the two needles alternated
# and grew (|F| 3.6e-9 N at step 320, 2.0e-8 N at 345) and the run stopped on the CFL check at step
# 346. Now:
#  - the run reaches step 360 (exit status 0);
#  - the loads do not grow: the largest |F| of steps 321-360 is within 10% of that of steps 281-320
#    (measured +1.5%; the old rule gave 5.6 times by step 345);
#  - saturated rows were taken (the progress line's count).
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
deck=$(cd "$(dirname "$0")/../.." && pwd)/input/quiescent_needle_resolved.nml
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

if "$AGGLO" "$deck" --set run.seed=1013 --set run.max_steps=360 --set run.progress_interval=20 \
    --set "pair.hydrodynamics_from='first_contact'" --set bodies.max_sweeps=1000 --set collision.lubrication=.false. \
    --set "output.directory='run'" > run.out 2>&1; then
  echo "PASS resolved_subcell_gap_run_finishes"
else
  echo "FAIL resolved_subcell_gap_run_finishes: $(grep -m1 'agglo: error' run.out | cut -c1-200)"
fi
# Largest |F| of either body over steps 281-320 and 321-360 (bodies_loads.dat: step, time, body, F).
ratio=$(awk 'NR > 1 && $1 > 280 {F = sqrt($4^2 + $5^2 + $6^2); if ($1 <= 320) { if (F > a) a = F } else if (F > b) b = F}
             END {if (a > 0 && b > 0) printf "%.4f", b / a; else print "nan"}' run/bodies_loads.dat 2>/dev/null)
if awk -v r="${ratio:-nan}" 'BEGIN {exit !(r + 0 > 0 && r + 0 <= 1.10)}'; then
  echo "PASS resolved_subcell_gap_loads_do_not_grow ($ratio)"
else
  echo "FAIL resolved_subcell_gap_loads_do_not_grow: largest |F| of steps 321-360 over that of 281-320 = ${ratio:-nan} (at most 1.10)"
fi
saturated=$(sed -n 's/.*fallback rows [0-9]* (saturated [0-9]*; most [0-9]*, \([0-9]*\)).*/\1/p' run.out | tail -n 1)
if [ "${saturated:-0}" -gt 0 ]; then
  echo "PASS resolved_subcell_gap_saturated_rows_taken ($saturated)"
else
  echo "FAIL resolved_subcell_gap_saturated_rows_taken: no saturated row counted"
fi
