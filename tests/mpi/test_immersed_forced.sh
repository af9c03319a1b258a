#!/usr/bin/env bash
# checks: 4
# Bodies in prescribed motion in the Eswaran-Pope forced box (&scene particles = 'prescribed',
# forcing = 'eswaran_pope', with the uniform drive of &bodies driving_force; docs/decks.md):
#  - the deck runs on 2 ranks (a translating sphere crossing the rank boundary and a rotating
#    needle, 16^3), one row per body per step, and the log names the forcing;
#  - the forcing acts: the loads differ from those of the same run with forcing = 'none';
#  - 1 and 2 ranks give the same loads to 1e-10 of the largest (the forcing's realisation does not
#    depend on the ranks; the Jacobi ghost sweeps neither);
#  - a restart from the step-6 checkpoint (the step-12 one deleted, as if killed there) continues
#    bodies_loads.dat and fluid_statistics.dat to the bit: the forcing's OU state and stream are in
#    the checkpoint, the body motion is a function of time.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, forcing
  cat <<NML
&run name = '$1', max_steps = 12, end_time = 1.0, dt = 2.0e-5, dt_mode = 'fixed', overwrite = .true.,
     progress_interval = 6 /
&scene fluid = 'resolved', particles = 'prescribed', ibm_coupling = 'implicit', forcing = '$2' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'rest', pressure_scheme = 'non_incremental' /
&forcing time_scale = 0.01, epsilon_star = 1.0e-2, kappa_f_ratio = 2.3, update = 'exact' /
&bodies count = 2,
  shape(1) = 'sphere', radius(1) = 1.6e-4, centre(:,1) = 0.3e-3, 0.4e-3, 0.49e-3,
  velocity(:,1) = 2.0e-3, 0.0, 1.0e-3,
  shape(2) = 'needle', radius(2) = 2.0e-4, aspect_ratio(2) = 2.0, centre(:,2) = 0.7e-3, 0.65e-3, 0.9e-3,
  axis(:,2) = 1.0, 1.0, 0.5, angular_velocity(:,2) = 0.0, 30.0, 10.0,
  driving_force = 5.0, 0.0, -2.0 /
&output directory = '$1', checkpoint_interval = 6, field_interval = 0.0 /
NML
}
run() { # ranks, deck file, extra arguments
  local ranks=$1 file=$2; shift 2
  mpirun -np "$ranks" "$AGGLO" "$file" "$@" > "$file.out" 2>&1
}
compare_loads() { # file a, file b: worst difference relative to the largest load (python prints it)
  python3 - "$1" "$2" <<'PY'
import sys
a = [l.split() for l in open(sys.argv[1]) if not l.startswith('#')]
b = [l.split() for l in open(sys.argv[2]) if not l.startswith('#')]
assert len(a) == len(b) == 24, f'rows {len(a)} {len(b)} (24 = 2 bodies x 12 steps)'
scale = max(abs(float(x)) for r in a for x in r[3:9])
worst = max(abs(float(x) - float(y)) for r, s in zip(a, b) for x, y in zip(r[3:9], s[3:9]))
assert scale > 0
print(f'{worst / scale:.3e}')
PY
}

deck forced_two eswaran_pope > forced_two.nml
deck forced_one eswaran_pope > forced_one.nml
deck unforced none > unforced.nml
if run 2 forced_two.nml && run 1 forced_one.nml && run 2 unforced.nml; then
  rows=$(grep -vc '^#' forced_two/bodies_loads.dat)
  if [ "$rows" -eq 24 ] && grep -q 'forcing: Eswaran-Pope' forced_two.nml.out; then
    echo "PASS immersed_forced/runs_on_two_ranks  ($rows rows; $(grep -m1 -i 'immersed boundary: sweeps' forced_two.nml.out | head -c 120))"
  else
    echo "FAIL immersed_forced/runs_on_two_ranks: $rows rows (24 expected) or no 'forcing: Eswaran-Pope' line in the log"
  fi
  if difference=$(compare_loads forced_two/bodies_loads.dat unforced/bodies_loads.dat 2>&1) && \
     python3 -c "import sys; sys.exit(0 if float('$difference') > 1e-3 else 1)"; then
    echo "PASS immersed_forced/forcing_changes_the_loads  (largest change ${difference} of the largest load)"
  else
    echo "FAIL immersed_forced/forcing_changes_the_loads: relative change ${difference} (above 1e-3 expected)"
  fi
  if difference=$(compare_loads forced_one/bodies_loads.dat forced_two/bodies_loads.dat 2>&1) && \
     python3 -c "import sys; sys.exit(0 if float('$difference') <= 1e-10 else 1)"; then
    echo "PASS immersed_forced/one_and_two_ranks_equal  (worst difference ${difference} of the largest load)"
  else
    echo "FAIL immersed_forced/one_and_two_ranks_equal: ${difference} (1e-10 allowed)"
  fi
else
  echo "FAIL immersed_forced/runs_on_two_ranks: a run failed: $(tail -n 3 ./*.nml.out | head -c 600)"
fi

# Restart on 2 ranks from the step-6 checkpoint.
if [ -f forced_two/checkpoints/checkpoint_0000000012.h5 ]; then
  cp forced_two/bodies_loads.dat uninterrupted_loads.dat
  cp forced_two/fluid_statistics.dat uninterrupted_statistics.dat
  rm forced_two/checkpoints/checkpoint_0000000012.h5
  if run 2 forced_two.nml --set run.restart=.true.; then
    if cmp -s uninterrupted_loads.dat forced_two/bodies_loads.dat && \
       cmp -s uninterrupted_statistics.dat forced_two/fluid_statistics.dat; then
      echo "PASS immersed_forced/restart_bit_for_bit  ($(grep -vc '^#' forced_two/bodies_loads.dat) load rows, fluid statistics equal)"
    else
      echo "FAIL immersed_forced/restart_bit_for_bit: $(diff uninterrupted_loads.dat forced_two/bodies_loads.dat | head -c 300)"
    fi
  else
    echo "FAIL immersed_forced/restart_bit_for_bit: the restart failed: $(tail -n 3 forced_two.nml.out | head -c 400)"
  fi
else
  echo "FAIL immersed_forced/restart_bit_for_bit: no step-12 checkpoint"
fi
