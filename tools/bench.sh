#!/usr/bin/env bash
# Agglo benchmark (`make bench`): fluid time per step and its parts at 64^3 and 128^3 on 1 and 2
# ranks, and the Poisson solve against one forward + inverse 3-D FFT of the same grid.
# Medians over repetitions (the machine may be shared: compare ratios). Results: docs/performance.md.
set -eu
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
make --no-print-directory -s build
# Same flags as `make build` in release mode (Makefile MODE=release).
HDF5_LIB=/usr/lib/$(gcc -print-multiarch)/hdf5/openmpi
mpifort -fwrapv -fimplicit-none -ffree-line-length-132 -O3 -march=native -funroll-loops -I"$BUILD/mod" \
  -I/usr/include -I/usr/include/hdf5/openmpi -o "$BUILD/bench_fluid" tools/bench/bench_fluid.f90 \
  "$BUILD/libagglo.a" -L"$HDF5_LIB" -Wl,-rpath,"$HDF5_LIB" -lhdf5_fortran -lhdf5 -lfftw3_mpi -lfftw3 -lHYPRE -llapack -lblas
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
exe=$PWD/$BUILD/bench_fluid
echo "Agglo fluid benchmark on $(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "compiler: $(mpifort --version | head -n 1); flags: -O3 -march=native -funroll-loops; FFTW_ESTIMATE plans"
echo "    N  R  fft_pair   poisson      step  adv+diff  proj(P)      halo   io(4f)   [ms, medians]  ns/pt/step  poisson/fft"
for n in 64 128; do
  steps=$(( n == 64 ? 40 : 15 ))
  for ranks in 1 2; do
    line=$(cd "$work" && mpirun -np $ranks "$exe" $n $steps)
    echo "$line" | awk -v n=$n '{ printf "%s  %10.1f  %11.2f\n", $0, $5 * 1e6 / (n^3), $4 / $3 }'
  done
done
