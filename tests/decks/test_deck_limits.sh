#!/usr/bin/env bash
# Decks that ran for ever or changed the case without a word, and the limits that refuse them
# (docs/decks.md, &run dt, &pair centre_position, &bodies centre, &fluid init_file):
#  - a step count to end_time beyond max(&run max_steps, 1e9) (dt = 1e-300 s ran until max_steps,
#    10^9 steps); the limit itself, and a smaller max_steps set on purpose, are accepted, and a
#    pair scene stopped by max_steps before its end time says so in its log;
#  - a pair centre or a body centre outside the periodic box (it was wrapped), a body of a body
#    file too (free bodies); a pair centre of a scene without a box is not bounded; a body file the
#    scene does not use is not opened;
#  - a field file that does not say its box size: refused with the command that adds it, and that
#    command makes the file usable (the run starts from the file's own field).
# Refusals: non-zero exit and the message naming the group, the variable, the value and the range.
# checks: 23
set -u
AGGLO=${AGGLO:?AGGLO must point to the built executable}
here=$(cd "$(dirname "$0")" && pwd)
. "$here/deck_error_lib.sh"
add_box_size=$here/../../tools/add-box-size
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
expect_error() { expect_deck_error "$1" 1 "$2" "${@:3}"; }
# accepted NAME DECK_TEXT: the deck passes every check (--print-deck checks it and runs nothing).
accepted() {
  printf '%s\n' "$2" > "$1.nml"
  if "$AGGLO" "$1.nml" --print-deck > "$1.out" 2>&1; then echo "PASS $1  (accepted)"
  else echo "FAIL $1: refused: $(grep -m1 'agglo: error' "$1.out" | cut -c1-300)"; fi
}

fluid="&scene fluid = 'resolved' /
&grid nx = 8, ny = 8, nz = 8 /"
pair="&scene fluid = 'none', particles = 'pair' /"

# --- Steps to end_time ----------------------------------------------------------------------------
# The deck of the report: a resolved fluid with dt = 1e-300 s as the largest CFL step.
expect_error cfl_dt_1e-300 "&run name = 'f', dt = 1.0e-300, dt_mode = 'cfl' /
$fluid" '&run dt = 1.00000E-300 is not allowed' 'reaches end_time = 1.00000E-03 s within 1000000000 steps' \
  'end_time / dt = 1.00000E+297 steps at least (with dt_mode = '"'cfl'"' dt is the largest step)'
# A fixed dt in a pair scene: 1e10 steps of 1e-12 s to end_time = 1e-2 s.
expect_error pair_fixed_dt_1e10_steps "&run name = 'p', dt = 1.0e-12, end_time = 1.0e-2 /
$pair" '&run dt = 1.00000E-12' 'within 1000000000 steps, max(max_steps, 1e9); end_time / dt = 1.00000E+10 steps'
# A larger max_steps raises the limit: 2e9 allows 1.5e9 steps, not 3e9.
expect_error steps_above_max_steps "&run name = 'p', dt = 1.0e-12, end_time = 3.0e-3, max_steps = 2000000000 /
$pair" '&run dt = 1.00000E-12' 'within 2000000000 steps' 'end_time / dt = 3.00000E+09 steps'
accepted steps_within_max_steps "&run name = 'p', dt = 1.0e-12, end_time = 1.5e-3, max_steps = 2000000000 /
$pair"
# The limit itself (end_time / dt = 1e9 up to round-off), and a run stopped by max_steps on purpose.
accepted steps_at_limit "&run name = 'p', dt = 1.0e-9, end_time = 1.0 /
$pair"
accepted max_steps_stops_first "&run name = 'f', dt = 1.0e-8, end_time = 1.0, max_steps = 5 /
$fluid"

# A pair scene stopped by max_steps before its end time runs (the limit is 1e9 steps) and says so.
printf '%s\n' "&run name = 'cut', dt = 1.0e-7, end_time = 1.0e-2, max_steps = 50, progress_interval = 20 /" \
  "&scene fluid = 'stokes', particles = 'pair' /" "&output directory = 'cut' /" > cut.nml
if "$AGGLO" cut.nml > cut.out 2>&1 \
   && grep -q 'pair scene: stopped by &run max_steps = 50 at t = 5.00000E-06 s, before the end time 1.00000E-02 s' cut.out \
   && grep -q '"steps": 50,' cut/summary.json; then
  echo "PASS pair_scene_stopped_by_max_steps_says_so  ($(grep -m1 'stopped by' cut.out))"
else
  echo "FAIL pair_scene_stopped_by_max_steps_says_so: $(grep -m1 -e 'agglo: error' -e 'stopped by' cut.out)"
fi

