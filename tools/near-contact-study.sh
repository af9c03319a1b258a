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
paper's omission of the squeeze film (&collision lubrication = .false.) and with the sub-grid
lubrication model on (lubrication = .true., as the decks ship). Run from the repository root after
`make build tools-deps`.

  0. the converged forced field of the decks (output/hit_box_128/final_field.h5), made when missing
  1. batches (tools/montecarlo.sh), seeds S..S+N-1, the same seeds for every shape, rung and model:
       OUT/<shape>-<rung>-omission      --set collision.lubrication=.false.
       OUT/<shape>-<rung>-lubrication   --set collision.lubrication=.true. (the decks as shipped)
     for rung in point, resolved (point first: it is about 5 times cheaper); field snapshots off.
     End of each run: the paper's 3 ms (end_rule = 'paper'), the outcome by the pair's mechanical
     state then (docs/theory.md, "Run outcome"), with whether it was settled. --settled CAP runs
     on until the outcome is settled, capped at CAP seconds.
     Variants of the lubricated batch, --variant-runs runs each, the same seeds:
       OUT/<shape>-<rung>-lubrication-roughness<R>  --roughness "R1 R2": lubrication_roughness = R (m)
                                                    (docs/theory.md, "The roughness gap of calcite")
       OUT/<shape>-<rung>-lubrication-tangential    --tangential: lubrication_tangential = .true.
       OUT/<shape>-<rung>-lubrication-noise         --noise: the start gap 1e-12 relative wider
                                                    (how many outcomes the chaotic flow alone changes)
  2. statistics (tools/agglo-stats, OUT/stats-<rung>-<model>, every shape) and the run-by-run
     transitions omission -> lubrication per shape and rung (OUT/comparison.csv,
     OUT/comparison.txt, OUT/transitions-<shape>-<rung>.csv); per variant its rates
     (OUT/stats-<rung>-<variant>) and its run-by-run comparison with the lubricated batch on the
     shared seeds (OUT/comparison-variants.csv, OUT/comparison-variants.txt)
  3. OUT/batch_times.tsv and OUT/batch_costs.tsv

Options of this study:
      --point-runs N       runs of each point batch (default 120)
      --resolved-runs N    runs of each resolved batch (default 60)
      --rungs "A B"        rungs (default "point resolved")
      --shapes "A B"       shapes (default "needle disk sphere")
      --settled CAP        end rule 'settled' (paper_end_time 3 ms), &run end_time = CAP (s)
      --roughness "R1 R2"  roughness gaps (m) of the roughness variants (default: none)
      --tangential         the variant with the tangential and rotational terms
      --noise              the variant with the start gap perturbed by 1e-12 relative
      --variant-runs N     runs of each variant batch (default 10)

Cost (2 cores, idle): a point run 13-40 s, a resolved run 50-70 s at the paper's 3 ms.
On a cluster: --slurm --ranks 8 --time 60 -j 60, then bash OUT/submit-all.sh.
EOF
}

source "$(dirname "${BASH_SOURCE[0]}")/study_lib.sh"
study_parse_arguments "$@"
resolved_runs=60 point_runs=120 shapes="needle disk sphere" rungs="point resolved" settled_cap=''
roughness_values='' variant_runs=10 tangential=0 noise=0
set -- "${study_extra_arguments[@]}"
while [ $# -gt 0 ]; do
  case "$1" in
    --resolved-runs) resolved_runs=${2:?}; shift 2 ;;
    --point-runs) point_runs=${2:?}; shift 2 ;;
    --shapes) shapes=${2:?}; shift 2 ;;
    --rungs) rungs=${2:?}; shift 2 ;;
    --settled) settled_cap=${2:?}; shift 2 ;;
    --roughness) roughness_values=${2:?}; shift 2 ;;
    --variant-runs) variant_runs=${2:?}; shift 2 ;;
    --tangential) tangential=1; shift ;;
    --noise) noise=1; shift ;;
    *) study_die "unknown argument '$1' (see --help)" ;;
  esac
done
for value in "$resolved_runs" "$point_runs" "$variant_runs"; do
  [[ $value =~ ^[1-9][0-9]*$ ]] || study_die "'$value' is not an integer >= 1"
