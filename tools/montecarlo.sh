#!/usr/bin/env bash
# Monte-Carlo batches of Agglo runs: one base deck, many seeds, locally in parallel or as a Slurm
# job array. Resumable; a failed run is recorded and the batch carries on. `--help` says how.
# Needs bash >= 5.1 (wait -n -p) and coreutils only.
set -uo pipefail
export LC_ALL=C   # byte lengths and plain ASCII case mapping

script_name=${0##*/}
script_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd -P)

usage() {
  cat <<EOF
Usage: $script_name --deck FILE --runs N --seed S --out ROOT [options]

Runs N copies of the base deck FILE that differ only in &run seed (S, S+1, ..., S+N-1) and name.
Run i (1-based) lives in ROOT/run_NNNN (NNNN = i with 4 digits) with its own deck ROOT/run_NNNN/deck.nml:
the base deck with &run name = 'run_NNNN', seed, overwrite = .true., restart = .false. and
&output directory = ROOT/run_NNNN merged into the deck's own &run and &output groups (added if the
deck has none) by the code itself (agglo DECK --set ... --print-deck), which checks every deck as
it would a run's. The code draws the particles' orientations and positions from the seed.

Required:
  -d, --deck FILE        base deck (namelist file, e.g. input/<case>.nml)
  -N, --runs N           number of runs in the batch (a later call may raise it to extend the batch)
  -s, --seed S           seed of run 1; run i gets S+i-1
  -o, --out ROOT         output root of the batch (created; spaces in the path are fine)

