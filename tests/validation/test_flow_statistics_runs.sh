#!/usr/bin/env bash
# checks: 4
# Flow statistics in a resolved run without forcing (&output flow_statistics_interval), with $AGGLO:
#  - a decaying random field, 16^3 on 2 ranks, 10 steps, interval 5: flow_statistics.h5 holds the
#    rows of steps 5 and 10 and their spectra, <f.u> = 0 (no forcing), and the log ends with the
#    time averages ("flow averages:", from t = 0 without forcing);
#  - one dissipation routine: epsilon in flow_statistics.h5 equals the dissipation column of
#    fluid_statistics.dat at the same steps (both nu <|D+ u|^2>, fluid_diagnostics) to 1e-12;
#  - Parseval: sum_s E(s kappa0) kappa0 equals the fluctuation kinetic energy 3/2 u_rms^2 to 1e-12
#    (the definition in src/fluid/flow_statistics.f90), through the solver's FFT plans;
#  - a negative interval is refused with a message naming &output flow_statistics_interval.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # interval
  cat <<NML
&run name = 'decay', max_steps = 10, end_time = 1.0, dt = 1.0e-4, dt_mode = 'cfl', cfl_target = 0.3,
     overwrite = .true., progress_interval = 1000 /
&scene fluid = 'resolved' /
&grid nx = 16, ny = 16, nz = 16, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'crank_nicolson', init = 'random', init_amplitude = 0.02,
       init_peak_wavenumber = 2.0 /
&output directory = 'decay', field_interval = 0.0, flow_statistics_interval = $1 /
NML
}
# The values of one dataset, one per line, with 17 significant digits.
values() { h5dump -y -m '%.17g' -d "$2" "$1" | sed -n '/DATA {/,/}/p' | grep -oE '[-]?[0-9][0-9.e+-]*'; }

deck 5 > decay.nml
if ! mpirun -np 2 "$AGGLO" decay.nml > decay.out 2>&1; then
  echo "FAIL flow_statistics_runs/unforced_run: the run failed: $(tail -n 3 decay.out | head -c 400)"
  exit 1
fi
stats=decay/flow_statistics.h5
steps=$(values $stats step | tr '\n' ' ')
spectra=$(h5ls $stats/spectra 2>/dev/null | grep -c '^energy_')
power=$(values $stats power_input | awk '{ if ($1 != 0) bad = 1 } END { print bad ? "nonzero" : "zero" }')
if [ "$steps" = "5 10 " ] && [ "$spectra" = 2 ] && [ "$power" = zero ] && grep -q '^flow averages: u_rms' decay.out; then
  echo "PASS flow_statistics_runs/unforced_run_writes_flow_statistics  (rows at steps $steps; 2 spectra; <f.u> = 0; averages logged)"
else
  echo "FAIL flow_statistics_runs/unforced_run_writes_flow_statistics: steps '$steps', $spectra spectra, <f.u> $power"
fi

# epsilon of both outputs at steps 5 and 10.
paste <(values $stats dissipation) <(awk '$1 == 5 || $1 == 10 { print $5 }' decay/fluid_statistics.dat) > eps.txt
if [ "$(wc -l < eps.txt)" = 2 ] && awk '{ d = $1 - $2; if (d < 0) d = -d; if (!(d <= 1e-12 * $2 && $2 > 0)) bad = 1 }
    END { exit bad }' eps.txt; then
  echo "PASS flow_statistics_runs/one_dissipation_in_both_outputs  (epsilon $(head -n 1 eps.txt | cut -f1) m^2/s^3 at step 5, within 1e-12)"
else
  echo "FAIL flow_statistics_runs/one_dissipation_in_both_outputs: $(tr '\n' ';' < eps.txt)"
fi

kappa0=$(values $stats spectra/wavenumber | head -n 1)
energy=$(values $stats spectra/energy_0000000010 | awk -v k="$kappa0" '{ s += $1 * k } END { printf "%.17g", s }')
k_e=$(values $stats kinetic_energy | tail -n 1)
if awk -v a="$energy" -v b="$k_e" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(b > 0 && d <= 1e-12 * b) }'; then
  echo "PASS flow_statistics_runs/spectrum_parseval  (sum E kappa0 = $energy, k = $k_e m^2/s^2)"
else
  echo "FAIL flow_statistics_runs/spectrum_parseval: sum E kappa0 = $energy, k = $k_e"
fi

deck -1 > negative.nml
if ! mpirun -np 1 "$AGGLO" negative.nml > negative.out 2>&1 \
   && grep -q "&output flow_statistics_interval = -1 is not allowed; allowed: >= 0" negative.out; then
  echo "PASS flow_statistics_runs/negative_interval_refused"
else
  echo "FAIL flow_statistics_runs/negative_interval_refused: $(grep -m1 error negative.out)"
fi
