#!/usr/bin/env bash
# quiescent-study.sh: reproduces the quiescent pair study of docs/studies/results-quiescent.md.
# `tools/quiescent-study.sh --help` says what it runs; docs/studies/results-quiescent.md discusses the results.
set -u -o pipefail

usage() {
  cat <<'EOF'
Usage: tools/quiescent-study.sh [options]

Reproduces docs/studies/results-quiescent.md: the paper's quiescent pair protocol (decks
input/quiescent_{needle,disk,sphere}_{none,stokes}.nml) as six Monte-Carlo batches, then the
statistics and figures, then the sensitivity batches of physics.md section 7. Run it from the
repository root after `make build tools-deps`.

  1. six batches, one at a time (tools/montecarlo.sh -j J), N runs each, seeds S..S+N-1 (the same
     seeds for every shape and fluid, so the orientations and approach directions are shared):
       OUT/{needle,disk,sphere}-{none,stokes}
  2. tools/agglo-stats: OUT/stats-none (the three shapes at 'none'), OUT/stats-stokes (at
     'stokes'), OUT/stats-all (the six batches, grouped by shape and fluid); and
     tools/quiescent_capture.py: OUT/capture (rebound speed against chi_eta at first contact)
  3. sensitivity at 'none' for needles and disks, M runs each, same seeds S..S+M-1:
       OUT/sensitivity/{needle,disk}-none-floor0.5nm   &collision detection_floor = 0.5e-9 m
       OUT/sensitivity/{needle,disk}-none-derjaguin    &dlvo curvature_factor = 'derjaguin'
     each compared run by run with the first M runs of OUT/{needle,disk}-none
     (tools/compare_outcomes.py; table in OUT/sensitivity/comparison.csv), and
     tools/agglo-stats --group-by batch over base and variants: OUT/stats-sensitivity
  4. OUT/batch_times.tsv: the wall time of every batch call of this invocation (appended), with
     the number of runs the call had to run (0 when the batch was already complete)

Options:
  -N, --runs N               runs per batch of step 1 (default 120)
  -M, --sensitivity-runs M   runs per sensitivity batch (default 120; 0 skips step 3)
  -s, --seed S               seed of run 1 (default 1001)
  -j, --jobs J               runs at a time within a batch (default 2); batches run one at a time
  -o, --out DIR              output directory (default output/quiescent-study)
  -h, --help                 this text

Resumable: a second call skips complete runs (tools/montecarlo.sh) and redoes the statistics.
Exit status: 0 when every batch is complete and every statistics step succeeded, 1 otherwise,
2 for a usage error.
EOF
}

runs=120
sensitivity_runs=120
seed=1001
jobs=2
out=output/quiescent-study
while [ $# -gt 0 ]; do
  case "$1" in
    -N|--runs) runs=${2:?}; shift 2 ;;
    -M|--sensitivity-runs) sensitivity_runs=${2:?}; shift 2 ;;
    -s|--seed) seed=${2:?}; shift 2 ;;
    -j|--jobs) jobs=${2:?}; shift 2 ;;
    -o|--out) out=${2:?}; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "quiescent-study: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
for value in "$runs" "$sensitivity_runs" "$seed" "$jobs"; do
  [[ "$value" =~ ^[0-9]+$ ]] || { echo "quiescent-study: '$value' is not a non-negative integer" >&2; exit 2; }
done
[ "$runs" -ge 1 ] && [ "$jobs" -ge 1 ] || { echo "quiescent-study: --runs and --jobs must be >= 1" >&2; exit 2; }
[ "$sensitivity_runs" -le "$runs" ] || {
  echo "quiescent-study: --sensitivity-runs ($sensitivity_runs) must not exceed --runs ($runs):" \
       "each sensitivity run is compared with the base run of the same seed" >&2; exit 2; }

