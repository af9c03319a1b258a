#!/usr/bin/env bash
# near-contact-study.sh: the chaotic pair protocol with and without the sub-grid lubrication model,
# on the same seeds (docs/studies/results-chaotic.md, "With the squeeze film"). `--help` says what it runs.
set -u -o pipefail
study_name=near-contact-study

study_usage_specific() {
  cat <<'EOF'
Usage: tools/near-contact-study.sh [options]

The paper's chaotic pair protocol (input/chaotic_<shape>_<rung>.nml: converged forced field at
128^3, random centre and orientations, 2 um gap, 4.2 mm/s) run twice on the same seeds: with the
paper's omission of the squeeze film (&collision lubrication = .false., the decks as shipped) and
with the sub-grid lubrication model on (lubrication = .true.). Run from the repository root after
`make build tools-deps`.

  0. the converged forced field of the decks (output/hit_box_128/final_field.h5), made when missing
  1. batches (tools/montecarlo.sh), seeds S..S+N-1, the same seeds for every shape, rung and model:
       OUT/<shape>-<rung>-omission      the deck as shipped
       OUT/<shape>-<rung>-lubrication   --set collision.lubrication=.true.
     for rung in point, resolved (point first: it is about 5 times cheaper); field snapshots off.
     End of each run: the paper's 3 ms (end_rule = 'paper'), the outcome by the pair's mechanical
     state then (docs/theory.md, "Run outcome"), with whether it was settled. --settled CAP runs
     on until the outcome is settled, capped at CAP seconds.
  2. statistics (tools/agglo-stats, OUT/stats-<rung>-<model>, every shape) and the run-by-run
     transitions omission -> lubrication per shape and rung (OUT/comparison.csv,
     OUT/comparison.txt, OUT/transitions-<shape>-<rung>.csv)
  3. OUT/batch_times.tsv and OUT/batch_costs.tsv

Options of this study:
      --point-runs N       runs of each point batch (default 120)
      --resolved-runs N    runs of each resolved batch (default 60)
      --rungs "A B"        rungs (default "point resolved")
      --shapes "A B"       shapes (default "needle disk sphere")
      --settled CAP        end rule 'settled' (paper_end_time 3 ms), &run end_time = CAP (s)

Cost (2 cores, idle): a point run 13-40 s, a resolved run 50-70 s at the paper's 3 ms.
On a cluster: --slurm --ranks 8 --time 60 -j 60, then bash OUT/submit-all.sh.
EOF
}

source "$(dirname "${BASH_SOURCE[0]}")/study_lib.sh"
study_parse_arguments "$@"
resolved_runs=60 point_runs=120 shapes="needle disk sphere" rungs="point resolved" settled_cap=''
set -- "${study_extra_arguments[@]}"
while [ $# -gt 0 ]; do
  case "$1" in
    --resolved-runs) resolved_runs=${2:?}; shift 2 ;;
    --point-runs) point_runs=${2:?}; shift 2 ;;
    --shapes) shapes=${2:?}; shift 2 ;;
    --rungs) rungs=${2:?}; shift 2 ;;
    --settled) settled_cap=${2:?}; shift 2 ;;
    *) study_die "unknown argument '$1' (see --help)" ;;
  esac
done
for value in "$resolved_runs" "$point_runs"; do
  [[ $value =~ ^[1-9][0-9]*$ ]] || study_die "'$value' is not an integer >= 1"
done
read -r -a shape_list <<< "$shapes"
read -r -a rung_list <<< "$rungs"
for rung in "${rung_list[@]}"; do
  [[ $rung =~ ^(point|resolved)$ ]] || study_die "--rungs: '$rung' is not point or resolved"
done
end_rule=()
if [ -n "$settled_cap" ]; then
  [[ $settled_cap =~ ^[0-9.]+([eE][-+]?[0-9]+)?$ ]] || study_die "--settled: '$settled_cap' is not a time in s"
  end_rule=(--set "pair.end_rule='settled'" --set pair.paper_end_time=3.0e-3 --set "run.end_time=$settled_cap")
fi
common_sets=(--set output.field_interval=0.0 "${end_rule[@]}")

for rung in "${rung_list[@]}"; do
  runs=$resolved_runs; [ "$rung" = point ] && runs=$point_runs
  for shape in "${shape_list[@]}"; do
    deck="input/chaotic_${shape}_${rung}.nml"
    study_batch "$shape-$rung-omission" "$deck" "$runs" "${common_sets[@]}"
    study_batch "$shape-$rung-lubrication" "$deck" "$runs" "${common_sets[@]}" --set collision.lubrication=.true.
  done
done

if [ "$study_mode" = run ] && (( study_analysis )); then
  rm -f "$study_out/comparison.csv" "$study_out/comparison.txt"
  for rung in "${rung_list[@]}"; do
    for model in omission lubrication; do
      roots=()
      for shape in "${shape_list[@]}"; do
        study_has_runs "$shape-$rung-$model" && roots+=("$study_out/$shape-$rung-$model")
      done
      [ ${#roots[@]} -gt 0 ] || continue
      echo "== statistics -> $study_out/stats-$rung-$model"
      "$study_tools/agglo-stats" -o "$study_out/stats-$rung-$model" "${roots[@]}" \
        | tee "$study_out/stats-$rung-$model.txt" || study_status_all=1
    done
    for shape in "${shape_list[@]}"; do
      study_has_runs "$shape-$rung-omission" && study_has_runs "$shape-$rung-lubrication" || continue
      "$study_python" "$study_tools/compare_outcomes.py" "$study_out/$shape-$rung-omission" \
        "$study_out/$shape-$rung-lubrication" --label "$shape $rung: omission -> lubrication" \
        --csv "$study_out/comparison.csv" | tee -a "$study_out/comparison.txt" || study_status_all=1
      "$study_python" "$study_tools/study_compare.py" "$study_out/$shape-$rung-omission" \
        "$study_out/$shape-$rung-lubrication" -o "$study_out/transitions-$shape-$rung.csv" \
        | tee -a "$study_out/comparison.txt" || study_status_all=1
    done
  done
fi
study_finish
