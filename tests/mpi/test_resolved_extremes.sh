#!/usr/bin/env bash
# checks: 17
# The resolved pair scene at its extremes (&scene particle_coupling = 'resolved';
# docs/studies/validation.md, "Extremes"), with $AGGLO on short runs of
# one base deck (a sphere pair, r = 40 um, 32^3 in a 0.25 mm box, D/dx = 10.2, fluid at rest,
# 2 um apart, 4.2 mm/s closing, DLVO and collisions on) changed by --set. Each case either
#  - runs: exit 0, summary.json written, no NaN or infinity in particles.h5 and in
#    fluid_statistics.dat (and what the case is about, e.g. the collision it provokes), or
#  - stops: a non-zero exit with the expected message (a deck check, or a run-time stop).
# Cases: CFL at 0.9 of its limit; the fluid step at the diffusion limit (fixed, and 'cfl' with
# cfl_target = 1) and just above it (refused); a particle step of 1e-9 s, and the fluid at it;
# needles of aspect ratio 10 on the grid they need, aspect ratio 20 and a disk of 10 on a grid too
# coarse (refused, naming the grid they need); density ratios 1.0 and 0.5; contact at the start of a
# fluid step; a start inside the collision detection distance (refused); a pair crossing the
# periodic boundary and a pair crossing the rank boundary on 1 and 2 ranks (the same to 1e-9
# of each quantity's scale); a CFL above the limit and too few ghost-row sweeps near contact (run-time stops).
# EXTREMES=long (make validate) adds the needle of aspect ratio 20 at 168^3 and the disk of aspect
# ratio 10 at 180^3, a few fluid steps each.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
# This run's count (tests/run_tests.sh, "Declared checks"): the 17 declared above, and with
# EXTREMES=long the two long cases.
checks=17; [ "${EXTREMES:-}" = long ] && checks=$((checks + 2)); echo "CHECKS $checks"

cat > base.nml <<'NML'
&run name = 'extreme', seed = 5, max_steps = 6, end_time = 1.0, dt = 1.0e-5, dt_mode = 'cfl', cfl_target = 0.4,
     progress_interval = 1 /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'resolved', particle_substeps = 10,
       added_mass = .true. /
&grid nx = 32, ny = 32, nz = 32, length_x = 0.25e-3, length_y = 0.25e-3, length_z = 0.25e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'rest' /
&bodies max_sweeps = 1000 /
&pair shape = 'sphere', radius = 40.0e-6, density = 2710.0, gap = 2.0e-6, relative_speed = 4.2e-3,
      approach = 'given', approach_direction = 1.0, 0.0, 0.0, centre = 'given',
      centre_position = 0.125e-3, 0.125e-3, 0.125e-3 /
&dlvo hamaker = 22.3e-21, debye_kappa = 328947368.0, surface_charge_density = 3.7e-4, vdw_cutoff = 5.0e-9 /
&collision restitution = 0.4, detection_floor = 1.0e-9 /
&output stats_interval = 1, checkpoint_interval = 0, field_interval = 0.0 /
NML
# The explicit diffusion limit of the base grid, 1 / (4 nu (3 / dx^2)) (time_step_control).
limit=$(python3 -c "print(repr(1.0 / (4.0e-6 * 3.0 / (0.25e-3 / 32)**2)))")

