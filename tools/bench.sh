#!/usr/bin/env bash
# Agglo benchmark (`make bench`): fluid time per step and its parts at 64^3 and 128^3 on 1 and 2
# ranks, and the Poisson solve against one forward + inverse 3-D FFT of the same grid; the staged
# step against the fused one with each stage against the memory-bandwidth floor (BENCH_PARTS=stages);
# the coupled step with immersed bodies against the fluid-only step, by part and against the number
# of bodies (BENCH_PARTS=immersed); the coupled step with 10^3 to 10^5 point particles against the
# particle-free step, by stage (BENCH_PARTS=point).
# Medians over repetitions (the machine may be shared: compare ratios; poisson = the in-buffer solve
# the step uses, pois(copy) = the poisson_solve API with its copies in and out). Results: docs/studies/performance.md.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
make --no-print-directory -s build "$BUILD/bench/bench_fluid" "$BUILD/bench/bench_pair" \
  "$BUILD/bench/bench_forcing" "$BUILD/bench/bench_stages" "$BUILD/bench/bench_immersed"
BUILD=$(cd "$BUILD" && pwd -P)   # absolute from here on: the programs run from a work directory
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
exe=$BUILD/bench/bench_fluid
pair_exe=$BUILD/bench/bench_pair
forcing_exe=$BUILD/bench/bench_forcing
stages_exe=$BUILD/bench/bench_stages
immersed_exe=$BUILD/bench/bench_immersed
agglo=$BUILD/agglo
parts=${BENCH_PARTS:-fluid stages pair forcing immersed point cn}   # e.g. BENCH_PARTS=pair make bench
echo "Agglo fluid benchmark on $(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "compiler: $(mpifort --version | head -n 1); flags: $(cat "$BUILD/flags.txt" 2>/dev/null); FFTW_ESTIMATE plans"
if [[ $parts == *fluid* ]]; then
echo "    N  R  fft_pair   poisson      step  adv+diff   proj(P)      halo    io(4f) pois(copy)  [ms, medians]  ns/pt/step  poisson/fft  step/fft"
for n in 64 128; do
  steps=$(( n == 64 ? 40 : 15 ))
  for ranks in 1 2; do
    line=$(cd "$work" && mpirun -np $ranks "$exe" $n $steps)
    echo "$line" | awk -v n=$n '{ printf "%s  %10.1f  %11.2f  %8.2f\n", $0, $5 * 1e6 / (n^3), $4 / $3, $5 / $3 }'
  done
done
echo "Timer registry, last run above ($n^3, $ranks ranks; averages over its steps, not medians): $(cat "$work/timer_breakdown.txt")"
fi

# The staged step (fluid_predict, fluid_project, fluid_finish_step) against the fused one, each stage
# in ns per grid point next to the bytes it moves and the floor set by the memory bandwidth (a
# STREAM-like triad on the same ranks). Minima over the repetitions (docs/studies/performance.md).
if [[ $parts == *stages* ]]; then
  echo
  echo "Staged step and the roofline:"
  for n in 64 128; do
    for ranks in 1 2; do
      (cd "$work" && mpirun -np $ranks "$stages_exe" $n $(( n == 64 ? 30 : 10 )) explicit)
    done
  done
  (cd "$work" && mpirun -np 1 "$stages_exe" 128 10 crank_nicolson)
fi

# Eswaran-Pope forcing per step against a whole Crank-Nicolson fluid step (input/hit_box.nml);
# target <= 10% (docs/studies/performance.md). Means over 20 (64^3) or 5 (128^3) repetitions, slowest rank.
if [[ $parts == *forcing* ]]; then
  echo
  echo "Forcing:    N  R  forcing_ms   step_ms  percent"
  for n in 64 128; do
    for ranks in 1 2; do
      echo "         $(cd "$work" && mpirun -np $ranks "$forcing_exe" $n $(( n == 64 ? 20 : 5 )) | tail -n 1)"
    done
  done
fi

