#!/usr/bin/env bash
# checks: 37
# Decks that a namelist read alone would accept while running a different case (or that crashed):
# each must stop with a non-zero exit and one message naming the group, the variable, the value and
# what is allowed, or the file, the line and what is wrong (docs/decks.md, "Errors").
set -u
AGGLO=${AGGLO:?AGGLO must point to the built executable}
. "$(cd "$(dirname "$0")" && pwd)/deck_error_lib.sh"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
expect_error() { expect_deck_error "$1" 1 "$2" "${@:3}"; }
repeat() { printf "%${2}s" '' | tr ' ' "$1"; }   # repeat CHAR COUNT

pair="&run name = 'p', end_time = 1.0e-6, dt = 1.0e-7 /
&scene fluid = 'none', particles = 'pair' /"
fluid="&run name = 'f', end_time = 1.0e-6, dt = 1.0e-7 /
&grid nx = 8, ny = 8, nz = 8 /"

# --- The text of the deck ---------------------------------------------------------------------
# An unclosed string swallowed the rest of its group (viscosity was lost, the run went ahead).
expect_error unterminated_string "$fluid
&fluid init = 'random
  viscosity = 2.0e-6 /" 'line 3 of unterminated_string.nml' 'not closed on its line'
# A line longer than 512 characters was cut; now read whole (the dt at its end is seen).
expect_error long_line_read_whole "&run name = 'a', $(repeat ' ' 600) dt = 0.0 /" '&run dt = 0.00000E+00' '> 0'
expect_error dollar_group "\$run name = 'a' \$end" 'line 1 of dollar_group.nml' '"$" groups'
expect_error ampersand_end "&run name = 'a' &end" '"&end" inside namelist group &run' 'close every group with "/"'
expect_error group_opened_inside_group "&run name = 'a'
&scene fluid = 'none', particles = 'pair' /" '"&scene" inside namelist group &run (opened on line 1)'
expect_error ampersand_without_name "& name = 'a' /" '"&" without a group name'
expect_error text_after_group "&run name = 'a' / seed = 5" 'text outside a namelist group: "seed = 5"'
expect_error text_between_groups "&run name = 'a' /
nx = 8
&scene fluid = 'none', particles = 'pair' /" 'line 2 of text_between_groups.nml' 'text outside a namelist group'
: > empty.nml
expect_deck_file_error empty_file 1 empty.nml 'empty.nml holds no namelist group'
printf '! only a comment\n\n' > comment_only.nml
expect_deck_file_error comment_only 1 comment_only.nml 'holds no namelist group'
expect_error plain_text "This is not a deck." 'text outside a namelist group: "This is not a deck."'
expect_error json '{"run": {"name": "a", "dt": 1e-7}}' 'text outside a namelist group' 'line 1 of json.nml'
printf '\x7fELF\x02\x01\x01\x00\x00\xff\xfe&\x00/\n\x01\x02' > garbage.nml
expect_deck_file_error binary_garbage 1 garbage.nml 'line 1 of garbage.nml: a control character (code 127) in column 1'

# An empty value (a namelist null value) kept the default without a word.
expect_error empty_value "$pair
&pair gap = , radius = 40.0e-6 /" 'line 3 of empty_value.nml: "gap =" has no value'
expect_error empty_value_before_next_line "&run name = 'p', end_time = 1.0e-6,
  dt =
  seed = 4 /
&scene fluid = 'none', particles = 'pair' /" 'line 2 of empty_value_before_next_line.nml: "dt =" has no value'
expect_error empty_value_at_group_end "$pair
&collision restitution = /" '"restitution =" has no value'
expect_error empty_list_element "$pair
&pair orientation = 'given', axis1 = 1.0,, 0.0 /" 'an empty value ",," in a list'

printf "&run name = 'p', dt = 1.0e-7\x00 /\n&scene fluid = 'none', particles = 'pair' /\n" > control.nml
expect_deck_file_error control_character 1 control.nml 'line 1 of control.nml: a control character (code 0)'

# --- Values longer than their variable (a namelist read cuts them silently) ----------------------
expect_error name_too_long "&run name = '$(repeat n 256)' /" '&run name' '(256 characters or more)' \
  'at most 255 characters'
expect_error directory_too_long "$pair
&output directory = '$(repeat d 4200)' /" '&output directory' 'at most 4095 characters'
expect_error init_file_too_long "$fluid
&fluid init = 'file', init_file = 'a/$(repeat f 4100).h5' /" '&fluid init_file' 'at most 4095 characters'

