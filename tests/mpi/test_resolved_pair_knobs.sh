#!/usr/bin/env bash
# checks: 7
# The speed-accuracy knobs of the resolved pair scene (&scene particle_coupling = 'resolved'; issue
# "the studies", section 3), each in a short free-pair run with $AGGLO (docs/studies/validation.md,
# "Crank-Nicolson with free particles" and "Knobs of the resolved pair scene"):
#  - &fluid viscous_scheme = 'crank_nicolson' with free particles: a sphere pair in a forced box at
#    5x the explicit-diffusion bound, 5 um apart; n fluid steps, then &run restart to 2n, equals 2n steps in one
#    go bit for bit (the newest checkpoint, with the history estimate of resolved_hydrodynamics, and
#    particles.h5; h5diff without tolerance), on 1 and on 2 ranks; 1 and 2 ranks agree to 1e-6 (the
#    hypre solve stops at a relative residual of 1e-8, so the ranks' sums differ at that level);
#  - &bodies geometry = 'mesh' at mesh_level 1, 2, 3 (80, 320, 1280 faces): the first fluid step's
#    force on each sphere approaches the analytic geometry's as the level rises (measured 16%, 4%,
#    1.1% at most), level 3 within 2%;
#  - &bodies load_method = 'surface' (the face sum): finite, within 15% of the momentum-balance
#    force in the first two fluid steps (the start: the bodies' velocities are injected; measured
#    10.6%) and within 5% over steps 3 to 8 (measured 3.1%);
#  - &scene ibm_coupling = 'explicit': finite, within 5% of the implicit coupling's force after 8
#    fluid steps (measured 2%);
#  - &scene particle_substeps for a particle step of 2e-7 s and of 2e-6 s (fluid step 4e-6 s), the
#    pair 0.1 um apart: one collision each, the first collision's normal velocity within 5%
#    (measured 2.2%: the coarse step detects it one particle step earlier) and its angles theta,
#    phi, psi within 1e-3 rad (measured 2e-4).
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

# A sphere pair (D/dx = 10) in a forced 32^3 box; the explicit-diffusion bound is
# dx^2 / (12 nu) = 5.086e-6 s.
pair_deck() { # directory, max_steps, restart
  cat <<NML
&run name = 'spheres', seed = 5, max_steps = $2, restart = $3, end_time = 1.0, dt = 1.0e-5, dt_mode = 'cfl',
     cfl_target = 0.4, progress_interval = 1 /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'resolved', particle_substeps = 10,
       forcing = 'eswaran_pope', added_mass = .true. /
&grid nx = 32, ny = 32, nz = 32, length_x = 0.25e-3, length_y = 0.25e-3, length_z = 0.25e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'random', init_amplitude = 0.002, init_peak_wavenumber = 2.0 /
&forcing time_scale = 0.01, target_dissipation = 1.0e-5, statistics_interval = 0 /
&bodies max_sweeps = 1000 /
&pair shape = 'sphere', radius = 40.0e-6, density = 2710.0, gap = 0.1e-6, relative_speed = 4.2e-3,
      approach = 'given', approach_direction = 1.0, 0.2, 0.6, centre = 'given',
      centre_position = 0.125e-3, 0.125e-3, 0.126e-3, relative_to_fluid = .true. /
&dlvo hamaker = 22.3e-21, debye_kappa = 328947368.0, surface_charge_density = 3.7e-4, vdw_cutoff = 5.0e-9 /
&collision restitution = 0.4, detection_floor = 1.0e-9 /
&output directory = '$1', stats_interval = 5, checkpoint_interval = 2, checkpoints_kept = 5, field_interval = 0.0 /
NML
}
cn=(--set "fluid.viscous_scheme='crank_nicolson'" --set "run.dt_mode='fixed'" --set "run.dt=2.5e-5" --set "pair.gap=5.0e-6")

