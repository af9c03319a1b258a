#!/usr/bin/env bash
# checks: 7
# End-to-end runs of the prescribed-body scene with Crank-Nicolson diffusion (&fluid viscous_scheme =
# 'crank_nicolson'): the predictor's system holds the immersed-boundary rows and is solved with
# hypre (docs/theory.md, "Linear solver (hypre)"):
#  - a translating sphere and a rotating needle in a driven box at nu dt / dx^2 = 0.5 (above the
#    explicit-diffusion limit 1/12), 1 rank and 2 ranks (a body crosses the rank boundary and the
#    periodic wrap): every load in bodies_loads.dat equal to 1e-9 of the largest load (the Krylov
#    solve converges to 1e-12 on both; only the order of the sums differs), for both couplings;
#  - the log names the Krylov iterations and the residual;
#  - non-convergence stops the run with the iterations, the residual and the advice;
#  - &fluid predictor_tolerance out of range is refused naming the variable;
#  - a restart continues bodies_loads.dat bit for bit.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"

deck() { # name, coupling, predictor_tolerance, predictor_max_iterations
  cat <<NML
&run name = '$1', max_steps = 8, end_time = 1.0, dt = 5.0e-4, dt_mode = 'fixed', overwrite = .true.,
     progress_interval = 4 /
&scene fluid = 'resolved', particles = 'prescribed', ibm_coupling = '$2' /
&grid nx = 32, ny = 32, nz = 32, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&fluid viscosity = 1.0e-6, viscous_scheme = 'crank_nicolson', init = 'rest', pressure_scheme = 'incremental',
       predictor_tolerance = $3, predictor_max_iterations = $4 /
&bodies count = 2,
  shape(1) = 'sphere', radius(1) = 1.6e-4, centre(:,1) = 0.3e-3, 0.4e-3, 0.5e-3,
  velocity(:,1) = 2.0e-5, 0.0, 1.0e-5,
  shape(2) = 'needle', radius(2) = 1.3e-4, aspect_ratio(2) = 2.0, centre(:,2) = 0.7e-3, 0.6e-3, 0.98e-3,
  axis(:,2) = 1.0, 1.0, 0.5, angular_velocity(:,2) = 0.0, 0.3, 0.1,
  driving_force = 5.0, 0.0, -2.0 /
&output directory = '$1', checkpoint_interval = 0, field_interval = 0.0 /
NML
}
run() { # ranks, deck file
  mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1
}

for coupling in implicit explicit; do
  deck one_$coupling $coupling 1.0e-12 200 > one_$coupling.nml
  deck two_$coupling $coupling 1.0e-12 200 > two_$coupling.nml
  if run 1 one_$coupling.nml && run 2 two_$coupling.nml; then
    if python3 - one_$coupling/bodies_loads.dat two_$coupling/bodies_loads.dat > cmp.txt 2>&1 <<'PY'
import sys
a = [l.split() for l in open(sys.argv[1]) if not l.startswith('#')]
b = [l.split() for l in open(sys.argv[2]) if not l.startswith('#')]
assert len(a) == len(b) == 16, f'rows {len(a)} {len(b)} (16 = 2 bodies x 8 steps)'
scale = max(abs(float(x)) for r in a for x in r[3:9])
worst = max(abs(float(x) - float(y)) for r, s in zip(a, b) for x, y in zip(r[3:9], s[3:9]))
assert scale > 0 and worst <= 1e-9 * scale, f'worst {worst:.3e} scale {scale:.3e}'
print(f'worst difference {worst:.2e} of largest load {scale:.2e}')
PY
    then
      echo "PASS immersed_cn_runs/${coupling}_one_and_two_ranks_equal  ($(cat cmp.txt))"
    else
      echo "FAIL immersed_cn_runs/${coupling}_one_and_two_ranks_equal: $(head -c 400 cmp.txt)"
    fi
    if grep -q 'immersed boundary: Krylov iterations [0-9]*, residual' two_$coupling.nml.out; then
      echo "PASS immersed_cn_runs/${coupling}_log_names_iterations  ($(grep 'Krylov iterations' two_$coupling.nml.out | tail -n 1 | head -c 160))"
    else
      echo "FAIL immersed_cn_runs/${coupling}_log_names_iterations: no Krylov iterations line in the log"
    fi
  else
    echo "FAIL immersed_cn_runs/${coupling}_one_and_two_ranks_equal: a run failed: $(tail -n 3 ./*_$coupling.nml.out | head -c 400)"
  fi
done

refused() { # test name, deck file, expected text in the message
  if run 1 "$2"; then
    echo "FAIL immersed_cn_runs/$1: the deck ran"
  elif grep -q "$3" "$2.out"; then
    echo "PASS immersed_cn_runs/$1  ($(grep -m1 "$3" "$2.out" | head -c 300))"
  else
    echo "FAIL immersed_cn_runs/$1: message without '$3': $(tail -n 3 "$2.out" | head -c 300)"
  fi
}
deck stuck implicit 1.0e-14 2 > stuck.nml
refused stops_when_not_converged stuck.nml 'did not converge in 2 iterations (relative residual .* > tolerance .*smaller &run dt'
deck loose implicit 0.5 200 > loose.nml
refused refuses_loose_tolerance loose.nml 'predictor_tolerance = '

# Restart: checkpointed at step 4, the last checkpoint (step 8) deleted as if killed there,
# restarted: bodies_loads.dat equals the uninterrupted run's to the bit (the Krylov solve starts
# from u^n, which the checkpoint holds, and its matrices are rebuilt from the bodies' placement).
deck restart implicit 1.0e-10 200 | sed 's/checkpoint_interval = 0/checkpoint_interval = 4/' > restart.nml
if run 1 restart.nml && cp restart/bodies_loads.dat uninterrupted.dat && rm restart/checkpoints/checkpoint_0000000008.h5 \
   && mpirun -np 1 "$AGGLO" restart.nml --set run.restart=.true. > restart.out 2>&1; then
  if cmp -s uninterrupted.dat restart/bodies_loads.dat; then
    echo "PASS immersed_cn_runs/restart_continues_loads_bit_for_bit  ($(grep -vc '^#' restart/bodies_loads.dat) rows)"
  else
    echo "FAIL immersed_cn_runs/restart_continues_loads_bit_for_bit: $(diff uninterrupted.dat restart/bodies_loads.dat | head -c 300)"
  fi
else
  echo "FAIL immersed_cn_runs/restart_continues_loads_bit_for_bit: a run failed: $(tail -n 3 restart.out restart.nml.out 2>/dev/null | head -c 400)"
fi
