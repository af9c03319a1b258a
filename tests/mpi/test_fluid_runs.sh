#!/usr/bin/env bash
# checks: 6
# End-to-end runs of the resolved scene with $AGGLO (docs/studies/validation.md, Fluid):
#  - restart: 2n steps in one run == n steps + restart + n steps, bit for bit (h5diff, no tolerance)
#    on 2 ranks with CFL-controlled dt and Crank-Nicolson (the multistep history and dt_old travel
#    through the checkpoint); the time series fluid_statistics.dat of the restarted run equals the
#    uninterrupted one (same rows, same bytes), also after a simulated kill that left rows written
#    after the last checkpoint (they are dropped on restart, not duplicated);
#  - 1 rank vs 2 ranks: the same deck gives the same fields to 1e-12 x amplitude (only the FFT's
#    round-off differs between decompositions);
#  - a fixed dt above the explicit-diffusion limit is refused with a message naming &run dt.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, max_steps, restart, dt_mode, viscous_scheme, dt[, checkpoint_interval]
  cat <<NML
&run name = '$1', max_steps = $2, restart = $3, end_time = 1.0, dt = $6, dt_mode = '$4',
     cfl_target = 0.3, overwrite = .true., progress_interval = 1000 /
&scene fluid = 'resolved' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = '$5', init = 'random', init_amplitude = 0.02,
       init_peak_wavenumber = 2.0 /
&output directory = '$1', checkpoint_interval = ${7:-0}, checkpoints_kept = 5, field_interval = 0.0 /
NML
}
run() { # ranks, deck file
  mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1
}
final_checkpoint() { ls "$1"/checkpoints/checkpoint_*.h5 | sort | tail -n 1; }

# --- restart bit for bit --------------------------------------------------------------------
deck whole 20 .false. cfl crank_nicolson 1.0e-4 > whole.nml
deck split 10 .false. cfl crank_nicolson 1.0e-4 > split1.nml
deck split 20 .true. cfl crank_nicolson 1.0e-4 > split2.nml
if run 2 whole.nml && run 2 split1.nml && run 2 split2.nml; then
  a=$(final_checkpoint whole); b=$(final_checkpoint split)
  if [ "$(basename "$a")" = checkpoint_0000000020.h5 ] && h5diff -q "$a" "$b" > diff.txt 2>&1; then
    echo "PASS fluid_runs/restart_2n_equals_n_restart_n_bit_for_bit  ($(basename "$a"), h5diff exact)"
  else
    echo "FAIL fluid_runs/restart_2n_equals_n_restart_n_bit_for_bit: $a vs $b: $(head -c 300 diff.txt)"
  fi
else
  echo "FAIL fluid_runs/restart_2n_equals_n_restart_n_bit_for_bit: a run failed: $(tail -n 3 ./*.nml.out | head -c 400)"
fi

# The time series of the restarted run: the same 21 rows (steps 0..20), byte for byte.
if cmp -s whole/fluid_statistics.dat split/fluid_statistics.dat \
   && [ "$(grep -vc '^#' split/fluid_statistics.dat)" = 21 ]; then
  echo "PASS fluid_runs/restart_time_series_equals_uninterrupted  (21 rows, identical bytes)"
else
  echo "FAIL fluid_runs/restart_time_series_equals_uninterrupted: $(diff whole/fluid_statistics.dat \
       split/fluid_statistics.dat 2>&1 | head -c 300)"
fi

# --- restart after a kill: rows written after the last checkpoint are dropped ------------------
# 14 steps with checkpoints at 4, 8, 12 and the end-of-run one at 14; deleting checkpoint 14 leaves
# the directory as a run killed after writing the row of step 14 but before its checkpoint: the
# restart continues from step 12, and rows 13 and 14 must not appear twice.
deck killed 14 .false. cfl crank_nicolson 1.0e-4 4 > killed1.nml
deck killed 20 .true. cfl crank_nicolson 1.0e-4 4 > killed2.nml
if run 2 killed1.nml && rm -f killed/checkpoints/checkpoint_0000000014.h5 \
   && [ "$(grep -vc '^#' killed/fluid_statistics.dat)" = 15 ] && run 2 killed2.nml; then
  rows=$(grep -vc '^#' killed/fluid_statistics.dat)
  if grep -q 'continuing from .*checkpoint_0000000012.h5' killed2.nml.out \
     && cmp -s whole/fluid_statistics.dat killed/fluid_statistics.dat \
     && h5diff -q "$(final_checkpoint whole)" "$(final_checkpoint killed)" > diff.txt 2>&1; then
    echo "PASS fluid_runs/restart_after_kill_drops_rows_past_checkpoint  ($rows rows = uninterrupted run, identical bytes; final checkpoint bit for bit)"
  else
    echo "FAIL fluid_runs/restart_after_kill_drops_rows_past_checkpoint: $rows rows; $(diff whole/fluid_statistics.dat \
         killed/fluid_statistics.dat 2>&1 | head -c 300) $(head -c 200 diff.txt)"
  fi
else
  echo "FAIL fluid_runs/restart_after_kill_drops_rows_past_checkpoint: a run failed: $(tail -n 3 killed*.nml.out | head -c 400)"
fi

# --- 1 rank vs 2 ranks ----------------------------------------------------------------------
deck one 20 .false. fixed explicit 2.0e-5 > one.nml
deck two 20 .false. fixed explicit 2.0e-5 > two.nml
if run 1 one.nml && run 2 two.nml; then
  ok=1; detail=""
  for f in u v w; do
    # Absolute tolerance 1e-12 x the 0.02 m/s amplitude.
    if ! h5diff -d 2e-14 "$(final_checkpoint one)" "$(final_checkpoint two)" "/fluid/$f" > diff.txt 2>&1; then
      ok=0; detail="$detail $f: $(head -c 200 diff.txt)"
    fi
  done
  if [ $ok = 1 ]; then echo "PASS fluid_runs/one_rank_equals_two_ranks_to_1e-12  (u, v, w after 20 steps)"
  else echo "FAIL fluid_runs/one_rank_equals_two_ranks_to_1e-12:$detail"; fi
else
  echo "FAIL fluid_runs/one_rank_equals_two_ranks_to_1e-12: a run failed: $(tail -n 3 one.nml.out two.nml.out | head -c 400)"
fi

# --- time-series file written every step ----------------------------------------------------
rows=$(grep -vc '^#' one/fluid_statistics.dat 2>/dev/null || echo 0)
if [ "$rows" = 21 ]; then echo "PASS fluid_runs/statistics_row_per_step  (21 rows: start + 20 steps)"
else echo "FAIL fluid_runs/statistics_row_per_step: $rows rows in one/fluid_statistics.dat, expected 21"; fi

# --- dt above the explicit-diffusion limit is refused ---------------------------------------
# 16^3 in 1 mm, nu = 1e-6: limit dx^2 / (12 nu) = 3.26e-4 s; 1e-3 s must be refused.
deck bad 20 .false. fixed explicit 1.0e-3 > bad.nml
if run 1 bad.nml; then
  echo "FAIL fluid_runs/dt_above_viscous_limit_refused: the run was accepted"
elif grep -q "&run dt = 1.00000E-03 is not allowed; allowed: <= 3.25521E-04" bad.nml.out; then
  echo "PASS fluid_runs/dt_above_viscous_limit_refused"
else
  echo "FAIL fluid_runs/dt_above_viscous_limit_refused: message was: $(grep -m1 error bad.nml.out)"
fi