# --- Crank-Nicolson: restart bit for bit, 1 and 2 ranks ---------------------------------------------
newest() { ls "$1"/checkpoints/checkpoint_*.h5 | sort | tail -n 1; }
for ranks in 1 2; do
  pair_deck whole$ranks 8 .false. > whole$ranks.nml
  pair_deck split$ranks 4 .false. > split${ranks}a.nml
  pair_deck split$ranks 8 .true. > split${ranks}b.nml
  if mpirun -np $ranks "$AGGLO" whole$ranks.nml "${cn[@]}" > whole$ranks.out 2>&1 \
     && mpirun -np $ranks "$AGGLO" split${ranks}a.nml "${cn[@]}" > split${ranks}a.out 2>&1 \
     && mpirun -np $ranks "$AGGLO" split${ranks}b.nml "${cn[@]}" > split${ranks}b.out 2>&1; then
    if [ "$(basename "$(newest whole$ranks)")" = "$(basename "$(newest split$ranks)")" ] \
       && h5diff -q "$(newest whole$ranks)" "$(newest split$ranks)" > diff$ranks.txt 2>&1 \
       && h5diff -q whole$ranks/particles.h5 split$ranks/particles.h5 >> diff$ranks.txt 2>&1 \
       && grep -q 'continuing from' split${ranks}b.out \
       && [ "$(basename "$(newest whole$ranks)")" = checkpoint_0000000008.h5 ]; then
      echo "PASS resolved_pair_knobs/crank_nicolson_restart_bit_for_bit_${ranks}_ranks  (4 + restart + 4 fluid steps at 5x the explicit-diffusion bound; checkpoint and particles.h5)"
    else
      echo "FAIL resolved_pair_knobs/crank_nicolson_restart_bit_for_bit_${ranks}_ranks: $(head -c 300 diff$ranks.txt)"
    fi
  else
    echo "FAIL resolved_pair_knobs/crank_nicolson_restart_bit_for_bit_${ranks}_ranks: a run failed: $(tail -n 3 ./*$ranks*.out | head -c 400)"
  fi
done
if [ -f whole1/particles.h5 ] && [ -f whole2/particles.h5 ] \
   && h5diff -q --relative=1e-6 whole1/particles.h5 whole2/particles.h5 > ranks.txt 2>&1; then
  echo "PASS resolved_pair_knobs/crank_nicolson_one_and_two_ranks_agree  (particles.h5 to 1e-6 relative)"
else
  echo "FAIL resolved_pair_knobs/crank_nicolson_one_and_two_ranks_agree: $(head -c 300 ranks.txt 2>/dev/null)"
fi

# --- the knobs: 8 fluid steps each, the pair 5 um apart ---------------------------------------------
pair_deck base 8 .false. > knob.nml
run_knob() { # name, --set arguments...
  local name=$1; shift
  local args=()
  for s in "$@"; do args+=(--set "$s"); done
  mpirun -np 1 "$AGGLO" knob.nml --set "pair.gap=5.0e-6" --set "output.checkpoint_interval=0" \
    --set "output.directory='$name'" "${args[@]}" > "$name.out" 2>&1
}
# The |F| of each body at each fluid step: lines "step body |F|".
forces() { awk '/immersed boundary: sweeps/ {n++; for (i = 1; i <= NF; i++) if ($i == "=") {print n, 1, $(i+1); print n, 2, $(i+2)}}' "$1"; }
# Largest relative difference |F_a - F_b| / |F_b| over the given steps (all finite, same count) or "nan".
largest_difference() { # a.out b.out first_step last_step
  python3 - "$@" <<'PY'
import math, subprocess, sys
def load(path):
    rows = {}
    for line in open(path):
        if 'immersed boundary: sweeps' in line:
            words = line.split()
            k = words.index('=')
            rows[len(rows) + 1] = [float(words[k + 1]), float(words[k + 2])]
    return rows
a, b = load(sys.argv[1]), load(sys.argv[2])
first, last = int(sys.argv[3]), int(sys.argv[4])
try:
    values = [abs(a[s][i] - b[s][i]) / abs(b[s][i]) for s in range(first, last + 1) for i in range(2)]
    finite = all(math.isfinite(x) for s in range(first, last + 1) for x in a[s] + b[s])
    print(max(values) if finite else 'nan')
except (KeyError, ZeroDivisionError):
    print('nan')
PY
}
below() { python3 -c "import math, sys; x = float('$1'); sys.exit(0 if math.isfinite(x) and x < $2 else 1)"; }

