# study_lib.sh: what the study scripts (tools/chaotic-study.sh, tools/quiescent-resolved-study.sh,
# tools/speed-accuracy-study.sh, tools/suspension-study.sh) share: their common options, one
# Monte-Carlo batch per call of study_batch (local, --status or --slurm), the converged forced
# fields they start from, and the record of every batch's wall time. Sourced, never run; docs/tools.md ("Study scripts") explains it.
# The caller sets study_name and defines study_usage_specific (its own part of --help) before
# sourcing, then calls study_parse_arguments "$@", declares its batches and calls study_finish.

study_tools=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)
study_repo=$(cd "$study_tools/.." && pwd -P)
study_python=${AGGLO_PYTHON:-$study_repo/.venv/bin/python}

study_die() { printf '%s: %s\n' "$study_name" "$1" >&2; exit "${2:-2}"; }

study_usage_common() {
  cat <<'EOF'
Common options:
  -o, --out DIR            output root of the study (default output/<study>)
  -s, --seed S             seed of run 1 of every batch (default 1001; run i has seed S+i-1, so
                           every batch of the study shares its orientations, positions, approach)
  -j, --jobs J             runs at a time within a batch (default 1); batches run one at a time;
                           with --slurm: array tasks at once
  -n, --ranks R            MPI ranks per run of the resolved batches (default 2)
      --launcher CMD       MPI launcher (default mpirun; with --slurm srun), e.g. "mpirun --oversubscribe"
      --time MINUTES       wall-time limit of one run (local: stopped and recorded as failed;
                           Slurm: the array task's --time, default 120)
      --only REGEX         only the batches whose name matches REGEX (bash regex), e.g. 'stokes'
      --list               print the batches (name, runs, deck, --set values) and run nothing
      --status             print each batch's state (complete / failed / not run) and the recorded
                           costs, run nothing
      --slurm              write one sbatch script per batch (tools/montecarlo.sh --slurm), one per
                           missing converged forced field, and OUT/submit-all.sh that submits them
                           in order (the batches depend on their forced field); run nothing
      --sbatch-option O    extra "#SBATCH O" line in every script (repeatable), e.g. --partition=short
      --keep-checkpoints   keep each complete run's checkpoints (default: deleted after the batch,
                           they are only needed to restart an interrupted run: 118 MB at 128^3)
      --keep-fields        keep each complete run's field snapshots and final field (default:
                           deleted after the batch; the analysis reads summary.json and
                           particles.h5 only; 3 x 67 MB per resolved run at 128^3)
      --reuse-from DIR     before running a batch, hard-link in the complete runs of an identical
                           batch under DIR (a DIR/<batch>/ with the same base deck text and seed,
                           tools/montecarlo.sh's batch.nml and batch.conf) instead of computing
                           them again; repeatable; --no-reuse drops the study's default
      --no-analysis        skip the statistics and figures at the end
      --publish            after the analysis, copy its figures (PNG) and small tables (rates,
                           means, illustrative runs, suspension tables, comparisons, costs; not
                           runs.csv) into docs/figures/<study>/ (or $AGGLO_STUDY_PUBLISH_DIR) as
                           <stats directory>_<file>, the output root removed from paths inside
  -h, --help               this text

Resumable: call the same command again; complete runs are skipped (tools/montecarlo.sh), a
forced field that exists is not recomputed (an interrupted one restarts from its checkpoint).
Every batch call's wall time is appended to OUT/batch_times.tsv; OUT/batch_costs.tsv holds, per
batch, the complete runs and the sum, median and maximum of their wall times (summary.json), for
local and Slurm runs alike. Exit status: 0 when every selected batch is complete and the analysis
succeeded, 1 otherwise, 2 for a usage error.
EOF
}