done
read -r -a shape_list <<< "$shapes"
read -r -a rung_list <<< "$rungs"
# The variants of the lubricated batch: name and its --set values (one string, split on spaces).
variant_names=() variant_sets=()
read -r -a roughness_list <<< "$roughness_values"
for roughness in "${roughness_list[@]}"; do
  [[ $roughness =~ ^[0-9.]+([eE][-+]?[0-9]+)?$ ]] || study_die "--roughness: '$roughness' is not a gap in m"
  variant_names+=("roughness$roughness") variant_sets+=("--set collision.lubrication_roughness=$roughness")
done
(( tangential )) && variant_names+=(tangential) variant_sets+=("--set collision.lubrication_tangential=.true.")
(( noise )) && variant_names+=(noise) variant_sets+=("--set pair.gap=2.000000000002e-6")
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
    study_batch "$shape-$rung-omission" "$deck" "$runs" "${common_sets[@]}" --set collision.lubrication=.false.
    study_batch "$shape-$rung-lubrication" "$deck" "$runs" "${common_sets[@]}" --set collision.lubrication=.true.
    for k in "${!variant_names[@]}"; do
      read -r -a sets <<< "${variant_sets[$k]}"
      study_batch "$shape-$rung-lubrication-${variant_names[$k]}" "$deck" "$variant_runs" "${common_sets[@]}" \
        --set collision.lubrication=.true. "${sets[@]}"
    done
  done
done

# shape_statistics SUFFIX NAME: tools/agglo-stats over the batches <shape>-SUFFIX that have runs, every
# shape, into OUT/stats-NAME (and its table into OUT/stats-NAME.txt).
shape_statistics() {
  local suffix=$1 name=$2 shape roots=()
  for shape in "${shape_list[@]}"; do
    study_has_runs "$shape-$suffix" && roots+=("$study_out/$shape-$suffix")
  done
  [ ${#roots[@]} -gt 0 ] || return 0
  echo "== statistics -> $study_out/stats-$name"
  "$study_tools/agglo-stats" -o "$study_out/stats-$name" "${roots[@]}" | tee "$study_out/stats-$name.txt" \
    || study_status_all=1
}

if [ "$study_mode" = run ] && (( study_analysis )); then
  rm -f "$study_out/comparison.csv" "$study_out/comparison.txt" "$study_out/comparison-variants.csv" \
    "$study_out/comparison-variants.txt"
  for rung in "${rung_list[@]}"; do
    for model in omission lubrication; do shape_statistics "$rung-$model" "$rung-$model"; done
    for shape in "${shape_list[@]}"; do
      study_has_runs "$shape-$rung-omission" && study_has_runs "$shape-$rung-lubrication" || continue
      "$study_python" "$study_tools/compare_outcomes.py" "$study_out/$shape-$rung-omission" \
        "$study_out/$shape-$rung-lubrication" --label "$shape $rung: omission -> lubrication" \
        --csv "$study_out/comparison.csv" | tee -a "$study_out/comparison.txt" || study_status_all=1
      "$study_python" "$study_tools/study_compare.py" "$study_out/$shape-$rung-omission" \
        "$study_out/$shape-$rung-lubrication" -o "$study_out/transitions-$shape-$rung.csv" \
        | tee -a "$study_out/comparison.txt" || study_status_all=1
    done
    for variant in "${variant_names[@]}"; do
      shape_statistics "$rung-lubrication-$variant" "$rung-$variant"
      for shape in "${shape_list[@]}"; do
        study_has_runs "$shape-$rung-lubrication" && study_has_runs "$shape-$rung-lubrication-$variant" || continue
        "$study_python" "$study_tools/compare_outcomes.py" "$study_out/$shape-$rung-lubrication" \
          "$study_out/$shape-$rung-lubrication-$variant" --label "$shape $rung: lubrication -> $variant" \
          --csv "$study_out/comparison-variants.csv" | tee -a "$study_out/comparison-variants.txt" \
          || study_status_all=1
      done
    done
  done
fi
study_finish
