#!/usr/bin/env bash
# checks: 6
# A fresh forced run from a converged forced field (&fluid init = 'file'), with $AGGLO, 2 ranks
# (docs/studies/validation.md, Forcing, "Start from a converged forced field"; docs/theory.md):
#  - spin-up: a 16^3 box of the hit_box deck (epsilon* = 1.6e-4 m^2/s^3, T_L = 0.01 s) forced from
#    rest to t = 0.1 s (10 T_L; about 20 k/epsilon); its final_field.h5 holds forcing/state;
#  - &forcing initial_state = 'field' (default): the OU coefficients of that file, so the power input
#    <f.u> is near its stationary value epsilon from the first step (mean of steps 1-5 in [0.7, 1.5]
#    epsilon) and the kinetic energy stays within 10% of its start over 3 ms (about half k/epsilon =
#    5.6 ms); stationary means P = epsilon (energy balance, Pope 2000 Eq. 6.1 with dk/dt = 0);
#  - initial_state = 'stationary': coefficients drawn from N(0, sigma^2), uncorrelated with u, so
#    |<f.u>| < 0.3 epsilon in the first step and the energy falls by more than 10% over the same 3 ms;
#  - a file without forcing/state, other forced modes, or an unknown initial_state stop with a message
#    naming the variables.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, end_time, seed, init text, extra &forcing text[, statistics_interval]
  cat <<NML
&run name = '$1', end_time = $2, dt = 2.5e-4, dt_mode = 'cfl', cfl_target = 0.4, cfl_limit = 0.8,
     overwrite = .true., progress_interval = 1000, seed = $3 /
&scene fluid = 'resolved', forcing = 'eswaran_pope' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', $4 /
&forcing time_scale = 0.01, epsilon_star = 1.6e-4, kappa_f_ratio = 2.3, statistics_interval = ${6:-1} $5 /
&output directory = '$1', checkpoint_interval = 0, field_interval = 0.0 /
NML
}
run() { mpirun -np 2 "$AGGLO" "$1" > "$1.out" 2>&1; }
series() { # run directory, dataset: the values of flow_statistics.h5/dataset, one a line
  h5dump -y -d "/$2" "$1/flow_statistics.h5" | sed -n '/DATA {/,/}/p' | grep -oE '[-]?[0-9]+\.[0-9]+(e[-+]?[0-9]+)?'
}
from_spin="init = 'file', init_file = 'spin/final_field.h5'"

deck spin 0.1 77 "init = 'rest'" "" 100 > spin.nml
if ! run spin.nml || [ ! -f spin/final_field.h5 ]; then
  echo "FAIL forced_start/spin_up: the spin-up run failed: $(tail -n 3 spin.nml.out | head -c 400)"
  exit 0
fi

# A batch run: another seed than the spin-up, 3 ms with a statistics row every step.
for state in field stationary; do
  deck "$state" 3.0e-3 5 "$from_spin" ", initial_state = '$state'" > "$state.nml"
  if run "$state.nml"; then
    paste <(series "$state" power_input) <(series "$state" dissipation) > "$state.pe"
    k0=$(awk 'NR == 3 { print $4 }' "$state/fluid_statistics.dat")     # step 0: the loaded field
    k_end=$(series "$state" kinetic_energy | tail -n 1)
    read -r p1 p5 k_ratio <<< "$(awk -v k0="$k0" -v k="$k_end" '
      NR == 1 { p1 = $1 / $2 } NR <= 5 { s += $1 / $2 } END { printf "%.4f %.4f %.4f", p1, s / 5, k / k0 }' "$state.pe")"
    eval "${state}_p1=$p1 ${state}_p5=$p5 ${state}_k=$k_ratio"
  else
    echo "FAIL forced_start/${state}_run: $(tail -n 3 "$state.nml.out" | head -c 400)"
    eval "${state}_p1=nan ${state}_p5=nan ${state}_k=nan"
  fi
done

if grep -q "forcing: OU coefficients from the initial field spin/final_field.h5" field.nml.out \
   && awk -v p="$field_p5" -v k="$field_k" 'BEGIN { exit !(p >= 0.7 && p <= 1.5 && k > 0.9 && k < 1.1) }'; then
  echo "PASS forced_start/field_keeps_power_input_and_energy  (<f.u>/epsilon: step 1 $field_p1, steps 1-5 $field_p5 in [0.7, 1.5]; K(3 ms)/K(0) = $field_k in (0.9, 1.1))"
else
  echo "FAIL forced_start/field_keeps_power_input_and_energy: <f.u>/epsilon steps 1-5 $field_p5 (want [0.7, 1.5]), K(3 ms)/K(0) = $field_k (want (0.9, 1.1)); $(grep -m1 'forcing: OU' field.nml.out)"
fi
if grep -q 'forcing: OU coefficients drawn from the stationary distribution' stationary.nml.out \
   && awk -v p="$stationary_p1" -v k="$stationary_k" 'BEGIN { exit !(p > -0.3 && p < 0.3 && k < 0.9) }'; then
  echo "PASS forced_start/stationary_starts_without_power_input  (<f.u>/epsilon step 1 $stationary_p1 in (-0.3, 0.3); K(3 ms)/K(0) = $stationary_k < 0.9)"
else
  echo "FAIL forced_start/stationary_starts_without_power_input: <f.u>/epsilon step 1 $stationary_p1 (want (-0.3, 0.3)), K(3 ms)/K(0) = $stationary_k (want < 0.9)"
fi

# --- errors -----------------------------------------------------------------------------------
expect_failure() { # test name, deck file, text the output must hold
  if run "$2"; then echo "FAIL forced_start/$1: the run succeeded"
  elif grep -qF "$3" "$2.out"; then echo "PASS forced_start/$1"
  else echo "FAIL forced_start/$1: no '$3' in: $(grep -m2 -iE 'error|deck|forcing:' "$2.out" | head -c 400)"; fi
}
deck snapshot 2.6e-4 5 "init = 'file', init_file = 'spin/fields_0000000000.h5'" "" > snapshot.nml
expect_failure field_needs_forcing_state snapshot.nml \
  "&forcing initial_state = 'field' with &fluid init = 'file' needs the forcing state (forcing/state)"
deck snapshot_stationary 2.6e-4 5 "init = 'file', init_file = 'spin/fields_0000000000.h5'" \
  ", initial_state = 'stationary'" > snapshot_stationary.nml
if run snapshot_stationary.nml; then echo "PASS forced_start/stationary_needs_no_forcing_state"
else echo "FAIL forced_start/stationary_needs_no_forcing_state: $(tail -n 2 snapshot_stationary.nml.out | head -c 300)"; fi
deck modes 2.6e-4 5 "$from_spin" "" | sed 's/kappa_f_ratio = 2.3/kappa_f_ratio = 1.5/' > modes.nml
expect_failure field_needs_same_forced_modes modes.nml "kappa_f_ratio or the &grid box differ"
deck unknown 2.6e-4 5 "$from_spin" ", initial_state = 'warm'" > unknown.nml
expect_failure unknown_initial_state unknown.nml \
  "&forcing initial_state = 'warm' is not allowed; allowed: one of 'field' | 'stationary'"
