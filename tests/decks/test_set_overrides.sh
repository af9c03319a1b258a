#!/usr/bin/env bash
# checks: 15
# agglo DECK --set group.variable=value: the override reaches the run (run.nml, the resolved deck),
# later values win, and a bad override is refused like a bad deck, by its name (docs/decks.md).
set -u
AGGLO=${AGGLO:?AGGLO must point to the built executable}
. "$(cd "$(dirname "$0")" && pwd)/deck_error_lib.sh"
montecarlo="$(cd "$(dirname "$0")/../.." && pwd)/tools/montecarlo.sh"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

cat > base.nml <<'DECK'
&run name = 'base', ! seed = 3 / a comment with a slash
     seed = 5, end_time = 1.0e-6, dt = 1.0e-7 /
&scene fluid = 'none', particles = 'pair' /
DECK

# resolved VARIABLE: its value in the run.nml of output/set (upper-case names, as written)
resolved() { sed -n "s/^ *$1=\([^,]*\),*\$/\1/p" output/set/run.nml | head -n 1 | tr -d " '\""; }

if "$AGGLO" base.nml --set "output.directory='output/set'" --set run.seed=41 --set run.seed=42 \
     --set "run.name='set'" --set collision.restitution=0.25 > run.out 2>&1 \
   && [ "$(resolved SEED)" = 42 ] && [ "$(resolved NAME)" = set ] \
   && [ "$(resolved RESTITUTION)" = 0.25000000000000000 ]; then
  echo "PASS set_values_reach_the_run"
else echo "FAIL set_values_reach_the_run: $(grep -m1 error run.out) SEED=$(resolved SEED) NAME=$(resolved NAME) RESTITUTION=$(resolved RESTITUTION)"; fi

# --print-deck: the merged text is a deck of its own that gives the same configuration.
"$AGGLO" base.nml --set run.seed=41 --set collision.restitution=0.25 --print-deck > merged.nml 2> merged.err
if grep -q '^  seed = 41$' merged.nml && grep -q "^&collision restitution = 0.25 /$" merged.nml \
   && [ "$(grep -c '&run' merged.nml)" -eq 1 ] && "$AGGLO" merged.nml --print-deck | cmp -s - merged.nml; then
  echo "PASS print_deck_merges_into_the_deck_text"
else echo "FAIL print_deck_merges_into_the_deck_text: $(head -c 300 merged.nml) $(head -c 200 merged.err)"; fi

extra_args=(--set run.dtt=1.0); expect_deck_file_error set_unknown_variable_named 1 base.nml '--set run.dtt=1.0' '&run'
extra_args=(--set rnu.seed=1); expect_deck_file_error set_unknown_group 1 base.nml "--set 'rnu.seed=1': unknown namelist group &rnu"
extra_args=(--set run.seed=abc); expect_deck_file_error set_wrong_type 1 base.nml 'cannot read namelist group &run (line 1 of --set run.seed=abc)'
extra_args=(--set seed=3); expect_deck_file_error set_without_group 1 base.nml "--set 'seed=3' is not allowed; allowed: GROUP.VARIABLE=VALUE"
extra_args=(--set run.seed=); expect_deck_file_error set_without_value 1 base.nml 'no value after "="'
extra_args=(--set "run.name='open"); expect_deck_file_error set_unclosed_quote 1 base.nml "--set run.name='open" 'not closed on its line'
extra_args=(--set "run.seed=1 / &grid nx = 4"); expect_deck_file_error set_value_closing_group 1 base.nml 'the value ends the group'
extra_args=(--set pair.gap=0.0); expect_deck_file_error set_checked_like_the_deck 1 base.nml '&pair gap = 0.00000E+00' '> 0'
extra_args=(--set run.dt=NaN); expect_deck_file_error set_not_finite 1 base.nml '&run dt = NaN' 'finite numbers'
extra_args=(--set); expect_deck_file_error set_without_argument 1 base.nml '--set needs group.variable=value'
extra_args=(other.nml); expect_deck_file_error second_deck_refused 1 base.nml 'unknown argument "other.nml"'
extra_args=()

# tools/montecarlo.sh has no namelist parser of its own: its --set goes to the code, which refuses a
# bad one by name and merges a good one into every run's deck.
"$montecarlo" --deck base.nml --runs 2 --seed 9 --out "mc bad" --agglo "$AGGLO" --slurm --set run.dtt=1 > mc_bad.out 2>&1
status=$?
if [ $status -eq 2 ] && grep -q 'refused by the code: agglo: error: .*--set run.dtt=1.*dtt' mc_bad.out && [ ! -e "mc bad/batch.nml" ]; then
  echo "PASS montecarlo_set_refused_by_the_code"
else echo "FAIL montecarlo_set_refused_by_the_code: status $status, $(head -c 300 mc_bad.out)"; fi
"$montecarlo" --deck base.nml --runs 2 --seed 9 --out "mc good" --agglo "$AGGLO" --slurm --set run.dt=2.0e-8 > mc_good.out 2>&1
if "$AGGLO" "mc good/run_0002/deck.nml" --print-deck > run2.nml 2>&1 && grep -q '^  dt = 2.0e-8$' run2.nml \
   && grep -q "^  name = 'run_0002'$" run2.nml && grep -q '^  seed = 10$' run2.nml && grep -q '^  overwrite = .true.$' run2.nml; then
  echo "PASS montecarlo_run_deck_merged_by_the_code"
else echo "FAIL montecarlo_run_deck_merged_by_the_code: $(head -c 400 "mc good/run_0002/deck.nml" 2>&1) $(tail -n 2 mc_good.out)"; fi
