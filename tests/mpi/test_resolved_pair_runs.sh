#!/usr/bin/env bash
# checks: 10
# Free particles resolved by the immersed boundary (&scene particle_coupling = 'resolved'), with
# $AGGLO on small decks (docs/studies/validation.md, "Free particles"):
#  - added mass: a calcite-shaped disk pair (aspect ratio 5) set moving face-on in fluid at rest,
#    one progress line per fluid step. At the density ratio 0.5 the lagged loads without the
#    stabilisation (&scene added_mass = .false.) flip the approach speed's sign every fluid step
#    with a growing amplitude (more than 10x the start speed within 20 steps: unstable), with the
#    stabilisation the speed stays below the start speed (stable). At the paper's ratio 2.72 the
#    stabilised run decays without a sign change.
#  - restart: n fluid steps, then &run restart to 2n, equals 2n steps in one go bit for bit (the
#    newest checkpoint with its fluid, forcing, particles, pair_scene and resolved_hydrodynamics
#    groups, and particles.h5; h5diff without tolerance), on 1 and on 2 ranks, for a sphere pair
#    0.1 um apart: in DLVO range (closest points warm-started) at the restart, colliding after it;
#    1 and 2 ranks agree to 1e-9.
#  - a particle less than half as dense as the fluid is refused by the deck checks, naming &pair density;
#  - &pair hydrodynamics_from = 'first_contact' in the 'stokes' scene: before the first collision
#    the pair feels no drag, so the first collision is the fluid-free scene's (to 1e-12 relative).
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

# --- added mass: the disk pair moving face-on ----------------------------------------------------
# 80^3 keeps the disk 4.2 cells thick in the smallest box the pair's minimum-image check allows.
cat > disk.nml <<'NML'
&run name = 'disk', seed = 1, end_time = 1.0, max_steps = 20, dt = 1.0e-5, dt_mode = 'cfl', cfl_target = 0.4,
     progress_interval = 1 /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'resolved', particle_substeps = 10,
       added_mass = .true., dlvo = .false. /
&grid nx = 80, ny = 80, nz = 80, length_x = 0.6514e-3, length_y = 0.6514e-3, length_z = 0.6514e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'rest' /
&pair shape = 'disk', aspect_ratio = 5.0, radius = 50.0e-6, density = 2710.0, orientation = 'given',
      axis1 = 0.0, 0.0, 1.0, angle1 = 0.0, axis2 = 0.0, 0.0, 1.0, angle2 = 0.0, approach = 'given',
      approach_direction = 1.0, 0.0, 0.0, gap = 20.0e-6, relative_speed = 0.875e-3, centre = 'given',
      centre_position = 0.3257e-3, 0.3257e-3, 0.3257e-3 /
&output stats_interval = 1, field_interval = 0.0 /
NML
# The approach speeds v_n of the progress lines, one per fluid step.
speeds() { awk '/pair: gap =/ {print $8}' "$1"; }
# largest |v_n| / start speed; number of sign changes
speed_summary() {
  speeds "$1" | python3 -c "
import sys
v = [float(x) for x in sys.stdin.read().split()]
if not v: print('nan 0'); sys.exit()
flips = sum(1 for a, b in zip(v, v[1:]) if a * b < 0)
print(max(abs(x) for x in v) / 0.875e-3, flips, len(v))"
}
mpirun -np 1 "$AGGLO" disk.nml --set "pair.density=498.5" --set "scene.added_mass=.false." \
  --set "output.directory='light_off'" > light_off.out 2>&1
read -r growth flips steps <<< "$(speed_summary light_off.out)"
if python3 -c "import sys; sys.exit(0 if float('$growth') > 10 and $flips >= 10 else 1)" \
   && grep -q 'added-mass stabilisation off' light_off.out; then
  echo "PASS resolved_pair_runs/face_on_disk_light_unstable_without_stabilisation  (max |v_n| / v_0 = $growth, $flips sign flips in $steps steps)"
else
  echo "FAIL resolved_pair_runs/face_on_disk_light_unstable_without_stabilisation: max |v_n| / v_0 = $growth, $flips flips in $steps steps $(tail -n 2 light_off.out | head -c 300)"
fi
if mpirun -np 1 "$AGGLO" disk.nml --set "pair.density=498.5" --set "output.directory='light_on'" > light_on.out 2>&1; then
  read -r growth flips steps <<< "$(speed_summary light_on.out)"
  if python3 -c "import sys; sys.exit(0 if float('$growth') < 1 and $steps == 20 else 1)"; then
    echo "PASS resolved_pair_runs/face_on_disk_light_stable_with_stabilisation  (max |v_n| / v_0 = $growth in $steps steps)"
  else
    echo "FAIL resolved_pair_runs/face_on_disk_light_stable_with_stabilisation: max |v_n| / v_0 = $growth, $steps steps"
  fi