Options:
  -j, --jobs J           runs at the same time (default 1); with --slurm: at most J array tasks at once
  -n, --ranks R          MPI ranks per run (default 1; R > 1 starts each run with the launcher)
      --set G.V=VALUE    set variable V of group &G in every run, VALUE as written in a deck
                         (e.g. --set run.end_time=2e-3 --set "scene.fluid='stokes'"); repeatable;
                         part of the batch's base deck; passed to the code's own --set
      --agglo PATH       the executable (default: \$AGGLO, else build/agglo of this repository)
      --launcher CMD     MPI launcher for R > 1, words split on blanks (default "mpirun";
                         with --slurm "srun"); called as CMD -n R AGGLO DECK
      --time MINUTES     wall-time limit of one run: locally the run is stopped and recorded as
                         failed; with --slurm the array task's --time (default there: 60)
      --min-free MIB     start a run only while the file system of ROOT has at least MIB MiB free
                         (default 1024; 0: no check): a full disk fails every run that writes;
                         with less, the runs in flight finish and the call ends (exit status 1),
                         to be called again once there is room
      --slurm            write ROOT/montecarlo.sbatch (one array task per incomplete run) and stop;
                         submit it with: sbatch ROOT/montecarlo.sbatch
      --sbatch-option O  extra "#SBATCH O" line, e.g. --sbatch-option --partition=short (repeatable)
      --status           print how many runs are complete / failed / not run, run nothing
  -F, --from-run K       this call's runs are K..N only (default 1): runs 1..K-1 are kept elsewhere
                         (a study's run table of an earlier session, their directories gone) and
                         are neither run nor counted; run i still gets seed S+i-1
  -h, --help             this text

Resume: call the same command again. Complete runs (summary.json present, no FAILED marker) are
skipped; incomplete, failed or interrupted runs start again from scratch (overwrite = .true.).
The root keeps the batch's base deck (ROOT/batch.nml, with the --set values applied) and base seed
(ROOT/batch.conf); a call with a different base deck or seed for the same root is refused.

Suspension decks (&scene particles = 'suspension') are run the same way. The code writes no
summary.json for them (there is no pair outcome): when such a run exits 0 with its particles.h5,
this script writes its summary.json ("scene": "suspension", "complete": true, name, seed, the
deck's end_time, wall_time in seconds, whether clusters.h5 exists), so that a run is complete,
here and for the study and statistics tools alike, when its summary.json says so.

A run failed when the executable exits non-zero, or exits 0 without writing summary.json. Its
directory then holds FAILED (the reason) next to stdout.log (everything the run printed) and the
code's agglo.log; ROOT/failed.txt lists the failed runs of the last call. Runs start in the current
directory, so relative paths inside the deck resolve from where you call this script.

Exit status: 0 when every run of the batch is complete, 1 when some run failed or is incomplete,
2 for a usage error or a refused root, 130 when interrupted (the interrupted runs are incomplete).
EOF
}

die() { printf '%s: %s\n' "$script_name" "$1" >&2; exit "${2:-2}"; }
say() { printf '%s: %s\n' "$script_name" "$*"; }

if (( BASH_VERSINFO[0] < 5 || (BASH_VERSINFO[0] == 5 && BASH_VERSINFO[1] < 1) )); then
  die "needs bash >= 5.1 (this is $BASH_VERSION)"
fi

# ---------------------------------------------------------------------------------------------
# Decks: the code itself merges overrides into a deck and checks the result
# (agglo DECK --set group.variable=value ... --print-deck), so there is one namelist parser.
# ---------------------------------------------------------------------------------------------
fortran_string() { # text -> a Fortran string literal ('' doubles a quote)
  local q="'"
  printf "'%s'" "${1//$q/$q$q}"
}

# ---------------------------------------------------------------------------------------------
# One run's result (also copied verbatim into the Slurm script, so both paths judge alike).
# ---------------------------------------------------------------------------------------------
record_run_result() { # run directory, exit status[, wall seconds] -> 0 complete, 1 failed (FAILED written)
  local dir=$1 status=$2 reason=''
  # A suspension run ends without summary.json (it has no pair outcome): its summary is written here.
  if [[ $status -eq 0 && ! -f $dir/summary.json ]] && is_suspension_deck "$dir/deck.nml"; then
    if [[ -f $dir/particles.h5 ]]; then write_suspension_summary "$dir" "${3:-}"
    else reason="exited 0 but wrote no particles.h5 (a suspension run)"; fi
  fi
  if [[ -n $reason ]]; then :
  elif [[ $status -eq 124 ]]; then reason="stopped at the time limit (exit status 124)"
  elif [[ $status -ne 0 ]]; then reason="exit status $status"
  elif [[ ! -f $dir/summary.json ]]; then reason="exited 0 but wrote no summary.json"
  fi
  if [[ -z $reason ]]; then rm -f "$dir/FAILED"; return 0; fi
  # A summary from a run that then failed is not trusted: keep it aside, so resume reruns the run.
  [[ -f $dir/summary.json ]] && mv -f "$dir/summary.json" "$dir/summary.json.rejected"
  printf 'reason: %s\nfinished: %s\nlog: %s\n' "$reason" "$(date '+%Y-%m-%d %H:%M:%S')" \
    "$dir/stdout.log" > "$dir/FAILED"
  return 1
}

# A complete run has summary.json (the code's, or write_suspension_summary's) that does not say
# "complete": false, and no FAILED marker.
run_is_complete() { [[ -f $1/summary.json && ! -e $1/FAILED ]] && ! grep -Eq '"complete"[[:space:]]*:[[:space:]]*false' "$1/summary.json"; }

deck_value() { # deck file, variable -> its value as written (the last assignment wins, as in a namelist)
  sed -e 's/!.*//' "$1" 2>/dev/null | tr ',' '\n' | \
    sed -n -E "s/^[[:space:]&a-zA-Z_]*[[:space:]]?(^|[[:space:]])$2[[:space:]]*=[[:space:]]*//Ip" | tail -n 1 | \
    sed -E "s/[[:space:]]*\/?[[:space:]]*$//; s/^['\"]//; s/['\"]$//"
}

is_suspension_deck() { [[ -f $1 && $(deck_value "$1" particles) == [Ss][Uu][Ss][Pp][Ee][Nn][Ss][Ii][Oo][Nn] ]]; }

write_suspension_summary() { # run directory[, wall seconds]: the run's summary.json (atomically)
  local dir=$1 wall=${2:-} name seed end
  name=$(deck_value "$dir/deck.nml" name); seed=$(deck_value "$dir/deck.nml" seed)
  end=$(deck_value "$dir/deck.nml" end_time); end=${end//[dD]/e}
  end=$(printf '%.17g' "$end" 2>/dev/null) || end=null
  [[ $seed =~ ^-?[0-9]+$ ]] || seed=null
  [[ $wall =~ ^[0-9]+(\.[0-9]+)?$ ]] || wall=null
  printf '{\n  "scene": "suspension",\n  "complete": true,\n  "name": "%s",\n  "seed": %s,\n  "end_time": %s,\n  "wall_time": %s,\n  "clusters": %s,\n  "written_by": "tools/montecarlo.sh"\n}\n' \
    "${name//[\"\\]/_}" "$seed" "$end" "$wall" "$([[ -f $dir/clusters.h5 ]] && echo true || echo false)" \
    > "$dir/summary.json.tmp" && mv -f "$dir/summary.json.tmp" "$dir/summary.json"
}

now_ms() { local t=${EPOCHREALTIME/[.,]/}; printf '%s' $((10#$t / 1000)); }   # wall clock, milliseconds

format_seconds() { # milliseconds -> "0.4s", "12s", "3m05s", "2h10m"
  local ms=$1 t=$(($1 / 1000))
  if (( ms < 10000 )); then printf '%d.%ds' $((ms / 1000)) $((ms % 1000 / 100)); return; fi
  if (( t >= 3600 )); then printf '%dh%02dm' $((t / 3600)) $((t % 3600 / 60))
  elif (( t >= 60 )); then printf '%dm%02ds' $((t / 60)) $((t % 60))
  else printf '%ds' "$t"; fi
}

# ---------------------------------------------------------------------------------------------
# Arguments
# ---------------------------------------------------------------------------------------------
deck='' runs='' base_seed='' root='' jobs=1 jobs_given=0 ranks=1 agglo=${AGGLO:-} launcher=''
time_limit='' slurm=0 status_only=0 first_run=1 min_free=1024
declare -a sbatch_options=() user_sets=() set_arguments=()
need_value() { [[ $# -ge 2 ]] || die "option $1 needs a value (see --help)"; }
while [[ $# -gt 0 ]]; do
  case $1 in
    -h|--help) usage; exit 0 ;;
    -d|--deck) need_value "$@"; deck=$2; shift ;;
    -N|--runs) need_value "$@"; runs=$2; shift ;;
    -s|--seed) need_value "$@"; base_seed=$2; shift ;;
    -o|--out) need_value "$@"; root=$2; shift ;;
    -j|--jobs) need_value "$@"; jobs=$2; jobs_given=1; shift ;;
    -n|--ranks) need_value "$@"; ranks=$2; shift ;;
    --set) need_value "$@"; user_sets+=("$2"); shift ;;
    --agglo) need_value "$@"; agglo=$2; shift ;;
    --launcher) need_value "$@"; launcher=$2; shift ;;
    --time) need_value "$@"; time_limit=$2; shift ;;
    --min-free) need_value "$@"; min_free=$2; shift ;;
    --slurm) slurm=1 ;;
    --sbatch-option) need_value "$@"; sbatch_options+=("$2"); shift ;;
    --status) status_only=1 ;;
    -F|--from-run) need_value "$@"; first_run=$2; shift ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
  shift
