#!/usr/bin/env bash
# The suspension scene (&scene particles = 'suspension'; docs/scenes.md, "Suspension"), with $AGGLO:
#  - the smallest suspension deck (input/suspension_sphere_none.nml: 95 calcite spheres, 5% by
#    volume, in vacuum, 10 mm/s rms) for 4000 steps: collisions happen (the log counts them and
#    particles.h5 has their events), particles.h5 holds every body in the suspension layout
#    (/suspension/position of 3 x 95 values per row, a row every 500 steps), and no two bodies
#    overlap at the last sample;
#  - restart: 2000 steps + &run restart to 4000 give the 4000-step particles.h5 and last
#    checkpoint bit for bit (h5diff without tolerance): the same placement, the same collisions;
#  - 1 and 2 ranks, point particles in a random resolved field (16^3): the same placement (the
#    first sample's positions and orientations bit for bit), start velocities with the fluid's at
#    the centres (not the random ones alone), and after 4 fluid steps positions and velocities
#    within 1e-9 relative of each other (round-off of the field's sums over the slabs); on 2 ranks
#    2 fluid steps + &run restart to 4 give the 4-step particles.h5, clusters.h5 (DLVO is on by
#    default: the bodies' agglomerates) and checkpoint bit for bit;
#  - the same deck with &scene substep_bodies = 'near' (docs/theory.md, "Near-pair sub-steps"; one
#    pair near, 18 bodies in the one-step update) against every body sub-stepped, 1 rank: after 4
#    fluid steps positions within 2e-3 of the largest distance travelled, velocities within 1e-3 of
#    the largest, quaternions within 1e-5 (measured 5e-4, 1.4e-4, 9e-7: the 10 explicit Euler
#    sub-steps' own error against the exact relaxation, and the orientation and gradient the
#    one-step update holds over the step), no miss logged; 2 fluid steps + &run restart to 4 give
#    the 4-step particles.h5 and checkpoint bit for bit (the near bodies are found again from the
#    restored state); on 2 ranks (the search and the one-step update shared out) the same sub-step
#    members as on 1, the bodies within 1e-9 relative, and the 2 + 2-step restart bit for bit;
#  - ghost mode (&suspension ghost): 191 spheres at 10%, 20 mm/s rms, 4000 steps: every body's
#    velocity unchanged (bit for bit: no impulse, no DLVO), so the momentum is the start's; bodies
#    pass through each other (a negative gap logged); the collisions counted are exactly the
#    encounters an independent count finds on the straight-line trajectories x0 + v t (each pair's
#    steps with 0 <= gap < v_n dt at the minimum image, v_n the normal approach speed), pair by pair.
# Prints PASS/FAIL lines; works in a temporary directory.
# checks: 12
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
root=$(cd "$(dirname "$0")/../.." && pwd)
python=${AGGLO_PYTHON:-$root/.venv/bin/python}   # h5py, numpy
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
deck=$root/input/suspension_sphere_none.nml

# --- the 'none' deck: a run with collisions, and its restart ---
common=(--set run.end_time=1.0 --set output.checkpoint_interval=2000 --set output.particle_interval=500)
"$AGGLO" "$deck" "${common[@]}" --set run.max_steps=4000 --set "output.directory='full'" > full.out 2>&1
"$AGGLO" "$deck" "${common[@]}" --set run.max_steps=2000 --set "output.directory='split'" > split1.out 2>&1
"$AGGLO" "$deck" "${common[@]}" --set run.max_steps=4000 --set "output.directory='split'" --set run.restart=.true. \
  > split2.out 2>&1