study_parse_arguments() {
  study_out="output/$study_name" study_seed=1001 study_jobs=1 study_jobs_given=0 study_ranks=2
  study_launcher='' study_time='' study_only='' study_mode=run study_keep_checkpoints=0 study_keep_fields=0
  study_analysis=1 study_publish=0 study_reuse_given=0
  study_sbatch_options=() study_reuse_dirs=()
  study_extra_arguments=()
  while [ $# -gt 0 ]; do
    case "$1" in
      -o|--out) study_out=${2:?--out needs a value}; shift 2 ;;
      -s|--seed) study_seed=${2:?--seed needs a value}; shift 2 ;;
      -j|--jobs) study_jobs=${2:?--jobs needs a value}; study_jobs_given=1; shift 2 ;;
      -n|--ranks) study_ranks=${2:?--ranks needs a value}; shift 2 ;;
      --launcher) study_launcher=${2:?--launcher needs a value}; shift 2 ;;
      --time) study_time=${2:?--time needs a value}; shift 2 ;;
      --only) study_only=${2:?--only needs a value}; shift 2 ;;
      --list) study_mode=list; shift ;;
      --status) study_mode=status; shift ;;
      --slurm) study_mode=slurm; shift ;;
      --sbatch-option) study_sbatch_options+=("${2:?--sbatch-option needs a value}"); shift 2 ;;
      --keep-checkpoints) study_keep_checkpoints=1; shift ;;
      --keep-fields) study_keep_fields=1; shift ;;
      --reuse-from) study_reuse_dirs+=("${2:?--reuse-from needs a value}"); study_reuse_given=1; shift 2 ;;
      --no-reuse) study_reuse_dirs=(); study_reuse_given=1; shift ;;
      --no-analysis) study_analysis=0; shift ;;
      --publish) study_publish=1; shift ;;
      -h|--help) study_usage_specific; echo; study_usage_common; exit 0 ;;
      *) study_extra_arguments+=("$1"); shift ;;
    esac
  done
  for value in "$study_seed" "$study_jobs" "$study_ranks"; do
    [[ $value =~ ^[0-9]+$ ]] || study_die "'$value' is not a non-negative integer"
  done
  [ "$study_jobs" -ge 1 ] && [ "$study_ranks" -ge 1 ] || study_die "--jobs and --ranks must be >= 1"
  if [ -n "$study_time" ]; then
    [[ $study_time =~ ^[1-9][0-9]*$ ]] || study_die "--time '$study_time': whole minutes >= 1"
  fi
  [ -x "$study_repo/build/agglo" ] || study_die "build/agglo missing: run 'make build'"
  if [ "$study_mode" != list ]; then mkdir -p "$study_out" || exit 1; fi
  study_times="$study_out/batch_times.tsv"
  study_status_all=0
  study_batches=()
  study_submit_lines=()
  declare -gA study_field_jobs=()
  if [ "$study_mode" = slurm ]; then
    mkdir -p "$study_out/slurm" || exit 1
  fi
}

# study_selected NAME: whether --only selects the batch.
study_selected() { [ -z "$study_only" ] || [[ $1 =~ $study_only ]]; }

