#!/usr/bin/env bash
# The agglomerates of a suspension (clusters.h5; docs/outputs.md "clusters.h5", docs/theory.md
# "Agglomerates"), with $AGGLO on the smallest suspension deck (input/suspension_sphere_none.nml) made
# sticky: 191 spheres at 10% by volume with restitution 0, so every contact leaves its pair at rest
# in the DLVO well (E = U(h) < 0 <= U_b) and bonds form; 4000 steps, a row every 500:
#  - layout: every dataset of the layout with its shape, the root attributes; per row the cluster
#    sizes sum to N, the clusters and bonds are the row_start differences, mean sizes N / K and
#    sum s^2 / N, coordination 2 B / N, body/cluster numbered by smallest body;
#  - bonds checked independently from particles.h5 (same times): every bonded pair's surface gap at
#    the minimum image (centre distance - 2 r) lies in [-1 nm, h_r = 60 / kappa] and no bond is
#    counted twice; bonds > 0 at the end; formation events minus breakage events up to each row's
#    time equal the row's bonds; the collision count (one species pair) equals the contact
#    episodes of particles.h5 (its events rows) at the end;
#  - restart: 2000 steps + &run restart to 4000, and a finished run of 2300 steps (its last row not
#    on the output cadence) continued to 4000, give the 4000-step clusters.h5 and particles.h5 bit
#    for bit (same_files: the same datasets, shapes, values and attributes; h5diff -q alone passes
#    datasets of different shapes as "not comparable");
#  - 1 and 2 ranks (mpirun) write the same clusters.h5 bit for bit;
#  - fields.xdmf of a resolved suspension (point particles, 16^3, DLVO on): each body surface carries
#    its cluster as a Cell attribute, equal to clusters.h5's body/cluster at the snapshot's time.
# Prints PASS/FAIL lines; works in a temporary directory.
# checks: 6
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
root=$(cd "$(dirname "$0")/../.." && pwd)
python=${AGGLO_PYTHON:-$root/.venv/bin/python}   # h5py, numpy
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
deck=$root/input/suspension_sphere_none.nml
# Are two HDF5 files the same bit for bit: the same datasets and groups, shapes, dtypes, values
# (NaN equal to NaN) and attributes?
same_files() {
  "$python" - "$1" "$2" <<'PY'
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], 'r'), h5py.File(sys.argv[2], 'r')
names = lambda f: sorted(_walk(f))
def _walk(f):
    out = []
    f.visit(out.append)
    return out
def same(x, y):
    return x.shape == y.shape and x.dtype == y.dtype and np.array_equal(x[()], y[()], equal_nan=x.dtype.kind == 'f')
ok = names(a) == names(b) and all(
    (isinstance(a[n], h5py.Group) and isinstance(b[n], h5py.Group)) or
    (isinstance(a[n], h5py.Dataset) and isinstance(b[n], h5py.Dataset) and same(a[n], b[n])) for n in names(a))
ok &= sorted(a.attrs) == sorted(b.attrs) and all(np.array_equal(a.attrs[k], b.attrs[k]) for k in a.attrs)
sys.exit(0 if ok else 1)
PY
}
sticky=(--set run.end_time=1.0 --set output.checkpoint_interval=1000 --set output.particle_interval=500
        --set collision.restitution=0.0 --set suspension.volume_fraction=0.1)

