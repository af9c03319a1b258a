#!/usr/bin/env bash
# checks: 56
# Every shipped deck (input/*.nml) is accepted by the deck checks as it is (agglo --print-deck reads
# and checks it like a run, then prints the merged deck), and none sets &run overwrite = .true.: a
# copied deck must never replace an earlier run (README, docs/decks.md &run overwrite).
set -u
cd "$(dirname "$0")/../.."
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
for deck in input/*.nml; do
  name=$(basename "$deck" .nml)
  if (cd "$work" && "$AGGLO" "$OLDPWD/$deck" --print-deck > "$name.out" 2>&1); then
    echo "PASS shipped_deck_accepted_$name"
  else
    echo "FAIL shipped_deck_accepted_$name: $(grep -m1 'agglo: error' "$work/$name.out" | cut -c1-200)"
  fi
  if grep -qiE '^[[:space:]]*overwrite[[:space:]]*=[[:space:]]*\.?t' "$deck"; then
    echo "FAIL shipped_deck_keeps_earlier_runs_$name: sets &run overwrite"
  else
    echo "PASS shipped_deck_keeps_earlier_runs_$name"
  fi
done
