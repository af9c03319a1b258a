#!/usr/bin/env bash
# Long paths with $AGGLO (docs/outputs.md, "Path length"), 2 ranks: any path the system takes works.
#  - a resolved run with an &output directory of about 1000 characters (five components of 200,
#    below NAME_MAX 255) writes every output there; its snapshot and checkpoint equal bit for bit
#    those of the same run in a short directory (h5diff without tolerance);
#  - a restart from its checkpoint continues and ends bit for bit equal to the uninterrupted run;
#  - &fluid init = 'file' reads a field file of that directory (a path of about 1030 characters);
#  - a pair run (serial HDF5 particles.h5, summary.json) writes there too;
#  - a directory of 4054 characters runs (its checkpoint paths reach 4095, PATH_MAX - 1); one of 4055
#    is refused with the limit named, before anything is written; a value longer than the deck
#    variable (4095 characters) likewise.
# Prints PASS/FAIL lines; works in a temporary directory.
# checks: 7
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

# A relative directory of 5 components of 200 characters (1004 with the slashes).
long=$(for i in 1 2 3 4 5; do printf "level${i}_"; printf 'x%.0s' $(seq 1 193); [ $i -lt 5 ] && printf /; done)
# deck DIRECTORY MAX_STEPS RESTART [fluid extras]
deck() {
  cat <<NML
&run name = 'long', max_steps = $2, restart = $3, end_time = 1.0, dt = 1.0e-4, dt_mode = 'cfl',
     cfl_target = 0.3, progress_interval = 1000 /
&scene fluid = 'resolved' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'crank_nicolson', init = 'random', init_amplitude = 0.02,
       init_peak_wavenumber = 2.0 ${4:-} /
&output directory = '$1', checkpoint_interval = 4, checkpoints_kept = 5, field_interval = 1.0e-4 /
NML
}
run() { mpirun -np 2 "$AGGLO" "$1" > "$1.out" 2>&1; }
checkpoint() { printf '%s/checkpoints/checkpoint_%010d.h5' "$1" "$2"; }
first_error() { grep -m1 -E 'error|abort|overflow|Signal' "$1" | cut -c1-240; }

deck short 12 .false. > short.nml
deck "$long" 8 .false. > long1.nml
deck "$long" 12 .true. > long2.nml
run short.nml || echo "FAIL long_paths/reference_run: $(first_error short.nml.out)"

