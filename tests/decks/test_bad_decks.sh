#!/usr/bin/env bash
# checks: 39
# Bad decks: each must stop the run with a non-zero exit and a message that names the group,
# the variable and what is allowed (docs/design.md, "Errors"). Runs the built executable ($AGGLO).
set -u
AGGLO=${AGGLO:?AGGLO must point to the built executable}
. "$(cd "$(dirname "$0")" && pwd)/deck_error_lib.sh"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
expect_error() { expect_deck_error "$@"; }

fluid='&scene fluid = '"'"'resolved'"'"' /
&grid nx = 8, ny = 8, nz = 8 /'

if mpirun -np 1 "$AGGLO" does_not_exist.nml > missing.out 2>&1; then echo "FAIL missing_file: exit status 0"
elif grep -q 'cannot read the input deck "does_not_exist.nml"' missing.out; then echo "PASS missing_file"
else echo "FAIL missing_file: message does not name the file"; fi
expect_error unknown_variable 1 "&run name = 'a', dtt = 1.0 /" '&run' 'dtt'
expect_error group_typo 1 "&rnu name = 'a' /" 'unknown namelist group &rnu' 'known groups'
expect_error duplicate_group 1 "&run name = 'a' /
&run seed = 2 /" '&run appears more than once'
expect_error unclosed_group 1 "&run name = 'a'" 'not closed'
expect_error wrong_type 1 "&run name = 'a', seed = 'abc' /" '&run'
expect_error wrong_type_logical 1 "&run name = 'a', restart = 7 /" '&run'
expect_error nonpositive_cells 1 "&run name = 'a' /
&grid nx = 0 /" '&grid nx = 0' '>= 1'
expect_error nonpositive_length 1 "&run name = 'a' /
&grid length_x = -1.0e-3 /" '&grid length_x' '> 0'
expect_error nonpositive_dt 1 "&run name = 'a', dt = 0.0 /" '&run dt' '> 0'
expect_error nonpositive_end_time 1 "&run name = 'a', end_time = -1.0 /" '&run end_time' '> 0'
expect_error nonpositive_viscosity 1 "&run name = 'a' /
&fluid viscosity = 0.0 /" '&fluid viscosity' '> 0'
expect_error grid_not_divisible 2 "&run name = 'a' /
&grid nx = 8, ny = 8, nz = 9 /" '&grid nz = 9' 'multiple of the number of MPI ranks (2)'
expect_error unknown_scene_fluid 1 "&run name = 'a' /
&scene fluid = 'navier' /" "&scene fluid = 'navier'" "'none' | 'stokes' | 'resolved'"
expect_error unknown_dt_mode 1 "&run name = 'a', dt_mode = 'adaptive' /" "&run dt_mode = 'adaptive'" "'fixed' | 'cfl'"
expect_error unknown_init 1 "&run name = 'a' /
&fluid init = 'vortex' /" "&fluid init = 'vortex'" 'taylor_green'
touch not_a_directory
expect_error output_not_writable 1 "&run name = 'a' /
&output directory = 'not_a_directory/sub' /" '&output directory' 'not_a_directory/sub'

# An existing run is never replaced silently; overwrite = .true. replaces it; restart needs a run.
mkdir -p existing
echo "&run name = 'old' /" > existing/run.nml
expect_error existing_run_refused 1 "&run name = 'a', end_time = 1.0e-9, dt = 1.0e-9 /
$fluid
&output directory = 'existing' /" '&output directory' 'overwrite = .true.'
grep -q "name = 'old'" existing/run.nml && echo "PASS existing_run_untouched" || echo "FAIL existing_run_untouched: run.nml changed"
expect_error restart_without_run 1 "&run name = 'fresh', restart = .true. /
&output directory = 'nothing_here' /" '&run restart' 'no earlier run'

# The pair protocol (overlapping start, gap <= 0, unknown shape, aspect ratio <= 0).
pair="&run name = 'p' /
&scene fluid = 'none', particles = 'pair' /"
expect_error pair_zero_gap 1 "$pair
&pair gap = 0.0 /" '&pair gap' '> 0'
expect_error pair_overlapping_start 1 "$pair
&pair gap = -1.0e-6 /" '&pair gap' '> 0'
expect_error pair_unknown_shape 1 "$pair
&pair shape = 'cube' /" "&pair shape = 'cube'" "'sphere' | 'needle' | 'disk' | 'spheroid'"
expect_error pair_aspect_ratio_zero 1 "$pair
&pair shape = 'spheroid', aspect_ratio = 0.0 /" '&pair aspect_ratio' '> 0'
expect_error pair_needle_aspect_below_one 1 "$pair
&pair shape = 'needle', aspect_ratio = 0.5 /" '&pair aspect_ratio' "> 1 and <= 2.00000E+01 for shape = 'needle'"
expect_error pair_negative_speed 1 "$pair
&pair relative_speed = -1.0e-3 /" '&pair relative_speed' '>= 0'
expect_error pair_negative_settle_time 1 "$pair
&pair settle_time = -1.0e-3 /" '&pair settle_time' '>= 0 s'
expect_error pair_negative_paper_end_time 1 "$pair
&pair paper_end_time = -3.0e-3 /" '&pair paper_end_time' '>= 0 s (0: &run end_time)'
expect_error pair_zero_axis 1 "$pair
&pair orientation = 'given', axis1 = 0.0, 0.0, 0.0 /" '&pair axis1' 'non-zero'
expect_error pair_scene_cfl 1 "&run name = 'p', dt_mode = 'cfl' /
&scene fluid = 'none', particles = 'pair' /" "&run dt_mode = 'cfl'" "'fixed'"
expect_error pair_without_particles 1 "&run name = 'p' /
&scene fluid = 'stokes' /" '&scene particles' "'pair'"
expect_error resolved_pair_thin_body 1 "&run name = 'thin' /
&scene fluid = 'resolved', particles = 'pair' /" '&pair' 'cells thin on this grid'
expect_error resolved_pair_unknown_coupling 1 "&run name = 'p' /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'lagrange' /
&grid nx = 8, ny = 8, nz = 8 /" "&scene particle_coupling = 'lagrange'" "'point' | 'resolved'"
expect_error relative_to_fluid_without_fluid 1 "&run name = 'p' /
&scene fluid = 'stokes', particles = 'pair' /
&pair relative_to_fluid = .true. /" '&pair relative_to_fluid' 'only a resolved fluid'
expect_error added_mass_in_stokes_scene 1 "&run name = 'p' /
&scene fluid = 'stokes', particles = 'pair', added_mass = .true. /" '&scene added_mass' 'particle_coupling'
expect_error added_mass_history_with_crank_nicolson 1 "&run name = 'p' /
&scene fluid = 'resolved', particles = 'pair', added_mass = .true., added_mass_history = .true. /
&fluid viscous_scheme = 'crank_nicolson' /" '&scene added_mass_history' 'always taken'
expect_error point_pair_larger_than_box 1 "&run name = 'p' /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'point' /
&grid nx = 8, ny = 8, nz = 8, length_x = 4.0e-4, length_y = 4.0e-4, length_z = 4.0e-4 /
&pair shape = 'needle', aspect_ratio = 5.0, radius = 50.0e-6 /" '&pair radius' 'half the smallest box length'
expect_error pair_scene_restart_without_run 1 "&run name = 'p', restart = .true. /
&scene fluid = 'none', particles = 'pair' /" '&run restart' 'no earlier run'
expect_error pair_scene_substeps 1 "&run name = 'p' /
&scene fluid = 'stokes', particles = 'pair', particle_substeps = 4 /" '&scene particle_substeps' '1 (sub-steps'
