#!/usr/bin/env bash
# checks: 12
# End-to-end runs of the resolved scene with bodies in prescribed motion (&scene particles =
# 'prescribed', &bodies; docs/decks.md, docs/outputs.md bodies_loads.dat):
#  - a translating sphere and a rotating needle in a driven box, 1 rank and 2 ranks (a body crosses
#    the rank boundary and the periodic wrap): every load in bodies_loads.dat equal to 1e-10 of the
#    largest load (round-off; the Jacobi ghost sweeps do not depend on the ranks), for both couplings;
#  - the file has one row per body per step and the log names the sweeps and the residual;
#  - particles.h5 holds one row per step per body, its forces equal bodies_loads.dat's and its
#    positions the prescribed motion c0 + U t (wrapped);
#  - a restart continues bodies_loads.dat and particles.h5 bit for bit (rows after the checkpoint
#    dropped);
#  - a sphere crossing the periodic wrap in x and z (its centre wraps during the run) and, on 2
#    ranks, the rank boundaries (rung 9 of docs/studies/validation.md): its loads equal to round-off those of the same
#    sphere 16 cells lower, which crosses no periodic boundary (the periodic grid is invariant under
#    a shift by whole cells), and those of 2 ranks equal 1 rank's; the run logs its status changes
#    and load jumps;
#  - refused decks, before any step, with a message naming the variable: an unknown load_method,
#    a disk thinner than 4 cells (the message gives the grid). (Crank-Nicolson: test_immersed_cn_runs.sh.)
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, coupling, viscous_scheme, load_method, shape2, cells
  cat <<NML
&run name = '$1', max_steps = 12, end_time = 1.0, dt = 4.0e-6, dt_mode = 'fixed', overwrite = .true.,
     progress_interval = 4 /
&scene fluid = 'resolved', particles = 'prescribed', ibm_coupling = '$2' /
&grid nx = $6, ny = $6, nz = $6, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = '$3', init = 'rest', pressure_scheme = 'incremental' /
&bodies count = 2,
  shape(1) = 'sphere', radius(1) = 1.6e-4, centre(:,1) = 0.3e-3, 0.4e-3, 0.5e-3,
  velocity(:,1) = 2.0e-3, 0.0, 1.0e-3,
  shape(2) = '$5', radius(2) = 1.3e-4, aspect_ratio(2) = 2.0, centre(:,2) = 0.7e-3, 0.6e-3, 0.98e-3,
  axis(:,2) = 1.0, 1.0, 0.5, angular_velocity(:,2) = 0.0, 30.0, 10.0,
  driving_force = 5.0, 0.0, -2.0, load_method = '$4' /
&output directory = '$1', checkpoint_interval = 0, field_interval = 0.0 /
NML
}
run() { # ranks, deck file
  mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1
}

for coupling in implicit explicit; do
  deck one_$coupling $coupling explicit momentum needle 32 > one_$coupling.nml
  deck two_$coupling $coupling explicit momentum needle 32 > two_$coupling.nml
  if run 1 one_$coupling.nml && run 2 two_$coupling.nml; then
    if python3 - one_$coupling/bodies_loads.dat two_$coupling/bodies_loads.dat > cmp.txt 2>&1 <<'PY'
import sys
a = [l.split() for l in open(sys.argv[1]) if not l.startswith('#')]
b = [l.split() for l in open(sys.argv[2]) if not l.startswith('#')]
assert len(a) == len(b) == 24, f'rows {len(a)} {len(b)} (24 = 2 bodies x 12 steps)'
scale = max(abs(float(x)) for r in a for x in r[3:9])
worst = max(abs(float(x) - float(y)) for r, s in zip(a, b) for x, y in zip(r[3:9], s[3:9]))
assert scale > 0 and worst <= 1e-10 * scale, f'worst {worst:.3e} scale {scale:.3e}'
print(f'worst difference {worst:.2e} of largest load {scale:.2e}')
PY
    then
      echo "PASS immersed_runs/${coupling}_one_and_two_ranks_equal  ($(cat cmp.txt))"
    else
      echo "FAIL immersed_runs/${coupling}_one_and_two_ranks_equal: $(head -c 400 cmp.txt)"
    fi
    if grep -q 'immersed boundary: sweeps' two_$coupling.nml.out; then
      echo "PASS immersed_runs/${coupling}_log_names_sweeps  ($(grep 'immersed boundary: sweeps' two_$coupling.nml.out | tail -n 1 | head -c 160))"
    else
      echo "FAIL immersed_runs/${coupling}_log_names_sweeps: no sweeps line in the log"
    fi
  else
    echo "FAIL immersed_runs/${coupling}_one_and_two_ranks_equal: a run failed: $(tail -n 3 ./*_$coupling.nml.out | head -c 400)"
  fi
