#!/usr/bin/env bash
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
#  - collapsed CFL step (dt_mode = 'cfl', module time_step_guard): a random field of rms 1e30 m/s
#    gives a CFL step near 3e-36 s, below 1e-6 x the largest step (&run dt): the run stops before
#    its first step, on 2 ranks, naming the CFL number, the fastest velocity component and its
#    node, which must be the node of the largest |u_d|/dx_d in the field it wrote at step 0; a field
#    of rms 1 m/s with end_time = 1e4 s leaves some 3e9 CFL steps (more than 1e9) and stops too;
#    the same deck at rms 1 mm/s and end_time 1e-4 s runs to its end (no false stop).
# Prints PASS/FAIL lines; works in a temporary directory.
# checks: 8
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
python=${AGGLO_PYTHON:-$(cd "$(dirname "$0")/../.." && pwd)/.venv/bin/python}   # h5py, numpy
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
# Deck limit on dt for this field: cfl_limit / (3 x estimated peak / dx) = 1.4e-205 s; dt = 1e-206 s
# (and end_time 1e-205 s: 10 steps, within the step-count limit of &run).
cat > nan.nml <<NML
&run name = 'nan', max_steps = 5, end_time = 1.0e-205, dt = 1.0e-206, dt_mode = 'fixed', cfl_limit = 2.0,
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

# --- collapsed CFL step -----------------------------------------------------------------------------
collapse_deck() { # name, init_amplitude, end_time
  cat <<NML
&run name = '$1', end_time = $3, dt = 1.0e-4, dt_mode = 'cfl', cfl_target = 0.5, overwrite = .true.,
     progress_interval = 1000, seed = 5 /
&scene fluid = 'resolved' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'random', init_amplitude = $2 /
&output directory = '$1', checkpoint_interval = 0, field_interval = 0.0 /
NML
}
collapse_deck collapse 1.0e30 1.0e-3 > collapse.nml
mpirun -np 2 "$AGGLO" collapse.nml > collapse.out 2>&1; status=$?
message=$(grep -m1 'agglo: error: time step: the CFL step has collapsed' collapse.out)
# The largest step: min(&run dt = 1e-4, cfl_target x explicit-diffusion limit 3.26e-4 s) = 1e-4 s.
if [ "$status" -ne 0 ] && grep -qF 'collapsed at step 0 (t = 0.00000E+00 s): dt = ' <<< "$message" \
   && grep -qF 's is below 1.00000E-06 x the largest step 1.00000E-04 s' <<< "$message" \
   && grep -qF 'CFL number 5.00000E-01 with the fastest velocity component' <<< "$message"; then
  echo "PASS run_stops/cfl_collapse_stops_before_the_first_step  (exit $status: $(cut -c1-160 <<< "$message"))"
else
  echo "FAIL run_stops/cfl_collapse_stops_before_the_first_step: exit $status; message: ${message:-none}; $(tail -n 2 collapse.out | head -c 300)"
fi
# The node named is the largest |u_d|/dx_d of the field at step 0 (fields_0000000000.h5, written
# before the loop), with its velocity to the 6 digits of the message and the MAC position of
# src/fluid/fluid_grid.f90.
if "$python" - "$message" collapse/fields_0000000000.h5 > where.txt 2>&1 <<'PY'
import re, sys
import h5py, numpy as np
message, path = sys.argv[1], sys.argv[2]
found = re.search(r"component ([uvw]) = (\S+) m/s at [uvw]\((\d+), (\d+), (\d+)\) of &grid, position \((\S+), (\S+), (\S+)\) m",
                  message)
assert found, f"no node in the message: {message}"
name, velocity = found.group(1), float(found.group(2))
index = [int(found.group(n)) for n in (3, 4, 5)]
position = [float(found.group(n)) for n in (6, 7, 8)]
with h5py.File(path, "r") as f:
    fields = {c: np.asarray(f["fields/" + c][()]).T for c in "uvw"}    # h5py [k, j, i] -> [i, j, k]
    lengths = np.asarray(f["grid/lengths"][()])
spacing = lengths / 16
scaled = {c: np.abs(fields[c]) / spacing[d] for d, c in enumerate("uvw")}
best = max("uvw", key=lambda c: scaled[c].max())
i, j, k = np.unravel_index(np.argmax(scaled[best]), scaled[best].shape)
assert (name, index) == (best, [i + 1, j + 1, k + 1]), f"message {name}{index}, field {best}({i + 1}, {j + 1}, {k + 1})"
assert abs(velocity - fields[best][i, j, k]) <= 1e-5 * abs(fields[best][i, j, k]), (velocity, fields[best][i, j, k])
offset = {"u": (1.0, 0.5, 0.5), "v": (0.5, 1.0, 0.5), "w": (0.5, 0.5, 1.0)}[best]
expected = [(n + o - 1.0) * h for n, o, h in zip(index, offset, spacing)]
assert all(abs(a - b) <= 1e-5 * max(lengths) for a, b in zip(position, expected)), (position, expected)
print(f"{best}{tuple(index)} = {fields[best][i, j, k]:.5e} m/s at ({', '.join(f'{x:.5e}' for x in expected)}) m")
PY
then
  echo "PASS run_stops/cfl_collapse_names_the_fastest_node  ($(cat where.txt))"
else
  echo "FAIL run_stops/cfl_collapse_names_the_fastest_node: $(tail -n 3 where.txt)"
fi
# rms 1 m/s: CFL step about 3e-6 s (not collapsed), but 1e4 s / 3e-6 s = 3e9 steps to end_time.
collapse_deck far_end 1.0 1.0e4 > far_end.nml
"$AGGLO" far_end.nml > far_end.out 2>&1; status=$?
message=$(grep -m1 'agglo: error: time step: the CFL step has collapsed' far_end.out)
steps=$(sed -n 's/.*leaves (end_time - t) \/ dt = \([0-9.E+-]*\) steps to &run end_time = 1.00000E+04 s, more than 1000000000, max(max_steps, 1e9).*/\1/p' <<< "$message")
if [ "$status" -ne 0 ] && [ -n "$steps" ] && awk -v n="$steps" 'BEGIN { exit !(n > 1.0e9) }'; then
  echo "PASS run_stops/cfl_step_too_small_for_end_time_stops  (exit $status; $steps steps left)"
else
  echo "FAIL run_stops/cfl_step_too_small_for_end_time_stops: exit $status; message: ${message:-none}"
fi
collapse_deck gentle 1.0e-3 1.0e-4 > gentle.nml
"$AGGLO" gentle.nml > gentle.out 2>&1; status=$?
if [ "$status" -eq 0 ] && grep -q 'reached t = 1.00000E-04 s' gentle.out; then
  echo "PASS run_stops/cfl_run_without_collapse_reaches_end  ($(grep -c '' gentle/fluid_statistics.dat) lines of statistics)"
else
  echo "FAIL run_stops/cfl_run_without_collapse_reaches_end: exit $status; $(grep -m1 'agglo: error' gentle.out)"
fi