# study_deck_info DECK [--set ...]: "FLUID NX INIT_FILE" of the deck with the --set values, read
# from the code's own resolved deck (INIT_FILE empty when the deck starts from no file).
study_deck_info() {
  "$study_repo/build/agglo" "$@" --print-deck 2>/dev/null < /dev/null | awk '
    { line = $0; sub(/!.*/, "", line) }
    match(line, /^[ \t]*fluid[ \t]*=[ \t]*.[a-z_]*/) { v = substr(line, RSTART, RLENGTH); sub(/.*=[ \t]*./, "", v); fluid = v }
    match(line, /(^|[ ,])nx[ \t]*=[ \t]*[0-9]+/) { v = substr(line, RSTART, RLENGTH); sub(/.*=[ \t]*/, "", v); nx = v }
    match(line, /init_file[ \t]*=[ \t]*.[^\x27"]*/) { v = substr(line, RSTART, RLENGTH); sub(/.*=[ \t]*./, "", v); file = v }
    END { printf "%s %s %s\n", fluid, nx, file }'
}

# study_forced_field FILE NX: make sure the converged forced field FILE (input/hit_box.nml on an NX^3
# grid, written into FILE's directory) exists: locally it is computed (restarted from its newest
# checkpoint when an earlier call was interrupted); with --slurm an sbatch script is written and
# submitted first by submit-all.sh; with --status/--list its state is printed.
study_forced_field() {
  local file=$1 nx=$2 directory name status start end restart=.false. script
  directory=$(dirname "$file"); name=$(basename "$directory")
  [ -n "${study_field_sources[$file]+x}" ] && { study_regridded_field "$file" "$nx"; return; }
  [ -n "${study_field_jobs[$file]+x}" ] && return 0
  study_field_jobs[$file]=''
  local -a sets=(--set "grid.nx=$nx" --set "grid.ny=$nx" --set "grid.nz=$nx" --set "run.name='$name'"
                 --set "output.directory='$directory'")
  if [ -f "$file" ]; then
    [ "$study_mode" = run ] || echo "forced field $file: present"
    return 0
  fi
  case "$study_mode" in
    list|status) echo "forced field $file: MISSING (input/hit_box.nml at ${nx}^3; computed as the first step)"; return 0 ;;
    slurm)
      script="$study_out/slurm/forced_field_$name.sbatch"
      {
        printf '#!/bin/bash\n# Converged forced field %s: input/hit_box.nml at %s^3 (0.4 s simulated).\n' "$file" "$nx"
        printf '# Resubmitting restarts it from its newest checkpoint.\n'
        printf '#SBATCH --job-name=agglo-field-%s\n#SBATCH --ntasks=%s\n#SBATCH --time=%s\n' "$nx" "$study_ranks" 2880
        printf '#SBATCH --output=%q\n' "$study_out/slurm/forced_field_$name.log"
        local option; for option in "${study_sbatch_options[@]}"; do printf '#SBATCH %s\n' "$option"; done
        printf 'cd %q || exit 1\n' "$PWD"
        printf '# An interrupted field continues from its newest checkpoint; else a fresh run (overwrite).\n'
        printf 'resume=(--set run.overwrite=.true.)\n'
        printf 'ls %q/checkpoints/checkpoint_*.h5 > /dev/null 2>&1 && resume=(--set run.restart=.true.)\n' "$directory"
        printf '%s -n %s %q input/hit_box.nml' "${study_launcher:-srun}" "$study_ranks" "$study_repo/build/agglo"
        printf ' %q' "${sets[@]}"
        printf ' "${resume[@]}"\n'
      } > "$script"
      chmod +x "$script"
      study_field_jobs[$file]=$(printf 'field_%s' "$nx")
      study_submit_lines+=("field_$nx=\$(sbatch --parsable $(printf '%q' "$script")) || exit 1"
                           "echo \"forced field $nx^3: job \$field_$nx\"")
      echo "wrote $script"
      return 0 ;;
  esac
  local -a resume=(--set run.overwrite=.true.)
  if ls "$directory"/checkpoints/checkpoint_*.h5 > /dev/null 2>&1; then restart=.true.; resume=(--set run.restart=.true.); fi
  echo "== forced field $file: input/hit_box.nml at ${nx}^3 (restart $restart; about 4 min at 64^3 on 2 cores, x16 per doubling)"
  local -a launcher
  read -r -a launcher <<< "${study_launcher:-mpirun}"
  start=$(date +%s.%N)
  "${launcher[@]}" -n "$study_ranks" "$study_repo/build/agglo" input/hit_box.nml "${sets[@]}" \
    "${resume[@]}" > "$study_out/forced_field_$name.log" 2>&1 < /dev/null
  status=$?
  end=$(date +%s.%N)
  study_time_row "forced_field_$name" 1 "$study_ranks" 1 "$(echo "$end - $start" | bc)" "$status"
  if [ "$status" -ne 0 ] || [ ! -f "$file" ]; then
    echo "$study_name: forced field $file failed (log: $study_out/forced_field_$name.log)" >&2
    study_status_all=1
    return 1
  fi
}

# Fields that are another converged field resampled onto the batches' grid (study_field_from):
# FILE -> "BASE_NX BASE_FILE".
declare -A study_field_sources=()

# study_field_from FILE BASE_FILE BASE_NX: the batches whose &fluid init_file is FILE start from the
# converged forced field BASE_FILE (of a BASE_NX^3 grid) resampled onto their own grid by
# tools/regrid_field.py, instead of a field converged on that grid (study_regridded_field).
study_field_from() { study_field_sources[$1]="$3 $2"; }

