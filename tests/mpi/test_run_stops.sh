#!/usr/bin/env bash
# checks: 4
# Run-time stops of the resolved scene with $AGGLO (docs/studies/validation.md, "Restart hygiene and run
# stops"): a NaN or a CFL above the limit stops the run with a message and a final field dump; 2 ranks:
#  - CFL: a fixed dt with strong Eswaran-Pope forcing from rest; the flow accelerates until the
#    advective CFL number dt (|u|/dx + |v|/dy + |w|/dz)_max passes &run cfl_limit = 1. The run must
#    exit non-zero with the message naming the CFL number, the limit and the step, leave the field
#    of that step (fields_<step>.h5, listed in fields.xdmf), and write no checkpoint of the bad state;
#    the last time-series row is the step before, with a CFL number still <= the limit.
#  - NaN: the only deck that reaches the NaN check is one whose field overflows double precision in
#    one step (from any finite field with CFL <= cfl_limit <= 2 a step amplifies the velocity by a
#    bounded factor, so the CFL check fires first): a random field of rms 1e200 m/s with a dt that
#    passes the deck's advective limit. u*u overflows in the advection term at step 1. In a debug
#    build (-ffpe-trap=overflow, stated in the log's compiler options) the trap stops the run at the
#    first overflow, before the check: then a SIGFPE exit is the expected outcome.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

# --- CFL above the limit ----------------------------------------------------------------------
# 16^3 in 1 mm, dt = 2.5e-4 s (below the explicit viscous limit 3.26e-4 s); forcing power 1 m^2/s^3
# (E&P estimate) from rest: u_max reaches about dx / (3 dt) = 0.08 m/s, CFL 1, after about 10 steps.
cat > cfl.nml <<NML
&run name = 'cfl', max_steps = 400, end_time = 1.0, dt = 2.5e-4, dt_mode = 'fixed', cfl_limit = 1.0,
     overwrite = .true., progress_interval = 1000, seed = 5 /
&scene fluid = 'resolved', forcing = 'eswaran_pope' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'rest' /
&forcing time_scale = 0.01, target_dissipation = 1.0, statistics_interval = 0 /
&output directory = 'cfl', checkpoint_interval = 0, field_interval = 0.0 /
NML
mpirun -np 2 "$AGGLO" cfl.nml > cfl.out 2>&1; status=$?
message=$(grep -m1 'agglo: error: resolved scene: CFL number' cfl.out)
# "... CFL number 1.06406E+00 exceeds &run cfl_limit = 1.00000E+00 at step 10 (t = 2.50000E-03 s); the last field is in ..."
cfl=$(sed -n 's/.*CFL number \([0-9.E+-]*\) exceeds.*/\1/p' <<< "$message")
step=$(sed -n 's/.* at step \([0-9]*\) (t = .*/\1/p' <<< "$message")
if [ "$status" -ne 0 ] && [ -n "$cfl" ] && [ -n "$step" ] \
   && grep -q "exceeds &run cfl_limit = 1.00000E+00 at step $step (t = .* s); the last field is in cfl/fields.xdmf" <<< "$message" \
   && awk -v c="$cfl" 'BEGIN { exit !(c > 1.0) }'; then
  echo "PASS run_stops/cfl_above_limit_stops_with_message  (exit $status; CFL $cfl > 1 at step $step)"
else
  echo "FAIL run_stops/cfl_above_limit_stops_with_message: exit $status; message: ${message:-none}; $(tail -n 2 cfl.out | head -c 300)"
fi
# The last row of the time series is the step before the stop, with a CFL number within the limit.
last=$(grep -v '^#' cfl/fluid_statistics.dat 2>/dev/null | tail -n 1)
if [ -n "$step" ] && awk -v s="$step" '{ exit !($1 == s - 1 && $7 <= 1.0) }' <<< "$last"; then
  echo "PASS run_stops/cfl_last_row_is_the_step_before  (step $(awk '{ print $1 }' <<< "$last"), cfl $(awk '{ print $7 }' <<< "$last"))"
else
  echo "FAIL run_stops/cfl_last_row_is_the_step_before: last row '$last', stop step ${step:-?}"
fi
# The field dump of the stop step: fields_<step>.h5 holding that step, listed in fields.xdmf.
dump=cfl/fields_$(printf '%010d' "${step:-0}").h5
dumped_step=$(h5dump -d /step "$dump" 2>/dev/null | sed -n 's/.*(0): \([0-9]*\).*/\1/p')
if [ -n "$step" ] && [ "$dumped_step" = "$step" ] && grep -q "$(basename "$dump"):/fields/u" cfl/fields.xdmf \
   && [ ! -d cfl/checkpoints ]; then
  echo "PASS run_stops/cfl_stop_dumps_final_field  ($(basename "$dump") with /step = $step in fields.xdmf; no checkpoint)"
else
  echo "FAIL run_stops/cfl_stop_dumps_final_field: $dump /step = '${dumped_step}'; $(ls cfl 2>&1 | tr '\n' ' ')"
fi

# --- non-finite field ---------------------------------------------------------------------------
# Deck limit on dt for this field: cfl_limit / (3 x estimated peak / dx) = 1.4e-205 s; dt = 1e-206 s.
cat > nan.nml <<NML
&run name = 'nan', max_steps = 5, end_time = 1.0, dt = 1.0e-206, dt_mode = 'fixed', cfl_limit = 2.0,
     overwrite = .true., progress_interval = 1000, seed = 5 /
&scene fluid = 'resolved' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'random', init_amplitude = 1.0e200 /
&output directory = 'nan', checkpoint_interval = 0, field_interval = 0.0 /
NML
mpirun -np 2 "$AGGLO" nan.nml > nan.out 2>&1; status=$?
if grep -q -e '-ffpe-trap' nan/agglo.log 2>/dev/null; then   # the options may wrap over lines
  if [ "$status" -ne 0 ] && grep -q -E 'SIGFPE|Floating-point exception' nan.out; then
    echo "PASS run_stops/nan_stops_with_message  (debug build: -ffpe-trap stopped the overflow before the check, exit $status)"
  else
    echo "FAIL run_stops/nan_stops_with_message: debug build, exit $status without a floating-point trap: $(tail -n 2 nan.out)"
  fi
else
  if [ "$status" -ne 0 ] && grep -q "agglo: error: resolved scene: the velocity field is no longer finite (NaN or infinity) at step 1 (t = .* s); the last field is in nan/fields.xdmf" nan.out \
     && [ -f nan/fields_0000000001.h5 ] && grep -q 'fields_0000000001.h5:/fields/u' nan/fields.xdmf && [ ! -d nan/checkpoints ]; then
    echo "PASS run_stops/nan_stops_with_message  (exit $status at step 1; fields_0000000001.h5 dumped, no checkpoint)"
  else
    echo "FAIL run_stops/nan_stops_with_message: exit $status; $(grep -m1 'agglo: error' nan.out); $(ls nan 2>&1 | tr '\n' ' ')"
  fi
fi
