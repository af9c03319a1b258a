#!/usr/bin/env bash
# speed-accuracy-study.sh: the measured speed-accuracy trade (docs/studies/speed-accuracy.md).
# `--help` says what it runs.
set -u -o pipefail
study_name=speed-accuracy-study

study_usage_specific() {
  cat <<'EOF'
Usage: tools/speed-accuracy-study.sh [options]

Each knob of the resolved pair scene varied alone on the chaotic protocol
(input/chaotic_<shape>_resolved.nml, the 'base' setting: 128^3, analytic geometry, momentum
loads, implicit coupling, explicit diffusion at 0.94 of its limit, particle step 2e-7 s), on the
same N seeds per shape (S..S+N-1), against the knob's reference setting. Run from the repository
root after `make build tools-deps`.

  knob         variant      overrides (--set) on the base deck                            reference
  grid         grid96       grid 96^3, dt 8.4e-6 s, 42 sub-steps, field hit_box_128_on_96  grid192
               base         128^3, dt 4.8e-6 s, 24 sub-steps (the deck's), field hit_box_128
               grid192      grid 192^3, dt 2e-6 s, 10 sub-steps, field hit_box_128_on_192
               grid256      grid 256^3, dt 1.2e-6 s, 6 sub-steps, field hit_box_128_on_256
                            (first N256 seeds)
  geometry     mesh80/320/1280  &bodies geometry = 'mesh', mesh_level = 1/2/3              base
  load_method  surface      &bodies load_method = 'surface' (mesh_level 2)                  base
  coupling     explicit     &scene ibm_coupling = 'explicit'                                 base
  diffusion    dt2.4e-6     explicit diffusion at half the decks' step (dt 2.4e-6 s, 12      base
                            sub-steps): the time error of the base itself
               cn2/cn5/cn10 &fluid viscous_scheme = 'crank_nicolson', dt 2/5/10 x 4.8e-6 s,  base
                            sub-steps 48/120/240 (particle step stays 2e-7 s)
  substep      substep6e-7/1.2e-6/2.4e-6  particle_substeps 8/4/2 (particle step 6e-7..2.4e-6 s)  base
  noise        perturbed    &pair gap 2.000000000002e-6 m (1e-12 relative): the round-off     base
                            floor of every metric (the flow is chaotic)
  fidelity     point        input/chaotic_<shape>_point.nml                                  base
               stokes, none input/quiescent_<shape>_{stokes,none}.nml with the chaotic
                            protocol's gap 2 um, 4.2 mm/s, random approach, 3 ms, paper end
  The dt of each grid is 0.88-0.94 of the explicit diffusion limit dx^2 / (12 nu) (docs/decks.md,
  &run dt), a whole number of particle steps of 2e-7 s; 128^3 is the decks' 4.8e-6 s.
  Batches: OUT/<shape>-<variant>; the 'base' batch serves every knob that has it as reference.

  0. the converged forced field of the base decks (output/hit_box_128/final_field.h5; input/hit_box.nml
     at 128^3, computed first when missing: about 1 h on 2 cores, or on a cluster with --slurm),
     and for each other grid the SAME field resampled onto it (output/hit_box_128_on_<n>/
     final_field.h5, tools/regrid_field.py: spectral resampling at each component's staggered
     positions, then the discrete projection; seconds, made when missing; with --slurm made at
     once when the 128^3 field exists, else by a one-task job that waits for the field's job)
  1. the batches; field snapshots off (--set output.field_interval=0.0)
  2. OUT/manifest.tsv (knob, variant, shape, batch, reference) and tools/speed_accuracy.py:
     OUT/analysis/ (per knob variant against its reference on the shared seeds: outcome agreement,
     first-collision normal velocity and chi_eta errors, maximum particle speed error, cost per run
     and per simulated ms; comparison.csv, speed_accuracy.md, Pareto plots per metric)
  3. OUT/batch_times.tsv (every local batch call) and OUT/batch_costs.tsv (per batch)

Options of this study:
  -N, --runs N           seeds per shape (default 20)
      --runs-256 M       seeds of the 256^3 subset (default 3; 0 skips it)
      --shapes "A B"     shapes (default "needle disk sphere")
      --knobs "K ..."    knobs (default "noise grid geometry load_method coupling diffusion substep
                         fidelity")

Run tables (the study spans sessions and machines): the few numbers per complete run that the
analysis reads (tools/study_compare.py --table) are committed in TABLES (default
docs/figures/speed-accuracy-study/runs, one <batch>.csv each with its base deck <batch>.nml, and FIELD:
the fingerprint of the base field they were computed from, tools/regrid_field.py --fingerprint). A
batch whose table there has its N runs from the base seed S, and whose base deck is the one this
call would run, is not run again; the analysis reads it where the batch root is absent. A table
with fewer runs (runs 1..M of a session that ended) continues its batch: only runs M+1..N run here
(montecarlo.sh --from-run), the table is kept in the root as earlier_runs.csv, and the analysis
and --publish take the batch as those rows and the runs here. The tables are used only when this
machine's base field has the same fingerprint (the same flow to the bit) for the batches that
start from it; otherwise those batches run here (it says so), and --no-tables computes every
batch afresh.
      --tables DIR       the run tables' folder (default docs/figures/speed-accuracy-study/runs)
      --no-tables        neither read nor skip by run tables
      --lubrication      every batch with the sub-grid lubrication on (&collision lubrication =
                         .true., as the decks ship); default: off, the paper's omission, on which the
                         published tables were measured. Give it its own --out (and --no-reuse
                         --no-tables: the chaotic study and the tables are the paper's omission),
                         e.g. the grid knob with the model on:
                           --lubrication --knobs grid -o output/speed-accuracy-lubrication --no-reuse --no-tables
With --publish the analysis' run tables of the batches run here are copied into TABLES as well.

The base batches and the point batches are the chaotic study's on its first N seeds
(tools/chaotic-study.sh: the same decks, --set values and seeds): by default their complete runs
are reused from output/chaotic-study (--reuse-from; --no-reuse computes them again). Reuse
compares deck text and seeds, not the field file's content: it is right only when the chaotic
study ran from the same base field as this study.
EOF
}

source "$(dirname "${BASH_SOURCE[0]}")/study_lib.sh"
study_parse_arguments "$@"
runs=20 runs_256=3 shapes="needle disk sphere"
knobs="noise grid geometry load_method coupling diffusion substep fidelity"
tables=docs/figures/speed-accuracy-study/runs lubrication=.false.
set -- "${study_extra_arguments[@]}"
while [ $# -gt 0 ]; do
  case "$1" in
    -N|--runs) runs=${2:?}; shift 2 ;;
    --runs-256) runs_256=${2:?}; shift 2 ;;
    --shapes) shapes=${2:?}; shift 2 ;;
    --knobs) knobs=${2:?}; shift 2 ;;
    --tables) tables=${2:?}; shift 2 ;;
    --no-tables) tables=''; shift ;;
    --lubrication) lubrication=.true.; shift ;;
    *) study_die "unknown argument '$1' (see --help)" ;;
  esac
