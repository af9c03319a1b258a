# Shared by the deck-error tests (sourced): run the built executable ($AGGLO) on a deck that must be
# refused, and check the exit status and the message (docs/decks.md, "Errors").
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

# Extra command-line arguments after the deck (e.g. extra_args=(--set run.seed=4)); empty by default.
extra_args=()
# The exit status a refused deck must give: any non-zero one if empty; 2 is the clean stop of an error
# every rank knows (no MPI_Abort). A run on several ranks that has not ended after stop_timeout
# seconds is a failure (a rank left alone in a collective stop waits for ever).
expected_status=''
stop_timeout=120

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
    timeout "$stop_timeout" mpirun -np "$ranks" "$AGGLO" "$file" "${extra_args[@]}" > "$name.out" 2>&1; fi
  local status=$? text
  if [ $status -eq 0 ]; then echo "FAIL $name: exit status 0 for a bad deck"; return; fi
  if [ "$ranks" -gt 1 ] && [ $status -eq 124 ]; then
    echo "FAIL $name: still running after $stop_timeout s on $ranks ranks (a rank waits in a stop): $(grep -m1 'agglo: error' "$name.out" | cut -c1-200)"
    return
  fi
  if [ -n "$expected_status" ] && [ $status -ne "$expected_status" ]; then
    echo "FAIL $name: exit status $status, not $expected_status: $(grep -m1 'agglo: error' "$name.out" | cut -c1-200)"; return
  fi
  for text in "$@"; do
    if ! grep -qF -- "$text" "$name.out"; then
      echo "FAIL $name: message lacks \"$text\": $(grep -m1 'agglo: error' "$name.out" | cut -c1-300)"; return
    fi
  done
  echo "PASS $name  ($(grep -m1 'agglo: error' "$name.out" | cut -c1-150))"
}