done

# Rung 9: the same sphere, moving along x and z, centred 0.005 mm below the periodic wrap in x and
# z ('wrap', its centre wraps at steps 25 and 13) or 16 cells lower in z ('shifted', crossing no
# periodic boundary in z; on 2 ranks it crosses the rank boundary at z = L/2 instead).
crossing() { # name, centre z
  cat <<NML
&run name = '$1', max_steps = 40, end_time = 1.0, dt = 4.0e-6, dt_mode = 'fixed', overwrite = .true.,
     progress_interval = 20 /
&scene fluid = 'resolved', particles = 'prescribed', ibm_coupling = 'implicit' /
&grid nx = 32, ny = 32, nz = 32, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'rest', pressure_scheme = 'incremental' /
&bodies count = 1, shape(1) = 'sphere', radius(1) = 1.6e-4, centre(:,1) = 0.995e-3, 0.52e-3, $2,
  velocity(:,1) = 0.05, 0.0, 0.1 /
&output directory = '$1', checkpoint_interval = 0, field_interval = 0.0 /
NML
}
crossing wrap_one 0.995e-3 > wrap_one.nml
crossing wrap_two 0.995e-3 > wrap_two.nml
crossing shifted_one 0.495e-3 > shifted_one.nml
if run 1 wrap_one.nml && run 2 wrap_two.nml && run 1 shifted_one.nml; then
  for pair in "wrap_one shifted_one periodic_crossing_equals_shifted" "wrap_one wrap_two periodic_and_rank_crossing_two_ranks"; do
    set -- $pair
    if python3 - "$1/bodies_loads.dat" "$2/bodies_loads.dat" > cmp.txt 2>&1 <<'PY'
import sys
a = [l.split() for l in open(sys.argv[1]) if not l.startswith('#')]
b = [l.split() for l in open(sys.argv[2]) if not l.startswith('#')]
assert len(a) == len(b) == 40, f'rows {len(a)} {len(b)}'
scale = max(abs(float(x)) for r in a for x in r[3:9])
worst = max(abs(float(x) - float(y)) for r, s in zip(a, b) for x, y in zip(r[3:9], s[3:9]))
assert scale > 0 and worst <= 1e-10 * scale, f'worst {worst:.3e} scale {scale:.3e}'
print(f'worst difference {worst:.2e} of largest load {scale:.2e}')
PY
    then
      echo "PASS immersed_runs/$3  ($(cat cmp.txt))"
    else
      echo "FAIL immersed_runs/$3: $(head -c 400 cmp.txt)"
    fi
  done
  if grep -q 'status changes: [1-9][0-9]* nodes uncovered' wrap_two/agglo.log; then
    echo "PASS immersed_runs/crossing_logs_status_changes  ($(grep 'status changes' wrap_two/agglo.log | tail -n 1 | head -c 300))"
  else
    echo "FAIL immersed_runs/crossing_logs_status_changes: no status-change line with uncovered nodes in the log"
  fi
else
  echo "FAIL immersed_runs/periodic_crossing_equals_shifted: a run failed: $(tail -n 3 wrap_*.nml.out shifted_one.nml.out | head -c 400)"
fi

refused() { # test name, deck file, expected text in the message
  if run 1 "$2"; then
    echo "FAIL immersed_runs/$1: the deck ran"
  elif grep -q "$3" "$2.out"; then
    echo "PASS immersed_runs/$1  ($(grep -m1 "$3" "$2.out" | head -c 200))"
  else
    echo "FAIL immersed_runs/$1: message without '$3': $(tail -n 3 "$2.out" | head -c 300)"
  fi
}
deck faces implicit explicit faces needle 32 > faces.nml
refused refuses_unknown_load_method faces.nml 'load_method'
deck thin implicit explicit momentum disk 16 > thin.nml
refused refuses_thin_disk_with_grid thin.nml 'nx = ny = nz >='