"$AGGLO" "$deck" "${sticky[@]}" --set run.max_steps=4000 --set "output.directory='full'" > full.out 2>&1
"$python" - full <<'PY'
import sys, h5py, numpy as np
run = sys.argv[1]
try:
    c, p = h5py.File(f'{run}/clusters.h5', 'r'), h5py.File(f'{run}/particles.h5', 'r')
    N, T = 191, 9
    L, r, h_r = 1.0e-3, 50.0e-6, 60.0 / 328947368.0
    shapes = {'time': (T,), 'body/cluster': (T, N), 'body/coordination': (T, N), 'cluster/row_start': (T + 1,),
              'bond/row_start': (T + 1,), 'collisions/species_pairs': (1, 2), 'collisions/count': (T, 1),
              'collisions/volume': ()}
    for name in ('clusters', 'bonds', 'mean_size_number', 'mean_size_weight', 'largest', 'mean_coordination',
                 'percolating'):
        shapes['summary/' + name] = (T,)
    K, B, E = c['cluster/row_start'][-1], c['bond/row_start'][-1], len(c['events/time'])
    for name, shape in (('size', (K,)), ('radius_of_gyration', (K,)), ('radius_of_gyration_centres', (K,)),
                        ('gyration_eigenvalues', (K, 3)), ('centre', (K, 3)), ('percolating', (K,))):
        shapes['cluster/' + name] = shape
    shapes.update({'bond/pair': (B, 2), 'bond/psi': (B,), 'events/time': (E,), 'events/kind': (E,),
                   'events/pair': (E, 2), 'events/theta': (E, 2), 'events/phi': (E, 2),
                   'events/normal_speed': (E,), 'events/gap': (E,)})
    wrong = [f'{n} {c[n].shape if n in c else None} != {s}' for n, s in shapes.items()
             if n not in c or c[n].shape != s]
    attrs = c.attrs['bodies'] == N and np.allclose(c.attrs['box_length'], L) and \
        list(c.attrs['species_names']) == [b'sphere'] and b'U_b' in c.attrs['bond_rule']
    consistent = True
    rs, bs = c['cluster/row_start'][:], c['bond/row_start'][:]
    for t in range(T):
        sizes = c['cluster/size'][rs[t]:rs[t + 1]]
        labels = c['body/cluster'][t]
        k, b = rs[t + 1] - rs[t], bs[t + 1] - bs[t]
        first_members = [np.nonzero(labels == q + 1)[0][0] for q in range(k)]
        consistent &= sizes.sum() == N and c['summary/clusters'][t] == k and c['summary/bonds'][t] == b
        consistent &= np.isclose(c['summary/mean_size_number'][t], N / k)
        consistent &= np.isclose(c['summary/mean_size_weight'][t], (sizes.astype(float)**2).sum() / N)
        consistent &= np.isclose(c['summary/mean_coordination'][t], 2 * b / N) and c['summary/largest'][t] == sizes.max()
        consistent &= all(np.diff(first_members) > 0) and (np.bincount(labels - 1, minlength=k) == sizes).all()
    print(('PASS' if not wrong and attrs and consistent else 'FAIL') + ' clusters/layout_and_row_consistency'
          + (f': {wrong}' if wrong else '') + ('' if attrs else ': attributes') + ('' if consistent else ': rows'))
    # Independent bond check from particles.h5's positions at the same times.
    same_times = (p['time'][:] == c['time'][:]).all()
    worst, duplicate = 0.0, False
    for t in range(T):
        pairs = c['bond/pair'][bs[t]:bs[t + 1]] - 1
        duplicate |= len({tuple(q) for q in pairs}) != len(pairs) or (pairs[:, 0] >= pairs[:, 1]).any()
        if len(pairs) == 0: continue
        x = p['suspension/position'][t].reshape(N, 3)
        d = x[pairs[:, 1]] - x[pairs[:, 0]]
        d -= L * np.round(d / L)
        gaps = np.sqrt((d**2).sum(1)) - 2 * r
        worst = max(worst, np.abs(np.clip(gaps, None, -1.0e-9) + 1.0e-9).max(), np.clip(gaps - h_r, 0, None).max())
    times, kinds = c['events/time'][:], c['events/kind'][:]
    net = [((kinds == 1) & (times <= tt)).sum() - ((kinds == 2) & (times <= tt)).sum() for tt in c['time'][:]]
    episodes = len(p['events/time'])
    ok = same_times and worst == 0.0 and not duplicate and c['summary/bonds'][-1] > 0 and \
        (np.array(net) == c['summary/bonds'][:]).all() and c['collisions/count'][-1, 0] == episodes
    print(('PASS' if ok else 'FAIL') + f' clusters/bonds_in_the_well_and_events  ({c["summary/bonds"][-1]} bonds, '
          f'{E} events, {episodes} contact episodes, largest cluster {c["summary/largest"][-1]}; '
          f'gap outside [-1 nm, h_r] by {worst:.2e} m)')