else
  echo "FAIL resolved_pair_runs/face_on_disk_light_stable_with_stabilisation: the run failed: $(tail -n 2 light_on.out | head -c 300)"
fi
if mpirun -np 1 "$AGGLO" disk.nml --set "output.directory='calcite_on'" > calcite_on.out 2>&1; then
  read -r growth flips steps <<< "$(speed_summary calcite_on.out)"
  if python3 -c "import sys; sys.exit(0 if float('$growth') < 1 and $flips == 0 and $steps == 20 else 1)"; then
    echo "PASS resolved_pair_runs/face_on_disk_calcite_stable  (max |v_n| / v_0 = $growth, no sign change in $steps steps)"
  else
    echo "FAIL resolved_pair_runs/face_on_disk_calcite_stable: max |v_n| / v_0 = $growth, $flips flips in $steps steps"
  fi
else
  echo "FAIL resolved_pair_runs/face_on_disk_calcite_stable: the run failed: $(tail -n 2 calcite_on.out | head -c 300)"
fi

if mpirun -np 1 "$AGGLO" disk.nml --set "pair.density=400.0" --set "output.directory='too_light'" > too_light.out 2>&1; then
  echo "FAIL resolved_pair_runs/too_light_refused: the run was accepted"
elif grep -q "&pair density = 4.00000E+02 is not allowed; allowed: >= 0.5 x &fluid density" too_light.out \
     && [ ! -d too_light ]; then
  echo "PASS resolved_pair_runs/too_light_refused  ($(grep -o 'allowed: >= 0.5 x &fluid density = [^ ]*' too_light.out))"
else
  echo "FAIL resolved_pair_runs/too_light_refused: $(grep -m1 'agglo: error' too_light.out | cut -c1-200)"
fi

# --- restart and ranks: a sphere pair in a forced box ------------------------------------------------
pair_deck() { # directory, max_steps, restart, &scene added_mass_history
  cat <<NML
&run name = 'spheres', seed = 5, max_steps = $2, restart = $3, end_time = 1.0, dt = 1.0e-5, dt_mode = 'cfl',
     cfl_target = 0.4, progress_interval = 1000 /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'resolved', particle_substeps = 10,
       forcing = 'eswaran_pope', added_mass = .true., added_mass_history = ${4:-.false.} /
&grid nx = 32, ny = 32, nz = 32, length_x = 0.25e-3, length_y = 0.25e-3, length_z = 0.25e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'random', init_amplitude = 0.002, init_peak_wavenumber = 2.0 /
&forcing time_scale = 0.01, target_dissipation = 1.0e-5, statistics_interval = 0 /
&bodies max_sweeps = 1000 /
&pair shape = 'sphere', radius = 40.0e-6, density = 2710.0, gap = 0.1e-6, relative_speed = 4.2e-3,
      approach = 'given', approach_direction = 1.0, 0.2, 0.6, centre = 'given',
      centre_position = 0.125e-3, 0.125e-3, 0.126e-3, relative_to_fluid = .true. /
&dlvo hamaker = 22.3e-21, debye_kappa = 328947368.0, surface_charge_density = 3.7e-4, vdw_cutoff = 5.0e-9 /
&collision restitution = 0.4, detection_floor = 1.0e-9 /
&output directory = '$1', stats_interval = 5, checkpoint_interval = 3, checkpoints_kept = 5, field_interval = 0.0 /
NML
}
newest() { ls "$1"/checkpoints/checkpoint_*.h5 | sort | tail -n 1; }
# 1h: one rank with the stabilisation's history estimate (its start and memory are in the checkpoint;
# the restart only, the estimate's start term is meant for fluid at rest).
for case in 1 2 1h; do
  ranks=${case%h}; history=.false.; [ "$case" = 1h ] && history=.true.
  label=""; [ "$case" = 1h ] && label=_added_mass_history
  pair_deck whole$case 16 .false. $history > whole$case.nml
  pair_deck split$case 8 .false. $history > split${case}a.nml
  pair_deck split$case 16 .true. $history > split${case}b.nml
  if mpirun -np $ranks "$AGGLO" whole$case.nml > whole$case.out 2>&1 \
     && mpirun -np $ranks "$AGGLO" split${case}a.nml > split${case}a.out 2>&1 \
     && mpirun -np $ranks "$AGGLO" split${case}b.nml > split${case}b.out 2>&1; then
    if [ "$(basename "$(newest whole$case)")" = "$(basename "$(newest split$case)")" ] \
       && h5diff -q "$(newest whole$case)" "$(newest split$case)" > diff$case.txt 2>&1 \
       && h5diff -q whole$case/particles.h5 split$case/particles.h5 >> diff$case.txt 2>&1 \
       && grep -q 'continuing from' split${case}b.out \
       && python3 -c "import json, sys; sys.exit(0 if json.load(open('whole$case/summary.json'))['collisions'] > 0 else 1)"; then
      echo "PASS resolved_pair_runs/restart_bit_for_bit_${ranks}_ranks$label  (8 + restart + 8 = 16 fluid steps, in DLVO range at the restart, collision after it; checkpoint and particles.h5)"
    else
      echo "FAIL resolved_pair_runs/restart_bit_for_bit_${ranks}_ranks$label: $(head -c 300 diff$case.txt)"
    fi
  else
    echo "FAIL resolved_pair_runs/restart_bit_for_bit_${ranks}_ranks$label: a run failed: $(tail -n 3 whole$case.out split${case}a.out split${case}b.out | head -c 400)"
  fi
