#!/usr/bin/env bash
# Free bodies of any count through the one scene loop (&scene particles = 'free', particle_coupling =
# 'resolved'; docs/decks.md, &bodies), with $AGGLO: three calcite spheres (radius 50 um, D/dx = 8)
# released towards each other at 1 mm/s from the corners of an equilateral triangle (gaps 20 um) in
# water at rest, 16 fluid steps of 5 us with 4 particle sub-steps and the added-mass stabilisation.
# The triangle lies in the plane z = L/2, the boundary between the slabs of 2 ranks: every body lies
# across the rank boundary in the 2-rank run.
#  - the run goes through the loop: particles.h5 holds 3 bodies and a sample per fluid step,
#    bodies_loads.dat a row per body per fluid step;
#  - bodies 2 and 3 are mirror images in y = L/2 (the staggered grid is symmetric about that face):
#    their velocities and positions stay mirror images (to 1e-9 of the start speed);
#  - a body released in fluid at rest is slowed by it (added mass and drag, unsteady Stokes flow,
#    Maxey & Riley 1983): each body's speed towards the centre ends in (0, 1 mm/s), and every gap
#    has closed;
#  - 2 ranks give the 1-rank positions and velocities (to 1e-9 relative);
#  - restart: 8 fluid steps + &run restart to 16 give the 16-step particles.h5 and last checkpoint
#    bit for bit (h5diff without tolerance);
#  - the same bodies from a body file (&bodies file, CSV with a comment, a blank line, a quoted
#    shape and a line with the angular velocity) give the same particles.h5 bit for bit; a line of
#    11 fields is refused naming &bodies file and the line;
#  - a body file holds more bodies than a deck's arrays (16): 20 spheres on a lattice, 2 fluid steps,
#    give 20 bodies in particles.h5 and 20 rows per step in bodies_loads.dat;
#  - free bodies without the resolved fluid are refused naming &scene particles; bodies that
#    overlap at the start stop the run on 2 ranks, naming &bodies centre and both bodies.
# Prints PASS/FAIL lines; works in a temporary directory.
# checks: 10
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # directory, max_steps, restart
  cat <<NML
&run name = 'three_spheres', seed = 1, max_steps = $2, restart = $3, end_time = 1.0, dt = 5.0e-6,
     dt_mode = 'fixed', progress_interval = 4 /
&scene fluid = 'resolved', particles = 'free', particle_coupling = 'resolved', particle_substeps = 4,
       added_mass = .true., dlvo = .false. /
&grid nx = 40, ny = 40, nz = 40, length_x = 0.5e-3, length_y = 0.5e-3, length_z = 0.5e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'rest' /
&pair density = 2710.0 /
&bodies count = 3, shape = 3*'sphere', radius = 3*50.0e-6,
        centre = 0.3192820323e-3, 0.25e-3, 0.25e-3,  0.2153589838e-3, 0.31e-3, 0.25e-3,
                 0.2153589838e-3, 0.19e-3, 0.25e-3,
        velocity = -1.0e-3, 0.0, 0.0,  0.5e-3, -0.8660254038e-3, 0.0,  0.5e-3, 0.8660254038e-3, 0.0 /
&output directory = '$1', stats_interval = 4, checkpoint_interval = 8, field_interval = 0.0 /
NML
}
# The numbers of one dataset, one per line.
dataset() { # file, dataset
  h5dump -d "$2" -y -w 0 -m %.17g "$1" | sed -n '/DATA {/,/}/p' | grep -Eo '[-+0-9.eE]+' ; }
# Every body's position and velocity samples, one file per body and quantity.
extract() { # directory
  for p in 1 2 3; do
    for q in position velocity; do dataset "$1/particles.h5" /particle$p/$q > "$1.$q$p.txt"; done
  done
}

deck one 16 .false. > one.nml
deck two 16 .false. > two.nml
deck split 8 .false. > splita.nml
deck split 16 .true. > splitb.nml

if mpirun -np 1 "$AGGLO" one.nml > one.out 2>&1; then
  extract one
  python3 - <<'PY'