done

[[ -n $deck && -n $runs && -n $base_seed && -n $root ]] || die "--deck, --runs, --seed and --out are required (see --help)"
[[ -f $deck && -r $deck ]] || die "base deck '$deck' is not a readable file"
[[ $runs =~ ^[1-9][0-9]*$ ]] || die "--runs '$runs' is not allowed; allowed: an integer >= 1"
[[ $base_seed =~ ^-?[0-9]+$ ]] || die "--seed '$base_seed' is not allowed; allowed: an integer"
[[ $jobs =~ ^[1-9][0-9]*$ ]] || die "--jobs '$jobs' is not allowed; allowed: an integer >= 1"
[[ $ranks =~ ^[1-9][0-9]*$ ]] || die "--ranks '$ranks' is not allowed; allowed: an integer >= 1"
if [[ -n $time_limit ]]; then
  [[ $time_limit =~ ^[1-9][0-9]*$ ]] || die "--time '$time_limit' is not allowed; allowed: whole minutes >= 1"
fi
[[ $min_free =~ ^[0-9]+$ ]] || die "--min-free '$min_free' is not allowed; allowed: whole MiB >= 0 (0: no check)"
(( runs <= 99999 )) || die "--runs $runs is not allowed; allowed: at most 99999"
[[ $first_run =~ ^[1-9][0-9]*$ ]] && (( first_run <= runs )) || \
  die "--from-run '$first_run' is not allowed; allowed: an integer from 1 to --runs ($runs)"