# --- every output in a directory of 1004 characters, the same bits as in a short one ---------------
snapshot=$(cd short && ls fields_*.h5 | head -n 1)
if run long1.nml && [ ${#long} -ge 1000 ] && [ -f "$long/run.nml" ] && [ -f "$long/agglo.log" ] \
   && [ -f "$long/fields.xdmf" ] && [ -f "$long/fluid_statistics.dat" ] && [ -f "$long/agglo_manifest.txt" ] \
   && [ -f "$(checkpoint "$long" 8)" ] && [ -f "$long/$snapshot" ] \
   && h5diff -q "short/$snapshot" "$long/$snapshot" > diff1.txt 2>&1 \
   && h5diff -q "$(checkpoint short 8)" "$(checkpoint "$long" 8)" >> diff1.txt 2>&1; then
  echo "PASS long_paths/outputs_in_1000_character_directory  (${#long} characters; $snapshot and checkpoint 8 = short directory's, bit for bit)"
else
  echo "FAIL long_paths/outputs_in_1000_character_directory: $(first_error long1.nml.out) $(head -c 300 diff1.txt 2>/dev/null)"
fi

# --- restart from its checkpoint: the continued run equals the uninterrupted one ----------------------
if run long2.nml && grep -q "continuing from $(checkpoint "$long" 8)" long2.nml.out \
   && h5diff -q "$(checkpoint short 12)" "$(checkpoint "$long" 12)" > diff2.txt 2>&1 \
   && cmp -s short/fluid_statistics.dat "$long/fluid_statistics.dat"; then
  echo "PASS long_paths/restart_from_long_path_bit_for_bit  (from step 8 to 12 = the uninterrupted run)"
else
  echo "FAIL long_paths/restart_from_long_path_bit_for_bit: $(first_error long2.nml.out) $(head -c 300 diff2.txt 2>/dev/null)"
fi

# --- a field file of that directory as the initial field (read through MPI-IO) -----------------------
init_file="$long/$snapshot"
deck from_file 1 .false. ", init = 'file', init_file = '$init_file'" > from_file.nml
if run from_file.nml && [ -f "$(checkpoint from_file 1)" ] && grep -q "level5_" from_file/run.nml; then
  echo "PASS long_paths/init_file_of_1000_characters  (${#init_file} characters read)"
else
  echo "FAIL long_paths/init_file_of_1000_characters: $(first_error from_file.nml.out)"
fi

# --- a pair run (serial HDF5 and text outputs) -------------------------------------------------------
pair_dir="$long/pair"
cat > pair.nml <<NML
&run name = 'pair', seed = 1, end_time = 1.0e-5, dt = 2.0e-7, progress_interval = 10000 /
&scene fluid = 'none', particles = 'pair', dlvo = .true., collisions = .true. /
&pair shape = 'sphere', radius = 50.0e-6, density = 2710.0, gap = 5.0e-6, relative_speed = 0.875e-3 /
&output directory = '$pair_dir' /
NML
if run pair.nml && [ -s "$pair_dir/particles.h5" ] && [ -s "$pair_dir/summary.json" ] \
   && h5dump -d /name "$pair_dir/particles.h5" 2>/dev/null | grep -q '"pair"'; then
  echo "PASS long_paths/pair_outputs_in_long_directory  (particles.h5 and summary.json, ${#pair_dir} characters)"
else
  echo "FAIL long_paths/pair_outputs_in_long_directory: $(first_error pair.nml.out)"
fi

# --- the system's limit: the longest directory runs, one character more is refused up front ---------
# 4054 characters: <directory>/checkpoints/checkpoint_<10 digits>.h5.tmp is then 4095 (PATH_MAX - 1).
edge=$(for i in $(seq 1 19); do printf 'y%.0s' $(seq 1 200); printf /; done; printf 'z%.0s' $(seq 1 235))
deck "$edge" 4 .false. > edge.nml
if [ ${#edge} -eq 4054 ] && run edge.nml && [ -f "$(checkpoint "$edge" 4)" ]; then
  echo "PASS long_paths/longest_directory_runs  (${#edge} characters; checkpoint paths of 4095 while written)"
else
  echo "FAIL long_paths/longest_directory_runs: ${#edge} characters; $(first_error edge.nml.out)"
fi
rm -rf yyyy*
deck "${edge}z" 4 .false. > too_long.nml
run too_long.nml; status=$?
if [ $status -ne 0 ] && ! compgen -G "y*" > /dev/null \
   && grep -q "(4055 characters) is not allowed; allowed: a path of at most 4054 characters" too_long.nml.out \
   && grep -q "limit of 4095 characters" too_long.nml.out; then
  echo "PASS long_paths/beyond_path_max_refused_before_writing  (4055 characters: exit $status, the limit 4095 named)"
else
  echo "FAIL long_paths/beyond_path_max_refused_before_writing: exit $status; $(first_error too_long.nml.out)"
fi
longer=$(printf 'w%.0s' $(seq 1 4200))
mpirun -np 1 "$AGGLO" short.nml --set "output.directory='$longer'" > longer.out 2>&1; status=$?
if [ $status -ne 0 ] && [ ! -e "$longer" ] && grep -q "&output directory = 'www.*(4096 characters or more).*at most 4095 characters" longer.out; then
  echo "PASS long_paths/longer_than_deck_variable_refused  (exit $status)"
else
  echo "FAIL long_paths/longer_than_deck_variable_refused: exit $status; $(first_error longer.out)"
fi
