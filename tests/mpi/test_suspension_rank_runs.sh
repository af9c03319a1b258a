#!/usr/bin/env bash
# A suspension (&scene particles = 'suspension'; docs/scenes.md, "Suspension") restarts bit for bit
# and gives the same run on 1 and 2 ranks at every rung, with bodies crossing the boundary between
# the ranks' slabs (z = L/2 on 2 ranks) and the periodic wrap, with $AGGLO:
#  - 'none' and 'stokes': the smallest deck (input/suspension_sphere_none.nml, 95 spheres in vacuum;
#    in fluid at rest with 0.5 m/s rms start velocities) for 4000 steps: bodies cross the periodic
#    wrap after the restart step (particles.h5 rows 500 steps apart); 1 and 2 ranks give the same
#    particles.h5 and last checkpoint bit for bit (every rank does the same arithmetic: no fluid
#    grid, the particle system on every rank); on 2 ranks 2000 steps + &run restart to 4000 give
#    them bit for bit;
#  - 'point' and 'resolved': 10 calcite spheres (radius 40 um, D/dx = 5.1 at 32^3 in a 0.5 mm box)
#    in a random solenoidal field (10 mm/s), random velocities of 0.1 m/s rms on top of the
#    fluid's, 16 fluid steps of 10 us with a particles.h5 row per fluid step. Seed 41 places a
#    sphere 3 um below z = L/2 moving up and one 21 um above z = 0 moving down (random stream 4: the
#    same bodies at both rungs): after the restart step (4) one body's centre crosses z = L/2 (the
#    slab boundary) and another's the wrap z = 0 = L (the other slab boundary on 2 ranks), at both
#    rungs (found from the rows: a sign change of z - L/2, and a jump of more than L/2); on 2 ranks
#    4 fluid steps + &run restart to 16 give the 16-step particles.h5 and checkpoint bit for bit
#    (h5diff without tolerance); 1 and 2 ranks agree to 1e-9 of each quantity's largest value
#    (position, quaternion, velocity, angular velocity, hydrodynamic force and torque; measured
#    about 1e-14: round-off of the sums over the slabs, as tests/mpi/test_free_bodies_runs.sh).
# Prints PASS/FAIL lines; works in a temporary directory.
# checks: 12
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
root=$(cd "$(dirname "$0")/../.." && pwd)
python=${AGGLO_PYTHON:-$root/.venv/bin/python}   # h5py, numpy
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

# Did every run of a case end? (a failed run names its error in the FAIL lines)
ran() { # label, output files...
  local label=$1 out; shift
  for out in "$@"; do
    grep -q 'agglo: run complete' "$out" || { echo "$label: $(grep -m1 'error' "$out" | head -c 300)"; return 1; }
  done
}

# --- 'none' and 'stokes': the smallest deck, in vacuum and in fluid at rest ---
deck=$root/input/suspension_sphere_none.nml
for rung in none stokes; do
  common=(--set run.end_time=1.0 --set output.checkpoint_interval=2000 --set output.particle_interval=500)
  # In fluid at rest the spheres relax in 1.5 ms (2 rho_p a^2 / (9 mu)): 0.5 m/s rms carries some across the wrap.
  [ "$rung" = stokes ] && common+=(--set "scene.fluid='stokes'" --set suspension.velocity_rms=0.5)
  "$AGGLO" "$deck" "${common[@]}" --set run.max_steps=4000 --set "output.directory='${rung}1'" > ${rung}1.out 2>&1
  mpirun -np 2 "$AGGLO" "$deck" "${common[@]}" --set run.max_steps=4000 --set "output.directory='${rung}2'" \
    > ${rung}2.out 2>&1
  mpirun -np 2 "$AGGLO" "$deck" "${common[@]}" --set run.max_steps=2000 --set "output.directory='${rung}2split'" \
    > ${rung}2split1.out 2>&1
  mpirun -np 2 "$AGGLO" "$deck" "${common[@]}" --set run.max_steps=4000 --set "output.directory='${rung}2split'" \
    --set run.restart=.true. > ${rung}2split2.out 2>&1
  if failed=$(ran $rung ${rung}1.out ${rung}2.out ${rung}2split1.out ${rung}2split2.out); then
    "$python" - "$rung" <<'PY'
import sys, h5py, numpy as np
rung = sys.argv[1]
f = h5py.File(f'{rung}2/particles.h5', 'r')
z = f['suspension/position'][:].reshape(len(f['time']), 95, 3)
jumps = np.abs(np.diff(z, axis=0)) > 0.5e-3        # (row, body, axis): a wrap between two rows
after = int(jumps[4:].any(axis=2).sum())           # rows 4 on: after step 2000, the restart
print(('PASS' if after > 0 and len(f['time']) == 9 else 'FAIL') +
      f' suspension_ranks/{rung}_bodies_cross_the_wrap_after_the_restart  ({after} crossings after step 2000,'
      f' {int(jumps.any(axis=2).sum())} in all)')
