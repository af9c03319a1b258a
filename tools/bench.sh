#!/usr/bin/env bash
# Agglo benchmark (`make bench`): fluid time per step and its parts at 64^3 and 128^3 on 1 and 2
# ranks, and the Poisson solve against one forward + inverse 3-D FFT of the same grid.
# Medians over repetitions (the machine may be shared: compare ratios; poisson = the in-buffer solve
# the step uses, pois(copy) = the poisson_solve API with its copies in and out). Results: docs/performance.md.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
make --no-print-directory -s build "$BUILD/bench/bench_fluid"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
exe=$PWD/$BUILD/bench/bench_fluid
echo "Agglo fluid benchmark on $(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "compiler: $(mpifort --version | head -n 1); flags: -O3 -march=native -funroll-loops; FFTW_ESTIMATE plans"
echo "    N  R  fft_pair   poisson      step  adv+diff   proj(P)      halo    io(4f) pois(copy)  [ms, medians]  ns/pt/step  poisson/fft  step/fft"
for n in 64 128; do
  steps=$(( n == 64 ? 40 : 15 ))
  for ranks in 1 2; do
    line=$(cd "$work" && mpirun -np $ranks "$exe" $n $steps)
    echo "$line" | awk -v n=$n '{ printf "%s  %10.1f  %11.2f  %8.2f\n", $0, $5 * 1e6 / (n^3), $4 / $3, $5 / $3 }'
  done
done