done
(( study_reuse_given )) || study_reuse_dirs=(output/chaotic-study)
[[ $runs =~ ^[1-9][0-9]*$ ]] || study_die "--runs '$runs' is not an integer >= 1"
[[ $runs_256 =~ ^[0-9]+$ ]] || study_die "--runs-256 '$runs_256' is not an integer >= 0"
read -r -a shape_list <<< "$shapes"
read -r -a knob_list <<< "$knobs"
for knob in "${knob_list[@]}"; do
  [[ $knob =~ ^(noise|grid|geometry|load_method|coupling|diffusion|substep|fidelity)$ ]] || \
    study_die "--knobs: unknown knob '$knob'"
done

# The published tables of this study are the paper's omission of the squeeze film (the decks model it):
# without --lubrication every batch omits it.
quiet=(--set output.field_interval=0.0 --set "collision.lubrication=$lubrication")
manifest_rows=()
declare -A declared=()
# table_matches BATCH DECK [--set ...]: whether the committed run table of BATCH holds runs of this
# batch: runs from the study's base seed whose base deck (TABLES/BATCH.nml, montecarlo.sh's batch.nml
# of those runs) is DECK with these --set values as the code merges them, and, for a deck that starts
# from a forced field, started from this machine's base field (table_field_matches). A matching table
# is linked into OUT/committed-tables/, where the analysis reads the batches that have no root here.
table_matches() {
  local name=$1 table="$tables/$1.csv" text fluid nx field; shift
  [ -n "$tables" ] && [ -f "$table" ] && [ -f "$tables/$name.nml" ] || return 1
  [ "$(awk -F, 'NR == 2 { print $2 }' "$table")" = "$study_seed" ] || return 1
  text=$(study_agglo "$@" --print-deck 2> /dev/null) || return 1
  printf '%s\n' "$text" | cmp -s - "$tables/$name.nml" || return 1
  read -r fluid nx field <<< "$(study_deck_info "$@")"
  if [ -n "$field" ]; then table_field_matches || return 1; fi
  [ "$study_mode" = list ] && return 0
  mkdir -p "$study_out/committed-tables" && ln -sfn "$(cd "$tables" && pwd -P)/$name.csv" "$study_out/committed-tables/$name.csv"
}
# table_field_matches: whether this machine's base field is the one the committed tables started from
# (TABLES/FIELD, its fingerprint): the same flow to the bit, so that their runs pair with runs here.
# Decided once; a missing base field or another fingerprint is said once, and the tables of the
# batches that start from a field are then not used (those batches run here, from this field).
table_field_state=''
table_field_matches() {
  if [ -z "$table_field_state" ]; then
    local committed here
    table_field_state=no
    if [ ! -f "$tables/FIELD" ]; then
      echo "run tables: $tables/FIELD is missing: the tables of batches that start from a field are not used"
    elif [ ! -f "$base_field" ]; then
      echo "run tables: $base_field is missing: the tables of batches that start from it are not used (make it" \
           "first, the command in the header of ${resolved//SHAPE/${shape_list[0]}}, to continue from them)"
    else
      read -r committed _ < "$tables/FIELD"
      read -r here _ < <("$study_python" "$study_tools/regrid_field.py" "$base_field" --fingerprint)
      if [ "$committed" = "$here" ]; then
        table_field_state=yes
      else
        echo "run tables: $tables were computed from a base field with fingerprint $committed, but $base_field" \
             "has ${here:-none} (made on another machine or build?): the tables of batches that start from it" \
             "are not used, those batches run here"
      fi
    fi
  fi
  [ "$table_field_state" = yes ]
}
# variant KNOB VARIANT REFERENCE DECK RUNS [--set ...]: one batch per shape (SHAPE in DECK and the
# --set values is replaced by the shape), run once even when several knobs list it.
variant() {
  local knob=$1 name=$2 reference=$3 deck=$4 count=$5 shape; shift 5
  for shape in "${shape_list[@]}"; do
    local -a sets=("${@//SHAPE/$shape}")
    # A variant the code refuses for this shape (the disk, 4.4 cells thick at 128^3, is 3.3 at 96^3:
    # too thin for the immersed boundary) is left out of the study, with the code's reason.
    local refusal
    if ! refusal=$(study_agglo "${deck//SHAPE/$shape}" "${sets[@]}" --print-deck 2>&1 > /dev/null); then
      [ -n "${declared[$shape-$name]+x}" ] && continue
      declared[$shape-$name]=1
      echo "batch $shape-$name: not run: the code refuses its deck: $(grep -m1 -o 'deck: .*' <<< "$refusal")"
      continue
    fi
    manifest_rows+=("$knob"$'\t'"$name"$'\t'"$shape"$'\t'"$shape-$name"$'\t'"$reference")
    [ -n "${declared[$shape-$name]+x}" ] && continue
    declared[$shape-$name]=1
    local table="$tables/$shape-$name.csv" root="$study_out/$shape-$name" tabled
    if table_matches "$shape-$name" "${deck//SHAPE/$shape}" "${sets[@]}" && study_selected "$shape-$name"; then
      tabled=$(( $(wc -l < "$table") - 1 ))
      if [ ! -d "$root" ] && (( tabled >= count )); then
        # A matching table with COUNT runs stands for a batch that has no root here: not run again.
        [ "$study_mode" = list ] && study_batch "$shape-$name" "${deck//SHAPE/$shape}" "$count" "${sets[@]}"
        echo "batch $shape-$name: from its run table $table ($count runs), not run"
        continue
      fi
      if (( tabled >= 1 && tabled < count )) && table_is_prefix "$table" \
         && { [ -f "$root/earlier_runs.csv" ] || root_has_no_run_up_to "$root" "$tabled"; }; then
        # Fewer runs: the batch continues after them (study_batch, study_earlier_table).
        echo "batch $shape-$name: runs 1-$tabled from its run table $table, runs $((tabled + 1))-$count here"
        study_earlier_table=$table
      fi
    fi
    study_batch "$shape-$name" "${deck//SHAPE/$shape}" "$count" "${sets[@]}"
    study_earlier_table=''
  done
}
# table_is_prefix TABLE: whether the run table holds exactly the runs 1..M of its batch (run_0001 with
# the base seed, and so on), so that the batch can continue from run M+1.
table_is_prefix() {
  awk -F, -v seed="$study_seed" 'NR > 1 && ($1 != sprintf("run_%04d", NR - 1) || $2 != seed + NR - 2) { bad = 1 }
                                 END { exit bad }' "$1"
}
# root_has_no_run_up_to ROOT M: whether ROOT (a batch root, or nothing yet) holds none of the runs
# 1..M, complete or not: a root that a continued call started (and was stopped before it wrote
# earlier_runs.csv) then continues, while a batch begun here from run 1 does not.
root_has_no_run_up_to() {
  local i
  for ((i = 1; i <= $2; i++)); do
    [ -e "$1/$(printf 'run_%04d' "$i")" ] || [ -e "$1/$(printf '.run_%04d.partial' "$i")" ] && return 1
  done
  return 0
}
resolved=input/chaotic_SHAPE_resolved.nml
# Every grid variant starts from the base decks' converged field (output/hit_box_128/final_field.h5)
# resampled onto its grid, so that the variants differ in the grid alone, not in the realisation of
# the turbulence (docs/studies/speed-accuracy.md, "Why the grid variants share one field").
read -r _ base_nx base_field <<< "$(study_deck_info "${resolved//SHAPE/${shape_list[0]}}")"
[ -n "$base_field" ] || study_die "${resolved//SHAPE/${shape_list[0]}} starts from no &fluid init_file"
regridded_field() { printf '%s_on_%s/final_field.h5' "$(dirname "$base_field")" "$1"; }
grid_sets() {  # n dt substeps -> --set values of a grid variant
  printf '%s\n' --set "grid.nx=$1" --set "grid.ny=$1" --set "grid.nz=$1" --set "run.dt=$2" \
    --set "scene.particle_substeps=$3" --set "fluid.init_file='$(regridded_field "$1")'"
}
for n in 96 192 256; do study_field_from "$(regridded_field "$n")" "$base_field" "$base_nx"; done
[ "$study_mode" = list ] || rm -rf "$study_out/committed-tables"   # links of the last call, made anew
chaotic_protocol=(--set pair.gap=2.0e-6 --set pair.relative_speed=4.2e-3 --set "pair.approach='random'"
                  --set pair.mirror_first_collision=.false. --set run.end_time=3.0e-3 --set "pair.end_rule='paper'"
                  --set "collision.lubrication=$lubrication")
for knob in "${knob_list[@]}"; do
  case $knob in
    noise)
      # A perturbation far below any knob's effect: how far the chaotic flow alone moves each metric.
      variant noise base base "$resolved" "$runs" "${quiet[@]}"
      variant noise perturbed base "$resolved" "$runs" "${quiet[@]}" --set pair.gap=2.000000000002e-6 ;;
    grid)
      mapfile -t sets < <(grid_sets 96 8.4e-6 42); variant grid grid96 grid192 "$resolved" "$runs" "${quiet[@]}" "${sets[@]}"
      variant grid base grid192 "$resolved" "$runs" "${quiet[@]}"
      mapfile -t sets < <(grid_sets 192 2.0e-6 10); variant grid grid192 grid192 "$resolved" "$runs" "${quiet[@]}" "${sets[@]}"
      if (( runs_256 > 0 )); then
        mapfile -t sets < <(grid_sets 256 1.2e-6 6); variant grid grid256 grid192 "$resolved" "$runs_256" "${quiet[@]}" "${sets[@]}"
      fi ;;
    geometry)
      variant geometry base base "$resolved" "$runs" "${quiet[@]}"
      for level in 1 2 3; do
        faces=$((20 * 4 ** level))
        variant geometry "mesh$faces" base "$resolved" "$runs" "${quiet[@]}" --set "bodies.geometry='mesh'" \
          --set "bodies.mesh_level=$level"
      done ;;
    load_method)
      variant load_method base base "$resolved" "$runs" "${quiet[@]}"
      variant load_method surface base "$resolved" "$runs" "${quiet[@]}" --set "bodies.load_method='surface'" ;;
    coupling)
      variant coupling base base "$resolved" "$runs" "${quiet[@]}"
      variant coupling explicit base "$resolved" "$runs" "${quiet[@]}" --set "scene.ibm_coupling='explicit'" ;;
    diffusion)
      variant diffusion base base "$resolved" "$runs" "${quiet[@]}"
      # The finer explicit step: how far the base's own fluid step moves each metric.
      variant diffusion dt2.4e-6 base "$resolved" "$runs" "${quiet[@]}" --set run.dt=2.4e-6 --set scene.particle_substeps=12
      for factor in 2 5 10; do
        variant diffusion "cn$factor" base "$resolved" "$runs" "${quiet[@]}" \
          --set "fluid.viscous_scheme='crank_nicolson'" --set "run.dt=$(awk -v f="$factor" 'BEGIN { printf "%.1e", 4.8e-6 * f }')" \
          --set "scene.particle_substeps=$((24 * factor))"
      done ;;
    substep)
      variant substep base base "$resolved" "$runs" "${quiet[@]}"
      for pair in 6e-7:8 1.2e-6:4 2.4e-6:2; do
        variant substep "substep${pair%%:*}" base "$resolved" "$runs" "${quiet[@]}" --set "scene.particle_substeps=${pair##*:}"
      done ;;
    fidelity)
      variant fidelity base base "$resolved" "$runs" "${quiet[@]}"
      variant fidelity point base input/chaotic_SHAPE_point.nml "$runs" "${quiet[@]}"
      variant fidelity stokes base input/quiescent_SHAPE_stokes.nml "$runs" "${chaotic_protocol[@]}"
      variant fidelity none base input/quiescent_SHAPE_none.nml "$runs" "${chaotic_protocol[@]}" ;;
  esac