import math
def samples(name):
    values = [float(x) for x in open(name)]
    return [values[3 * n:3 * n + 3] for n in range(len(values) // 3)]
x = {p: samples(f'one.position{p}.txt') for p in (1, 2, 3)}
v = {p: samples(f'one.velocity{p}.txt') for p in (1, 2, 3)}
rows = [line.split() for line in open('one/bodies_loads.dat') if not line.startswith('#')]
log = open('one.out').read()
ok = all(len(x[p]) == 17 and len(v[p]) == 17 for p in (1, 2, 3)) and len(rows) == 48 \
    and [int(r[2]) for r in rows] == [1, 2, 3] * 16 and 'free bodies scene: 3 bodies' in log
print(('PASS' if ok else 'FAIL') + ' free_bodies/three_spheres_run_through_the_loop  '
      f'({len(v[3])} samples per body, expected 17; {len(rows)} rows in bodies_loads.dat, expected 48)')
v0, half = 1.0e-3, 0.25e-3
mirror = max(max(abs(v[2][-1][0] - v[3][-1][0]), abs(v[2][-1][1] + v[3][-1][1]), abs(v[2][-1][2] - v[3][-1][2])) / v0,
             max(abs(x[2][-1][0] - x[3][-1][0]), abs((x[2][-1][1] - half) + (x[3][-1][1] - half)),
                 abs(x[2][-1][2] - x[3][-1][2])) / (v0 * 8.0e-5))
print(('PASS' if mirror <= 1e-9 else 'FAIL') + ' free_bodies/mirror_images_stay_mirror_images  '
      f'(largest difference {mirror:.2e} of the start speed (and of its distance over the run) <= 1e-9)')
centre = [sum(x[p][0][k] for p in (1, 2, 3)) / 3 for k in range(3)]
def towards(p, n):   # speed towards the start's centre
    d = [centre[k] - x[p][n][k] for k in range(3)]
    return sum(a * b for a, b in zip(d, v[p][n])) / math.sqrt(sum(a * a for a in d))
def distance(p, q, n):
    return math.dist(x[p][n], x[q][n])
speeds = [towards(p, -1) for p in (1, 2, 3)]
closed = all(distance(p, q, -1) < distance(p, q, 0) for p, q in ((1, 2), (1, 3), (2, 3)))
ok = all(0.0 < s < v0 for s in speeds) and closed
print(('PASS' if ok else 'FAIL') + ' free_bodies/released_spheres_slowed_by_the_fluid  '
      f'(speeds towards the centre {", ".join(f"{s:.4e}" for s in speeds)} m/s in (0, 1e-3); gaps closed: {closed})')
PY
else
  for name in three_spheres_run_through_the_loop mirror_images_stay_mirror_images released_spheres_slowed_by_the_fluid; do
    echo "FAIL free_bodies/$name: the 1-rank run failed: $(tail -n 3 one.out | head -c 300)"
  done
fi

if mpirun -np 2 "$AGGLO" two.nml > two.out 2>&1; then
  extract two
  worst=$(python3 - <<'PY'
worst = 0.0
for p in (1, 2, 3):
    for q, scale in (('position', 0.5e-3), ('velocity', 1.0e-3)):
        a = [float(s) for s in open(f'one.{q}{p}.txt')]
        b = [float(s) for s in open(f'two.{q}{p}.txt')]
        if len(a) != len(b) or not a:
            worst = float('inf')
            continue
        worst = max(worst, max(abs(s - t) for s, t in zip(a, b)) / scale)
print(f'{worst:.3e}')
PY
)
  if python3 -c "import sys; sys.exit(0 if float('$worst') <= 1e-9 else 1)"; then
    echo "PASS free_bodies/two_ranks_equal_one_rank  (bodies across the rank boundary; largest difference $worst <= 1e-9 of the box and the start speed)"
  else
    echo "FAIL free_bodies/two_ranks_equal_one_rank: largest difference $worst (> 1e-9)"
  fi
else
  echo "FAIL free_bodies/two_ranks_equal_one_rank: the 2-rank run failed: $(tail -n 3 two.out | head -c 300)"
fi

if mpirun -np 1 "$AGGLO" splita.nml > splita.out 2>&1 && mpirun -np 1 "$AGGLO" splitb.nml > splitb.out 2>&1 \
   && grep -q 'continuing from' splitb.out && h5diff one/particles.h5 split/particles.h5 > /dev/null 2>&1 \
   && h5diff one/checkpoints/checkpoint_0000000016.h5 split/checkpoints/checkpoint_0000000016.h5 > /dev/null 2>&1; then
  echo "PASS free_bodies/restart_bit_for_bit  (8 + restart + 8 = 16 fluid steps: particles.h5 and the last checkpoint equal)"
else
  echo "FAIL free_bodies/restart_bit_for_bit: $(tail -n 2 splitb.out | head -c 300)"
fi

cat > bodies.csv <<'CSV'
# shape, radius, aspect_ratio, x, y, z, axis_x, axis_y, axis_z, u, v, w [, omega_x, omega_y, omega_z]
sphere, 50.0e-6, 5.0, 0.3192820323e-3, 0.25e-3, 0.25e-3, 0, 0, 0, -1.0e-3, 0.0, 0.0

'sphere', 50.0e-6, 5.0, 0.2153589838e-3, 0.31e-3, 0.25e-3, 0, 0, 0, 0.5e-3, -0.8660254038e-3, 0.0
sphere, 50.0e-6, 5.0, 0.2153589838e-3, 0.19e-3, 0.25e-3, 0, 0, 0, 0.5e-3, 0.8660254038e-3, 0.0, 0, 0, 0
CSV
deck file 16 .false. | sed "s/^&bodies count = 3.*$/\&bodies file = 'bodies.csv' \//; /^        centre = /d; /^                 0.2153589838e-3, 0.19e-3/d; /^        velocity = /d" > file.nml
if mpirun -np 1 "$AGGLO" file.nml > file.out 2>&1 && grep -q "file = 'bodies.csv'" file.nml \
   && h5diff one/particles.h5 file/particles.h5 > /dev/null 2>&1; then
  echo "PASS free_bodies/body_file_gives_the_deck_bodies  (3 bodies from bodies.csv: particles.h5 equal to the deck's)"
else
  echo "FAIL free_bodies/body_file_gives_the_deck_bodies: $(tail -n 2 file.out | head -c 300)"
fi
printf 'sphere, 50.0e-6, 5.0, 0.3e-3, 0.25e-3, 0.25e-3, 0, 0, 0, -1.0e-3, 0.0, 0.0\nsphere, 50.0e-6, 5.0, 0.2e-3, 0.31e-3, 0.25e-3, 0, 0, 0, 0.5e-3, 0.0\n' > bad.csv
sed "s/bodies.csv/bad.csv/; s/directory = 'file'/directory = 'bad'/" file.nml > bad.nml
mpirun -np 1 "$AGGLO" bad.nml > bad.out 2>&1; status=$?
message=$(grep -m1 'agglo: error' bad.out)
if [ "$status" -eq 2 ] && [[ $message == *'&bodies file = "bad.csv" line 2: 11 fields is not allowed'* ]]; then
  echo "PASS free_bodies/body_file_bad_line_refused  (exit 2: ${message:0:120})"
else
  echo "FAIL free_bodies/body_file_bad_line_refused: exit $status, message '$message'"
fi

python3 - <<'PY'
third = 1.0e-3 / 3
sites = [((i + 0.5) * third, (j + 0.5) * third, (k + 0.5) * third) for i in range(3) for j in range(3) for k in range(3)]
with open('twenty.csv', 'w') as out:
    out.write('# 20 spheres at rest on a lattice\n')
    for x, y, z in sites[:20]:
        out.write(f'sphere, 70.0e-6, 1.0, {x:.6e}, {y:.6e}, {z:.6e}, 0, 0, 0, 0.0, 0.0, 0.0\n')
PY
cat > twenty.nml <<'NML'
&run name = 'twenty', max_steps = 2, end_time = 1.0, dt = 1.0e-5, dt_mode = 'fixed', progress_interval = 1 /
&scene fluid = 'resolved', particles = 'free', particle_coupling = 'resolved', particle_substeps = 2,
       added_mass = .true., dlvo = .false. /
&grid nx = 32, ny = 32, nz = 32, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'rest' /
&pair density = 2710.0 /
&bodies file = 'twenty.csv' /
&output directory = 'twenty', stats_interval = 2, field_interval = 0.0 /
NML
if mpirun -np 1 "$AGGLO" twenty.nml > twenty.out 2>&1; then
  bodies=$(dataset twenty/particles.h5 /bodies)
  rows=$(grep -vc '^#' twenty/bodies_loads.dat)
  if [ "$bodies" = 20 ] && [ "$rows" = 40 ]; then
    echo "PASS free_bodies/body_file_holds_more_than_16_bodies  (20 bodies in particles.h5, $rows rows in bodies_loads.dat for 2 steps)"
  else
    echo "FAIL free_bodies/body_file_holds_more_than_16_bodies: $bodies bodies, $rows rows (expected 20, 40)"
  fi
else
  echo "FAIL free_bodies/body_file_holds_more_than_16_bodies: the run failed: $(tail -n 3 twenty.out | head -c 300)"
fi
sed "s/fluid = 'resolved', particles = 'free', particle_coupling = 'resolved', particle_substeps = 2,/fluid = 'stokes', particles = 'free',/; /^&grid/d; s/added_mass = .true., //; s/dt_mode = 'fixed', //" twenty.nml > stokes.nml
mpirun -np 1 "$AGGLO" stokes.nml > stokes.out 2>&1; status=$?
message=$(grep -m1 'agglo: error' stokes.out)
if [ "$status" -eq 2 ] && [[ $message == *"&scene particles = 'free' with fluid = 'stokes' is not allowed"* ]]; then
  echo "PASS free_bodies/free_bodies_need_the_resolved_fluid  (exit 2: ${message:0:110})"
else
  echo "FAIL free_bodies/free_bodies_need_the_resolved_fluid: exit $status, message '$message'"
fi
sed 's/0.2153589838e-3, 0.19e-3/0.2653589838e-3, 0.29e-3/' bodies.csv > overlap.csv
sed "s/bodies.csv/overlap.csv/; s/directory = 'file'/directory = 'overlap'/" file.nml > overlap.nml
mpirun -np 2 "$AGGLO" overlap.nml > overlap.out 2>&1; status=$?
message=$(grep -m1 'agglo: error' overlap.out)
if [ "$status" -eq 2 ] && [[ $message == *'&bodies centre(:, 3) = a body overlapping body 1 (gap -'* ]] \
   && [ "$(grep -c 'agglo: error' overlap.out)" -eq 1 ]; then
  echo "PASS free_bodies/overlapping_bodies_refused_on_two_ranks  (exit 2, one message: ${message:0:100})"
else
  echo "FAIL free_bodies/overlapping_bodies_refused_on_two_ranks: exit $status, message '$message'"
fi