# Immersed bodies in prescribed motion (the paper's needle and disk, moving and rotating: reclassified
# every step; explicit diffusion): the coupled step against the fluid-only step (target <= 1.3x,
# docs/studies/performance.md), by part, for both couplings, 1 and 2 ranks; then against the number of
# bodies (needles and disks at 128^3; spheres of D/dx = 10 at 64^3; N = 1..128 needles, disks and spheres
# at 128^3 with the immersed boundary per body and the exponent of its fit), against the mesh level of the
# ghost-node geometry, and in a dense suspension of 256 bodies. Medians over 10 (128^3) or 20 (64^3) repetitions, slowest rank; on 1 rank the process's
# CPU time (robust on a shared machine), on 2 ranks the wall time.
if [[ $parts == *immersed* ]]; then
  echo
  echo "Immersed:  N  R  B  coupling    fluid  coupled    ratio  reclass impose*  impose  loads     div    fluid  [ms, medians]"
  for coupling in implicit explicit; do
    (cd "$work" && mpirun -np 1 "$immersed_exe" 128 10 2 $coupling cpu)
    (cd "$work" && mpirun -np 2 "$immersed_exe" 128 10 2 $coupling wall)
  done
  for bodies in 1 4 8; do
    (cd "$work" && mpirun -np 1 "$immersed_exe" 128 10 $bodies implicit cpu)
  done
  (cd "$work" && mpirun -np 1 "$immersed_exe" 64 20 2 implicit cpu)
  for bodies in 1 4 16; do   # spheres of D/dx = 10 on a lattice at 64^3 (the cost per body)
    (cd "$work" && mpirun -np 1 "$immersed_exe" 64 20 $bodies implicit cpu -1 sphere)
    (cd "$work" && mpirun -np 2 "$immersed_exe" 64 20 $bodies implicit wall -1 sphere)
  done
  # The cost per body at 128^3: N needles, disks and spheres of the paper's size (D/dx about 13) on a
  # lattice, each run's immersed boundary (coupled less fluid-only step) per body, and the exponent p
  # of a least-squares fit cost ~ N^p over N (CPU time of the slowest rank, also on 2 ranks).
  echo "Cost per body (128^3, mixed shapes; IB = coupled - fluid, ms per step; last columns: IB, IB per body):"
  for ranks in 1 2; do
    for bodies in 1 4 16 64 128; do
      (cd "$work" && mpirun -np $ranks "$immersed_exe" 128 10 $bodies implicit cpu -1 mixed) | head -n 1 \
        | awk '{ ib = $6 - $5; printf "%s  %8.2f %7.3f\n", $0, ib, ib / $3 }'
    done | tee "$work/per_body_$ranks.txt"
    awk -v r=$ranks '{ x = log($3); y = log($(NF - 1)); n++; sx += x; sy += y; sxx += x * x; sxy += x * y }
      END { printf "  %d rank(s): IB cost ~ N^%.2f (least squares over N = 1..128)\n", r, (n * sxy - sx * sy) / (n * sxx - sx * sx) }' \
      "$work/per_body_$ranks.txt"
  done
  for level in 1 2 3; do   # the ghost nodes on the icosphere (&bodies geometry = 'mesh')
    (cd "$work" && mpirun -np 1 "$immersed_exe" 128 10 2 implicit cpu $level)
  done
  # A dense suspension: input/suspension_<shape>_resolved.nml with 256 bodies (13.4% by volume, placed
  # 2 um apart: fallback rows and slowly converging ghost rows in the gaps), from a random field, 15
  # steps on 1 rank; the run's own stage timers (ms per step, means over the steps).
  echo "Dense suspension (128^3, 256 bodies, 1 rank; ms per step): shape  step  particles  IB  classification  imposition  sweeps"
  for shape in needle disk sphere; do
    deck=$PWD/input/suspension_${shape}_resolved.nml
    (cd "$work" && mpirun -np 1 "$agglo" "$deck" --set suspension.count=256 \
       --set "fluid.init='random'" --set fluid.init_amplitude=0.01 --set run.end_time=7.2e-5 \
       --set output.field_interval=0.0 --set "run.name='dense_$shape'") > "$work/dense.log" 2>&1
    awk -v s=$shape '/^  fluid step /{f=$5} /^  particle sub-steps /{p=$5} /^  immersed boundary /{ib=$5}
      /^    IB classification /{c=$5} /^    IB imposition /{i=$5} /immersed boundary: sweeps/{w=$4; sub(",", "", w)}
      END { printf "  %-7s %9.1f %9.1f %9.1f %9.1f %9.1f %6s\n", s, f + p, p, ib, c, i, w }' "$work/dense.log"
  done
