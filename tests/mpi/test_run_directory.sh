#!/usr/bin/env bash
# Run directories with $AGGLO (docs/outputs.md, "Run directory and manifest"), 2 ranks unless said:
#  - no shell sees deck text: &output directory = 'out_$(touch x)' and a name with spaces, quotes,
#    backquotes and non-ASCII letters are made literally, and no command runs;
#  - the manifest lists every file the run wrote; overwrite deletes exactly those (a stale
#    final_field.h5 of an earlier forced run included), never a user's fields_backup_mine.h5;
#  - a refused restart (changed grid) leaves run.nml as it was;
#  - after a CFL stop and a restart from the last checkpoint, the stop's field dump leaves the run and
#    fields.xdmf lists only snapshots of the continued history;
#  - &fluid init = 'file' and restart refuse a file whose box size differs from the deck's.
# Long directory paths are tested in test_long_paths.sh.
# Prints PASS/FAIL lines; works in a temporary directory.
# checks: 8
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

# deck DIRECTORY [run extras] [scene extras] [grid length] [output extras]
deck() {
  cat <<NML
&run name = 'r', max_steps = 6, end_time = 1.0, dt = 2.5e-4, dt_mode = 'fixed', progress_interval = 1000,
     seed = 5 ${2:-} /
&scene fluid = 'resolved' ${3:-} /
&grid nx = 8, ny = 8, nz = 8, length_x = ${4:-1.0e-3}, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'random', init_amplitude = 0.01,
       init_peak_wavenumber = 2.0 /
&forcing time_scale = 0.01, target_dissipation = 8.0e-3, statistics_interval = 2 /
&output directory = '$1', checkpoint_interval = 2, checkpoints_kept = 5, field_interval = 5.0e-4 ${5:-} /
NML
}
run() { mpirun -np 2 "$AGGLO" "$1" > "$1.out" 2>&1; }

# --- no shell: command substitution and special characters are taken literally -------------------
deck 'out_$(touch x)' > inject.nml
if run inject.nml && [ ! -e x ] && [ -f 'out_$(touch x)/run.nml' ] && [ -f 'out_$(touch x)/checkpoints/checkpoint_0000000006.h5' ]; then
  echo "PASS run_directory/no_shell_command_substitution  (directory 'out_\$(touch x)' made literally, no file x)"
else
  echo "FAIL run_directory/no_shell_command_substitution: x exists: $([ -e x ] && echo yes || echo no); $(ls; tail -n 2 inject.nml.out)"
fi
special='dir with "quotes" `touch y` $HOME ü'
deck "$special" > special.nml
if run special.nml && [ ! -e y ] && [ -f "$special/run.nml" ] && [ -f "$special/fields.xdmf" ]; then
  echo "PASS run_directory/special_characters_literal  (spaces, quotes, backquotes, \$, non-ASCII)"
else
  echo "FAIL run_directory/special_characters_literal: $(ls | tr '\n' '|'); $(tail -n 2 special.nml.out)"
fi

# --- manifest and overwrite --------------------------------------------------------------------
deck reuse '' ", forcing = 'eswaran_pope'" > forced.nml
if run forced.nml && [ -f reuse/final_field.h5 ]; then
  # Every file of the run directory is in the manifest (and nothing else but the manifest itself).
  listed=$(sort reuse/agglo_manifest.txt | grep -v '^checkpoints$' | tr '\n' ' ')
  present=$(cd reuse && find . -type f ! -name agglo_manifest.txt | sed 's|^\./||' | sort | tr '\n' ' ')
  if [ "$listed" = "$present" ]; then
    echo "PASS run_directory/manifest_lists_every_file  ($(wc -l < reuse/agglo_manifest.txt) entries)"
  else
    echo "FAIL run_directory/manifest_lists_every_file: manifest '$listed' vs directory '$present'"
  fi
  echo mine > reuse/fields_backup_mine.h5
  echo mine > reuse/checkpoints/notes.txt
  deck reuse ", overwrite = .true., max_steps = 2" > again.nml
  if run again.nml && [ ! -e reuse/final_field.h5 ] && [ ! -e reuse/flow_statistics.h5 ] \
     && [ -f reuse/fields_backup_mine.h5 ] && [ -f reuse/checkpoints/notes.txt ] \
     && [ "$(ls reuse/checkpoints | tr '\n' ' ')" = "checkpoint_0000000002.h5 notes.txt " ] \
     && [ "$(ls reuse/fields_00*.h5 | tr '\n' ' ')" = "reuse/fields_0000000000.h5 reuse/fields_0000000002.h5 " ]; then
    echo "PASS run_directory/overwrite_deletes_exactly_agglo_files  (final_field.h5, flow_statistics.h5, old checkpoints gone; user files kept)"
  else
    echo "FAIL run_directory/overwrite_deletes_exactly_agglo_files: $(ls -R reuse | tr '\n' ' ')"
  fi