done

if [ "$study_mode" != list ]; then
  { printf 'knob\tvariant\tshape\tbatch\treference\n'; printf '%s\n' "${manifest_rows[@]}"; } > "$study_out/manifest.tsv"
fi
if [ "$study_mode" = run ] && (( study_analysis )); then
  echo "== speed-accuracy analysis -> $study_out/analysis"
  analysis=("$study_python" "$study_tools/speed_accuracy.py" "$study_out/manifest.tsv" -o "$study_out/analysis"
            --save-tables "$study_out/tables")
  [ -d "$study_out/committed-tables" ] && analysis+=(--tables "$study_out/committed-tables")
  "${analysis[@]}" | tee "$study_out/analysis.txt" || study_status_all=1
  if (( study_publish )) && [ -n "$tables" ] && compgen -G "$study_out/tables/*.csv" > /dev/null; then
    # Tables of two fields never share a folder: FIELD speaks for every table in it.
    fingerprint=$("$study_python" "$study_tools/regrid_field.py" "$base_field" --fingerprint) || fingerprint=''
    if [ -z "$fingerprint" ]; then
      echo "$study_name: run tables not published: no fingerprint of $base_field" >&2; study_status_all=1
    elif [ -f "$tables/FIELD" ] && [ "$(cut -d' ' -f1 "$tables/FIELD")" != "${fingerprint%% *}" ]; then
      echo "$study_name: run tables not published: $tables holds tables of another base field ($tables/FIELD);" \
           "publish into another folder (--tables DIR)" >&2; study_status_all=1
    else
      mkdir -p "$tables" || exit 1
      for table in "$study_out"/tables/*.csv; do
        batch=$(basename "$table" .csv)
        cp "$table" "$tables/" && cp "$study_out/$batch/batch.nml" "$tables/$batch.nml" || study_status_all=1
      done
      printf '%s\n' "$fingerprint" > "$tables/FIELD"
      echo "published the run tables and their base decks into $tables"
    fi
  fi
fi
study_finish