# No NaN or infinity in a run's particles.h5 (every dataset) and fluid_statistics.dat.
finite() { # directory
  [ -f "$1/particles.h5" ] && [ -f "$1/fluid_statistics.dat" ] && [ -f "$1/summary.json" ] || return 1
  ! h5dump "$1/particles.h5" 2>/dev/null | grep -qiwE 'nan|-?inf' && ! grep -qiwE 'nan|-?inf' "$1/fluid_statistics.dat"
}
summary() { # directory, key
  python3 -c "import json; print(json.load(open('$1/summary.json'))['$2'])" 2>/dev/null
}
# ran name ranks overrides...: the run must end with exit 0 and finite outputs; sets $out.
ran() {
  local name=$1 ranks=$2; shift 2
  local args=() o
  for o in "$@"; do args+=(--set "$o"); done
  out=$name.out
  if mpirun -np "$ranks" "$AGGLO" base.nml --set "output.directory='$name'" "${args[@]}" > "$out" 2>&1 \
     && finite "$name"; then
    return 0
  fi
  echo "FAIL resolved_extremes/$name: exit or non-finite output: $(grep -m1 'agglo: error' "$out" | cut -c1-300)"
  return 1
}
# stopped name ranks message overrides...: non-zero exit with the message (grep -F).
stopped() {
  local name=$1 ranks=$2 message=$3; shift 3
  local args=() o
  for o in "$@"; do args+=(--set "$o"); done
  if mpirun -np "$ranks" "$AGGLO" base.nml --set "output.directory='$name'" "${args[@]}" > "$name.out" 2>&1; then
    echo "FAIL resolved_extremes/$name: the run was accepted and finished"
  elif grep -qF -- "$message" "$name.out"; then
    echo "PASS resolved_extremes/$name  (stopped: $(grep -m1 'agglo: error' "$name.out" | cut -c14-220)...)"
  else
    echo "FAIL resolved_extremes/$name: stopped without '$message': $(grep -m1 'agglo: error' "$name.out" | cut -c1-300)"
  fi
}
# Two particles.h5 agree to 1e-9 of each dataset's physical scale: its own largest magnitude, for an
# angular velocity the body's largest speed over its radius, for a torque the matching force times
# the radius (a head-on sphere pair turns and feels torques only at round-off, where a relative
# test like h5diff's compares noise); text datasets exactly. Prints the worst dataset.
agree() { # file1 file2
  python3 - "$1" "$2" <<'PY'
import re, subprocess, sys
def names(path):
    out = subprocess.run(["h5ls", "-r", path], capture_output=True, text=True).stdout
    return [l.split()[0] for l in out.splitlines() if "Dataset" in l]
def values(path, name):
    out = subprocess.run(["h5dump", "-y", "-m", "%.17e", "-d", name, path], capture_output=True, text=True).stdout
    data = out.split("DATA {", 1)[1]
    numbers = re.findall(r"-?\d\.\d+e[-+]\d+", data)
    return [float(x) for x in numbers] if numbers else data.strip()
def largest(path, name):
    return max((abs(v) for v in values(path, name)), default=0.0)
a, b = sys.argv[1:3]
if names(a) != names(b):
    print("different datasets"); sys.exit(1)
radius = values(a, "/radius")[0]
worst, where = 0.0, "-"
for name in names(a):
    x, y = values(a, name), values(b, name)
    if isinstance(x, str) or isinstance(y, str):
        if x != y: print(f"{name} differs"); sys.exit(1)
        continue
    if len(x) != len(y): print(f"{name}: {len(x)} vs {len(y)} values"); sys.exit(1)
    group, leaf = name.rsplit("/", 1)
    if leaf == "angular_velocity":
        scale = largest(a, group + "/velocity") / radius
    elif leaf.startswith("torque_"):
        scale = largest(a, group + "/force_" + leaf[len("torque_"):]) * radius
    else:
        scale = max((abs(v) for v in x), default=0.0)
    if scale == 0.0: continue
    error = max(abs(u - v) for u, v in zip(x, y)) / scale
    if error > worst: worst, where = error, name
print(f"{worst:.1e} ({where})")
sys.exit(0 if worst <= 1e-9 else 1)
PY
}
largest_cfl() { grep -v '^#' "$1/fluid_statistics.dat" | awk 'NR > 1 && $7 > m { m = $7 } END { print m + 0 }'; }

# --- the fluid step at its limits ------------------------------------------------------------------
# A random field of 0.5 m/s rms: the advective CFL sets the step (2.4e-6 s at the viscous limit
# would be CFL about 1.1), at 0.9 of &run cfl_limit = 1.
if ran cfl_at_0.9 1 "fluid.init='random'" "fluid.init_amplitude=0.5" "fluid.init_peak_wavenumber=2.0" \
       "run.cfl_target=0.9" "run.cfl_limit=1.0"; then
  cfl=$(largest_cfl cfl_at_0.9)
  if awk -v c="$cfl" 'BEGIN { exit !(c > 0.8 && c <= 1.0) }'; then
    echo "PASS resolved_extremes/cfl_at_0.9  (ran: largest CFL $cfl, limit 1)"
  else
    echo "FAIL resolved_extremes/cfl_at_0.9: largest CFL $cfl, expected in (0.8, 1]"
  fi
fi
if ran dt_at_diffusion_limit 1 "run.dt_mode='fixed'" "run.dt=$limit"; then
  echo "PASS resolved_extremes/dt_at_diffusion_limit  (ran: fixed dt = $limit s, the explicit limit)"
fi
if ran cfl_target_1 1 "run.cfl_target=1.0"; then
  dt=$(grep -v '^#' cfl_target_1/fluid_statistics.dat | awk 'NR == 2 { print $3 }')
  if python3 -c "import sys; sys.exit(0 if abs($dt / $limit - 1) < 1e-12 else 1)"; then
    echo "PASS resolved_extremes/cfl_target_1  (ran: dt = $dt s, the diffusion limit)"
  else
    echo "FAIL resolved_extremes/cfl_target_1: dt = $dt s, limit $limit s"
  fi