PY
    if h5diff -q ${rung}1/particles.h5 ${rung}2/particles.h5 && \
       h5diff -q ${rung}1/checkpoints/checkpoint_0000004000.h5 ${rung}2/checkpoints/checkpoint_0000004000.h5; then
      echo "PASS suspension_ranks/${rung}_1_and_2_ranks_bit_for_bit  (particles.h5 and the 4000-step checkpoint)"
    else echo "FAIL suspension_ranks/${rung}_1_and_2_ranks_bit_for_bit"; fi
    if h5diff -q ${rung}2/particles.h5 ${rung}2split/particles.h5 && \
       h5diff -q ${rung}2/checkpoints/checkpoint_0000004000.h5 ${rung}2split/checkpoints/checkpoint_0000004000.h5; then
      echo "PASS suspension_ranks/${rung}_restart_bit_for_bit_2_ranks  (2000 + 2000 steps: particles.h5 and the last checkpoint)"
    else echo "FAIL suspension_ranks/${rung}_restart_bit_for_bit_2_ranks"; fi
  else
    for check in bodies_cross_the_wrap_after_the_restart 1_and_2_ranks_bit_for_bit restart_bit_for_bit_2_ranks; do
      echo "FAIL suspension_ranks/${rung}_$check: $failed"
    done
  fi
done

# --- 'point' and 'resolved': spheres crossing the slab boundary and the wrap ---
cat > crossing.nml <<'NML'
&run name = 'suspension_crossing', seed = 41, end_time = 1.0, max_steps = 16, dt = 1.0e-5, dt_mode = 'fixed',
     progress_interval = 4 /
&scene fluid = 'resolved', particles = 'suspension', particle_coupling = 'resolved', particle_substeps = 4,
       added_mass = .true. /
&grid nx = 32, ny = 32, nz = 32, length_x = 0.5e-3, length_y = 0.5e-3, length_z = 0.5e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'random', init_amplitude = 1.0e-2 /
&pair density = 2710.0, radius = 40.0e-6 /
&suspension shape = 'sphere', radius = 40.0e-6, count = 10, velocity_rms = 0.1 /
&output stats_interval = 4, particle_interval = 4, checkpoint_interval = 4, field_interval = 0.0 /
NML
for rung in point resolved; do
  set_rung=(--set "scene.particle_coupling='$rung'")
  "$AGGLO" crossing.nml "${set_rung[@]}" --set "output.directory='${rung}1'" > ${rung}1.out 2>&1
  mpirun -np 2 "$AGGLO" crossing.nml "${set_rung[@]}" --set "output.directory='${rung}2'" > ${rung}2.out 2>&1
  mpirun -np 2 "$AGGLO" crossing.nml "${set_rung[@]}" --set "output.directory='${rung}2split'" --set run.max_steps=4 \
    > ${rung}2split1.out 2>&1
  mpirun -np 2 "$AGGLO" crossing.nml "${set_rung[@]}" --set "output.directory='${rung}2split'" --set run.restart=.true. \
    > ${rung}2split2.out 2>&1
  if ! failed=$(ran $rung ${rung}1.out ${rung}2.out ${rung}2split1.out ${rung}2split2.out); then
    for check in bodies_cross_the_slab_boundary_and_the_wrap restart_bit_for_bit_2_ranks 1_and_2_ranks_agree; do
      echo "FAIL suspension_ranks/${rung}_$check: $failed"
    done
    continue
  fi
  "$python" - "$rung" <<'PY'
import sys, h5py, numpy as np
rung, L, n = sys.argv[1], 0.5e-3, 10
f = h5py.File(f'{rung}2/particles.h5', 'r')
z = f['suspension/position'][:].reshape(len(f['time']), n, 3)[:, :, 2]
dz = np.diff(z, axis=0)
# Rows 4 on (after the restart step): a centre moving across z = L/2, or across z = 0 = L.
slab = np.nonzero(((np.sign(z[4:-1] - L / 2) != np.sign(z[5:] - L / 2)) & (np.abs(dz[4:]) < L / 4)).any(0))[0]
wrap = np.nonzero((np.abs(dz[4:]) > L / 2).any(0))[0]
ok = len(f['time']) == 17 and len(slab) > 0 and len(wrap) > 0 and set(slab) != set(wrap)
print(('PASS' if ok else 'FAIL') + f' suspension_ranks/{rung}_bodies_cross_the_slab_boundary_and_the_wrap  '
      f'(after step 4: bodies {[int(i) + 1 for i in slab]} cross z = L/2, bodies {[int(i) + 1 for i in wrap]} z = 0 = L)')
PY
  if h5diff -q ${rung}2/particles.h5 ${rung}2split/particles.h5 && \
     h5diff -q ${rung}2/checkpoints/checkpoint_0000000016.h5 ${rung}2split/checkpoints/checkpoint_0000000016.h5; then
    echo "PASS suspension_ranks/${rung}_restart_bit_for_bit_2_ranks  (4 + 12 fluid steps: particles.h5 and the last checkpoint)"
  else echo "FAIL suspension_ranks/${rung}_restart_bit_for_bit_2_ranks: $(grep -m1 error ${rung}2split2.out)"; fi
  "$python" - "$rung" <<'PY'
import sys, h5py, numpy as np
rung = sys.argv[1]
try:
    a, b = h5py.File(f'{rung}1/particles.h5', 'r'), h5py.File(f'{rung}2/particles.h5', 'r')
    worst, name = 0.0, ''
    for q in ('position', 'quaternion', 'velocity', 'angular_velocity', 'force_hydrodynamic', 'torque_hydrodynamic'):
        x, y = a[f'suspension/{q}'][:], b[f'suspension/{q}'][:]
        rel = np.abs(x - y).max() / np.abs(x).max()
        if not rel <= worst:
            worst, name = rel, q
    ok = worst < 1.0e-9 and len(a['time']) == 17
    print(('PASS' if ok else 'FAIL') + f' suspension_ranks/{rung}_1_and_2_ranks_agree  (largest difference '
          f'{worst:.2e} of the largest value, {name})')
except Exception as error:
    print(f'FAIL suspension_ranks/{rung}_1_and_2_ranks_agree: {error}')
PY
done
