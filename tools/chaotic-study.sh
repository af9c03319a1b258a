#!/usr/bin/env bash
# chaotic-study.sh: the chaotic pair study (docs/studies/results-chaotic.md).
# `--help` says what it runs.
set -u -o pipefail
study_name=chaotic-study

study_usage_specific() {
  cat <<'EOF'
Usage: tools/chaotic-study.sh [options]

The paper's chaotic pair protocol (converged forced field, random centre and orientations, 2 um
gap, 4.2 mm/s, 3 ms) for needles, disks and spheres at resolved fidelity and as point particles
on the same seeds. Run from the repository root after `make build tools-deps`.

  0. the converged forced field each deck starts from (its &fluid init_file, e.g.
     output/hit_box_128/final_field.h5): when missing, input/hit_box.nml on the deck's grid is run
     first (0.4 s simulated; about 4 min at 64^3 on 2 cores, roughly 16x that per doubling of the
     grid; restarted from its checkpoint when interrupted)
  1. batches (tools/montecarlo.sh), seeds S..S+N-1, the same seeds for every shape and rung:
       OUT/{needle,disk,sphere}-resolved   input/chaotic_<shape>_resolved.nml, N_RESOLVED runs on
                                           --ranks ranks each
       OUT/{needle,disk,sphere}-point      input/chaotic_<shape>_point.nml, N_POINT runs (its
                                           first N_RESOLVED runs share the resolved batch's seeds)
     Field snapshots are switched off (--set output.field_interval=0.0: 0 means the first and last
     step only); --snapshots keeps the decks' own interval.
  2. statistics and figures (tools/agglo-stats --illustrate): OUT/stats-resolved and
     OUT/stats-point (the three shapes: rates with Wilson intervals, PDFs of separation and
     relative velocity with their means, maximum particle speed, psi and the collision points by
     outcome, time histories of the illustrative runs chosen by rule); OUT/stats-all (six
     batches, --group-by batch, no figures); the run-by-run comparison of point against resolved
     on the shared seeds: OUT/comparison.csv, OUT/comparison.txt, OUT/transitions-<shape>.csv
  3. OUT/batch_times.tsv (every local batch call) and OUT/batch_costs.tsv (per batch)

Options of this study:
      --resolved-runs N    runs of each resolved batch (default 60)
      --point-runs N       runs of each point batch (default 120)
      --shapes "A B"       shapes (default "needle disk sphere")
      --snapshots          keep the decks' field snapshots (about 64 MB each at 128^3)

Cost (estimates, 2 cores): a resolved 128^3 run 1-3 min x N_RESOLVED per shape; a point run
about a minute. On a cluster: --slurm --ranks 8 --time 60 -j 60, then bash OUT/submit-all.sh.
EOF
}

source "$(dirname "${BASH_SOURCE[0]}")/study_lib.sh"
study_parse_arguments "$@"
resolved_runs=60 point_runs=120 shapes="needle disk sphere" snapshots=0
set -- "${study_extra_arguments[@]}"
while [ $# -gt 0 ]; do
  case "$1" in
    --resolved-runs) resolved_runs=${2:?}; shift 2 ;;
    --point-runs) point_runs=${2:?}; shift 2 ;;
    --shapes) shapes=${2:?}; shift 2 ;;
    --snapshots) snapshots=1; shift ;;
    *) study_die "unknown argument '$1' (see --help)" ;;
  esac
done
for value in "$resolved_runs" "$point_runs"; do
  [[ $value =~ ^[1-9][0-9]*$ ]] || study_die "'$value' is not an integer >= 1"
done
read -r -a shape_list <<< "$shapes"
no_snapshots=(); (( snapshots )) || no_snapshots=(--set output.field_interval=0.0)
# The published tables of this study are the paper's omission of the squeeze film (the decks model it).
no_snapshots+=(--set collision.lubrication=.false.)

for rung in resolved point; do
  runs=$resolved_runs; [ "$rung" = point ] && runs=$point_runs
  for shape in "${shape_list[@]}"; do
    study_batch "$shape-$rung" "input/chaotic_${shape}_${rung}.nml" "$runs" "${no_snapshots[@]}"
  done
done

if [ "$study_mode" = run ] && (( study_analysis )); then
  stats() {  # stats OUTDIR [agglo-stats options --] BATCH-NAME...
    local dir=$1 name; shift
    local -a options=() roots=()
    while [ $# -gt 0 ] && [ "$1" != -- ]; do options+=("$1"); shift; done
    shift
    for name in "$@"; do study_has_runs "$name" && roots+=("$study_out/$name"); done
    [ ${#roots[@]} -gt 0 ] || { echo "== statistics $dir: no complete batch yet"; return 0; }
    echo "== statistics -> $dir (${roots[*]})"
    "$study_tools/agglo-stats" -o "$dir" "${options[@]}" "${roots[@]}" | tee "$dir.txt" || study_status_all=1
  }
  all=()
  for rung in resolved point; do
    names=(); for shape in "${shape_list[@]}"; do names+=("$shape-$rung"); done
    all+=("${names[@]}")
    stats "$study_out/stats-$rung" --illustrate -- "${names[@]}"
  done
  stats "$study_out/stats-all" --group-by batch --no-figures -- "${all[@]}"
  rm -f "$study_out/comparison.csv" "$study_out/comparison.txt"
  for shape in "${shape_list[@]}"; do
    study_has_runs "$shape-resolved" && study_has_runs "$shape-point" || continue
    "$study_python" "$study_tools/compare_outcomes.py" "$study_out/$shape-resolved" "$study_out/$shape-point" \
      --label "$shape: resolved -> point" --csv "$study_out/comparison.csv" | tee -a "$study_out/comparison.txt" \
      || study_status_all=1
    "$study_python" "$study_tools/study_compare.py" "$study_out/$shape-resolved" "$study_out/$shape-point" \
      -o "$study_out/transitions-$shape.csv" | tee -a "$study_out/comparison.txt" || study_status_all=1
  done
fi
study_finish