# --- Finite numbers only, in any real variable and any vector component --------------------------
expect_error nan_dt "&run name = 'p', dt = NaN /
&scene fluid = 'none', particles = 'pair' /" '&run dt = NaN' 'finite numbers'
expect_error plus_infinity "$pair
&pair radius = +Inf /" '&pair radius = Infinity' 'finite numbers'
expect_error minus_infinity "&run name = 'p', end_time = -Infinity /
&scene fluid = 'none', particles = 'pair' /" '&run end_time = -Infinity' 'finite numbers'
expect_error nan_axis "$pair
&pair orientation = 'given', axis1 = NaN, NaN, NaN /" '&pair axis1 = 3*NaN' 'finite numbers'
expect_error nan_component "$pair
&pair centre_position = 0.5e-3, Inf, 0.5e-3 /" '&pair centre_position' 'Infinity' 'finite numbers'
expect_error nan_in_unused_group "$pair
&forcing time_scale = NaN /" '&forcing time_scale = NaN' 'finite numbers'

# --- Upper bounds -----------------------------------------------------------------------------
expect_error needle_aspect_ratio_huge "$pair
&pair shape = 'needle', aspect_ratio = 1.0e6 /" '&pair aspect_ratio = 1.00000E+06' '<= 2.00000E+01'
expect_error disk_aspect_ratio_huge "$pair
&pair shape = 'disk', aspect_ratio = 21.0 /" '&pair aspect_ratio = 2.10000E+01' '<= 2.00000E+01'
expect_error spheroid_aspect_ratio_tiny "$pair
&pair shape = 'spheroid', aspect_ratio = 1.0e-3 /" '&pair aspect_ratio = 1.00000E-03' '[5.00000E-02, 2.00000E+01]'
expect_error peak_above_nyquist "$fluid
&fluid init = 'random', init_peak_wavenumber = 5.0 /" '&fluid init_peak_wavenumber = 5.00000E+00' \
  "<= 4.00000E+00, the grid's smallest Nyquist wavenumber"
expect_error gap_at_detection_floor "$pair
&pair gap = 1.0e-9 /" '&pair gap = 1.00000E-09' '> 1.00000E-09 m, the collision detection distance'
expect_error gap_inside_detection_distance "&run name = 'p', end_time = 1.0e-3, dt = 1.0e-4 /
&scene fluid = 'none', particles = 'pair' /
&pair gap = 5.0e-8 /" '&pair gap = 5.00000E-08' '> 8.75000E-08 m'

# --- The real conflict first, numbers in every message ------------------------------------------
expect_error forcing_in_pair_deck "&run name = 'p' /
&scene fluid = 'none', particles = 'pair', forcing = 'eswaran_pope' /" \
  "&scene forcing = 'eswaran_pope' with fluid = 'none' is not allowed"
expect_error cfl_target_above_limit "&run name = 'a', dt_mode = 'cfl', cfl_target = 0.9, cfl_limit = 0.5 /
&grid nx = 8, ny = 8, nz = 8 /" '&run cfl_target = 9.00000E-01' '<= cfl_limit = 5.00000E-01'

# --- One clean message on several ranks: printed once, no MPI_Abort banner ----------------------
printf '%s\n' "$pair" "&pair gap = 0.0 /" > two_ranks.nml
mpirun -np 2 "$AGGLO" two_ranks.nml > two_ranks.out 2>&1; status=$?
messages=$(grep -c 'agglo: error' two_ranks.out)
if [ $status -eq 0 ]; then echo "FAIL deck_error_on_two_ranks: exit status 0"
elif [ "$messages" -ne 1 ]; then echo "FAIL deck_error_on_two_ranks: $messages error lines (want 1)"
elif grep -qE 'MPI_ABORT|ORTE_ERROR_LOG' two_ranks.out; then echo "FAIL deck_error_on_two_ranks: abort banner: $(grep -m1 -E 'MPI_ABORT|ORTE' two_ranks.out)"
else echo "PASS deck_error_on_two_ranks"; fi
# With mpirun -q (Open MPI's own note on the exit status suppressed) the message is the last line.
mpirun -q -np 2 "$AGGLO" two_ranks.nml > quiet.out 2>&1; status=$?
if [ $status -ne 0 ] && tail -n 1 quiet.out | grep -q '^agglo: error: deck: &pair gap'; then echo "PASS deck_error_is_last_line"
else echo "FAIL deck_error_is_last_line: status $status, last line: $(tail -n 1 quiet.out)"; fi
