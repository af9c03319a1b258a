#!/usr/bin/env bash
# checks: 2
# Restarts from damaged checkpoints with $AGGLO (docs/outputs.md, "Checkpoints"), 2 ranks:
#  - the newest checkpoint truncated (a full disk, a copy cut short) and a file merely named like a
#    newer checkpoint (checkpoint_9999999999.h5, a copy of an older one): both are named in a warning
#    and passed over; the run continues from the previous valid checkpoint and ends bit for bit equal
#    to the uninterrupted run (h5diff without tolerance; the time series byte for byte);
#  - every checkpoint zeroed: the restart is refused with a message, and run.nml is left as it was.
# A corrupted data byte (caught by the Fletcher-32 checksum) is tested in test_checkpoint_files.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, max_steps, restart, checkpoint_interval
  cat <<NML
&run name = '$1', max_steps = $2, restart = $3, end_time = 1.0, dt = 1.0e-4, dt_mode = 'cfl',
     cfl_target = 0.3, progress_interval = 1000 /
&scene fluid = 'resolved' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'crank_nicolson', init = 'random', init_amplitude = 0.02,
       init_peak_wavenumber = 2.0 /
&output directory = '$1', checkpoint_interval = $4, checkpoints_kept = 5, field_interval = 0.0 /
NML
}
run() { mpirun -np 2 "$AGGLO" "$1" > "$1.out" 2>&1; }
checkpoint() { printf '%s/checkpoints/checkpoint_%010d.h5' "$1" "$2"; }

deck whole 20 .false. 0 > whole.nml
deck damaged 14 .false. 4 > damaged1.nml
deck damaged 20 .true. 4 > damaged2.nml
if run whole.nml && run damaged1.nml; then
  newest=$(checkpoint damaged 14)
  truncate -s $(( $(stat -c %s "$newest") / 2 )) "$newest"
  cp "$(checkpoint damaged 8)" "$(checkpoint damaged 9999999999)"
  if run damaged2.nml \
     && grep -q "warning: checkpoint $(checkpoint damaged 9999999999) is not usable (it holds step 8, not the step in its name)" damaged2.nml.out \
     && grep -q "warning: checkpoint $newest is not usable (" damaged2.nml.out \
     && grep -q "continuing from $(checkpoint damaged 12)" damaged2.nml.out \
     && h5diff -q "$(checkpoint whole 20)" "$(checkpoint damaged 20)" > diff.txt 2>&1 \
     && cmp -s whole/fluid_statistics.dat damaged/fluid_statistics.dat; then
    echo "PASS checkpoint_restarts/damaged_newest_passed_over_bit_for_bit  (truncated 14 and a fake 9999999999 named; from 12 to 20 = uninterrupted run)"
  else
    echo "FAIL checkpoint_restarts/damaged_newest_passed_over_bit_for_bit: $(grep -m3 -E 'warning|continuing|error' damaged2.nml.out | cut -c1-200) $(head -c 200 diff.txt 2>/dev/null)"
  fi
else
  echo "FAIL checkpoint_restarts/damaged_newest_passed_over_bit_for_bit: a run failed: $(tail -n 3 ./*.nml.out | head -c 400)"
fi

# Every checkpoint zeroed: nothing to continue from.
cp damaged/run.nml run.nml.before
for f in damaged/checkpoints/checkpoint_*.h5; do
  size=$(stat -c %s "$f"); head -c "$size" /dev/zero > "$f"
done
deck damaged 24 .true. 4 > damaged3.nml
run damaged3.nml; status=$?
if [ $status -ne 0 ] && grep -q "holds no complete and valid checkpoint to continue from" damaged3.nml.out \
   && [ "$(grep -c 'is not usable' damaged3.nml.out)" -ge 4 ] && cmp -s run.nml.before damaged/run.nml; then
  echo "PASS checkpoint_restarts/all_damaged_refused_run_nml_kept  (exit $status; $(grep -c 'is not usable' damaged3.nml.out) files named)"
else
  echo "FAIL checkpoint_restarts/all_damaged_refused_run_nml_kept: exit $status; $(grep -m1 'agglo: error' damaged3.nml.out | cut -c1-200)"
fi
