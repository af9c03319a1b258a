#!/usr/bin/env bash
# checks: 6
# End-to-end runs with the face-sum loads and the mesh geometry (&bodies load_method = 'surface',
# geometry = 'mesh', mesh_level; docs/decks.md, docs/outputs.md bodies_loads.dat):
#  - a fixed sphere and a rotating needle in a driven box on the icosphere of 80 faces, 1 and 2
#    ranks: bodies_loads.dat has one row of 25 columns per body per step, the written force and
#    torque are the face-sum columns, the momentum columns are filled, and every load equals the
#    other rank count's to 1e-10 of the largest (each probe is evaluated by one rank, the Jacobi
#    sweeps do not depend on the ranks); the log compares both methods;
#  - with load_method = 'momentum' the face sum is not computed (its columns zero, no comparison in
#    the log) unless compare_loads = .true., which fills them with the values of the 'surface' run;
#  - refused decks naming the variable: an unknown geometry, mesh_level 5.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, geometry, mesh_level
  cat <<NML
&run name = '$1', max_steps = 8, end_time = 1.0, dt = 4.0e-6, dt_mode = 'fixed', overwrite = .true. /
&scene fluid = 'resolved', particles = 'prescribed', ibm_coupling = 'implicit' /
&grid nx = 24, ny = 24, nz = 24, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'explicit', init = 'rest', pressure_scheme = 'incremental' /
&bodies count = 2,
  shape(1) = 'sphere', radius(1) = 1.6e-4, centre(:,1) = 0.3e-3, 0.4e-3, 0.5e-3,
  shape(2) = 'needle', radius(2) = 1.3e-4, aspect_ratio(2) = 2.0, centre(:,2) = 0.7e-3, 0.6e-3, 0.52e-3,
  axis(:,2) = 1.0, 1.0, 0.5, angular_velocity(:,2) = 0.0, 30.0, 10.0,
  driving_force = 5.0, 0.0, -2.0, load_method = 'surface', geometry = '$2', mesh_level = $3 /
&output directory = '$1', checkpoint_interval = 0, field_interval = 0.0 /
NML
}
run() { # ranks, deck file
  mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1
}

deck one mesh 1 > one.nml
deck two mesh 1 > two.nml
if run 1 one.nml && run 2 two.nml; then
  if python3 - one/bodies_loads.dat two/bodies_loads.dat > cmp.txt 2>&1 <<'PY'
import sys
a = [l.split() for l in open(sys.argv[1]) if not l.startswith('#')]
b = [l.split() for l in open(sys.argv[2]) if not l.startswith('#')]
assert len(a) == len(b) == 16, f'rows {len(a)} {len(b)} (16 = 2 bodies x 8 steps)'
assert all(len(r) == 25 for r in a + b), 'a row without 25 columns'
# Written force and torque (columns 4-9) are the surface ones (20-25); the momentum ones (14-19) are filled.
assert all(r[3:9] == r[19:25] for r in a), 'force/torque columns differ from the surface columns'
assert all(any(float(x) != 0.0 for x in r[13:19]) for r in a), 'momentum columns empty'
scale = max(abs(float(x)) for r in a for x in r[3:9] + r[13:25])
worst = max(abs(float(x) - float(y)) for r, s in zip(a, b) for x, y in zip(r[3:9] + r[13:25], s[3:9] + s[13:25]))
assert scale > 0 and worst <= 1e-10 * scale, f'worst {worst:.3e} scale {scale:.3e}'
print(f'worst difference {worst:.2e} of largest load {scale:.2e}')
PY
  then
    echo "PASS immersed_surface_runs/surface_loads_written_and_one_two_ranks_equal  ($(cat cmp.txt))"
  else
    echo "FAIL immersed_surface_runs/surface_loads_written_and_one_two_ranks_equal: $(head -c 400 cmp.txt)"
  fi
  if grep -q 'last step |F| momentum' two.nml.out; then
    echo "PASS immersed_surface_runs/log_compares_methods  ($(grep -m1 'last step |F| momentum' two.nml.out | head -c 200))"
  else
    echo "FAIL immersed_surface_runs/log_compares_methods: no comparison line in the log"
  fi
else
  echo "FAIL immersed_surface_runs/surface_loads_written_and_one_two_ranks_equal: a run failed: $(tail -n 3 one.nml.out two.nml.out | head -c 400)"
fi

# The face sum only when asked for: 'momentum' alone leaves its columns zero; compare_loads fills
# them, and they equal the 1-rank 'surface' run's face sum to round-off (the same computation).
deck moment mesh 1 | sed "s/load_method = 'surface'/load_method = 'momentum'/" > moment.nml
deck compare mesh 1 | sed "s/load_method = 'surface'/load_method = 'momentum', compare_loads = .true./" > compare.nml
if run 1 moment.nml && run 1 compare.nml; then
  if python3 - moment/bodies_loads.dat compare/bodies_loads.dat one/bodies_loads.dat > cmp.txt 2>&1 <<'PY'
import sys
rows = lambda name: [l.split() for l in open(name) if not l.startswith('#')]
moment, compare, surface = rows(sys.argv[1]), rows(sys.argv[2]), rows(sys.argv[3])
assert all(float(x) == 0.0 for r in moment for x in r[19:25]), 'face-sum columns filled without compare_loads'
assert all(r[3:9] == r[13:19] for r in compare), 'written loads are not the momentum ones'
scale = max(abs(float(x)) for r in surface for x in r[19:25])
worst = max(abs(float(x) - float(y)) for r, s in zip(compare, surface) for x, y in zip(r[19:25], s[19:25]))
assert scale > 0 and worst <= 1e-12 * scale, f'face sum differs from the surface run by {worst:.2e} of {scale:.2e}'
print(f'momentum only: face sum zero; compare_loads: face sum = surface run to {worst:.1e}')
PY
  then
    echo "PASS immersed_surface_runs/face_sum_only_when_asked  ($(cat cmp.txt))"
  else
    echo "FAIL immersed_surface_runs/face_sum_only_when_asked: $(head -c 400 cmp.txt)"
  fi
  if grep -q 'last step |F| momentum' moment.nml.out; then
    echo "FAIL immersed_surface_runs/no_comparison_without_face_sum: the log compares a face sum not computed"
  else
    echo "PASS immersed_surface_runs/no_comparison_without_face_sum"
  fi
else
  echo "FAIL immersed_surface_runs/face_sum_only_when_asked: a run failed: $(tail -n 3 moment.nml.out compare.nml.out | head -c 400)"
fi

refused() { # test name, deck file, expected text in the message
  if run 1 "$2"; then
    echo "FAIL immersed_surface_runs/$1: the deck ran"
  elif grep -q "$3" "$2.out"; then
    echo "PASS immersed_surface_runs/$1  ($(grep -m1 "$3" "$2.out" | head -c 200))"
  else
    echo "FAIL immersed_surface_runs/$1: message without '$3': $(tail -n 3 "$2.out" | head -c 300)"
  fi
}
deck geometry triangles 2 > geometry.nml
refused refuses_unknown_geometry geometry.nml 'geometry'
deck level mesh 5 > level.nml
refused refuses_mesh_level_5 level.nml 'mesh_level'