else
  echo "FAIL run_directory/manifest_lists_every_file: the forced run failed: $(tail -n 2 forced.nml.out)"
fi

# --- a refused restart leaves run.nml as it was --------------------------------------------------
cp reuse/run.nml run.nml.before
sed -e 's/nx = 8/nx = 16/' -e 's/seed = 5/seed = 5, restart = .true., max_steps = 4/' again.nml > grid.nml
run grid.nml; status=$?
if [ $status -ne 0 ] && grep -q "holds a 8 x 8 x 8 grid, the deck's &grid is 16 x 8 x 8" grid.nml.out \
   && cmp -s run.nml.before reuse/run.nml; then
  echo "PASS run_directory/refused_restart_keeps_run_nml  (grid changed: refused, run.nml unchanged)"
else
  echo "FAIL run_directory/refused_restart_keeps_run_nml: exit $status; $(grep -m1 'agglo: error' grid.nml.out | cut -c1-200); $(diff run.nml.before reuse/run.nml | head -n 4)"
fi

# --- the box size of a file must be the deck's ---------------------------------------------------
deck box ", max_steps = 1" "" 2.0e-3 ", checkpoint_interval = 0" \
  | sed "s|init = 'random'|init = 'file', init_file = 'reuse/checkpoints/checkpoint_0000000002.h5'|" > box.nml
run box.nml; status=$?
if [ $status -ne 0 ] && grep -q "holds a box of 1.00000E-03 x 1.00000E-03 x 1.00000E-03 m, the deck's &grid length_x, length_y, length_z are 2.00000E-03 x 1.00000E-03 x 1.00000E-03 m" box.nml.out; then
  echo "PASS run_directory/init_file_box_size_checked"
else
  echo "FAIL run_directory/init_file_box_size_checked: exit $status; $(grep -m1 'agglo: error' box.nml.out | cut -c1-250)"
fi
sed -e 's/length_x = 1.0e-3/length_x = 2.0e-3/' -e 's/seed = 5/seed = 5, restart = .true., max_steps = 4/' again.nml > box2.nml
run box2.nml; status=$?
if [ $status -ne 0 ] && grep -q "holds a box of 1.00000E-03 x" box2.nml.out && cmp -s run.nml.before reuse/run.nml; then
  echo "PASS run_directory/restart_box_size_checked  (refused, run.nml unchanged)"
else
  echo "FAIL run_directory/restart_box_size_checked: exit $status; $(grep -m1 'agglo: error' box2.nml.out | cut -c1-250)"
fi

# --- CFL stop, restart: fields.xdmf follows the continued history ---------------------------------
# The forced deck of run_stops (CFL 1 after about 10 steps at dt = 2.5e-4 s), checkpoints every 4
# steps and a snapshot every step; the restart from checkpoint 8 halves dt and runs to step 14.
cat > cfl.nml <<NML
&run name = 'cfl', max_steps = 400, end_time = 1.0, dt = 2.5e-4, dt_mode = 'fixed', cfl_limit = 1.0,
     progress_interval = 1000, seed = 5 /
&scene fluid = 'resolved', forcing = 'eswaran_pope' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'rest' /
&forcing time_scale = 0.01, target_dissipation = 1.0, statistics_interval = 0 /
&output directory = 'cfl', checkpoint_interval = 4, checkpoints_kept = 5, field_interval = 0.0 /
NML
run cfl.nml
stop=$(sed -n 's/.*CFL number .* at step \([0-9]*\) (t = .*/\1/p' cfl.nml.out | head -n 1)
checkpoint=$(ls cfl/checkpoints | sort | tail -n 1 | sed 's/checkpoint_0*\([0-9]*\)\.h5/\1/')
sed -e 's/dt = 2.5e-4/dt = 1.0e-4/' -e "s/max_steps = 400/max_steps = $(( ${stop:-10} + 4 )), restart = .true./" cfl.nml > cfl2.nml
dump=fields_$(printf '%010d' "${stop:-0}").h5
if [ -n "$stop" ] && grep -q "$dump" cfl/fields.xdmf && run cfl2.nml; then
  final=fields_$(printf '%010d' $(( stop + 4 ))).h5
  if ! grep -q "$dump" cfl/fields.xdmf && [ ! -e "cfl/$dump" ] && grep -q "$final" cfl/fields.xdmf \
     && grep -q "restart: $dump (written after step $checkpoint by the interrupted run) removed" cfl2.nml.out; then
    echo "PASS run_directory/xdmf_after_stop_and_restart_lists_continued_history  (stop at $stop, restart from $checkpoint: $dump removed)"
  else
    echo "FAIL run_directory/xdmf_after_stop_and_restart_lists_continued_history: $(grep -o 'fields_[0-9]*.h5' cfl/fields.xdmf | sort -u | tr '\n' ' ')"
  fi
else
  echo "FAIL run_directory/xdmf_after_stop_and_restart_lists_continued_history: stop '${stop}', $(tail -n 2 cfl2.nml.out 2>/dev/null)"
fi
