#!/usr/bin/env bash
# suspension-study.sh: the suspension study (agglomeration of many bodies in the forced box, point
# against resolved on the same seeds and placements, and ghost collision rates). `--help` says what
# it runs; docs/tools.md ("tools/suspension-study.sh") explains it.
set -u -o pipefail
study_name=suspension-study

study_usage_specific() {
  cat <<'EOF'
Usage: tools/suspension-study.sh [options]

Suspensions of 64 calcite needles, disks and spheres in the paper's forced 1 mm box (the decks
input/suspension_<shape>_{point,resolved}.nml), at the point and resolved rungs on the same seeds,
so that run i of every batch starts from the same placement (random stream 4 of seed S+i-1), plus
a ghost-collision batch of point spheres for the kinematic collision rate. Run from the repository
root after `make build tools-deps`.

  0. the converged forced field the decks start from (their &fluid init_file,
     output/hit_box_<grid>/final_field.h5): when missing, input/hit_box.nml on that grid is run
     first (0.4 s simulated; about 4 min at 64^3 on 2 cores, roughly 16x that per doubling)
  1. batches (tools/montecarlo.sh), seeds S..S+N-1:
       OUT/{needle,disk,sphere}-resolved   input/suspension_<shape>_resolved.nml, N runs on --ranks
                                           ranks each
       OUT/{needle,disk,sphere}-point      input/suspension_<shape>_point.nml, N runs
       OUT/sphere-ghost                    input/suspension_sphere_point.nml with &suspension ghost
                                           (no impulse, no DLVO: the bodies pass through each
                                           other and every meeting is counted), N_GHOST runs
     Field snapshots are switched off (--set output.field_interval=0.0); --snapshots keeps them.
  2. statistics and figures (tools/agglo-stats --suspension): OUT/stats-point, OUT/stats-resolved
     (per shape: mean cluster size and bonds against time with seed-to-seed t intervals, size
     distributions at --times, radius of gyration against size with the fractal dimension, psi of
     bonded neighbours, collision rates and kernels, a 3D snapshot coloured by cluster),
     OUT/stats-ghost (the ghost collision rate and kernel), OUT/stats-collision (the point spheres'
     collision kernel over the ghost spheres': the collision efficiency) and
     OUT/stats-comparison/suspension_comparison.csv, copied to OUT/comparison.csv: point against
     resolved per shape (mean cluster size, bonds, fractal dimension, mean psi, collision kernel,
     each with its interval, and the ratio resolved / point)
  3. OUT/batch_times.tsv (every local batch call) and OUT/batch_costs.tsv (per batch)

Options of this study:
  -N, --runs N            runs of each point and resolved batch (default 8)
      --ghost-runs N      runs of the ghost batch (default: --runs; 0 leaves it out)
      --shapes "A B"      shapes (default "needle disk sphere")
      --rungs "A B"       rungs (default "point resolved")
      --end-time T        simulated time of every run (s; default the decks' 3e-3)
      --grid N            grid N^3 of every batch (default the decks' 128) and the converged field
                          output/hit_box_N/final_field.h5 they start from; resolved needles need
                          N >= 69 (4 cells thick), so 72 is the smallest grid for all three shapes
      --regrid-field      with --grid N: start from the decks' 128^3 field resampled onto N^3
                          (output/hit_box_128_on_N/final_field.h5, tools/regrid_field.py, seconds)
                          instead of a field converged on N^3 (minutes to hours)
      --bodies N          bodies of the point and resolved batches (default the decks' 64)
      --ghost-bodies N    bodies of the ghost batch (default 64)
      --ghost-radius R    volume-equivalent radius of the ghost spheres (m; default 50e-6)
      --times T1,T2       times (s) of the size distributions (default: half the end time and the end)
      --snapshots         keep the decks' field snapshots
      --lubrication       model the squeeze film (&collision lubrication = .true., as the decks
                          ship); without it every batch omits it, as the published tables do

Cost (estimates, 2 cores, 3 ms): a point run at 128^3 1-2 min, a resolved run at 128^3 about
15 min (the immersed boundary of 64 bodies). Full size on a cluster (8 seeds per shape, 64 bodies
at 128^3): --slurm --runs 8 --ranks 8 --time 180, then bash OUT/submit-all.sh.
EOF
}

source "$(dirname "${BASH_SOURCE[0]}")/study_lib.sh"
study_parse_arguments "$@"
runs=8 ghost_runs='' shapes="needle disk sphere" rungs="point resolved" end_time='' grid='' bodies=''
ghost_bodies=64 ghost_radius=50e-6 times='' snapshots=0 regrid=0 lubrication=.false.
set -- "${study_extra_arguments[@]}"
while [ $# -gt 0 ]; do
  case "$1" in
    -N|--runs) runs=${2:?--runs needs a value}; shift 2 ;;
    --ghost-runs) ghost_runs=${2:?--ghost-runs needs a value}; shift 2 ;;
    --shapes) shapes=${2:?--shapes needs a value}; shift 2 ;;
    --rungs) rungs=${2:?--rungs needs a value}; shift 2 ;;
    --end-time) end_time=${2:?--end-time needs a value}; shift 2 ;;
    --grid) grid=${2:?--grid needs a value}; shift 2 ;;
    --bodies) bodies=${2:?--bodies needs a value}; shift 2 ;;
    --ghost-bodies) ghost_bodies=${2:?--ghost-bodies needs a value}; shift 2 ;;
    --ghost-radius) ghost_radius=${2:?--ghost-radius needs a value}; shift 2 ;;
    --times) times=${2:?--times needs a value}; shift 2 ;;
    --snapshots) snapshots=1; shift ;;
    --regrid-field) regrid=1; shift ;;
    --lubrication) lubrication=.true.; shift ;;
    *) study_die "unknown argument '$1' (see --help)" ;;
  esac
