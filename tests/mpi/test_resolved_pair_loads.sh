#!/usr/bin/env bash
# checks: 3
# The free pair's hydrodynamic load histories (&scene particle_coupling = 'resolved'; docs/outputs.md,
# "The free pair's loads"), with $AGGLO on a small forced sphere-pair deck, 1 rank:
#  - bodies_loads.dat has one row per body per fluid step, 25 columns, steps 1..16 in order;
#  - without the added-mass stabilisation (&scene added_mass = .false.) and without gravity the
#    load a particle feels is the immersed boundary's own: particles.h5's force_hydrodynamic and
#    torque_hydrodynamic at the end of each fluid step (a sample every particle_substeps sub-steps)
#    equal the file's force and torque columns of that step (to 1e-14 relative: the file is
#    written with 17 significant digits);
#  - restart: 8 fluid steps + &run restart to 16 give the same file as 16 steps in one go (the
#    rows after the checkpoint dropped, byte for byte).
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

pair_deck() { # directory, max_steps, restart
  cat <<NML
&run name = 'spheres', seed = 5, max_steps = $2, restart = $3, end_time = 1.0, dt = 1.0e-5, dt_mode = 'cfl',
     cfl_target = 0.4, progress_interval = 1000 /
&scene fluid = 'resolved', particles = 'pair', particle_coupling = 'resolved', particle_substeps = 10,
       forcing = 'eswaran_pope', added_mass = .false. /
&grid nx = 32, ny = 32, nz = 32, length_x = 0.25e-3, length_y = 0.25e-3, length_z = 0.25e-3 /
&fluid density = 997.0, viscosity = 1.0e-6, init = 'random', init_amplitude = 0.002, init_peak_wavenumber = 2.0 /
&forcing time_scale = 0.01, target_dissipation = 1.0e-5, statistics_interval = 0 /
&bodies max_sweeps = 1000 /
&pair shape = 'sphere', radius = 40.0e-6, density = 2710.0, gap = 2.0e-6, relative_speed = 4.2e-3,
      approach = 'given', approach_direction = 1.0, 0.2, 0.6, centre = 'given',
      centre_position = 0.125e-3, 0.125e-3, 0.126e-3, relative_to_fluid = .true. /
&dlvo hamaker = 22.3e-21, debye_kappa = 328947368.0, surface_charge_density = 3.7e-4, vdw_cutoff = 5.0e-9 /
&collision restitution = 0.4, detection_floor = 1.0e-9 /
&output directory = '$1', stats_interval = 10, checkpoint_interval = 8, checkpoints_kept = 5, field_interval = 0.0 /
NML
}
# The numbers of one dataset, one per line.
dataset() { # file, dataset
  h5dump -d "$2" -y -w 0 -m %.17g "$1" | sed -n '/DATA {/,/}/p' | grep -Eo '[-+0-9.eE]+' ; }

pair_deck whole 16 .false. > whole.nml
pair_deck split 8 .false. > splita.nml
pair_deck split 16 .true. > splitb.nml
if mpirun -np 1 "$AGGLO" whole.nml > whole.out 2>&1; then
  for q in force torque; do
    for p in 1 2; do dataset whole/particles.h5 /particle$p/${q}_hydrodynamic > ${q}$p.txt; done
  done
  # A crash of the check prints its traceback (the log) and a FAIL line, never nothing.
  python3 - <<'PY' || echo "FAIL resolved_pair_loads/python_check: the embedded Python check crashed (traceback above)"
import sys
rows = [line.split() for line in open('whole/bodies_loads.dat') if not line.startswith('#')]
ok_shape = len(rows) == 32 and all(len(r) == 25 for r in rows) \
    and [int(r[0]) for r in rows] == [s for s in range(1, 17) for _ in (1, 2)] \
    and [int(r[2]) for r in rows] == [1, 2] * 16
print(('PASS' if ok_shape else 'FAIL') + ' resolved_pair_loads/bodies_loads_one_row_per_body_and_step  '
      f'({len(rows)} rows of {sorted(set(len(r) for r in rows))} columns; expected 32 rows of 25, steps 1..16)')
worst, scale = 0.0, 0.0
for quantity, columns in (('force', slice(3, 6)), ('torque', slice(6, 9))):
    for body in (1, 2):
        values = [float(x) for x in open(f'{quantity}{body}.txt')]
        samples = [values[3 * n:3 * n + 3] for n in range(len(values) // 3)]
        felt = samples[1:17]          # row 0 is the start (t = 0); rows 1..16 end fluid steps 1..16
        written = [[float(x) for x in r[columns]] for r in rows if int(r[2]) == body]
        if len(felt) != 16 or len(written) != 16:
            print(f'FAIL resolved_pair_loads/felt_load_is_the_written_one: {len(felt)} samples, {len(written)} rows')
            sys.exit(0)
        size = max(abs(v) for row in written for v in row)
        scale = max(scale, size)
        worst = max(worst, max(abs(a - b) / size for fa, wa in zip(felt, written) for a, b in zip(fa, wa)))
print(('PASS' if worst <= 1e-14 and scale > 0 else 'FAIL') + ' resolved_pair_loads/felt_load_is_the_written_one  '
      f'largest difference / largest load {worst:.2e} <= 1e-14 (force and torque, both bodies, 16 steps)')
PY
else
  echo "FAIL resolved_pair_loads/bodies_loads_one_row_per_body_and_step: the run failed: $(tail -n 3 whole.out | head -c 300)"
fi
if mpirun -np 1 "$AGGLO" splita.nml > splita.out 2>&1 && mpirun -np 1 "$AGGLO" splitb.nml > splitb.out 2>&1 \
   && grep -q 'continuing from' splitb.out && cmp -s whole/bodies_loads.dat split/bodies_loads.dat; then
  echo "PASS resolved_pair_loads/restart_continues_bodies_loads_byte_for_byte  (8 + restart + 8 = 16 fluid steps)"
else
  echo "FAIL resolved_pair_loads/restart_continues_bodies_loads_byte_for_byte: $(tail -n 2 splitb.out | head -c 300)"
fi