collisions=$(grep -Eo 'suspension scene: 95 bodies, [0-9]+ collisions' full.out | grep -Eo '[0-9]+ collisions' | cut -d' ' -f1)
if [ -n "$collisions" ] && [ "$collisions" -gt 0 ] && "$python" - full/particles.h5 "$collisions" <<'PY'
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], 'r')
events = len(f['events/time'])
rows = len(f['time'])
x = f['suspension/position'][-1].reshape(95, 3)
d = x[:, None, :] - x[None, :, :]
d -= 1.0e-3 * np.round(d / 1.0e-3)
r = np.sqrt((d**2).sum(-1)) + np.eye(95)
print(f'  {events} events, {rows} samples, smallest centre distance {r.min():.4e} m')
sys.exit(0 if events == int(sys.argv[2]) and rows == 9 and r.min() > 100.0e-6 else 1)
PY
then echo "PASS suspension/none_deck_runs_with_collisions  ($collisions collisions in 4000 steps)"
else echo "FAIL suspension/none_deck_runs_with_collisions: $(grep -m1 -E 'error|collisions, t' full.out)"; fi
last=$(cd full/checkpoints && ls -d checkpoint_*.h5 | sort | tail -1)
if h5diff -q full/particles.h5 split/particles.h5 && h5diff -q "full/checkpoints/$last" "split/checkpoints/$last"; then
  echo "PASS suspension/restart_bit_for_bit  (particles.h5 and $last)"
else echo "FAIL suspension/restart_bit_for_bit: $(grep -m1 error split2.out)"; fi

# --- point particles in a resolved field on 1 and 2 ranks ---
cat > point.nml <<'NML'
&run name = 'suspension_point', seed = 3, end_time = 1.0, max_steps = 4, dt = 2.0e-5, progress_interval = 2 /
&scene fluid = 'resolved', particles = 'suspension', particle_coupling = 'point', particle_substeps = 10,
       added_mass = .true. /
&grid nx = 16, ny = 16, nz = 16 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'random', init_amplitude = 5.0e-3 /
&pair density = 2710.0, radius = 20.0e-6 /
&suspension shape = 'needle', 'sphere', radius = 20.0e-6, 20.0e-6, aspect_ratio = 5.0, 1.0, count = 10, 10,
            velocity_rms = 1.0e-3 /
&output stats_interval = 10 /
NML
mpirun -np 1 "$AGGLO" point.nml --set "output.directory='one'" > one.out 2>&1
mpirun -np 2 "$AGGLO" point.nml --set "output.directory='two'" > two.out 2>&1
mpirun -np 2 "$AGGLO" point.nml --set "output.directory='twosplit'" --set run.max_steps=2 > split3.out 2>&1
mpirun -np 2 "$AGGLO" point.nml --set "output.directory='twosplit'" --set run.restart=.true. > split4.out 2>&1
if h5diff -q two/particles.h5 twosplit/particles.h5 && \
   h5diff -q two/checkpoints/checkpoint_0000000004.h5 twosplit/checkpoints/checkpoint_0000000004.h5 && \
   "$python" -c 'import sys, h5py, numpy as np
a, b = h5py.File("two/clusters.h5", "r"), h5py.File("twosplit/clusters.h5", "r")
names = lambda f: (lambda out: (f.visit(out.append), sorted(out))[1])([])
sys.exit(0 if names(a) == names(b) and all(isinstance(a[n], h5py.Group) or (a[n].shape == b[n].shape and
         np.array_equal(a[n][()], b[n][()])) for n in names(a)) and len(a["time"]) == 5 else 1)'; then
  echo "PASS suspension/point_restart_bit_for_bit  (2 + 2 fluid steps on 2 ranks: particles.h5, clusters.h5 and the last checkpoint)"
else echo "FAIL suspension/point_restart_bit_for_bit: $(grep -m1 error split4.out)"; fi
"$python" - <<'PY'
import h5py, numpy as np
try:
    a, b = h5py.File('one/particles.h5', 'r'), h5py.File('two/particles.h5', 'r')
    # (body, row, component), from the suspension layout (rows, 3 N) or (rows, 4 N)
    get = lambda f, q: f[f'suspension/{q}'][:].reshape(len(f['time']), 20, -1).transpose(1, 0, 2)
    same = all((get(a, q)[:, 0] == get(b, q)[:, 0]).all() for q in ('position', 'quaternion'))
    v0 = get(a, 'velocity')[:, 0]
    # The random velocities have no net momentum; the fluid's at the centres (5 mm/s rms) adds some.
    masses = np.array([1.0] * 20)   # equal volumes, equal density
    fluid_added = np.abs(v0.mean(0)).max() > 1.0e-5
    print(('PASS' if same and fluid_added and len(a['time']) == 5 else 'FAIL') +
          f' suspension/same_placement_on_1_and_2_ranks  (mean start velocity {np.abs(v0.mean(0)).max():.2e} m/s)')
    rel = max(np.abs(get(a, q)[:, -1] - get(b, q)[:, -1]).max() / np.abs(get(a, q)[:, -1]).max()
              for q in ('position', 'velocity'))
    print(('PASS' if rel < 1.0e-9 else 'FAIL') + f' suspension/point_1_and_2_ranks_agree  (largest relative difference {rel:.2e})')
