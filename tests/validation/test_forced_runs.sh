#!/usr/bin/env bash
# checks: 8
# End-to-end forced runs of the resolved scene with $AGGLO (docs/studies/validation.md, Forcing):
#  - restart with forcing: 2n steps in one run == n steps + restart + n steps, bit for bit
#    (h5diff without tolerance on the whole final checkpoint: fluid/* and forcing/state), 2 ranks;
#  - the time series of the restarted run (flow_statistics.h5: rows and spectra; fluid_statistics.dat)
#    equal the uninterrupted run's, also after a simulated kill that left rows and a spectrum written
#    after the last checkpoint (dropped on restart, not duplicated);
#  - 1 rank vs 2 ranks: the same forced deck gives u, v, w within 1e-12 x max|u| after 60 steps;
#  - the log states T_L, sigma, epsilon* and the E&P estimate (docs/decks.md, &forcing);
#  - flow_statistics.h5 holds the time series and one spectrum per statistics row.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, max_steps, restart[, checkpoint_interval]
  cat <<NML
&run name = '$1', max_steps = $2, restart = $3, end_time = 1.0, dt = 2.5e-4, dt_mode = 'fixed',
     overwrite = .true., progress_interval = 1000, seed = 77 /
&scene fluid = 'resolved', forcing = 'eswaran_pope' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'rest' /
&forcing time_scale = 0.01, target_dissipation = 8.0e-3, statistics_interval = 10 /
&output directory = '$1', checkpoint_interval = ${4:-0}, checkpoints_kept = 5, field_interval = 0.0 /
NML
}
run() { mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1; }
final_checkpoint() { ls "$1"/checkpoints/checkpoint_*.h5 | sort | tail -n 1; }

# --- restart with forcing, bit for bit ------------------------------------------------------
deck whole 60 .false. > whole.nml
deck split 30 .false. > split1.nml
deck split 60 .true. > split2.nml
if run 2 whole.nml && run 2 split1.nml && run 2 split2.nml; then
  a=$(final_checkpoint whole); b=$(final_checkpoint split)
  if [ "$(basename "$a")" = checkpoint_0000000060.h5 ] && h5diff "$a" "$b" /forcing/state > /dev/null 2>&1 \
     && h5diff -q "$a" "$b" > diff.txt 2>&1; then
    echo "PASS forced_runs/restart_with_forcing_bit_for_bit  ($(basename "$a"): fluid/* and forcing/state identical)"
  else
    echo "FAIL forced_runs/restart_with_forcing_bit_for_bit: $a vs $b: $(head -c 300 diff.txt 2>/dev/null)"
  fi
  if grep -q 'forcing: OU state and random stream restored' split2.nml.out; then
    echo "PASS forced_runs/restart_restores_forcing_state"
  else echo "FAIL forced_runs/restart_restores_forcing_state: no restore line in the log"; fi
else
  echo "FAIL forced_runs/restart_with_forcing_bit_for_bit: a run failed: $(tail -n 3 ./*.nml.out | head -c 400)"
fi

# Time series after the restart: every dataset of flow_statistics.h5 (6 rows, 6 spectra) and the
# text series identical to the uninterrupted run (h5diff without tolerance; cmp).
series_equal() { # run directory: prints nothing and succeeds if its time series equal whole/'s
  h5diff -q whole/flow_statistics.h5 "$1"/flow_statistics.h5 > "$1.diff" 2>&1 \
    && h5diff -q "$1"/flow_statistics.h5 whole/flow_statistics.h5 >> "$1.diff" 2>&1 \
    && [ "$(h5ls "$1"/flow_statistics.h5/spectra | grep -c '^energy_')" = 6 ] \
    && [ "$(h5ls "$1"/flow_statistics.h5/u_rms | sed -n 's/.*Dataset {\([0-9]*\)\/Inf}.*/\1/p')" = 6 ] \
    && cmp -s whole/fluid_statistics.dat "$1"/fluid_statistics.dat
}
if series_equal split; then
  echo "PASS forced_runs/restart_time_series_equal_uninterrupted  (flow_statistics.h5: 6 rows, 6 spectra, h5diff exact; fluid_statistics.dat identical)"
else
  echo "FAIL forced_runs/restart_time_series_equal_uninterrupted: $(head -c 300 split.diff)"
fi

# --- restart after a kill: rows and spectra written after the last checkpoint are dropped -------
# 55 steps with checkpoints at 20, 40 and the end-of-run one at 55; deleting checkpoint 55 leaves the
# directory as a run killed after step 55 but before its checkpoint: the restart continues from step
# 40, so the statistics row and spectrum of step 50 (and text rows 41..55) were written past it.
deck killed 55 .false. 20 > killed1.nml
deck killed 60 .true. 20 > killed2.nml
if run 2 killed1.nml && rm -f killed/checkpoints/checkpoint_0000000055.h5 && run 2 killed2.nml; then
  if grep -q 'continuing from .*checkpoint_0000000040.h5' killed2.nml.out \
     && grep -q 'flow statistics: 1 rows after step 40 (written after the checkpoint) dropped' killed2.nml.out \
     && series_equal killed && h5diff -q "$(final_checkpoint whole)" "$(final_checkpoint killed)" >> killed.diff 2>&1; then
    echo "PASS forced_runs/restart_after_kill_drops_rows_past_checkpoint  (from step 40: row and spectrum of step 50 rewritten once; series and final checkpoint = uninterrupted run)"
  else
    echo "FAIL forced_runs/restart_after_kill_drops_rows_past_checkpoint: $(head -c 300 killed.diff) $(grep -m2 -E 'continuing|dropped' killed2.nml.out)"
  fi