done
# The fidelity written in full (summary.json and particles.h5 name it; batches are grouped by it).
if [ -f whole1/summary.json ] && grep -q '"fluid": "resolved_resolved"' whole1/summary.json \
   && h5dump -d /fluid whole1/particles.h5 2>/dev/null | grep -q '"resolved_resolved"'; then
  echo "PASS resolved_pair_runs/fidelity_named_in_outputs  (fluid = resolved_resolved)"
else
  echo "FAIL resolved_pair_runs/fidelity_named_in_outputs: $(grep -o '"fluid": "[^"]*"' whole1/summary.json 2>/dev/null)"
fi
if [ -f whole1/particles.h5 ] && [ -f whole2/particles.h5 ] \
   && h5diff -q --relative=1e-9 whole1/particles.h5 whole2/particles.h5 > ranks.txt 2>&1; then
  echo "PASS resolved_pair_runs/one_and_two_ranks_agree  (particles.h5 to 1e-9 relative)"
else
  echo "FAIL resolved_pair_runs/one_and_two_ranks_agree: $(head -c 300 ranks.txt 2>/dev/null)"
fi

# --- hydrodynamics_from = 'first_contact' in the 'stokes' scene --------------------------------------
pair="&pair shape = 'needle', radius = 50.0e-6, density = 2710.0, gap = 1.0e-6, relative_speed = 0.875e-3,
      approach = 'given', approach_direction = 1.0, 0.3, -0.2 /
&dlvo hamaker = 22.3e-21, debye_kappa = 328947368.0, surface_charge_density = 3.7e-4, vdw_cutoff = 5.0e-9 /
&collision restitution = 0.4, detection_floor = 1.0e-9 /
&output stats_interval = 1000 /"
for fluid in none stokes; do
  cat > $fluid.nml <<NML
&run name = '$fluid', seed = 3, end_time = 0.02, dt = 2.0e-7, progress_interval = 1000000 /
&scene fluid = '$fluid', particles = 'pair' /
$pair
NML
done
if mpirun -np 1 "$AGGLO" none.nml > none.out 2>&1 \
   && mpirun -np 1 "$AGGLO" stokes.nml --set "pair.hydrodynamics_from='first_contact'" > stokes.out 2>&1; then
  result=$(python3 - output/none/summary.json output/stokes/summary.json <<'PY'
import json, sys
a, b = (json.load(open(p))["first_collision"] for p in sys.argv[1:3])
if a is None or b is None:
    print("no first collision")
else:
    bad = [k for k in ("time", "normal_velocity_before") if abs(a[k] - b[k]) > 1e-12 * abs(a[k])]
    print("; ".join(f"{k} {a[k]!r} vs {b[k]!r}" for k in bad) or "ok %.6e s" % a["time"])
PY
)
  if [[ $result == ok* ]]; then
    echo "PASS resolved_pair_runs/stokes_first_contact_equals_fluid_free_approach  (first collision at ${result#ok })"
  else
    echo "FAIL resolved_pair_runs/stokes_first_contact_equals_fluid_free_approach: $result"
  fi
else
  echo "FAIL resolved_pair_runs/stokes_first_contact_equals_fluid_free_approach: a run failed: $(tail -n 2 none.out stokes.out | head -c 400)"
fi