# study_regridded_field FILE NX: make sure FILE (study_field_from's BASE_FILE on an NX^3 grid)
# exists: the base field first (study_forced_field), then tools/regrid_field.py (seconds; its
# output appears only when complete). With --slurm: done now when the base field exists, else a
# one-task sbatch script that waits for the base field's job; with --status/--list its state.
study_regridded_field() {
  local file=$1 nx=$2 base base_nx name status start end script job
  read -r base_nx base <<< "${study_field_sources[$file]}"
  name=$(basename "$(dirname "$file")")
  [ -n "${study_field_jobs[$file]+x}" ] && return 0
  study_field_jobs[$file]=''
  local -a regrid=("$study_python" "$study_tools/regrid_field.py" "$base" --grid "$nx" -o "$file")
  if [ -f "$file" ]; then
    [ "$study_mode" = run ] || echo "regridded field $file: present"
    return 0
  fi
  case "$study_mode" in
    list|status)
      echo "regridded field $file: MISSING (tools/regrid_field.py: $base resampled onto ${nx}^3, made first)"
      study_forced_field "$base" "$base_nx"
      return 0 ;;
    slurm)
      study_forced_field "$base" "$base_nx"
      if [ -n "${study_field_jobs[$base]}" ]; then
        script="$study_out/slurm/regrid_field_$name.sbatch" job="field_${base_nx}_on_$nx"
        {
          printf '#!/bin/bash\n# %s: the converged field %s resampled onto %s^3 (tools/regrid_field.py).\n' \
            "$file" "$base" "$nx"
          printf '#SBATCH --job-name=agglo-regrid-%s\n#SBATCH --ntasks=1\n#SBATCH --time=30\n' "$nx"
          printf '#SBATCH --mem=4G\n'   # measured peak: 2.1 GB for 128^3 -> 256^3
          printf '#SBATCH --output=%q\n' "$study_out/slurm/regrid_field_$name.log"
          local option; for option in "${study_sbatch_options[@]}"; do printf '#SBATCH %s\n' "$option"; done
          printf 'cd %q || exit 1\n' "$PWD"
          printf '[ -f %q ] && exit 0\n' "$file"
          printf '%q ' "${regrid[@]}"; printf '\n'
        } > "$script"
        chmod +x "$script"
        study_field_jobs[$file]=$job
        local after="--dependency=afterok:\$${study_field_jobs[$base]}"
        study_submit_lines+=("$job=\$(sbatch --parsable $after $(printf '%q' "$script")) || exit 1"
                             "echo \"regridded field ${nx}^3: job \$$job\"")
        echo "wrote $script"
        return 0
      fi ;;
    *) study_forced_field "$base" "$base_nx" || return 1 ;;
  esac
  echo "== regridded field $file: $base resampled onto ${nx}^3 (tools/regrid_field.py)"
  mkdir -p "$study_out" || return 1
  start=$(date +%s.%N)
  "${regrid[@]}" > "$study_out/regrid_field_$name.log" 2>&1 < /dev/null
  status=$?
  end=$(date +%s.%N)
  study_time_row "regrid_field_$name" 1 1 1 "$(echo "$end - $start" | bc)" "$status"
  if [ "$status" -ne 0 ] || [ ! -f "$file" ]; then
    echo "$study_name: regridded field $file failed (log: $study_out/regrid_field_$name.log)" >&2
    study_status_all=1
    return 1
  fi
}

# study_agglo ARGS...: the code as the study scripts check decks with it ($AGGLO, else this
# repository's build), standard input closed.
study_agglo() { "${AGGLO:-$study_repo/build/agglo}" "$@" < /dev/null; }

study_time_row() {  # batch runs jobs runs_run wall status
  [ -f "$study_times" ] || printf 'batch\truns\tjobs\truns_run_by_this_call\twall_seconds\tstatus\tdate\n' > "$study_times"
  printf '%s\t%s\t%s\t%s\t%.1f\t%s\t%s\n' "$1" "$2" "$3" "$4" "$5" "$6" "$(date -Iseconds)" >> "$study_times"
}