else
  echo "FAIL forced_runs/restart_after_kill_drops_rows_past_checkpoint: a run failed: $(tail -n 3 killed*.nml.out | head -c 400)"
fi

# --- 1 rank vs 2 ranks -----------------------------------------------------------------------
deck one 60 .false. > one.nml
if run 1 one.nml; then
  umax=$(h5dump -y -d /fluid/u "$(final_checkpoint one)" | sed -n '/DATA {/,/}/p' \
         | grep -oE '[-]?[0-9]+\.[0-9]+(e[-+]?[0-9]+)?' | awk '{ v = ($1 < 0) ? -$1 : $1; if (v > m) m = v } END { printf "%.6e", m }')
  tol=$(awk -v m="$umax" 'BEGIN { printf "%.3e", 1e-12 * m }')
  ok=1; detail=""
  for f in u v w; do
    if ! h5diff -d "$tol" "$(final_checkpoint one)" "$(final_checkpoint whole)" "/fluid/$f" > diff.txt 2>&1; then
      ok=0; detail="$detail $f: $(head -c 200 diff.txt)"
    fi
  done
  if h5diff "$(final_checkpoint one)" "$(final_checkpoint whole)" /forcing/state > /dev/null 2>&1; then :; else
    ok=0; detail="$detail forcing/state differs"; fi
  if [ $ok = 1 ]; then echo "PASS forced_runs/one_rank_equals_two_ranks_to_1e-12  (max|u| = $umax m/s, tol $tol; forcing state identical)"
  else echo "FAIL forced_runs/one_rank_equals_two_ranks_to_1e-12:$detail"; fi
else
  echo "FAIL forced_runs/one_rank_equals_two_ranks_to_1e-12: the run failed: $(tail -n 3 one.nml.out | head -c 400)"
fi

# --- the log states T_L, sigma, epsilon* and the E&P estimate ---------------------------------
if grep -q 'forcing: T_L = 1.00000E-02 s, sigma = .* m/s^2, epsilon\* = sigma^2 T_L = .* (from target_dissipation)' \
     one/agglo.log && grep -q 'forcing: E&P power estimate 8.00000E-03 m^2/s^3' one/agglo.log; then
  echo "PASS forced_runs/log_states_forcing_parameters"
else echo "FAIL forced_runs/log_states_forcing_parameters: $(grep -m3 '^forcing' one/agglo.log)"; fi

# --- flow statistics file: 6 rows (steps 10..60) and 6 spectra --------------------------------
rows=$(h5ls one/flow_statistics.h5/u_rms 2>/dev/null | sed -n 's/.*Dataset {\([0-9]*\)\/Inf}.*/\1/p')
spectra=$(h5ls one/flow_statistics.h5/spectra 2>/dev/null | grep -c '^energy_')
if [ "$rows" = 6 ] && [ "$spectra" = 6 ]; then echo "PASS forced_runs/flow_statistics_time_series_and_spectra  (6 rows, 6 spectra)"
else echo "FAIL forced_runs/flow_statistics_time_series_and_spectra: $rows rows, $spectra spectra (expected 6, 6)"; fi

# --- the final field loads with &fluid init = 'file' on another rank count ----------------------
# one/ ran on 1 rank; load it on 2 ranks: the first snapshot of the new run is the loaded field, exactly.
if [ -f one/final_field.h5 ]; then
  sed -e "s/name = 'one'/name = 'load'/" -e "s/directory = 'one'/directory = 'load'/" \
      -e "s/init = 'rest'/init = 'file', init_file = 'one\/final_field.h5'/" -e 's/max_steps = 60/max_steps = 1/' \
      one.nml > load.nml
  if run 2 load.nml && h5diff one/final_field.h5 load/fields_0000000000.h5 /fluid/u /fields/u > diff.txt 2>&1 \
     && h5diff one/final_field.h5 load/fields_0000000000.h5 /fluid/w /fields/w >> diff.txt 2>&1; then
    echo "PASS forced_runs/final_field_loads_on_another_rank_count  (1-rank final_field.h5 -> 2-rank init = 'file', exact)"
  else
    echo "FAIL forced_runs/final_field_loads_on_another_rank_count: $(head -c 300 diff.txt) $(tail -n 2 load.nml.out)"
  fi
else
  echo "FAIL forced_runs/final_field_loads_on_another_rank_count: one/final_field.h5 was not written"
fi
