#!/usr/bin/env bash
# checks: 15
# Bad &forcing input is rejected before anything runs, with a message naming the group, the
# variable and the allowed range (docs/decks.md, &forcing). Each case runs $AGGLO on a small deck
# and greps the error; a good deck must pass the checks.
set -u
. "$(cd "$(dirname "$0")" && pwd)/deck_error_lib.sh"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

run="&run name = 'f', end_time = 1.0e-4, dt = 1.0e-5, overwrite = .true. /"
base="$run
&grid nx = 8, ny = 8, nz = 8 /"

# case name, expected text (fixed string), then the deck groups after the base
expect_error() { expect_deck_error "$1" 1 "$base
$3" "$2"; }

forced="&scene fluid = 'resolved', forcing = 'eswaran_pope' /"
expect_error kappa_f_below_kappa0 "&forcing kappa_f_ratio = 5.00000E-01 is not allowed" \
  "$forced
&forcing sigma = 0.1, kappa_f_ratio = 0.5 /"
expect_error time_scale_zero "&forcing time_scale = 0.00000E+00 is not allowed; allowed: > 0" \
  "$forced
&forcing sigma = 0.1, time_scale = 0.0 /"
expect_error time_scale_negative "&forcing time_scale = -1.00000E-02 is not allowed" \
  "$forced
&forcing sigma = 0.1, time_scale = -0.01 /"
expect_error sigma_negative "&forcing sigma = -1.00000E-01 is not allowed; allowed: > 0" \
  "$forced
&forcing sigma = -0.1 /"
expect_error epsilon_star_negative_variance "&forcing epsilon_star = -1.00000E-03 is not allowed" \
  "$forced
&forcing epsilon_star = -1.0e-3 /"
expect_error target_dissipation_zero "&forcing target_dissipation = 0.00000E+00 is not allowed" \
  "$forced
&forcing target_dissipation = 0.0 /"
expect_error no_strength "&forcing sigma / epsilon_star / target_dissipation = none given" \
  "$forced
&forcing time_scale = 0.01 /"
expect_error two_strengths "more than one given (sigma epsilon_star)" \
  "$forced
&forcing sigma = 0.1, epsilon_star = 1.0e-4 /"
expect_error unknown_update "&forcing update = 'rk4' is not allowed; allowed: one of 'exact' | 'euler_maruyama'" \
  "$forced
&forcing sigma = 0.1, update = 'rk4' /"
base="$run
&grid nx = 4, ny = 8, nz = 8 /"
expect_error cutoff_above_nyquist "which needs nx > 4 cells (nx = 4)" \
  "$forced
&forcing sigma = 0.1 /"
base="$run
&grid nx = 8, ny = 8, nz = 8 /"
expect_error euler_maruyama_dt_above_time_scale "&forcing update = 'euler_maruyama' with &run dt" \
  "$forced
&forcing sigma = 0.1, update = 'euler_maruyama', time_scale = 1.0e-6 /"
expect_error forcing_without_fluid "&scene forcing = 'eswaran_pope' with fluid = 'none' is not allowed" \
  "&scene fluid = 'none', particles = 'pair', forcing = 'eswaran_pope' /
&forcing sigma = 0.1 /"
expect_error forcing_with_stokes "&scene forcing = 'eswaran_pope' with fluid = 'stokes' is not allowed" \
  "&scene fluid = 'stokes', particles = 'pair', forcing = 'eswaran_pope' /
&forcing sigma = 0.1 /"

# A good deck passes the checks (the run itself is the resolved scene's business).
printf '%s\n%s\n%s\n' "$base" "$forced" "&forcing target_dissipation = 8.0e-3, update = 'euler_maruyama' /" > good.nml
if "$AGGLO" good.nml > good.out 2>&1; then echo "PASS good_forcing_deck_accepted"
else echo "FAIL good_forcing_deck_accepted: $(head -c 300 good.out)"; fi

# The resolved deck run.nml (unset strength inputs written as -huge) reads back as a valid deck.
if [ -f output/f/run.nml ] && cp output/f/run.nml resolved.nml && "$AGGLO" resolved.nml > resolved.out 2>&1 \
   && grep -q 'from target_dissipation' resolved.out; then
  echo "PASS resolved_deck_with_unset_strengths_reads_back"
else echo "FAIL resolved_deck_with_unset_strengths_reads_back: $(grep -m1 error resolved.out 2>/dev/null)"; fi