# study_batch NAME DECK RUNS [--set G.V=VALUE ...]: one Monte-Carlo batch OUT/NAME of the study.
# Resolved decks (with a &fluid init_file) get their forced field first and run on --ranks ranks.
# A batch continued from an earlier session: when the caller sets study_earlier_table to the run
# table of the batch's runs 1..K-1 (their directories gone; tools/study_compare.py), only runs
# K..RUNS run here (montecarlo.sh --from-run K) and the table is kept in the root as
# earlier_runs.csv, where the analysis reads those runs.
study_earlier_table=''
study_batch() {
  local name=$1 deck=$2 runs=$3; shift 3
  local root="$study_out/$name" fluid field nx ranks=1 before=0 start end status first_run=1
  [ -n "$study_earlier_table" ] && first_run=$(wc -l < "$study_earlier_table")   # a header and K-1 rows
  study_selected "$name" || return 0
  study_batches+=("$name")
  read -r fluid nx field <<< "$(study_deck_info "$deck" "$@")"
  [ "$fluid" = resolved ] && ranks=$study_ranks
  if [ "$study_mode" = list ]; then
    printf '%-34s %5s  %s %s%s\n' "$name" "$runs" "$deck" "$*" "${field:+  (field $field)}"
    [ -n "$field" ] && study_forced_field "$field" "$nx"
    return 0
  fi
  local -a common=(--deck "$deck" --runs "$runs" --seed "$study_seed" --out "$root" --ranks "$ranks" "$@")
  [ -n "$study_launcher" ] && common+=(--launcher "$study_launcher")
  (( first_run > 1 )) && common+=(--from-run "$first_run")
  case "$study_mode" in
    status)
      [ -n "$field" ] && study_forced_field "$field" "$nx"
      if [ -f "$root/batch.conf" ]; then
        "$study_tools/montecarlo.sh" "${common[@]}" --status || study_status_all=1
      else
        echo "batch $root: not started ($runs runs)"; study_status_all=1
      fi
      return 0 ;;
    slurm)
      if [ -n "$field" ]; then study_forced_field "$field" "$nx" || { study_status_all=1; return 0; }; fi
      local -a slurm=(--slurm --time "${study_time:-120}")
      (( study_jobs_given )) && slurm+=(--jobs "$study_jobs")
      local option; for option in "${study_sbatch_options[@]}"; do slurm+=(--sbatch-option "$option"); done
      "$study_tools/montecarlo.sh" "${common[@]}" "${slurm[@]}" || { study_status_all=1; return 0; }
      study_keep_earlier_runs "$root"
      if [ -f "$root/montecarlo.sbatch" ]; then
        local dependency=''
        [ -n "$field" ] && [ -n "${study_field_jobs[$field]}" ] && \
          dependency="--dependency=afterok:\$${study_field_jobs[$field]} "
        study_submit_lines+=("sbatch ${dependency}$(printf '%q' "$root/montecarlo.sbatch") || exit 1")
      fi
      return 0 ;;
  esac
  if [ -n "$field" ]; then
    study_forced_field "$field" "$nx" || { study_status_all=1; return 0; }
  fi
  study_reuse_runs "$root" "$runs" "$deck" "$@"
  [ -d "$root" ] && before=$(find "$root" -mindepth 2 -maxdepth 2 -name summary.json | wc -l)
  echo "== batch $root ($runs runs of $deck $*)"
  [ -n "$study_time" ] && common+=(--time "$study_time")
  start=$(date +%s.%N)
  "$study_tools/montecarlo.sh" "${common[@]}" -j "$study_jobs"
  status=$?
  end=$(date +%s.%N)
  study_keep_earlier_runs "$root"
  study_time_row "$root" "$runs" "$study_jobs" $((runs - first_run + 1 - before)) "$(echo "$end - $start" | bc)" "$status"
  [ "$status" -eq 0 ] || { echo "$study_name: batch $root exit status $status" >&2; study_status_all=1; }
  study_prune "$root"
}

