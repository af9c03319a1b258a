#!/usr/bin/env bash
# checks: 3
# End-to-end runs of the resolved scene with &fluid pressure_scheme (docs/decks.md, docs/theory.md):
#  - 'incremental' restarts bit for bit: 2n steps == n steps + restart + n steps (h5diff, no
#    tolerance; 2 ranks, CFL dt, Crank-Nicolson): the pressure p^{n-1/2}, which the incremental
#    predictor reads, travels through the checkpoint with its halos rebuilt on restart;
#  - 'incremental' and 'non_incremental' give the same fields to round-off in the periodic box
#    (the projection removes the old gradient exactly; docs/theory.md): |difference| <= 1e-12 in
#    u, v, w (m/s, amplitude 0.02) and p (Pa, about 0.4);
#  - an unknown scheme is refused with a message naming &fluid pressure_scheme, before any step.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, max_steps, restart, pressure_scheme
  cat <<NML
&run name = '$1', max_steps = $2, restart = $3, end_time = 1.0, dt = 1.0e-4, dt_mode = 'cfl',
     cfl_target = 0.3, overwrite = .true., progress_interval = 1000 /
&scene fluid = 'resolved' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'crank_nicolson', init = 'random', init_amplitude = 0.02,
       init_peak_wavenumber = 2.0, pressure_scheme = '$4' /
&output directory = '$1', checkpoint_interval = 0, checkpoints_kept = 5, field_interval = 0.0 /
NML
}
run() { # ranks, deck file
  mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1
}
final_checkpoint() { ls "$1"/checkpoints/checkpoint_*.h5 | sort | tail -n 1; }

# --- incremental: restart bit for bit ---------------------------------------------------------
deck whole 20 .false. incremental > whole.nml
deck split 10 .false. incremental > split1.nml
deck split 20 .true. incremental > split2.nml
if run 2 whole.nml && run 2 split1.nml && run 2 split2.nml; then
  a=$(final_checkpoint whole); b=$(final_checkpoint split)
  if [ "$(basename "$a")" = checkpoint_0000000020.h5 ] && h5diff -q "$a" "$b" > diff.txt 2>&1; then
    echo "PASS pressure_scheme_runs/incremental_restart_bit_for_bit  ($(basename "$a"), h5diff exact)"
  else
    echo "FAIL pressure_scheme_runs/incremental_restart_bit_for_bit: $a vs $b: $(head -c 300 diff.txt)"
  fi
else
  echo "FAIL pressure_scheme_runs/incremental_restart_bit_for_bit: a run failed: $(tail -n 3 ./*.nml.out | head -c 400)"
fi

# --- incremental == non_incremental to round-off in the periodic box ------------------------------
deck plain 20 .false. non_incremental > plain.nml
if run 2 plain.nml; then
  a=$(final_checkpoint whole); b=$(final_checkpoint plain)
  ok=1
  for field in u v w pressure; do
    h5diff -d 1e-12 "$a" "$b" "fluid/$field" "fluid/$field" > "diff_$field.txt" 2>&1 || ok=0
  done
  if [ $ok = 1 ]; then
    echo "PASS pressure_scheme_runs/incremental_equals_non_incremental_in_periodic_box  (u, v, w, p within 1e-12)"
  else
    echo "FAIL pressure_scheme_runs/incremental_equals_non_incremental_in_periodic_box: $(head -c 300 diff_*.txt)"
  fi
else
  echo "FAIL pressure_scheme_runs/incremental_equals_non_incremental_in_periodic_box: $(tail -n 3 plain.nml.out)"
fi

# --- an unknown scheme is refused ----------------------------------------------------------------
deck bad 5 .false. incrementl > bad.nml
if ! run 1 bad.nml && grep -q 'pressure_scheme' bad.nml.out && grep -q 'fluid' bad.nml.out && [ ! -d bad/checkpoints ]; then
  echo "PASS pressure_scheme_runs/unknown_scheme_refused  ($(grep -m1 pressure_scheme bad.nml.out | head -c 160))"
else
  echo "FAIL pressure_scheme_runs/unknown_scheme_refused: $(tail -n 3 bad.nml.out | head -c 300)"
fi
