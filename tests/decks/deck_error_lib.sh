# Shared by the deck-error tests (sourced): run the built executable ($AGGLO) on a deck that must be
# refused, and check the exit status and the message (docs/decks.md, "Errors").
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

# Extra command-line arguments after the deck (e.g. extra_args=(--set run.seed=4)); empty by default.
extra_args=()

# expect_deck_error NAME RANKS DECK_TEXT TEXT...: the run fails (non-zero exit) and its output
# contains every TEXT (fixed strings). One rank runs without mpirun (faster start).
expect_deck_error() {
  local name=$1 ranks=$2 deck=$3; shift 3
  printf '%s\n' "$deck" > "$name.nml"
  expect_deck_file_error "$name" "$ranks" "$name.nml" "$@"
}

# expect_deck_file_error NAME RANKS FILE TEXT...: the same for a deck file as it is (any bytes).
expect_deck_file_error() {
  local name=$1 ranks=$2 file=$3; shift 3
  if [ "$ranks" -eq 1 ]; then "$AGGLO" "$file" "${extra_args[@]}" > "$name.out" 2>&1; else
    mpirun -np "$ranks" "$AGGLO" "$file" "${extra_args[@]}" > "$name.out" 2>&1; fi
  local status=$? text
  if [ $status -eq 0 ]; then echo "FAIL $name: exit status 0 for a bad deck"; return; fi
  for text in "$@"; do
    if ! grep -qF -- "$text" "$name.out"; then
      echo "FAIL $name: message lacks \"$text\": $(grep -m1 'agglo: error' "$name.out" | cut -c1-300)"; return
    fi
  done
  echo "PASS $name  ($(grep -m1 'agglo: error' "$name.out" | cut -c1-150))"
}