fi
above=$(python3 -c "print(repr(1.001 * $limit))")
stopped dt_above_diffusion_limit 1 'the stability limit of explicit diffusion on this grid' \
  "run.dt_mode='fixed'" "run.dt=$above"
# A particle step of 1e-9 s: fluid 1e-7 s, 100 sub-steps (400 particle steps); then the fluid at
# 1e-9 s itself (the paper's setting: one sub-step).
if ran particle_step_1e-9 1 "run.dt_mode='fixed'" "run.dt=1.0e-7" "scene.particle_substeps=100" "run.max_steps=4"; then
  gap=$(summary particle_step_1e-9 final_gap)
  echo "PASS resolved_extremes/particle_step_1e-9  (ran: 400 particle steps of 1e-9 s, final gap $gap m)"
fi
if ran fluid_step_1e-9 1 "run.dt_mode='fixed'" "run.dt=1.0e-9" "scene.particle_substeps=1" "run.max_steps=20"; then
  echo "PASS resolved_extremes/fluid_step_1e-9  (ran: 20 fluid steps of 1e-9 s, final gap $(summary fluid_step_1e-9 final_gap) m)"
fi
# Bodies at +-2.5 m/s with the fixed step at the diffusion limit: the fluid they move is at CFL
# about 1.6 after the first step (a random field that fast is refused by the deck checks already).
stopped cfl_above_limit 1 'exceeds &run cfl_limit' "pair.relative_speed=5.0" "pair.gap=5.0e-6" \
  "run.dt_mode='fixed'" "run.dt=$limit"

# --- shapes: aspect ratios 10 and 20 ----------------------------------------------------------------
# Needle of aspect ratio 10 at r = 20 um: 18.6 um thick, 186 um long; the minimum-image check
# (2 x 92.8 um + gap < half the box) wants a box above 0.375 mm, the immersed boundary 4 cells
# across the thickness: 88^3 in 0.4 mm, 4.1 cells.
needle10=("pair.shape='needle'" "pair.aspect_ratio=10.0" "pair.radius=20.0e-6" "grid.nx=88" "grid.ny=88" "grid.nz=88"
          "grid.length_x=0.4e-3" "grid.length_y=0.4e-3" "grid.length_z=0.4e-3" "pair.centre_position=0.2e-3,0.2e-3,0.2e-3"
          "run.max_steps=3")
if ran needle_aspect_10 1 "${needle10[@]}"; then
  echo "PASS resolved_extremes/needle_aspect_10  (ran: 88^3, 3 fluid steps)"
fi
# On 32^3 in the box each needs: refused by the immersed boundary, naming the grid.
stopped needle_aspect_20_coarse 1 'cells thin on this grid) is not allowed; allowed: a body at least 4 cells thick for the immersed boundary: &grid nx = ny = nz >= 163' "pair.shape='needle'" "pair.aspect_ratio=20.0" \
  "pair.radius=20.0e-6" "grid.length_x=0.6e-3" "grid.length_y=0.6e-3" "grid.length_z=0.6e-3" \
  "pair.centre_position=0.3e-3,0.3e-3,0.3e-3"
stopped disk_aspect_10_coarse 1 '(disk 0.73 cells thin on this grid) is not allowed; allowed: a body at least 4 cells thick for the immersed boundary: &grid nx = ny = nz >= 177' "pair.shape='disk'" "pair.aspect_ratio=10.0" \
  "pair.radius=20.0e-6" "grid.length_x=0.38e-3" "grid.length_y=0.38e-3" "grid.length_z=0.38e-3" \
  "pair.centre_position=0.19e-3,0.19e-3,0.19e-3"

# --- density ratios ---------------------------------------------------------------------------------
for ratio in 1.0 0.5; do
  if ran density_ratio_$ratio 1 "pair.density=$(python3 -c "print(997.0 * $ratio)")" "run.max_steps=10"; then
    speed=$(summary density_ratio_$ratio final_relative_velocity)
    echo "PASS resolved_extremes/density_ratio_$ratio  (ran: 10 fluid steps, v_n $speed m/s)"
  fi
done

