#!/usr/bin/env bash
# checks: 8
# Deck errors that only rank 0 (or each rank for itself) can see, on 2 ranks: the run directory
# (an earlier run without overwrite, restart without a run or without a checkpoint, a directory
# that cannot be made) and &fluid init_file (missing, not an HDF5 file). Each must stop every rank
# together: exit status 2 (error_handling: a collective stop, no MPI_Abort), and no hang (a rank
# left alone in a collective stop would wait for ever; deck_error_lib.sh stops it after
# stop_timeout seconds and fails the check).
set -u
AGGLO=${AGGLO:?AGGLO must point to the built executable}
. "$(cd "$(dirname "$0")" && pwd)/deck_error_lib.sh"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
expected_status=2
stop_timeout=60

# expect_clean_stop NAME DECK_TEXT TEXT...: on 2 ranks, status 2, every TEXT, and no MPI_Abort.
expect_clean_stop() {
  local name=$1 result
  result=$(expect_deck_error "$name" 2 "${@:2}")
  if [[ $result == PASS* ]] && grep -q 'MPI_ABORT' "$name.out"; then
    result="FAIL $name: stopped by MPI_Abort, not together: $(grep -m1 'agglo: error' "$name.out" | cut -c1-200)"
  fi
  echo "$result"
}

fluid="&scene fluid = 'resolved' /
&grid nx = 8, ny = 8, nz = 8, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /"

mkdir -p existing
echo "&run name = 'old' /" > existing/run.nml
expect_clean_stop existing_run_refused_on_2_ranks "&run name = 'a', end_time = 1.0e-9, dt = 1.0e-9 /
$fluid
&output directory = 'existing' /" '&output directory' 'overwrite = .true.'
grep -q "name = 'old'" existing/run.nml && echo "PASS existing_run_untouched_on_2_ranks" \
  || echo "FAIL existing_run_untouched_on_2_ranks: run.nml changed"
expect_clean_stop restart_without_run_on_2_ranks "&run name = 'fresh', restart = .true. /
$fluid
&output directory = 'nothing_here' /" '&run restart' 'no earlier run'
expect_clean_stop pair_restart_without_run_on_2_ranks "&run name = 'p', restart = .true. /
&scene fluid = 'none', particles = 'pair' /" '&run restart' 'no earlier run'
mkdir -p no_checkpoint
echo "&run name = 'old' /" > no_checkpoint/run.nml
expect_clean_stop restart_without_checkpoint_on_2_ranks "&run name = 'a', restart = .true. /
$fluid
&output directory = 'no_checkpoint' /" '&run restart = .true.' 'holds no complete and valid checkpoint'
touch not_a_directory
expect_clean_stop output_not_creatable_on_2_ranks "&run name = 'a' /
$fluid
&output directory = 'not_a_directory/sub' /" '&output directory' 'not_a_directory/sub'

expect_clean_stop init_file_missing_on_2_ranks "&run name = 'a', max_steps = 1 /
$fluid
&fluid init = 'file', init_file = 'no_such_field.h5' /
&output directory = 'init_missing' /" "&fluid init_file = 'no_such_field.h5'" 'an existing file'
echo 'plain text, not HDF5' > notes.h5
expect_clean_stop init_file_not_hdf5_on_2_ranks "&run name = 'a', max_steps = 1 /
$fluid
&fluid init = 'file', init_file = 'notes.h5' /
&output directory = 'init_not_hdf5' /" 'cannot open notes.h5' 'not an HDF5 file'