# --- Positions in the periodic box --------------------------------------------------------------
resolved_pair="&run name = 'rp', dt = 1.0e-6, end_time = 1.0e-5 /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'point' /
&grid nx = 8, ny = 8, nz = 8, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 0.8e-3 /"
expect_error pair_centre_beyond_box "$resolved_pair
&pair centre = 'given', centre_position = 1.5e-3, 0.5e-3, 0.4e-3 /" \
  '&pair centre_position = 1.50000E-03, 5.00000E-04, 4.00000E-04 is not allowed' \
  '0 <= x <= length_x = 1.00000E-03 m, 0 <= y <= length_y = 1.00000E-03 m, 0 <= z <= length_z = 8.00000E-04 m' \
  'x = 1.50000E-03 m is outside; a position outside is not wrapped'
expect_error pair_centre_below_zero "$resolved_pair
&pair centre = 'given', centre_position = 0.5e-3, 0.5e-3, -1.0e-6 /" '&pair centre_position' \
  'z = -1.00000E-06 m is outside'
accepted pair_centre_on_box_faces "$resolved_pair
&pair centre = 'given', centre_position = 1.0e-3, 0.0, 0.8e-3 /"
# A random centre is drawn in the box: the given position is not used, whatever it is.
accepted pair_random_centre_ignores_position "$resolved_pair
&pair centre = 'random', centre_position = 5.0e-3, 5.0e-3, 5.0e-3 /"
# Without a fluid there is no box: any finite centre.
accepted pair_centre_without_box "&run name = 'p', dt = 1.0e-7, end_time = 1.0e-6 /
$pair
&pair centre = 'given', centre_position = 5.0e-3, -2.0e-3, 0.0 /"
expect_error body_centre_beyond_box "&run name = 'b', dt = 1.0e-6, end_time = 1.0e-5 /
&scene fluid = 'resolved', particles = 'prescribed' /
&grid nx = 16, ny = 16, nz = 16 /
&bodies count = 2, radius(1) = 1.6e-4, radius(2) = 1.6e-4, centre(:,1) = 0.3e-3, 0.3e-3, 0.3e-3,
  centre(:,2) = 0.7e-3, 0.7e-3, 1.2e-3 /" '&bodies centre(:, 2) = 7.00000E-04, 7.00000E-04, 1.20000E-03 is not allowed' \
  '0 <= z <= length_z = 1.00000E-03 m' 'z = 1.20000E-03 m is outside'
# Free bodies from a body file (shape, radius, aspect_ratio, centre, axis, velocity): the second
# body's x beyond the box.
printf 'sphere, 1.6e-4, 1.0, 0.3e-3, 0.3e-3, 0.3e-3, 0, 0, 0, 0, 0, 0\nsphere, 1.6e-4, 1.0, 1.3e-3, 0.7e-3, 0.7e-3, 0, 0, 0, 0, 0, 0\n' \
  > outside.csv
free_bodies="&run name = 'b', dt = 1.0e-6, end_time = 1.0e-5 /
&scene fluid = 'resolved', particles = 'free', particle_coupling = 'resolved' /
&grid nx = 16, ny = 16, nz = 16 /"
expect_error file_body_centre_beyond_box "$free_bodies
&bodies file = 'outside.csv' /" '&bodies file "outside.csv", body 2 (its centre) = 1.30000E-03, 7.00000E-04, 7.00000E-04 is not allowed' \
  'x = 1.30000E-03 m is outside'
# A body file named in a scene without bodies is neither read nor checked (it need not exist).
accepted unused_body_file_not_opened "$fluid
&run name = 'f', dt = 1.0e-6, end_time = 1.0e-5 /
&bodies file = 'no-such-file.csv' /"

# --- Bodies too thin for the immersed boundary ------------------------------------------------------
# The immersed boundary needs a body at least 4 cells thick (docs/theory.md, "Thin bodies"): the
# deck's checks refuse a thinner one before anything runs, --print-deck too (the paper's disk,
# 4.4 cells thick at 128^3 in the 1 mm box, is 3.28 at 96^3), naming the grid it needs; a body
# that is not imposed (free bodies coupled as points) has no such limit.
thin_disk="shape(1) = 'disk', radius(1) = 5.0e-5, aspect_ratio(1) = 5.0, centre(:,1) = 0.5e-3, 0.5e-3, 0.5e-3"
expect_error prescribed_thin_disk "&run name = 'b', dt = 1.0e-6, end_time = 1.0e-5 /
&scene fluid = 'resolved', particles = 'prescribed' /
&grid nx = 96, ny = 96, nz = 96 /
&bodies count = 1, $thin_disk /" \
  '&bodies radius(1) = 5.00000E-05 (disk 3.28 cells thin on this grid) is not allowed' '&grid nx = ny = nz >= 117'