run_knob analytic; ok_base=$?
# One fluid step is all the comparison needs (the finest mesh costs some 6x the analytic step).
run_knob mesh1 "bodies.geometry='mesh'" "bodies.mesh_level=1" "run.max_steps=1"
run_knob mesh2 "bodies.geometry='mesh'" "bodies.mesh_level=2" "run.max_steps=1"
run_knob mesh3 "bodies.geometry='mesh'" "bodies.mesh_level=3" "run.max_steps=1"
e1=$(largest_difference mesh1.out analytic.out 1 1)
e2=$(largest_difference mesh2.out analytic.out 1 1)
e3=$(largest_difference mesh3.out analytic.out 1 1)
if [ $ok_base -eq 0 ] && below "$e3" 0.02 && python3 -c "import sys; sys.exit(0 if $e3 < $e2 < $e1 else 1)" 2>/dev/null; then
  echo "PASS resolved_pair_knobs/mesh_geometry_converges_to_analytic  (first-step force vs analytic: 80 faces $e1, 320 $e2, 1280 $e3)"
else
  echo "FAIL resolved_pair_knobs/mesh_geometry_converges_to_analytic: 80 faces $e1, 320 $e2, 1280 $e3 $(grep -h -m1 'agglo: error' analytic.out mesh*.out | head -c 300)"
fi

run_knob surface "bodies.load_method='surface'"
start=$(largest_difference surface.out analytic.out 1 2)
later=$(largest_difference surface.out analytic.out 3 8)
if below "$start" 0.15 && below "$later" 0.05 && grep -q 'resolved pair scene: outcome' surface.out; then
  echo "PASS resolved_pair_knobs/surface_loads_close_to_momentum  (largest |F_surface - F_momentum| / |F_momentum|: steps 1-2 $start, steps 3-8 $later)"
else
  echo "FAIL resolved_pair_knobs/surface_loads_close_to_momentum: steps 1-2 $start, 3-8 $later $(grep -m1 'agglo: error' surface.out | head -c 300)"
fi

run_knob explicit_coupling "scene.ibm_coupling='explicit'"
d=$(largest_difference explicit_coupling.out analytic.out 8 8)
if below "$d" 0.05 && grep -q 'resolved pair scene: outcome' explicit_coupling.out; then
  echo "PASS resolved_pair_knobs/explicit_coupling_close_to_implicit  (|F| after 8 steps differs by $d)"
else
  echo "FAIL resolved_pair_knobs/explicit_coupling_close_to_implicit: $d $(grep -m1 'agglo: error' explicit_coupling.out | head -c 300)"
fi

# The first collision (summary.json) of the pair 0.1 um apart, colliding in the third fluid step.
run_knob substep_fine "run.dt_mode='fixed'" "run.dt=4.0e-6" "scene.particle_substeps=20" "pair.gap=0.1e-6"
run_knob substep_coarse "run.dt_mode='fixed'" "run.dt=4.0e-6" "scene.particle_substeps=2" "pair.gap=0.1e-6"
if result=$(python3 - <<'PY' 2>&1
import json, math, sys
fine, coarse = (json.load(open(d + '/summary.json')) for d in ('substep_fine', 'substep_coarse'))
a, b = fine['first_collision'], coarse['first_collision']
assert fine['collisions'] == coarse['collisions'] == 1, 'collisions %s %s' % (fine['collisions'], coarse['collisions'])
speed = abs(a['normal_velocity_before'] - b['normal_velocity_before']) / abs(a['normal_velocity_before'])
angles = max(abs(a[k] - b[k]) for k in ('theta1', 'phi1', 'theta2', 'phi2', 'psi'))
print('first-collision v_n %.4e and %.4e m/s (%.3f), angles within %.1e rad' % (
    a['normal_velocity_before'], b['normal_velocity_before'], speed, angles))
sys.exit(0 if speed < 0.05 and angles < 1.0e-3 else 1)
PY
); then
  echo "PASS resolved_pair_knobs/particle_substep_2e-7_vs_2e-6  ($result)"
else
  echo "FAIL resolved_pair_knobs/particle_substep_2e-7_vs_2e-6: $result $(grep -h -m1 'agglo: error' substep_*.out | head -c 300)"
fi