# study_reuse_runs ROOT RUNS DECK [--set ...]: the complete runs 1..RUNS of an identical batch under
# a --reuse-from directory, hard-linked (copied across file systems) into ROOT, so that
# tools/montecarlo.sh skips them. Identical means the same base deck text (batch.nml, the code's own
# --print-deck of DECK with the --set values, as tools/montecarlo.sh writes it) and the same base
# seed: run i then has the same seed and deck as in the other batch, and the same executable would
# repeat it to the bit. A ROOT that already holds a batch keeps its batch.nml and batch.conf.
study_reuse_runs() {
  local root=$1 runs=$2 deck=$3 source_root conf text i run linked=0; shift 3
  (( ${#study_reuse_dirs[@]} )) || return 0
  text=$(study_agglo "$deck" "$@" --print-deck 2> /dev/null) || return 0
  text+=$'\n'
  local -a confs=()
  for source_root in "${study_reuse_dirs[@]}"; do
    for conf in "$source_root"/*/batch.conf; do [ -f "$conf" ] && confs+=("$conf"); done
  done
  for conf in "${confs[@]}"; do
    source_root=$(dirname "$conf")
    [ "$(cd "$source_root" && pwd -P)" = "$(cd "$root" 2> /dev/null && pwd -P)" ] && continue
    [ "$(sed -n 's/^base_seed=//p' "$conf")" = "$study_seed" ] || continue
    printf '%s' "$text" | cmp -s - "$source_root/batch.nml" || continue
    if [ -f "$root/batch.conf" ]; then
      cmp -s "$root/batch.nml" "$source_root/batch.nml" || continue
    else
      mkdir -p "$root" && cp "$source_root/batch.nml" "$source_root/batch.conf" "$root/" || return 0
    fi
    for ((i = 1; i <= runs; i++)); do
      run=$(printf 'run_%04d' "$i")
      [ -f "$source_root/$run/summary.json" ] && [ ! -e "$source_root/$run/FAILED" ] || continue
      [ -e "$root/$run" ] && continue
      rm -rf "$root/.$run.partial"
      cp -al "$source_root/$run" "$root/.$run.partial" 2> /dev/null || \
        { rm -rf "$root/.$run.partial"; cp -a "$source_root/$run" "$root/.$run.partial"; } || continue
      mv "$root/.$run.partial" "$root/$run" || continue
      linked=$((linked + 1))
    done
    (( linked )) && echo "== batch $root: $linked complete runs reused from $source_root (same deck and seeds)"
    return 0
  done
}

# study_prune ROOT: the bulky files of the complete runs of a batch. Checkpoints are only needed to
# restart a run, and a complete run is never restarted; the analysis reads summary.json and
# particles.h5, not the field snapshots (fields_<step>.h5, fields.xdmf) or the final field.
# study_keep_earlier_runs ROOT: study_earlier_table (if set) as ROOT/earlier_runs.csv, once montecarlo.sh
# has made the root (it refuses a non-empty root without its batch.conf).
study_keep_earlier_runs() {
  [ -n "$study_earlier_table" ] && [ -f "$1/batch.conf" ] || return 0
  cmp -s "$study_earlier_table" "$1/earlier_runs.csv" && return 0
  cp "$study_earlier_table" "$1/earlier_runs.csv.tmp" && mv -f "$1/earlier_runs.csv.tmp" "$1/earlier_runs.csv" || study_status_all=1
}

study_prune() {
  local run
  for run in "$1"/run_*/; do
    [ -f "$run/summary.json" ] && [ ! -e "$run/FAILED" ] || continue
    (( study_keep_checkpoints )) || rm -f "$run"/checkpoints/checkpoint_*.h5
    (( study_keep_fields )) || rm -f "$run"/fields_*.h5 "$run"/fields.xdmf "$run"/final_field.h5
  done
  return 0
}

# study_has_runs NAME: whether OUT/NAME has any complete run (analysis steps skip empty batches).
study_has_runs() { compgen -G "$study_out/$1/run_*/summary.json" > /dev/null; }

# study_costs: OUT/batch_costs.tsv, per batch the complete runs and their wall times (summary.json).
study_costs() {
  [ "$study_mode" = list ] && return 0
  "$study_python" "$study_tools/batch_costs.py" "$study_out" -o "$study_out/batch_costs.tsv" \
    || study_status_all=1
}

# study_publish_results: the analysis' figures and small tables into docs/figures/<study>/, with
# the study's output root removed from the paths inside (no machine paths in the repository). The
# two cost tables keep what earlier sessions published there (their output roots are gone):
# batch_times.tsv gains the rows it lacks, batch_costs.tsv's rows are replaced batch by batch.
study_publish_results() {
  local target="${AGGLO_STUDY_PUBLISH_DIR:-$study_repo/docs/figures/$study_name}" file name directory
  mkdir -p "$target" || { study_status_all=1; return; }
  for file in "$study_out"/stats-*/*.png "$study_out"/stats-*/{rates,history_means,illustrative}.csv \
              "$study_out"/stats-*/suspension_{table,comparison}.csv \
              "$study_out"/analysis/*.png "$study_out"/analysis/{comparison.csv,speed_accuracy.md} \
              "$study_out"/{comparison.csv,batch_costs.tsv,batch_times.tsv} "$study_out"/transitions-*.csv; do
    [ -f "$file" ] || continue
    directory=$(basename "$(dirname "$file")"); name=$(basename "$file")
    [ "$(dirname "$file")" = "$study_out" ] || name="${directory}_$name"
    case "$name" in
      *.png) cp "$file" "$target/$name" ;;
      batch_times.tsv|batch_costs.tsv)
        study_strip_root "$file" > "$target/$name.new" && study_merge_table "$name" "$target/$name" "$target/$name.new" \
          && mv -f "$target/$name.new" "$target/$name" || study_status_all=1 ;;
      *) study_strip_root "$file" > "$target/$name" ;;
    esac
  done
  echo "published the figures and tables into $target"
}

study_strip_root() { sed -e "s|$(cd "$study_out" && pwd -P)/||g" -e "s|$study_out/||g" "$1"; }

# study_merge_table NAME PUBLISHED NEW: NEW (rewritten in place) with the rows of the PUBLISHED table it
# lacks: batch_times.tsv keeps every published row and appends the new ones it does not hold yet;
# batch_costs.tsv keeps the published batches that NEW has no row for, all sorted by batch.
study_merge_table() {
  [ -f "$2" ] || return 0
  if [ "$1" = batch_times.tsv ]; then
    awk '!seen[$0]++' "$2" "$3" > "$3.tmp"
  else
    { head -n 1 "$3"
      awk -F '\t' 'FNR == 1 { next } NR == FNR { row[$1] = $0; next } { row[$1] = $0 }
                   END { for (batch in row) print row[batch] }' "$2" "$3" | LC_ALL=C sort -t $'\t' -k 1,1; } > "$3.tmp"
  fi && mv -f "$3.tmp" "$3"
}

study_finish() {
  case "$study_mode" in
    list) exit 0 ;;
    slurm)
      local submit="$study_out/submit-all.sh"
      {
        printf '#!/bin/bash\n# Submits every sbatch script of %s written by --slurm (forced fields first;\n' "$study_name"
        printf '# each batch waits for its field). Rerun the --slurm command after a partial run: the new\n'
        printf '# scripts list only the runs that are not complete.\nset -u\n'
        local line; for line in "${study_submit_lines[@]}"; do printf '%s\n' "$line"; done
        printf 'echo "after the jobs: %s (same options, without --slurm) does the analysis;' "$study_name"
        printf ' --status shows progress"\n'
      } > "$submit"
      chmod +x "$submit"
      echo "wrote $submit (${#study_submit_lines[@]} submissions); submit with: bash $submit"
      exit "$study_status_all" ;;
    status)
      study_costs
      [ -f "$study_out/batch_costs.tsv" ] && column -t -s $'\t' "$study_out/batch_costs.tsv"
      exit "$study_status_all" ;;
  esac
  study_costs
  (( study_publish )) && study_publish_results
  if [ -f "$study_times" ]; then
    echo "== batch wall times ($study_times)"
    column -t -s $'\t' "$study_times" 2>/dev/null || cat "$study_times"
  fi
  exit "$study_status_all"
}