extra_args=(--print-deck)
expect_error pair_thin_disk_print_deck "&run name = 'p', dt = 1.0e-6, end_time = 1.0e-5 /
&scene fluid = 'resolved', particles = 'pair' /
&grid nx = 96, ny = 96, nz = 96 /
&pair shape = 'disk', aspect_ratio = 5.0, radius = 5.0e-5 /" \
  '&pair radius = 5.00000E-05 (disk 3.28 cells thin on this grid) is not allowed' '&grid nx = ny = nz >= 117'
extra_args=()
accepted free_point_thin_disk "&run name = 'b', dt = 1.0e-6, end_time = 1.0e-5 /
&scene fluid = 'resolved', particles = 'free', particle_coupling = 'point' /
&grid nx = 96, ny = 96, nz = 96 /
&bodies count = 1, $thin_disk /"

# --- A field file that does not say its box size ------------------------------------------------
# A field written by the code in a box of 0.7 mm, its box dataset then deleted (as in a file of an
# older version): the snapshot's grid/lengths, and a checkpoint's fluid/box_length.
box="&grid nx = 8, ny = 8, nz = 8, length_x = 0.7e-3, length_y = 0.7e-3, length_z = 0.7e-3 /"
printf '%s\n' "&run name = 'source', dt = 1.0e-5, end_time = 2.0e-5 /" "&scene fluid = 'resolved' /" "$box" \
  "&fluid init = 'random', init_amplitude = 1.0e-3 /" "&output directory = 'source' /" > source.nml
"$AGGLO" source.nml > source.out 2>&1 || echo "FAIL field_without_box: the source run failed: $(tail -n 2 source.out)"
cp source/fields_0000000002.h5 snapshot.h5
cp source/checkpoints/checkpoint_0000000002.h5 checkpoint.h5
python=${AGGLO_PYTHON:-$here/../../.venv/bin/python}
"$python" -c "
import h5py
with h5py.File('snapshot.h5', 'r+') as f: del f['grid/lengths']
with h5py.File('checkpoint.h5', 'r+') as f: del f['fluid/box_length']" \
  || echo "FAIL field_without_box: could not delete the box datasets with h5py"
for kind in snapshot checkpoint; do
  dataset=$([ $kind = snapshot ] && echo grid/lengths || echo fluid/box_length)
  deck="&run name = 'from_$kind', dt = 1.0e-5, end_time = 1.0e-5, overwrite = .true. /
&scene fluid = 'resolved' /
$box
&fluid init = 'file', init_file = '$kind.h5' /
&output directory = 'from_$kind' /"
  expect_error ${kind}_without_box "$deck" "file $kind.h5 does not say its box size ($dataset is missing" \
    "add that box to the file with the repository's tools/add-box-size '$kind.h5' --box 6.99999999999999993E-004"
  # The remedy as the message gives it: the command after "tools/add-box-size", run from here.
  arguments=$(sed -n "s/.*tools\/add-box-size \(.* --box [^(]*\) (docs\/decks.md.*/\1/p" ${kind}_without_box.out)
  if [ -n "$arguments" ] && eval "\"$add_box_size\" $arguments" > ${kind}_add.out 2>&1 \
     && "$AGGLO" ${kind}_without_box.nml > ${kind}_rerun.out 2>&1; then
    # The run starts from the file's field: its step-0 kinetic energy is the source's at step 2
    # (both rows print the same stored doubles).
    source_energy=$(awk '$1 == 2 { print $4 }' source/fluid_statistics.dat)
    start_energy=$(awk '$1 == 0 { print $4 }' from_$kind/fluid_statistics.dat)
    if [ -n "$source_energy" ] && [ "$start_energy" = "$source_energy" ]; then
      echo "PASS ${kind}_box_added_by_the_named_command  ($(cat ${kind}_add.out); the run starts at k = $start_energy m2/s2)"
    else
      echo "FAIL ${kind}_box_added_by_the_named_command: start k '$start_energy', source k '$source_energy'"
    fi
  else
    echo "FAIL ${kind}_box_added_by_the_named_command: arguments '$arguments'; $(cat ${kind}_add.out 2>/dev/null);" \
         "$(grep -m1 'agglo: error' ${kind}_rerun.out 2>/dev/null | cut -c1-200)"
  fi
done
# The tool adds a missing box only: a file that says another box is left alone (exit 2, named).
"$add_box_size" snapshot.h5 --box 1.0e-3 > other_box.out 2>&1; status=$?
if [ $status -eq 2 ] && grep -q "already says its box, grid/lengths = 0.00069999999999999999" other_box.out; then
  echo "PASS tool_refuses_to_change_a_box  ($(cut -c1-120 other_box.out))"
else
  echo "FAIL tool_refuses_to_change_a_box: exit $status: $(cat other_box.out)"
fi