# particles.h5 of the 1-rank implicit run: 12 rows; the hydrodynamic force of each body equals the
# force columns of bodies_loads.dat (written with 17 digits: round trip to 1e-15), and body 1's
# centre is c0 + U t wrapped into the box at every row (the motion is prescribed: to 1e-12 m).
dump() { h5dump -y -w 0 -m '%.17g' -d "$2" "$1" 2>/dev/null | sed -n '/DATA {/,/}/p' | tr -d 'DATA{}(),:' ; }
if dump one_implicit/particles.h5 /particle1/force_hydrodynamic > f1.txt && \
   dump one_implicit/particles.h5 /particle2/force_hydrodynamic > f2.txt && \
   dump one_implicit/particles.h5 /particle1/position > x1.txt && dump one_implicit/particles.h5 /time > t.txt && \
   python3 - one_implicit/bodies_loads.dat > cmp.txt 2>&1 <<'PY'
import sys
numbers = lambda name: [float(x) for x in open(name).read().split()]
rows = [l.split() for l in open(sys.argv[1]) if not l.startswith('#')]
t, x1 = numbers('t.txt'), numbers('x1.txt')
assert len(t) == 12 and len(x1) == 36, f'{len(t)} times, {len(x1) // 3} positions (12 steps)'
worst = 0.0
for body, name in ((1, 'f1.txt'), (2, 'f2.txt')):
    h5 = numbers(name)
    text = [float(x) for r in rows if int(r[2]) == body for x in r[3:6]]
    assert len(h5) == len(text) == 36, f'body {body}: {len(h5)} vs {len(text)} values'
    scale = max(abs(v) for v in text)
    worst = max(worst, max(abs(a - b) for a, b in zip(h5, text)) / scale)
assert worst <= 1e-15, f'force differs by {worst:.2e} relative'
c0, U = (0.3e-3, 0.4e-3, 0.5e-3), (2.0e-3, 0.0, 1.0e-3)
moved = max(abs(x1[3 * i + d] - (c0[d] + U[d] * t[i]) % 1.0e-3) for i in range(12) for d in range(3))
assert moved <= 1e-12, f'body 1 position off the prescribed motion by {moved:.2e} m'
print(f'12 rows, force vs bodies_loads.dat {worst:.1e} relative, position {moved:.1e} m')
PY
then
  echo "PASS immersed_runs/particles_h5_rows_loads_and_motion  ($(cat cmp.txt))"
else
  echo "FAIL immersed_runs/particles_h5_rows_loads_and_motion: $(head -c 400 cmp.txt)"
fi

# Restart (docs/outputs.md bodies_loads.dat): the moving bodies' run checkpointed at step 6, its
# last checkpoint (step 12) deleted as if killed there, restarted: the rows after step 6 are dropped
# and written again, and the file equals the uninterrupted run's to the bit (the body motion is a
# function of time; the fluid, with the values left at uncovered nodes, is in the checkpoint).
deck restart implicit explicit momentum needle 32 | sed 's/checkpoint_interval = 0/checkpoint_interval = 6/' > restart.nml
if run 1 restart.nml && cp restart/bodies_loads.dat uninterrupted.dat && cp restart/particles.h5 uninterrupted.h5 \
   && rm restart/checkpoints/checkpoint_0000000012.h5 \
   && mpirun -np 1 "$AGGLO" restart.nml --set run.restart=.true. > restart.out 2>&1; then
  if cmp -s uninterrupted.dat restart/bodies_loads.dat; then
    echo "PASS immersed_runs/restart_continues_loads_bit_for_bit  ($(grep -vc '^#' restart/bodies_loads.dat) rows)"
  else
    echo "FAIL immersed_runs/restart_continues_loads_bit_for_bit: $(diff uninterrupted.dat restart/bodies_loads.dat | head -c 300)"
  fi
  if h5diff uninterrupted.h5 restart/particles.h5 > h5diff.txt 2>&1; then
    echo "PASS immersed_runs/restart_continues_particles_h5_bit_for_bit  (h5diff, no tolerance)"
  else
    echo "FAIL immersed_runs/restart_continues_particles_h5_bit_for_bit: $(head -c 300 h5diff.txt)"
  fi
else
  echo "FAIL immersed_runs/restart_continues_loads_bit_for_bit: a run failed: $(tail -n 3 restart.out restart.nml.out 2>/dev/null | head -c 400)"
fi
