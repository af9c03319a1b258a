#!/usr/bin/env bash
# Runs the validation decks (validation/decks/*.nml) through agglo itself and checks each run with
# validation/check_deck.py, which prints one Markdown table row per case:
#   | case | reference | measured | error | tolerance |
#
#   validation/run.sh [CASE...]        (no CASE: every case; `make validate-decks` runs them all)
#
# Cases (one table row each): sphere_array (D/dx 8) and sphere_array_d16 (D/dx 16, 2 ranks) against
# Zick & Homsy 1982; rotating (D/dx 8 in three boxes) against 8 pi mu a^3 Omega; oscillating against
# Stokes 1851 with the box correction; settling (a free sphere under gravity) against Zick & Homsy;
# released (a free sphere started at U_0) against the unsteady Stokes decay. Environment: AGGLO (the
# executable, default build/agglo), AGGLO_PYTHON (default .venv/bin/python: h5py, numpy),
# VALIDATION_OUT (the runs' directories, default build/validation-decks; each run replaces its
# earlier one), MPIRUN (default `mpirun --oversubscribe`). Exit status: the number of cases outside
# their tolerance or whose run failed.
set -u
repo=$(cd "$(dirname "$0")/.." && pwd)
agglo=${AGGLO:-$repo/build/agglo}
python=${AGGLO_PYTHON:-$repo/.venv/bin/python}
out=${VALIDATION_OUT:-$repo/build/validation-decks}
mpirun=${MPIRUN:-mpirun --oversubscribe}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
decks=$repo/validation/decks

# case: check name, ranks, decks
declare -A check=([sphere_array]=sphere_array [sphere_array_d16]=sphere_array [rotating]=rotating
                  [oscillating]=oscillating [settling]=settling [released]=released)
declare -A ranks=([sphere_array]=1 [sphere_array_d16]=2 [rotating]=1 [oscillating]=1 [settling]=1 [released]=1)
declare -A deck_list=([sphere_array]='sphere_array_d8' [sphere_array_d16]='sphere_array_d16'
                      [oscillating]='oscillating_sphere' [settling]='settling_sphere'
                      [released]='released_sphere'
                      [rotating]='rotating_sphere_d8_box2 rotating_sphere_d8_box3 rotating_sphere_d8_box4')
order=(sphere_array sphere_array_d16 rotating oscillating settling released)

cases=("$@"); [ ${#cases[@]} -eq 0 ] && cases=("${order[@]}")
[ -x "$agglo" ] || { echo "validation/run.sh: no executable $agglo (make build)" >&2; exit 2; }
mkdir -p "$out"
failed=0
echo '| case | reference | measured | error | tolerance |'
echo '|---|---|---|---|---|'
for c in "${cases[@]}"; do
  if [ -z "${check[$c]:-}" ]; then
    echo "validation/run.sh: unknown case '$c'; cases: ${order[*]}" >&2; exit 2
  fi
  runs=()
  for d in ${deck_list[$c]}; do
    if ! $mpirun -np "${ranks[$c]}" "$agglo" "$decks/$d.nml" --set "output.directory='$out/$d'" \
         --set run.overwrite=.true. > "$out/$d.log" 2>&1; then
      echo "| $c | | run of $d failed (log: $out/$d.log) | | |"; failed=$((failed + 1)); continue 2
    fi
    runs+=("$out/$d")
  done
  "$python" "$repo/validation/check_deck.py" "${check[$c]}" "${runs[@]}" 2> "$out/$c.check.log" \
    || failed=$((failed + 1))
done
exit $failed