tools=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
python="$tools/../.venv/bin/python"
[ -x "$tools/../build/agglo" ] || { echo "quiescent-study: build/agglo missing: run 'make build'" >&2; exit 2; }
[ -x "$python" ] || { echo "quiescent-study: .venv missing: run 'make tools-deps'" >&2; exit 2; }
mkdir -p "$out" || exit 1
times="$out/batch_times.tsv"
[ -f "$times" ] || printf 'batch\truns\tjobs\truns_run_by_this_call\twall_seconds\tstatus\tdate\n' > "$times"
status_all=0

# run_batch ROOT DECK N [--set ...]: one montecarlo.sh call, timed, appended to batch_times.tsv.
run_batch() {
  local root=$1 deck=$2 count=$3; shift 3
  local before=0 start end status
  if [ -d "$root" ]; then
    before=$(find "$root" -mindepth 2 -maxdepth 2 -name summary.json | wc -l)
  fi
  echo "== batch $root ($count runs of $deck $*)"
  start=$(date +%s.%N)
  "$tools/montecarlo.sh" --deck "$deck" --runs "$count" --seed "$seed" --out "$root" -j "$jobs" "$@"
  status=$?
  end=$(date +%s.%N)
  printf '%s\t%d\t%d\t%d\t%.1f\t%d\t%s\n' "$root" "$count" "$jobs" $((count - before)) \
    "$(echo "$end - $start" | bc)" "$status" "$(date -Iseconds)" >> "$times"
  [ "$status" -eq 0 ] || { echo "quiescent-study: batch $root exit status $status" >&2; status_all=1; }
}

shapes=(needle disk sphere)
fluids=(none stokes)
for fluid in "${fluids[@]}"; do
  for shape in "${shapes[@]}"; do
    # The published tables are the paper's omission of the squeeze film (the 'stokes' decks model it).
    run_batch "$out/$shape-$fluid" "input/quiescent_${shape}_${fluid}.nml" "$runs" --set collision.lubrication=.false.
  done
done

stats() {  # stats OUTDIR [agglo-stats arguments]
  local dir=$1; shift
  echo "== statistics -> $dir"
  "$tools/agglo-stats" -o "$dir" "$@" | tee "$dir.txt" || status_all=1
}
stats "$out/stats-none" "$out"/{needle,disk,sphere}-none
stats "$out/stats-stokes" "$out"/{needle,disk,sphere}-stokes
stats "$out/stats-all" "$out"/{needle,disk,sphere}-{none,stokes} --no-figures
echo "== capture analysis -> $out/capture"
"$python" "$tools/quiescent_capture.py" -o "$out/capture" --sphere "$out/sphere-none" \
  "$out"/{needle,disk,sphere}-none | tee "$out/capture.txt" || status_all=1

if [ "$sensitivity_runs" -gt 0 ]; then
  sens="$out/sensitivity"
  mkdir -p "$sens"
  rm -f "$sens/comparison.csv" "$sens/comparison.txt"
  for shape in needle disk; do
    run_batch "$sens/$shape-none-floor0.5nm" "input/quiescent_${shape}_none.nml" "$sensitivity_runs" \
      --set collision.detection_floor=0.5e-9
    run_batch "$sens/$shape-none-derjaguin" "input/quiescent_${shape}_none.nml" "$sensitivity_runs" \
      --set "dlvo.curvature_factor='derjaguin'"
    for variant in floor0.5nm derjaguin; do
      "$python" "$tools/compare_outcomes.py" "$out/$shape-none" "$sens/$shape-none-$variant" \
        --label "$shape-none-$variant" --csv "$sens/comparison.csv" | tee -a "$sens/comparison.txt" \
        || status_all=1
    done
  done
  stats "$out/stats-sensitivity" --group-by batch \
    "$out"/{needle,disk}-none "$sens"/{needle,disk}-none-{floor0.5nm,derjaguin}
fi

echo "== batch wall times ($times)"
column -t -s $'\t' "$times" 2>/dev/null || cat "$times"
exit "$status_all"