except Exception as error:
    print(f'FAIL suspension/same_placement_on_1_and_2_ranks: {error}')
    print(f'FAIL suspension/point_1_and_2_ranks_agree: {error}')
PY

# --- &scene substep_bodies = 'near' against every body sub-stepped (the 1-rank run above) ---
mpirun -np 1 "$AGGLO" point.nml --set "output.directory='near'" --set "scene.substep_bodies='near'" > near.out 2>&1
"$python" - "$(grep -c 'misses so far 0$' near.out)" <<'PY'
import sys, h5py, numpy as np
try:
    a, b = h5py.File('one/particles.h5', 'r'), h5py.File('near/particles.h5', 'r')
    get = lambda f, q: f[f'suspension/{q}'][:].reshape(len(f['time']), 20, -1).transpose(1, 0, 2)
    travel = np.abs(get(a, 'position')[:, -1] - get(a, 'position')[:, 0]).max()
    dx = np.abs(get(a, 'position')[:, -1] - get(b, 'position')[:, -1]).max() / travel
    dv = np.abs(get(a, 'velocity')[:, -1] - get(b, 'velocity')[:, -1]).max() / np.abs(get(a, 'velocity')[:, -1]).max()
    dq = np.abs(get(a, 'quaternion')[:, -1] - get(b, 'quaternion')[:, -1]).max()
    ok = dx < 2.0e-3 and dv < 1.0e-3 and dq < 1.0e-5 and int(sys.argv[1]) == 2
    print(('PASS' if ok else 'FAIL') + f' suspension/point_near_substeps_match_all  (after 4 fluid steps: positions '
          f'{dx:.1e} of the travel, velocities {dv:.1e}, quaternions {dq:.1e}; no miss)')
except Exception as error:
    print(f'FAIL suspension/point_near_substeps_match_all: {error}')
PY

mpirun -np 1 "$AGGLO" point.nml --set "output.directory='nearsplit'" --set "scene.substep_bodies='near'" \
  --set run.max_steps=2 > near1.out 2>&1
mpirun -np 1 "$AGGLO" point.nml --set "output.directory='nearsplit'" --set "scene.substep_bodies='near'" \
  --set run.restart=.true. > near2.out 2>&1
if h5diff -q near/particles.h5 nearsplit/particles.h5 && \
   h5diff -q near/checkpoints/checkpoint_0000000004.h5 nearsplit/checkpoints/checkpoint_0000000004.h5; then
  echo "PASS suspension/point_near_restart_bit_for_bit  (2 + 2 fluid steps: particles.h5 and the last checkpoint)"
else echo "FAIL suspension/point_near_restart_bit_for_bit: $(grep -m1 error near2.out)"; fi

# 'near' on 2 ranks: the search by stride and the one-step update by block (shared_work) give the
# 1-rank run's members (the log's sub-step lines) and, to the round-off of the field's sums over
# the slabs, its bodies; a 2 + 2-step restart on 2 ranks is bit for bit.
mpirun -np 2 "$AGGLO" point.nml --set "output.directory='neartwo'" --set "scene.substep_bodies='near'" > neartwo.out 2>&1
mpirun -np 2 "$AGGLO" point.nml --set "output.directory='neartwosplit'" --set "scene.substep_bodies='near'" \
  --set run.max_steps=2 > neartwo1.out 2>&1
mpirun -np 2 "$AGGLO" point.nml --set "output.directory='neartwosplit'" --set "scene.substep_bodies='near'" \
  --set run.restart=.true. > neartwo2.out 2>&1
