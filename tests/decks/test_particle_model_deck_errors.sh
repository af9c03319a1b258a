#!/usr/bin/env bash
# checks: 30
# Bad &dlvo / &collision / &pair integrator input is rejected before anything runs, with a message
# naming the group, the variable, the value and the allowed range (docs/decks.md). Each case runs
# $AGGLO on a small fluid-free pair deck and greps the error; the defaults must pass the checks.
set -u
. "$(cd "$(dirname "$0")" && pwd)/deck_error_lib.sh"
resolved_needle="$(cd "$(dirname "$0")/../.." && pwd)/input/quiescent_needle_resolved.nml"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

base="&run name = 'p', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'none', particles = 'pair' /"

# case name, expected text (fixed string), then the deck groups after the base
expect_error() { expect_deck_error "$1" 1 "$base
$3" "$2"; }

expect_error restitution_above_one "&collision restitution = 1.50000E+00 is not allowed; allowed: [0.00000E+00, 1.00000E+00]" \
  "&collision restitution = 1.5 /"
expect_error restitution_negative "&collision restitution = -1.00000E-01 is not allowed" "&collision restitution = -0.1 /"
expect_error collision_model_unknown "&collision model = 'sticky' is not allowed; allowed: one of 'paper' | 'frictionless' | 'coulomb'" \
  "&collision model = 'sticky' /"
expect_error friction_negative "&collision friction_coefficient = -2.00000E-01 is not allowed; allowed: >= 0" \
  "&collision model = 'coulomb', friction_coefficient = -0.2 /"
expect_error detection_floor_zero "&collision detection_floor = 0.00000E+00 is not allowed; allowed: > 0" \
  "&collision detection_floor = 0.0 /"
expect_error detection_factor_negative "&collision detection_factor = -1.00000E+00 is not allowed; allowed: > 0" \
  "&collision detection_factor = -1.0 /"
expect_error max_impulse_sweeps_zero "&collision max_impulse_sweeps = 0 is not allowed; allowed: an integer >= 1" \
  "&collision max_impulse_sweeps = 0 /"
expect_error detection_floor_vs_radius "&collision detection_floor = 1.00000E-06 is not allowed; allowed: < 0.01 * &pair radius" \
  "&collision detection_floor = 1.0e-6 /"
expect_error hamaker_negative "&dlvo hamaker = -2.23000E-20 is not allowed; allowed: >= 0" "&dlvo hamaker = -22.3e-21 /"
expect_error debye_kappa_negative "&dlvo debye_kappa = -3.29000E+08 is not allowed; allowed: > 0" "&dlvo debye_kappa = -3.29e8 /"
expect_error debye_kappa_zero "&dlvo debye_kappa = 0.00000E+00 is not allowed; allowed: > 0" "&dlvo debye_kappa = 0.0 /"
expect_error theta_above_one "&dlvo theta = 1.20000E+00 is not allowed; allowed: [-1.00000E+00, 1.00000E+00]" \
  "&dlvo surface_potential_from = 'theta', theta = 1.2 /"
expect_error surface_source_unknown "&dlvo surface_potential_from = 'zeta' is not allowed" \
  "&dlvo surface_potential_from = 'zeta' /"
expect_error temperature_zero "&dlvo temperature = 0.00000E+00 is not allowed; allowed: > 0" "&dlvo temperature = 0.0 /"
expect_error permittivity_below_one "&dlvo relative_permittivity = 5.00000E-01 is not allowed" "&dlvo relative_permittivity = 0.5 /"
expect_error valence_zero "&dlvo valence = 0 is not allowed; allowed: an integer >= 1" "&dlvo valence = 0 /"
expect_error vdw_cutoff_negative "&dlvo vdw_cutoff = -5.00000E-09 is not allowed; allowed: > 0" "&dlvo vdw_cutoff = -5.0e-9 /"
expect_error vdw_cutoff_vs_radius "&dlvo vdw_cutoff = 1.00000E-06 is not allowed; allowed: < 0.01 * &pair radius" \
  "&dlvo vdw_cutoff = 1.0e-6 /"
expect_error curvature_factor_unknown "&dlvo curvature_factor = 'schiller' is not allowed; allowed: one of 'eq14' | 'derjaguin' | 'none'" \
  "&dlvo curvature_factor = 'schiller' /"
expect_error integrator_unknown "&pair integrator = 'rk4' is not allowed; allowed: one of 'euler' | 'verlet'" \
  "&pair integrator = 'rk4' /"
stokes="&run name = 'p', end_time = 1.0e-6, dt = 1.0e-7, overwrite = .true. /
&scene fluid = 'stokes', particles = 'pair' /"
expect_deck_error lubrication_without_fluid 1 "$base
&collision lubrication = .true. /" "&collision lubrication = .true. with &scene fluid = 'none' is not allowed"
expect_deck_error lubrication_roughness_zero 1 "$stokes
&collision lubrication = .true., lubrication_roughness = 0.0 /" \
  "&collision lubrication_roughness = 0.00000E+00 is not allowed; allowed: > 0"
expect_deck_error lubrication_handover_negative 1 "$stokes
&collision lubrication = .true., lubrication_handover = -1.0 /" \
  "&collision lubrication_handover = -1.00000E+00 is not allowed; allowed: > 0"
expect_deck_error lubrication_tangential_without_lubrication 1 "$stokes
&collision lubrication_tangential = .true. /" \
  "&collision lubrication_tangential = .true. with lubrication = .false. is not allowed"
expect_deck_error lubrication_roughness_vs_handover 1 "$stokes
&collision lubrication = .true., lubrication_roughness = 1.0e-4 /" \
  "&collision lubrication_roughness = 1.00000E-04 is not allowed; allowed: < the hand-over gap"
# The default hand-over (lubrication_handover = 0) follows the resolved pair's pressure scheme
# (config_collision, default_lubrication_handover; docs/studies/validation.md, "The decks' pressure scheme"):
# 0.75 cell with the decks' 'non_incremental', 0.5 cell with 'incremental' (48 cells in 0.64 mm).
extra_args=(--set collision.lubrication=.true. --set collision.lubrication_roughness=2e-5)
expect_deck_file_error handover_default_non_incremental 1 "$resolved_needle" \
  "lubrication_handover * &grid spacing = 1.00000E-05 m"
extra_args+=(--set "fluid.pressure_scheme='incremental'")
expect_deck_file_error handover_default_incremental 1 "$resolved_needle" \
  "lubrication_handover * &grid spacing = 6.66667E-06 m"
extra_args=()
# Without a resolved squeeze flow (the 'stokes' scene, point particles) the default hand-over is one
# &pair radius (50 um), whatever the grid (config_collision, default_lubrication_handover).
expect_deck_error handover_default_stokes_one_radius 1 "$stokes
&collision lubrication = .true., lubrication_roughness = 6.0e-5 /" \
  "lubrication_handover * &grid spacing = 5.00000E-05 m"
extra_args=(--set collision.lubrication=.true. --set collision.lubrication_roughness=6e-5
            --set "scene.particle_coupling='point'")
expect_deck_file_error handover_default_point_one_radius 1 "$resolved_needle" \
  "lubrication_handover * &grid spacing = 5.00000E-05 m"
extra_args=()

# The defaults (Table 1) and every option pass the checks (the run may stop later for other reasons,
# but never with a deck error from these groups).
printf '%s\n%s\n' "$base" "&dlvo curvature_factor = 'derjaguin', surface_potential_from = 'theta', theta = 0.0157 /
&collision model = 'coulomb', friction_coefficient = 0.3, restitution = 1.0 /
&pair integrator = 'verlet' /" > good.nml
"$AGGLO" good.nml > good.out 2>&1
if grep -qE "deck: &(dlvo|collision|pair) " good.out; then
  echo "FAIL good_particle_model_deck: $(grep -m1 'deck:' good.out)"
else
  echo "PASS good_particle_model_deck"
fi