fi

# Point particles, many (&scene particles = 'suspension', particle_coupling = 'point';
# tools/bench/decks/suspension_point_bench.nml: calcite spheres of radius 2.5 um, 128^3, 3 fluid
# steps from a random field, 200 sub-steps): the coupled step against the particle-free step of the
# same deck, by stage (the sampling of the fluid at the centres inside the fluid step; the
# near-body search, the one-step update and the sub-steps of the near bodies inside the particle
# stage), per body, on 1 and 2 ranks; &scene substep_bodies = 'near' for N = 10^3, 10^4, 10^5 and
# 'all' for 10^3, 10^4 (10^5 bodies all sub-stepped take tens of seconds per fluid step). Means
# over the 3 steps (the free and the coupled step of the slowest rank, the stages mean over ranks);
# the fitted exponent of the particle work against N (near rows).
if [[ $parts == *point* ]]; then
  deck=$PWD/tools/bench/decks/suspension_point_bench.nml
  echo
  echo "Point particles:  N  R  mode   free_ms coupled_ms  ratio   work/free  sample  search  update substep  [ms/step]  us/body"
  : > "$work/point_rows.txt"
  for ranks in 1 2; do
    free=$(cd "$work" && mpirun -np $ranks "$agglo" "$deck" --set "scene.particles='none'" --set scene.added_mass=.false. \
           --set "run.name='free_$ranks'" | awk '/^  fluid step /{print $5}')
    for n in 1000 10000 100000; do
      for mode in near all; do
        [[ $mode == all && $n == 100000 ]] && continue
        (cd "$work" && mpirun -np $ranks "$agglo" "$deck" --set suspension.count=$n --set "scene.substep_bodies='$mode'" \
           --set "run.name='point_${n}_${ranks}_$mode'") > "$work/point.log"
        # work: what the particles add to the particle-free step (the sampling inside the fluid step
        # and the particle stage), measured in the coupled run itself (robust on a shared machine).
        awk -v n=$n -v r=$ranks -v mode=$mode -v free="$free" '
          /^  fluid step /{fluid=$5} /^  particle sub-steps /{part=$5} /^  point sampling /{sample=$4}
          /^  near-body search /{search=$4} /^  one-step update /{update=$4}; /^  particle sub-steps /{partmean=$4}
          END { coupled = fluid + part; work = sample + part
                printf "  %15d %2d %5s %9.1f %9.1f %6.2f %9.3f %8.1f %7.1f %7.1f %7.1f  %18.3f\n", n, r, mode, free, \
                  coupled, coupled / free, work / free, sample, search, update, partmean - search - update, \
                  work * 1000 / n }' "$work/point.log" | tee -a "$work/point_rows.txt"
      done
    done
  done
  # Least-squares slope of log(work) against log(N), per rank count, 'near' rows.
  awk '$3 == "near" { k = $2; x = log($1); y = log($7 * $4); sx[k] += x; sy[k] += y; sxx[k] += x * x;
                                 sxy[k] += x * y; m[k]++ }
       END { for (k in m) printf "  fitted exponent of the particle work against N, %d rank(s): %.2f\n", k,
                                  (m[k] * sxy[k] - sx[k] * sy[k]) / (m[k] * sxx[k] - sx[k] * sx[k]) }' "$work/point_rows.txt"
fi