# --- contact ----------------------------------------------------------------------------------------
# 8 nm apart at 4.2 mm/s with a fixed fluid step of 2 us: contact within the first fluid step's
# sub-steps, the second fluid step starts with the pair touching.
if ran contact_at_step_start 1 "pair.gap=8.0e-9" "run.dt_mode='fixed'" "run.dt=2.0e-6"; then
  collisions=$(summary contact_at_step_start collisions)
  first=$(python3 -c "import json
print(json.load(open('contact_at_step_start/summary.json'))['first_collision']['time'])" 2>/dev/null)
  if [ "${collisions:-0}" -ge 1 ] && python3 -c "import sys; sys.exit(0 if 0 < $first <= 2.0e-6 else 1)" 2>/dev/null; then
    echo "PASS resolved_extremes/contact_at_step_start  (ran: first collision at $first s, in the first fluid step;" \
         "$collisions collision(s))"
  else
    echo "FAIL resolved_extremes/contact_at_step_start: collisions ${collisions:-none}, first at ${first:-none}"
  fi
fi
stopped touching_at_start 1 'the collision detection distance at the start' "pair.gap=0.5e-9"
stopped max_sweeps_near_contact 1 'raise &bodies max_sweeps' "pair.gap=0.1e-6" "bodies.max_sweeps=10"

# --- boundaries and ranks ---------------------------------------------------------------------------
# Periodic: body 1's centre 10 nm before x = 0 (wrapped to x = L - 10 nm), moving +x at 2.1 mm/s:
# it crosses the boundary in the second fluid step. Rank: approach along z, body 1's centre 10 nm
# below the slab boundary z = L/2 of 2 ranks, crossing it likewise.
periodic=("pair.centre_position=$(python3 -c "print(40.0e-6 + 1.0e-6 - 1.0e-8)"),0.125e-3,0.125e-3")
rank=("pair.approach_direction=0.0,0.0,1.0"
      "pair.centre_position=0.125e-3,0.125e-3,$(python3 -c "print(0.125e-3 + 41.0e-6 - 1.0e-8)")")
for case in periodic rank; do
  declare -n overrides=$case
  x=$([ "$case" = periodic ] && echo 1 || echo 3)
  if ran ${case}_crossing_1 1 "${overrides[@]}" && ran ${case}_crossing_2 2 "${overrides[@]}"; then
    crossed=$(h5dump -y -m '%.17e' -d /particle1/position ${case}_crossing_1/particles.h5 2>/dev/null | python3 -c "
import re, sys
v = [float(t) for t in re.findall(r'-?\d\.\d+e[-+]\d+', sys.stdin.read().split('DATA {')[1])]
c = v[$x - 1::3]
print('yes' if min(c) < 0.125e-3 < max(c) or (min(c) < 1e-6 and max(c) > 0.2e-3) else 'no')")
    if [ "$crossed" = yes ] && agree ${case}_crossing_1/particles.h5 ${case}_crossing_2/particles.h5 > ${case}_diff.txt 2>&1; then
      echo "PASS resolved_extremes/${case}_boundary_crossing_1_and_2_ranks  (ran: body 1 crossed;" \
           "1 and 2 ranks agree to $(cat ${case}_diff.txt) of each quantity's scale)"
    else
      echo "FAIL resolved_extremes/${case}_boundary_crossing_1_and_2_ranks: crossed = $crossed; $(head -c 300 ${case}_diff.txt)"
    fi
  fi
  unset -n overrides
done

# --- long cases (make validate) -----------------------------------------------------------------------
if [ "${EXTREMES:-}" = long ]; then
  # Needle of aspect ratio 20 at r = 20 um: 14.7 um thick, 295 um long; box above 0.594 mm:
  # 168^3 in 0.6 mm, 4.1 cells.
  if ran needle_aspect_20 1 "pair.shape='needle'" "pair.aspect_ratio=20.0" "pair.radius=20.0e-6" "grid.nx=168" \
         "grid.ny=168" "grid.nz=168" "grid.length_x=0.6e-3" "grid.length_y=0.6e-3" "grid.length_z=0.6e-3" \
         "pair.centre_position=0.3e-3,0.3e-3,0.3e-3" "run.max_steps=3"; then
    echo "PASS resolved_extremes/needle_aspect_20  (ran: 168^3, 3 fluid steps)"
  fi
  # Disk of aspect ratio 10 at r = 20 um: 8.6 um thick, 86 um across; the deck's minimum-image
  # bound (r 10^(2/3) for either shape) wants a box above 0.375 mm: 180^3 in 0.38 mm, 4.1 cells.
  if ran disk_aspect_10 1 "pair.shape='disk'" "pair.aspect_ratio=10.0" "pair.radius=20.0e-6" "grid.nx=180" \
         "grid.ny=180" "grid.nz=180" "grid.length_x=0.38e-3" "grid.length_y=0.38e-3" "grid.length_z=0.38e-3" \
         "pair.centre_position=0.19e-3,0.19e-3,0.19e-3" "run.max_steps=3"; then
    echo "PASS resolved_extremes/disk_aspect_10  (ran: 180^3, 3 fluid steps)"
  fi
fi
