#!/usr/bin/env bash
# quiescent-resolved-study.sh: the quiescent pair study at resolved fidelity (docs/studies/results-quiescent.md).
# `--help` says what it runs.
set -u -o pipefail
study_name=quiescent-resolved-study

study_usage_specific() {
  cat <<'EOF'
Usage: tools/quiescent-resolved-study.sh [options]

The paper's quiescent pair protocol for needles and disks at resolved fidelity, on the seeds of
the cheap-fidelity study (docs/studies/results-quiescent.md: seeds 1001...), compared run by run with the
'none' scene. Run from the repository root after `make build tools-deps`.

  1. batches (tools/montecarlo.sh), seeds S..S+N-1 in every batch:
       OUT/{needle,disk}-none                    input/quiescent_<shape>_none.nml, N_CHEAP runs
       OUT/{needle,disk}-stokes-first_contact    input/quiescent_<shape>_stokes.nml with
                                                 &pair hydrodynamics_from = 'first_contact', N_CHEAP
       OUT/{needle,disk}-resolved-start          input/quiescent_<shape>_resolved.nml, N_RESOLVED runs
                                                 on --ranks ranks
       OUT/{needle,disk}-resolved-first_contact  the same with hydrodynamics_from = 'first_contact'
  2. statistics (tools/agglo-stats): OUT/stats-stokes-first_contact, OUT/stats-resolved-start,
     OUT/stats-resolved-first_contact (shapes compared), OUT/stats-all (every batch, --group-by
     batch, no figures); the run-by-run comparison of each batch with the 'none' batch of its shape
     (tools/compare_outcomes.py): OUT/comparison.csv and OUT/comparison.txt, and the per-run
     transitions in OUT/transitions-<batch>.csv (tools/study_compare.py)
  3. OUT/batch_times.tsv (every local batch call) and OUT/batch_costs.tsv (per batch)

Options of this study:
      --cheap-runs N       runs of the 'none' and 'stokes' batches (default 120)
      --resolved-runs N    runs of each resolved batch (default 60)
      --shapes "A B"       shapes (default "needle disk")
      --lubrication        every batch with a fluid models the squeeze film (&collision lubrication =
                           .true., as the decks ship); default: the paper's omission, on which the
                           published tables were measured. Give it its own --out.

Cost: a 'none' or 'stokes' run about 1-2 s (120 runs: about 2-4 min per batch on 2 shared
cores); a resolved run several minutes on 2 ranks (60 runs: several hours per batch). Start with
e.g. --only 'none|stokes' for the cheap batches alone.
EOF
}

source "$(dirname "${BASH_SOURCE[0]}")/study_lib.sh"
study_parse_arguments "$@"
cheap_runs=120 resolved_runs=60 shapes="needle disk" lubrication=.false.
set -- "${study_extra_arguments[@]}"
while [ $# -gt 0 ]; do
  case "$1" in
    --cheap-runs) cheap_runs=${2:?}; shift 2 ;;
    --resolved-runs) resolved_runs=${2:?}; shift 2 ;;
    --lubrication) lubrication=.true.; shift ;;
    --shapes) shapes=${2:?}; shift 2 ;;
    *) study_die "unknown argument '$1' (see --help)" ;;
  esac
done
for value in "$cheap_runs" "$resolved_runs"; do
  [[ $value =~ ^[1-9][0-9]*$ ]] || study_die "'$value' is not an integer >= 1"
done
read -r -a shape_list <<< "$shapes"

first_contact="pair.hydrodynamics_from='first_contact'"
# The published tables of this study are the paper's omission of the squeeze film (the decks model
# it); --lubrication models it.
omission=(--set "collision.lubrication=$lubrication")
for shape in "${shape_list[@]}"; do
  study_batch "$shape-none" "input/quiescent_${shape}_none.nml" "$cheap_runs"
  study_batch "$shape-stokes-first_contact" "input/quiescent_${shape}_stokes.nml" "$cheap_runs" \
    --set "$first_contact" "${omission[@]}"
done
for shape in "${shape_list[@]}"; do
  study_batch "$shape-resolved-start" "input/quiescent_${shape}_resolved.nml" "$resolved_runs" \
    --set "pair.hydrodynamics_from='start'" "${omission[@]}"
  study_batch "$shape-resolved-first_contact" "input/quiescent_${shape}_resolved.nml" "$resolved_runs" \
    --set "$first_contact" "${omission[@]}"
done

if [ "$study_mode" = run ] && (( study_analysis )); then
  stats() {  # stats OUTDIR BATCH-NAME...: agglo-stats over the batches that have complete runs
    local dir=$1 name; shift
    local -a roots=()
    for name in "$@"; do study_has_runs "$name" && roots+=("$study_out/$name"); done
    [ ${#roots[@]} -gt 0 ] || { echo "== statistics $dir: no complete batch yet"; return 0; }
    echo "== statistics -> $dir (${roots[*]})"
    "$study_tools/agglo-stats" -o "$dir" --illustrate "${roots[@]}" "${study_stats_options[@]}" \
      | tee "$dir.txt" || study_status_all=1
  }
  study_stats_options=()
  for variant in stokes-first_contact resolved-start resolved-first_contact; do
    names=(); for shape in "${shape_list[@]}"; do names+=("$shape-$variant"); done
    stats "$study_out/stats-$variant" "${names[@]}"
  done
  names=()
  for shape in "${shape_list[@]}"; do
    for variant in none stokes-first_contact resolved-start resolved-first_contact; do names+=("$shape-$variant"); done
  done
  study_stats_options=(--group-by batch --no-figures)
  stats "$study_out/stats-all" "${names[@]}"
  rm -f "$study_out/comparison.csv" "$study_out/comparison.txt"
  for shape in "${shape_list[@]}"; do
    study_has_runs "$shape-none" || continue
    for variant in stokes-first_contact resolved-start resolved-first_contact; do
      study_has_runs "$shape-$variant" || continue
      "$study_python" "$study_tools/compare_outcomes.py" "$study_out/$shape-none" "$study_out/$shape-$variant" \
        --label "$shape: none -> $variant" --csv "$study_out/comparison.csv" | tee -a "$study_out/comparison.txt" \
        || study_status_all=1
      "$study_python" "$study_tools/study_compare.py" "$study_out/$shape-none" "$study_out/$shape-$variant" \
        -o "$study_out/transitions-$shape-$variant.csv" | tee -a "$study_out/comparison.txt" \
        || study_status_all=1
    done
  done
fi
study_finish