"$python" - "$(grep -c 'sub-steps: ' near.out)" "$(diff <(grep -o 'sub-steps: .*' near.out) <(grep -o 'sub-steps: .*' neartwo.out) > /dev/null && echo same)" <<'PY'
import sys, h5py, numpy as np
try:
    a, b = h5py.File('near/particles.h5', 'r'), h5py.File('neartwo/particles.h5', 'r')
    get = lambda f, q: f[f'suspension/{q}'][:].reshape(len(f['time']), 20, -1).transpose(1, 0, 2)
    rel = max(np.abs(get(a, q)[:, -1] - get(b, q)[:, -1]).max() / np.abs(get(a, q)[:, -1]).max()
              for q in ('position', 'velocity'))
    ok = rel < 1.0e-9 and int(sys.argv[1]) >= 2 and sys.argv[2] == 'same' and len(b['time']) == 5
    print(('PASS' if ok else 'FAIL') + f' suspension/point_near_1_and_2_ranks_agree  (largest relative difference '
          f'{rel:.2e}; sub-step lines {"the same" if sys.argv[2] == "same" else "differ"})')
except Exception as error:
    print(f'FAIL suspension/point_near_1_and_2_ranks_agree: {error}')
PY
if h5diff -q neartwo/particles.h5 neartwosplit/particles.h5 && \
   h5diff -q neartwo/checkpoints/checkpoint_0000000004.h5 neartwosplit/checkpoints/checkpoint_0000000004.h5; then
  echo "PASS suspension/point_near_restart_bit_for_bit_on_2_ranks  (2 + 2 fluid steps: particles.h5 and the last checkpoint)"
else echo "FAIL suspension/point_near_restart_bit_for_bit_on_2_ranks: $(grep -m1 error neartwo2.out)"; fi

# --- ghost mode ---
"$AGGLO" "$deck" --set run.max_steps=4000 --set run.end_time=1.0 --set suspension.ghost=.true. \
  --set suspension.volume_fraction=0.1 --set suspension.velocity_rms=2.0e-2 --set output.particle_interval=4000 \
  --set run.progress_interval=100 --set "output.directory='ghost'" > ghost.out 2>&1
counted=$(grep -Eo 'suspension scene: 191 bodies, [0-9]+ collisions' ghost.out | grep -Eo '[0-9]+ collisions' | cut -d' ' -f1)
"$python" - "${counted:-0}" <<'PY'
import sys, h5py, numpy as np
counted = int(sys.argv[1])
f = h5py.File('ghost/particles.h5', 'r')
n, L, R, dt, steps = 191, 1.0e-3, 50.0e-6, 5.0e-7, 4000
x0 = f['suspension/position'][0].reshape(n, 3)
v = f['suspension/velocity'][:].reshape(len(f['time']), n, 3).transpose(1, 0, 2)
unchanged = (v[:, -1] == v[:, 0]).all() and len(f['time']) == 2
print(('PASS' if unchanged else 'FAIL') + ' suspension/ghost_velocities_and_momentum_unchanged')
v = v[:, 0]
i, j = np.triu_indices(n, 1)
d0 = x0[j] - x0[i]
d0 -= L * np.round(d0 / L)
dv = v[j] - v[i]
# Only pairs that can come within 2R in the run.
near = np.sqrt((d0**2).sum(1)) - 2 * R < np.sqrt((dv**2).sum(1)) * steps * dt + 1.0e-5
expected = []
t = np.arange(steps + 1) * dt
for p in np.nonzero(near)[0]:
    r = d0[p] + dv[p] * t[:, None]
    r -= L * np.round(r / L)
    dist = np.sqrt((r**2).sum(1))
    gap = dist - 2 * R
    vn = -(r * dv[p]).sum(1) / dist
    hits = (gap >= 0) & (gap < vn * dt)
    expected += [(i[p] + 1, j[p] + 1)] * int(hits.sum())
events = sorted(zip(f['events/first'][:].astype(int), f['events/second'][:].astype(int)))
ok = counted == len(expected) and events == sorted(expected) and counted > 10
print(('PASS' if ok else 'FAIL') + f' suspension/ghost_collisions_counted  ({counted} counted, {len(expected)} '
      'encounters on the straight-line trajectories)')
PY
if grep -qE 'smallest gap = -[0-9]' ghost.out; then echo "PASS suspension/ghost_bodies_pass_through"
else echo "FAIL suspension/ghost_bodies_pass_through: no negative gap logged"; fi
