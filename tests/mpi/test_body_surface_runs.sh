#!/usr/bin/env bash
# checks: 11
# The bodies' surfaces in the field snapshots (docs/outputs.md, "Bodies in the snapshots"), end to
# end with $AGGLO; checked by check_body_surfaces.py (python3 standard library and h5dump):
#  - prescribed bodies (a translating sphere, a rotating needle that crosses the periodic wrap):
#    fields.xdmf parses and has the Triangle grids body_1, body_2 at every time, each HDF DataItem
#    names a dataset of the stated shape; every vertex lies on its spheroid at the pose stored next
#    to it (to 1e-12 of the quadric), the faces point outward; 2 ranks write the same surfaces as 1;
#  - restart: a run to step 10 (snapshots 0, 4, 8, 10) continued from its checkpoint of step 8 to 12
#    drops the snapshot of step 10 (and its surfaces) from the directory, the manifest and
#    fields.xdmf, and ends with the uninterrupted run's series (steps 0, 4, 8, 12, same surfaces);
#  - the pair in the resolved fluid (point coupling, a random initial field, the pair across the
#    periodic boundary): both disks in every snapshot, on their spheroids; 5 steps + restart to 10
#    gives the uninterrupted run's surfaces bit for bit.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
checker=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)/check_body_surfaces.py
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

pass_fail() { # name, command...: PASS when the command succeeds, else FAIL with its output
  local name=$1; shift
  if "$@" > check.out 2>&1; then echo "PASS $name: $(tail -n 1 check.out)"
  else echo "FAIL $name: $(tr '\n' ' ' < check.out | cut -c1-300)"; fi
}

prescribed() { # directory, max_steps, restart
  cat <<NML
&run name = '$1', max_steps = $2, end_time = 1.0, dt = 4.0e-6, dt_mode = 'fixed', overwrite = .true.,
     restart = $3, progress_interval = 4 /
&scene fluid = 'resolved', particles = 'prescribed', ibm_coupling = 'implicit' /
&grid nx = 24, ny = 24, nz = 24, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, init = 'rest', pressure_scheme = 'incremental' /
&bodies count = 2,
  shape(1) = 'sphere', radius(1) = 1.6e-4, centre(:,1) = 0.3e-3, 0.4e-3, 0.5e-3, velocity(:,1) = 2.0e-3, 0.0, 1.0e-3,
  shape(2) = 'needle', radius(2) = 1.3e-4, aspect_ratio(2) = 2.0, centre(:,2) = 0.7e-3, 0.6e-3, 0.98e-3,
  axis(:,2) = 1.0, 1.0, 0.5, angular_velocity(:,2) = 0.0, 30.0, 10.0, velocity(:,2) = 0.0, 0.0, 2.0e-3 /
&output directory = '$1', checkpoint_interval = 4, checkpoints_kept = 3, field_interval = 1.6e-5 /
NML
}
run() { # ranks, deck file
  mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1 || { echo "FAIL run_$2: exit status $? ($(tail -n 2 "$2.out"))"; return 1; }
}

# --- prescribed bodies: one run, 2 ranks, restart ------------------------------------------------
prescribed full 12 .false. > full.nml
prescribed ranks 12 .false. > ranks.nml
prescribed cut 10 .false. > cut.nml
prescribed cut 12 .true. > cut_restart.nml
if run 1 full.nml && run 2 ranks.nml; then
  pass_fail prescribed_xdmf_grids_and_datasets python3 "$checker" full xdmf 2
  pass_fail prescribed_vertices_on_spheroids python3 "$checker" full geometry
  pass_fail prescribed_two_ranks_same_surfaces python3 "$checker" ranks same full
fi
if run 1 cut.nml; then
  rm -f cut/checkpoints/checkpoint_0000000010.h5   # the run "was killed" after its snapshot of step 10
  if [ -f cut/fields_0000000010.h5 ] && run 1 cut_restart.nml; then
    pass_fail restart_series_steps python3 "$checker" cut steps 0,4,8,12
    pass_fail restart_same_surfaces_as_uninterrupted python3 "$checker" cut same full
    pass_fail restart_xdmf_grids_and_datasets python3 "$checker" cut xdmf 2
    if [ ! -e cut/fields_0000000010.h5 ] && ! grep -q 'fields_0000000010' cut/agglo_manifest.txt \
       && grep -q 'fields_0000000010.h5 .*removed' cut/agglo.log; then
      echo "PASS restart_abandoned_snapshot_removed_and_forgotten"
    else
      echo "FAIL restart_abandoned_snapshot_removed_and_forgotten: fields_0000000010.h5 in the directory," \
           "the manifest, or not logged"
    fi
  else
    echo "FAIL restart_series_steps: the interrupted run left no snapshot of step 10 or the restart failed"
  fi
fi

# --- the pair in the resolved fluid --------------------------------------------------------------
pair_deck() { # name, max_steps, restart
  cat <<NML
&run name = '$1', seed = 1, end_time = 2.0e-4, dt = 2.0e-5, dt_mode = 'fixed', max_steps = $2, restart = $3,
     overwrite = .true., progress_interval = 100 /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'point', particle_substeps = 10 /
&grid nx = 8, ny = 8, nz = 8, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'random', init_amplitude = 1.0e-3 /
&pair shape = 'disk', aspect_ratio = 5.0, radius = 50.0e-6, density = 2710.0, orientation = 'random',
      gap = 5.0e-6, relative_speed = 0.875e-3, centre = 'given', centre_position = 0.99e-3, 0.5e-3, 0.5e-3 /
&output stats_interval = 10, field_interval = 1.0e-4, checkpoint_interval = 0 /
NML
}
pair_deck pair 1000 .false. > pair.nml
pair_deck pair_cut 5 .false. > pair_cut.nml
pair_deck pair_cut 1000 .true. > pair_cut_restart.nml
if run 1 pair.nml; then
  pass_fail pair_xdmf_grids_and_datasets python3 "$checker" output/pair xdmf 2
  pass_fail pair_vertices_on_spheroids python3 "$checker" output/pair geometry
  pass_fail pair_series_steps python3 "$checker" output/pair steps 0,5,10
  # 5 steps, then restart to the end: the same bodies at the same steps (bit for bit).
  if run 1 pair_cut.nml && run 1 pair_cut_restart.nml; then
    pass_fail pair_restart_same_surfaces python3 "$checker" output/pair_cut same output/pair
  fi
fi