except Exception as error:
    print(f'FAIL clusters/layout_and_row_consistency: {error}')
    print(f'FAIL clusters/bonds_in_the_well_and_events: {error}')
PY

# --- restarts ---
"$AGGLO" "$deck" "${sticky[@]}" --set run.max_steps=2000 --set "output.directory='split'" > split1.out 2>&1
"$AGGLO" "$deck" "${sticky[@]}" --set run.max_steps=4000 --set "output.directory='split'" --set run.restart=.true. \
  > split2.out 2>&1
if same_files full/clusters.h5 split/clusters.h5 && same_files full/particles.h5 split/particles.h5; then
  echo "PASS clusters/restart_bit_for_bit  (2000 + 2000 steps: clusters.h5 and particles.h5)"
else echo "FAIL clusters/restart_bit_for_bit: $(grep -m1 -i error split2.out)"; fi
"$AGGLO" "$deck" "${sticky[@]}" --set run.max_steps=2300 --set "output.directory='late'" > late1.out 2>&1
"$AGGLO" "$deck" "${sticky[@]}" --set run.max_steps=4000 --set "output.directory='late'" --set run.restart=.true. \
  > late2.out 2>&1
if same_files full/clusters.h5 late/clusters.h5 && same_files full/particles.h5 late/particles.h5; then
  echo "PASS clusters/finished_run_continued_bit_for_bit  (2300, off the row cadence, continued to 4000)"
else echo "FAIL clusters/finished_run_continued_bit_for_bit: $(grep -m1 -i error late2.out)"; fi

# --- 1 and 2 ranks ---
mpirun -np 2 "$AGGLO" "$deck" "${sticky[@]}" --set run.max_steps=4000 --set "output.directory='two'" > two.out 2>&1
if same_files full/clusters.h5 two/clusters.h5; then echo "PASS clusters/one_and_two_ranks_bit_for_bit"
else echo "FAIL clusters/one_and_two_ranks_bit_for_bit: $(grep -m1 -i error two.out)"; fi

# --- the clusters on the body surfaces of fields.xdmf ---
cat > point.nml <<'NML'
&run name = 'suspension_point_clusters', seed = 3, end_time = 1.0, max_steps = 4, dt = 2.0e-5, progress_interval = 2 /
&scene fluid = 'resolved', particles = 'suspension', particle_coupling = 'point', particle_substeps = 10, dlvo = .true.,
       collisions = .true. /
&grid nx = 16, ny = 16, nz = 16 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'random', init_amplitude = 5.0e-3 /
&pair density = 2710.0, radius = 20.0e-6 /
&suspension shape = 'needle', 'sphere', radius = 20.0e-6, 20.0e-6, aspect_ratio = 5.0, 1.0, count = 3, 3,
            velocity_rms = 1.0e-3 /
&output stats_interval = 10, particle_interval = 40, field_interval = 1.0 /
NML
mpirun -np 2 "$AGGLO" point.nml --set "output.directory='point'" > point.out 2>&1
"$python" - <<'PY'
import glob, h5py, numpy as np
try:
    xdmf = open('point/fields.xdmf').read()
    c = h5py.File('point/clusters.h5', 'r')
    snapshots = sorted(glob.glob('point/fields_*.h5'))
    last = snapshots[-1]
    s = h5py.File(last, 'r')
    row = list(c['time'][:]).index(s['time'][()])
    labels = [s[f'surfaces/body_{n + 1}/cluster'][:] for n in range(6)]
    ok = all((l == c['body/cluster'][row][n]).all() and len(l) == len(s[f'surfaces/body_{n + 1}/faces'])
             for n, l in enumerate(labels))
    ok &= xdmf.count('<Attribute Name="cluster" AttributeType="Scalar" Center="Cell">') == 6 * len(snapshots)
    species = list(c.attrs['species_names']) == [b'needle', b'sphere'] and c['collisions/species_pairs'].shape == (3, 2)
    print(('PASS' if ok and species else 'FAIL') + f' clusters/cluster_on_body_surfaces  ({len(snapshots)} snapshots, '
          f'clusters at the last {c["body/cluster"][row].tolist()})')
except Exception as error:
    print(f'FAIL clusters/cluster_on_body_surfaces: {error}')
PY