for set_text in "${user_sets[@]}"; do
  [[ $set_text =~ ^([A-Za-z][A-Za-z0-9_]*)\.([A-Za-z][A-Za-z0-9_]*)=(.+)$ ]] || \
    die "--set '$set_text' is not allowed; allowed: GROUP.VARIABLE=VALUE, e.g. run.end_time=2e-3"
  group=${BASH_REMATCH[1],,}; variable=${BASH_REMATCH[2],,}
  if [[ ($group == run && $variable =~ ^(name|seed|overwrite|restart)$) || ($group == output && $variable == directory) ]]; then
    die "--set $group.$variable is not allowed: the batch sets it for every run"
  fi
  set_arguments+=(--set "$set_text")
done
if [[ -z $launcher ]]; then
  if (( slurm )); then launcher=srun; else launcher=mpirun; fi
fi
read -r -a launcher_words <<< "$launcher"
[[ ${#launcher_words[@]} -gt 0 ]] || die "--launcher is empty"

# ---------------------------------------------------------------------------------------------
# The batch root: its base deck and seed, and a lock against two calls working on it at once.
# ---------------------------------------------------------------------------------------------
if [[ -e $root && ! -d $root ]]; then die "output root '$root' exists and is not a directory"; fi
if (( status_only )) && [[ ! -f $root/batch.conf ]]; then die "output root '$root' holds no batch (no batch.conf)"; fi
if [[ -d $root && ! -f $root/batch.conf ]] && [[ -n $(ls -A "$root" 2>/dev/null) ]]; then
  die "output root '$root' is not empty and holds no batch (no batch.conf): choose a new or empty directory"
fi

if [[ -z $agglo ]]; then agglo="$script_dir/../build/agglo"; fi
[[ -f $agglo && -x $agglo ]] || die "executable '$agglo' not found or not executable (build it with 'make build', or pass --agglo / set AGGLO)"
agglo="$(cd "$(dirname "$agglo")" && pwd -P)/$(basename "$agglo")"

# The batch's base deck: the deck with the --set values merged and checked by the code.
refusal=$(mktemp) || die "cannot create a temporary file"
batch_deck_text=$("$agglo" "$deck" "${set_arguments[@]}" --print-deck 2> "$refusal" < /dev/null)
status=$?
batch_deck_text+=$'\n'
message=$(grep -m1 'error' "$refusal" || tail -n 1 "$refusal"); rm -f "$refusal"
(( status == 0 )) || die "base deck '$deck' (with the --set values) is refused by the code: $message"
mkdir -p "$root" || die "cannot create the output root '$root'"
root=$(cd "$root" && pwd -P) || die "cannot enter the output root"

lock="$root/.montecarlo.lock"
if ! mkdir "$lock" 2>/dev/null; then
  holder=$(cat "$lock/pid" 2>/dev/null)
  if [[ -n $holder ]] && kill -0 "$holder" 2>/dev/null; then
    die "another $script_name (pid $holder) is working on '$root'; wait for it or stop it first"
  fi
  rm -rf "$lock"; mkdir "$lock" || die "cannot lock '$root'"
fi
echo $$ > "$lock/pid"
declare -A running_run=()     # pid -> run index (local runs in flight)
cleanup() { rm -rf "$lock"; }
trap cleanup EXIT

if [[ -f $root/batch.conf ]]; then
  stored_seed=$(sed -n 's/^base_seed=//p' "$root/batch.conf")
  if ! printf '%s' "$batch_deck_text" | cmp -s - "$root/batch.nml"; then
    die "output root '$root' holds a batch of another base deck ($root/batch.nml differs from '$deck' with the --set values); use another output root"
  fi
  [[ $stored_seed == "$base_seed" ]] || \
    die "output root '$root' holds a batch with base seed $stored_seed, not $base_seed; use the same seed or another output root"
else
  printf '%s' "$batch_deck_text" > "$root/batch.nml.tmp" && mv -f "$root/batch.nml.tmp" "$root/batch.nml"
  {
    printf 'base_seed=%s\n' "$base_seed"
    printf 'deck_sha256=%s\n' "$(sha256sum < "$root/batch.nml" | cut -d' ' -f1)"
    printf 'source_deck=%s\n' "$deck"
    printf 'created=%s\n' "$(date '+%Y-%m-%d %H:%M:%S')"
  } > "$root/batch.conf.tmp" && mv -f "$root/batch.conf.tmp" "$root/batch.conf" || die "cannot write '$root/batch.conf'"
fi

run_name() { printf 'run_%04d' "$1"; }
runs_kept_elsewhere() { (( first_run == 1 )) || printf ' (runs 1-%d kept elsewhere, --from-run)' $((first_run - 1)); }

if (( status_only )); then
  complete=0; failed=0; not_run=0
  for ((i = first_run; i <= runs; i++)); do
    dir="$root/$(run_name "$i")"
    if run_is_complete "$dir"; then complete=$((complete + 1))
    elif [[ -e $dir/FAILED ]]; then failed=$((failed + 1))
    else not_run=$((not_run + 1)); fi
  done
  say "batch $root: $runs runs$(runs_kept_elsewhere): $complete complete, $failed failed, $not_run not run or incomplete"
  (( complete == runs - first_run + 1 )); exit $?
fi

# ---------------------------------------------------------------------------------------------
# Per-run decks: the batch deck with the run's identity (placeholders filled per run).
# ---------------------------------------------------------------------------------------------
max_seed=$((base_seed + runs - 1))
if (( max_seed > 2147483647 || base_seed < -2147483648 )); then
  say "warning: seeds $base_seed..$max_seed leave the 32-bit integer range; the code will refuse those runs"
fi

write_run_deck() { # run index -> run directory with deck.nml (the code's own merge of the run's identity)
  local i=$1 dir status
  dir="$root/$(run_name "$i")"
  mkdir -p "$dir" || return 1
  "$agglo" "$root/batch.nml" --set "run.name='$(run_name "$i")'" --set "run.seed=$((base_seed + i - 1))" \
    --set run.overwrite=.true. --set run.restart=.false. --set "output.directory=$(fortran_string "$dir")" \
    --print-deck > "$dir/deck.nml.tmp" 2> "$dir/stdout.log" < /dev/null
  status=$?
  if (( status != 0 )); then rm -f "$dir/deck.nml.tmp"; return "$status"; fi
  mv -f "$dir/deck.nml.tmp" "$dir/deck.nml"
}

# &output directory holds at most 255 characters in the code (a longer value is refused there).
(( ${#root} + 9 <= 255 )) || die "output root '$root' is too long (${#root} bytes): run directories must stay within the 255 characters of &output directory"

workdir=$(pwd -P)

pending=()
already=0
for ((i = first_run; i <= runs; i++)); do
  if run_is_complete "$root/$(run_name "$i")"; then already=$((already + 1)); else pending+=("$i"); fi
done

# ---------------------------------------------------------------------------------------------
# Slurm: a job-array script with one task per incomplete run.
# ---------------------------------------------------------------------------------------------
if (( slurm )); then
  if (( ${#pending[@]} == 0 )); then say "batch $root: all $((runs - first_run + 1)) runs are complete$(runs_kept_elsewhere); no script written"; exit 0; fi
  array='' first='' last=''
  for i in "${pending[@]}" ''; do              # compress the indices into ranges "1-4,7,9-12"
    if [[ -n $last && $i == $((last + 1)) ]]; then last=$i; continue; fi
    if [[ -n $first ]]; then
      [[ -n $array ]] && array+=,
      if [[ $first == "$last" ]]; then array+=$first; else array+="$first-$last"; fi
    fi
    first=$i; last=$i
  done
  (( jobs_given )) && array+="%$jobs"
  for i in "${pending[@]}"; do
    write_run_deck "$i" || die "cannot write the deck of $(run_name "$i"): $(tail -n 1 "$root/$(run_name "$i")/stdout.log" 2>/dev/null)"
  done
  script="$root/montecarlo.sbatch"
  {
    printf '#!/bin/bash\n'
    printf '# Agglo Monte-Carlo batch: one array task per incomplete run (written by %s).\n' "$script_name"
    printf '# Submit: sbatch <this file>. Resubmitting reruns only runs that are not complete.\n'
    printf '#SBATCH --job-name=agglo-mc\n'
    printf '#SBATCH --array=%s\n' "$array"
    printf '#SBATCH --ntasks=%s\n' "$ranks"
    printf '#SBATCH --time=%s\n' "${time_limit:-60}"
    printf '#SBATCH --output=/dev/null\n'   # each task logs into its own run directory
    for option in "${sbatch_options[@]}"; do printf '#SBATCH %s\n' "$option"; done
    printf 'set -u\n'
    printf 'root=%q\nagglo=%q\nworkdir=%q\n' "$root" "$agglo" "$workdir"
    printf 'launcher=(%s)\n' "$(printf '%q ' "${launcher_words[@]}")"
    printf 'ranks=%s\n' "$ranks"
    declare -f record_run_result run_is_complete deck_value is_suspension_deck write_suspension_summary
    cat <<'EOF'
index=${SLURM_ARRAY_TASK_ID:?submit this script with sbatch: it is a job array}
dir=$(printf '%s/run_%04d' "$root" "$index")
if run_is_complete "$dir"; then exit 0; fi
cd "$workdir" || exit 1
rm -f "$dir/FAILED" "$dir/summary.json" "$dir/summary.json.rejected"
start=$SECONDS
"${launcher[@]}" -n "$ranks" "$agglo" "$dir/deck.nml" > "$dir/stdout.log" 2>&1 < /dev/null
status=$?
record_run_result "$dir" $status $((SECONDS - start))
EOF
  } > "$script.tmp" && mv -f "$script.tmp" "$script" || die "cannot write '$script'"
  chmod +x "$script"
  say "wrote $script: ${#pending[@]} array tasks ($already of $((runs - first_run + 1)) runs already complete$(runs_kept_elsewhere)); submit with: sbatch $(printf '%q' "$script")"
  exit 0
fi

# ---------------------------------------------------------------------------------------------
# Local runs, up to `jobs` at once.
# ---------------------------------------------------------------------------------------------
total=${#pending[@]}
say "batch $root: $runs runs$(runs_kept_elsewhere), $already already complete, $total to run, $jobs at a time, $ranks rank(s) each"
(( total == 0 )) && exit 0

run_command=()
[[ -n $time_limit ]] && run_command+=(timeout --kill-after=30 "$((time_limit * 60))")
(( ranks > 1 )) && run_command+=("${launcher_words[@]}" -n "$ranks")
run_command+=("$agglo")

declare -A start_time=()
interrupted=0
trap 'interrupted=1' INT TERM
done_ok=0 done_failed=0 next=0 busy_ms=0 batch_start=$(now_ms)
failed_runs=()

start_run() { # run index
  local i=$1 dir status
  dir="$root/$(run_name "$i")"
  rm -f "$dir/FAILED" "$dir/summary.json" "$dir/summary.json.rejected"
  write_run_deck "$i"; status=$?
  if (( status != 0 )); then             # the code refused the run's deck: the run failed
    mkdir -p "$dir" 2>/dev/null
    record_run_result "$dir" "$status"
    failed_runs+=("$i"); done_failed=$((done_failed + 1))
    progress "$(run_name "$i") FAILED ($(sed -n 's/^reason: //p' "$dir/FAILED" 2>/dev/null)); log: $dir/stdout.log"
    tail -n 3 "$dir/stdout.log" 2>/dev/null | sed 's/^/    /'
    return
  fi
  "${run_command[@]}" "$dir/deck.nml" > "$dir/stdout.log" 2>&1 < /dev/null &
  running_run[$!]=$i
  start_time[$i]=$(now_ms)
}

progress() { # message about the run that just ended
  local finished=$((done_ok + done_failed)) remaining=$((total - next)) eta='--'
  if (( finished > 0 )); then
    eta=$(format_seconds $(( (busy_ms * (remaining + ${#running_run[@]})) / (finished * jobs) )))
  fi
  say "$1 | done $done_ok, failed $done_failed, running ${#running_run[@]}, remaining $remaining | elapsed $(format_seconds $(($(now_ms) - batch_start))), ETA $eta"
}

free_mib() { df -Pk -- "$root" 2>/dev/null | awk 'NR == 2 { print int($4 / 1024) }'; }   # free MiB of ROOT's file system

# Whether the next run may start: ROOT's file system has --min-free MiB; said once when it has not.
space_low=0
room_for_a_run() {
  (( min_free == 0 || space_low )) && return $(( space_low ))
  local free
  free=$(free_mib)
  [[ $free =~ ^[0-9]+$ ]] || return 0           # df could not tell: do not stop a batch for it
  (( free >= min_free )) && return 0
  space_low=1
  say "only $free MiB free on the file system of $root (--min-free $min_free): no further run starts;" \
      "the runs in flight finish"
  return 1
}

stop_if_interrupted() { # after INT or TERM: stop the runs in flight (they stay incomplete) and leave
  (( interrupted )) || return 0
  local pid
  for pid in "${!running_run[@]}"; do kill -TERM "$pid" 2>/dev/null; done
  wait "${!running_run[@]}" 2>/dev/null
  say "interrupted: ${#running_run[@]} run(s) stopped and left incomplete; call the same command again to resume"
  exit 130
}

while (( (next < total && ! space_low) || ${#running_run[@]} > 0 )); do
  while (( ! interrupted && next < total && ${#running_run[@]} < jobs )) && room_for_a_run; do
    start_run "${pending[next]}"; next=$((next + 1))
  done
  (( ${#running_run[@]} == 0 )) && continue
  stop_if_interrupted
  finished_pid=''
  wait -n -p finished_pid "${!running_run[@]}" 2>/dev/null; status=$?
  stop_if_interrupted
  if [[ -z ${finished_pid:-} ]]; then
    # wait -n names no run if bash reaped one before it was asked (a run that ended at once) and
    # dropped it from its job table: collect such a run by its pid (bash keeps its status), else
    # pause before waiting again rather than spin.
    for pid in "${!running_run[@]}"; do
      if ! kill -0 "$pid" 2>/dev/null; then wait "$pid"; status=$?; finished_pid=$pid; break; fi
    done
    [[ -n ${finished_pid:-} ]] || { sleep 0.2; continue; }
  fi
  i=${running_run[$finished_pid]}; unset "running_run[$finished_pid]"
  dir="$root/$(run_name "$i")"
  run_ms=$(($(now_ms) - start_time[$i])); busy_ms=$((busy_ms + run_ms))
  if record_run_result "$dir" "$status" "$((run_ms / 1000)).$(printf '%03d' $((run_ms % 1000)))"; then
    done_ok=$((done_ok + 1))
    progress "$(run_name "$i") complete ($(format_seconds "$run_ms"))"
  else
    done_failed=$((done_failed + 1)); failed_runs+=("$i")
    progress "$(run_name "$i") FAILED ($(sed -n 's/^reason: //p' "$dir/FAILED")); log: $dir/stdout.log"
    tail -n 3 "$dir/stdout.log" 2>/dev/null | sed 's/^/    /'
  fi
done

{
  for i in "${failed_runs[@]}"; do
    printf '%s\t%s\n' "$(run_name "$i")" "$(sed -n 's/^reason: //p' "$root/$(run_name "$i")/FAILED")"
  done
} > "$root/failed.txt"
complete=0
for ((i = first_run; i <= runs; i++)); do run_is_complete "$root/$(run_name "$i")" && complete=$((complete + 1)); done
if (( complete == runs - first_run + 1 )); then
  say "batch $root: all $complete runs complete$(runs_kept_elsewhere) ($already were already complete); wall time $(format_seconds $(($(now_ms) - batch_start)))"
  exit 0
fi
say "batch $root: $complete of $((runs - first_run + 1)) runs complete$(runs_kept_elsewhere); ${#failed_runs[@]} failed (listed in $root/failed.txt); call the same command again to rerun them"
(( space_low )) && say "$((total - next)) run(s) not started for want of free space (--min-free $min_free MiB): free some, then call the same command again"
exit 1