done
ghost_runs=${ghost_runs:-$runs}
[[ $runs =~ ^[1-9][0-9]*$ ]] || study_die "--runs '$runs' is not allowed; allowed: an integer >= 1"
[[ $ghost_runs =~ ^[0-9]+$ ]] || study_die "--ghost-runs '$ghost_runs' is not allowed; allowed: an integer >= 0"
for value in "$grid" "$bodies" "$ghost_bodies"; do
  [ -z "$value" ] || [[ $value =~ ^[1-9][0-9]*$ ]] || study_die "'$value' is not allowed for --grid/--bodies/--ghost-bodies; allowed: an integer >= 1"
done
real='^[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?$'
[ -z "$end_time" ] || [[ $end_time =~ $real ]] || study_die "--end-time '$end_time' is not allowed; allowed: a time > 0 in seconds, e.g. 1e-3"
[[ $ghost_radius =~ $real ]] || study_die "--ghost-radius '$ghost_radius' is not allowed; allowed: a radius > 0 in metres, e.g. 50e-6"
read -r -a shape_list <<< "$shapes"
read -r -a rung_list <<< "$rungs"
for shape in "${shape_list[@]}"; do
  [[ $shape =~ ^(needle|disk|sphere)$ ]] || study_die "--shapes: '$shape' is not allowed; allowed: needle, disk, sphere"
done
for rung in "${rung_list[@]}"; do
  [[ $rung =~ ^(point|resolved)$ ]] || study_die "--rungs: '$rung' is not allowed; allowed: point, resolved"
done

# The --set values every batch shares: end time, grid and its converged field, no snapshots.
# The published tables of this study are the paper's omission of the squeeze film (the decks model
# it); --lubrication models it.
common=(--set "collision.lubrication=$lubrication")
(( snapshots )) || common+=(--set output.field_interval=0.0)
[ -n "$end_time" ] && common+=(--set "run.end_time=$end_time")
(( regrid )) && [ -z "$grid" ] && study_die "--regrid-field needs --grid N"
if [ -n "$grid" ]; then
  field="output/hit_box_$grid/final_field.h5"
  if (( regrid )) && [ "$grid" != 128 ]; then
    field="output/hit_box_128_on_$grid/final_field.h5"
    study_field_from "$field" output/hit_box_128/final_field.h5 128
  fi
  common+=(--set "grid.nx=$grid" --set "grid.ny=$grid" --set "grid.nz=$grid" --set "fluid.init_file='$field'")
fi
counted=(); [ -n "$bodies" ] && counted+=(--set "suspension.count=$bodies")

for rung in "${rung_list[@]}"; do
  for shape in "${shape_list[@]}"; do
    study_batch "$shape-$rung" "input/suspension_${shape}_${rung}.nml" "$runs" "${common[@]}" "${counted[@]}"
  done
done
if (( ghost_runs > 0 )); then
  study_batch "sphere-ghost" "input/suspension_sphere_point.nml" "$ghost_runs" "${common[@]}" \
    --set suspension.ghost=.true. --set "suspension.count=$ghost_bodies" \
    --set "suspension.radius=$ghost_radius" --set "pair.radius=$ghost_radius"
fi

if [ "$study_mode" = run ] && (( study_analysis )); then
  if [ -z "$times" ]; then
    end=${end_time:-3e-3}
    times=$(awk -v t="$end" 'BEGIN { printf "%.6g,%.6g", t / 2, t }')
  fi
  stats() {  # stats OUTDIR [agglo-stats options --] BATCH-NAME...
    local dir=$1 name; shift
    local -a options=() roots=()
    while [ $# -gt 0 ] && [ "$1" != -- ]; do options+=("$1"); shift; done
    shift
    for name in "$@"; do study_has_runs "$name" && roots+=("$study_out/$name"); done
    [ ${#roots[@]} -gt 0 ] || { echo "== statistics $dir: no complete batch yet"; return 0; }
    echo "== statistics -> $dir (${roots[*]})"
    mkdir -p "$dir"
    "$study_tools/agglo-stats" --suspension -o "$dir" "${options[@]}" "${roots[@]}" | tee "$dir.txt" \
      || study_status_all=1
  }
  all=()
  for rung in "${rung_list[@]}"; do
    names=(); for shape in "${shape_list[@]}"; do names+=("$shape-$rung"); done
    all+=("${names[@]}")
    stats "$study_out/stats-$rung" --times "$times" -- "${names[@]}"
  done
  if (( ghost_runs > 0 )); then
    stats "$study_out/stats-ghost" --no-figures -- sphere-ghost
    # The collision efficiency: the point spheres' collision kernel over the ghost spheres'.
    [[ " ${rung_list[*]} " == *" point "* && " ${shape_list[*]} " == *" sphere "* ]] && \
      stats "$study_out/stats-collision" --group-by batch --no-figures --compare ghost,point -- sphere-ghost sphere-point
  fi
  rm -f "$study_out/comparison.csv"
  if (( ${#rung_list[@]} == 2 )); then
    stats "$study_out/stats-comparison" --group-by batch --no-figures \
      --compare "${rung_list[0]},${rung_list[1]}" -- "${all[@]}"
    [ -f "$study_out/stats-comparison/suspension_comparison.csv" ] && \
      cp "$study_out/stats-comparison/suspension_comparison.csv" "$study_out/comparison.csv"
  fi
fi
study_finish