# Crank-Nicolson with two resolved bodies at 128^3 on 2 ranks (docs/performance.md): the needle pair
# of input/quiescent_needle_resolved.nml at 128^3, 5 steps at dt = 1e-5 s (4.8 times the explicit
# step, nu dt/dx^2 = 0.4), against 6 explicit steps at 2e-6 s; then the sphere pair of
# input/chaotic_sphere_resolved.nml at 5 times its explicit step when its forced field exists.
# Three alternated rounds; each run's median step of steps 2-5 (the first holds the FFT plans).
if [[ $parts == *cn* ]]; then
  echo
  echo "Crank-Nicolson with two bodies, 128^3, 2 ranks: case  round  CN_ms  explicit_ms  ratio  FFT_solves/step  outer_iterations"
  median_step() { awk '/^step [2-9] /{print $(NF-3)}' "$1" | sort -g | awk '{v[NR]=$1} END{print v[int((NR+1)/2)]}'; }
  needle=$PWD/input/quiescent_needle_resolved.nml
  sphere=$PWD/input/chaotic_sphere_resolved.nml
  cases=(needle)
  field=$(awk -F"'" '/^ *init_file *=/{print $2}' "$sphere")
  if [[ -f $field ]]; then cases+=(sphere); else echo "  (spheres skipped: no forced field $field)"; fi
  for round in 1 2 3; do
    for case in "${cases[@]}"; do
      if [[ $case == needle ]]; then
        deck=$needle; common=(--set grid.nx=128 --set grid.ny=128 --set grid.nz=128)
        cn=(--set run.dt=1e-5 --set run.end_time=5e-5); explicit=(--set run.dt=2e-6 --set run.end_time=1.2e-5)
      else
        deck=$sphere; common=(--set "fluid.init_file='$PWD/$field'")
        cn=(--set run.dt=2.4e-5 --set scene.particle_substeps=120 --set run.end_time=1.2e-4)
        explicit=(--set run.end_time=2.88e-5)
      fi
      (cd "$work" && mpirun -np 2 "$agglo" "$deck" "${common[@]}" --set run.progress_interval=1 \
         --set "fluid.viscous_scheme='crank_nicolson'" "${cn[@]}" --set "run.name='cn_${case}_$round'") > "$work/cn.log" 2>&1
      (cd "$work" && mpirun -np 2 "$agglo" "$deck" "${common[@]}" --set run.progress_interval=1 "${explicit[@]}" \
         --set "run.name='explicit_${case}_$round'") > "$work/explicit.log" 2>&1
      cn_ms=$(median_step "$work/cn.log"); explicit_ms=$(median_step "$work/explicit.log")
      solves=$(grep -o 'FFT solves [0-9]*' "$work/cn.log" | head -n 1 | awk '{print $3 / 5}')
      outer=$(grep -o 'last step GMRES iterations [0-9]*' "$work/cn.log" | head -n 1 | awk '{print $5}')
      awk -v c=$case -v r=$round -v a="$cn_ms" -v b="$explicit_ms" -v f="$solves" -v o="$outer" \
        'BEGIN { printf "  %-8s %5d %8.1f %10.1f %7.2f %10.1f %12s\n", c, r, a, b, a / b, f, o }'
    done
  done
fi

[[ $parts == *pair* ]] || exit 0

# Particle pair: cost of one particle step by part, and the wall time of one paper-protocol run
# (input/quiescent_*.nml, seed 1, 1 rank) at each cheap fidelity.
echo
echo "Pair step (quiescent disk pair, warm-started closest points), medians of 5 x 100000 steps:"
(cd "$work" && mpirun -np 1 "$pair_exe" 100000)
echo
echo "One quiescent paper-protocol run (seed 1, 1 rank): shape fidelity steps wall_s us/step outcome"
for deck in input/quiescent_{needle,disk,sphere}_{none,stokes}.nml; do
  name=$(basename "$deck" .nml)
  # Each run in a directory of its own (an earlier run is never overwritten).
  deck_path=$PWD/$deck
  (cd "$work" && mpirun -np 1 "$agglo" "$deck_path" --set "run.name='$name'" > "$name.log" 2>&1)
  python3 - "$work/output/$name/summary.json" "$name" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print(f"{sys.argv[2]:28s} {d['steps']:7d} {d['wall_time']:7.2f} {1e6 * d['wall_time'] / d['steps']:6.1f} {d['outcome']}")
PY
done
