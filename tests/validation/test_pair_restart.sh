#!/usr/bin/env bash
# checks: 10
# Restart of the pair scenes with $AGGLO (docs/studies/validation.md, Pair scenes; docs/outputs.md,
# Checkpoints), fluid = 'none' and 'stokes', on 1 and 2 ranks. Two needles of aspect ratio 5 placed
# 0.2 um apart at 0.3 mm/s agglomerate through a train of collisions (about 1500 and 2300 impulses,
# the first at step 3202 and 4519): the checkpoint lies between collisions already counted and ones
# still to come (checked from the checkpoint's pair_scene/collisions and the summary).
#  - split: n steps (&run max_steps = n, n past the first collision and not a multiple of
#    stats_interval), then &run restart = .true. to the end; particles.h5 equals that of the
#    uninterrupted run (h5diff without tolerance, every dataset of the same shape) and summary.json
#    field by field (not wall_time);
#  - kill: a run with checkpoint_interval = 1000 to the end, its last checkpoint deleted (a run killed
#    before writing it, having written rows after the one before): the restart continues from the
#    previous checkpoint, drops the rows written after it, and ends equal to the uninterrupted run.
# Prints PASS/FAIL lines; works in a temporary directory.
set -u
AGGLO=${AGGLO:?AGGLO must be the agglo executable}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
PY=/usr/bin/python3; [ -x "$PY" ] || PY=python3

deck() { # directory, fluid, max_steps, restart, checkpoint_interval
  cat <<NML
&run name = 'needles', seed = 1, dt = 2.0e-7, end_time = 0.01, max_steps = $3, restart = $4,
     progress_interval = 100000 /
&scene fluid = '$2', particles = 'pair', dlvo = .true., collisions = .true. /
&pair shape = 'needle', aspect_ratio = 5.0, orientation = 'random', gap = 0.2e-6, relative_speed = 3.0e-4 /
&collision restitution = 0.4, detection_floor = 1.0e-9 /
&output directory = '$1', stats_interval = 100, checkpoint_interval = $5, checkpoints_kept = 20 /
NML
}
run() { # ranks, deck file
  mpirun -np "$1" "$AGGLO" "$2" > "$2.out" 2>&1 \
    || { echo "FAIL pair_restart/$2: the run failed: $(grep -m1 -i 'error' "$2.out" | cut -c1-200)"; return 1; }
}
checkpoint() { printf '%s/checkpoints/checkpoint_%010d.h5' "$1" "$2"; }
# collisions counted in a checkpoint
collisions_in() { h5dump -d /pair_scene/collisions "$1" | sed -n 's/^ *(0): *\([0-9]*\).*/\1/p'; }
# summary.json of two runs, field by field (all but wall_time); prints the differing fields
summary_diff() {
  "$PY" - "$1/summary.json" "$2/summary.json" <<'PY'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for d in (a, b):
    d.pop("wall_time")
print(" ".join(k for k in sorted(set(a) | set(b)) if a.get(k, "missing") != b.get(k, "missing")))
PY
}
same_run() { # label, reference directory, directory
  local differing
  differing=$(summary_diff "$2" "$3")
  # h5diff (1.10) exits 0 for datasets of different shapes ("not comparable"): -c names them.
  if h5diff -c "$2/particles.h5" "$3/particles.h5" > "$3.h5diff" 2>&1 && ! grep -qi 'not comparable' "$3.h5diff" \
     && [ -z "$differing" ]; then
    return 0
  fi
  echo "FAIL $1: particles.h5 $(head -c 200 "$3.h5diff" | tr '\n' ' ') summary fields differing: '$differing'"
  return 1
}

for fluid in none stokes; do
  case $fluid in none) n=4050 ;; stokes) n=6050 ;; esac
  for ranks in 1 2; do
    tag=${fluid}_${ranks}rank
    deck whole_$tag $fluid 100000000 .false. 0 > whole_$tag.nml
    deck split_$tag $fluid $n .false. 0 > split1_$tag.nml
    deck split_$tag $fluid 100000000 .true. 0 > split2_$tag.nml
    deck kill_$tag $fluid 100000000 .false. 1000 > kill1_$tag.nml
    deck kill_$tag $fluid 100000000 .true. 1000 > kill2_$tag.nml
    run "$ranks" whole_$tag.nml || continue
    steps=$("$PY" -c 'import json,sys; print(json.load(open(sys.argv[1]))["steps"])' whole_$tag/summary.json)
    total=$("$PY" -c 'import json,sys; print(json.load(open(sys.argv[1]))["collisions"])' whole_$tag/summary.json)

    # n steps + restart + the rest = the uninterrupted run
    if run "$ranks" split1_$tag.nml && run "$ranks" split2_$tag.nml; then
      before=$(collisions_in "$(checkpoint split_$tag $n)")
      if ! grep -q "continuing from $(checkpoint split_$tag $n)" split2_$tag.nml.out; then
        echo "FAIL pair_restart/split_$tag: the restart did not continue from step $n"
      elif ! [ "${before:-0}" -gt 0 ] 2>/dev/null || ! [ "$before" -lt "$total" ]; then
        echo "FAIL pair_restart/split_$tag: collisions not on both sides of the checkpoint ($before of $total before)"
      elif same_run "pair_restart/split_$tag" whole_$tag split_$tag; then
        echo "PASS pair_restart/split_$tag  ($n + $((steps - n)) steps = $steps; $before of $total collisions before the checkpoint; particles.h5 and summary.json identical)"
      fi
    fi

    # killed after its last in-loop checkpoint: the final one never written
    if run "$ranks" kill1_$tag.nml; then
      last=$(( (steps - 1) / 1000 * 1000 ))
      rm -f "$(checkpoint kill_$tag "$steps")"
      if run "$ranks" kill2_$tag.nml; then
        before=$(collisions_in "$(checkpoint kill_$tag $last)")
        if ! grep -q "continuing from $(checkpoint kill_$tag $last)" kill2_$tag.nml.out; then
          echo "FAIL pair_restart/kill_$tag: the restart did not continue from step $last"
        elif same_run "pair_restart/kill_$tag" whole_$tag kill_$tag; then
          echo "PASS pair_restart/kill_$tag  (checkpoint $steps deleted; from $last to $steps, $before of $total collisions before; rows after $last dropped; identical to the uninterrupted run)"
        fi
      fi
    fi
  done
done

# A pair-scene checkpoint cannot continue a resolved run's deck and vice versa: the fluid state is missing.
deck mixed none 100 .false. 0 > mixed1.nml
if run 1 mixed1.nml; then
  cat > mixed2.nml <<'NML'
&run name = 'needles', restart = .true., end_time = 1.0, dt = 1.0e-4, max_steps = 120 /
&scene fluid = 'resolved' /
&grid nx = 8, ny = 8, nz = 8, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /
&output directory = 'mixed' /
NML
  mpirun -np 1 "$AGGLO" mixed2.nml > mixed2.nml.out 2>&1; status=$?
  if [ $status -ne 0 ] && grep -q "holds no fluid state" mixed2.nml.out; then
    echo "PASS pair_restart/resolved_deck_refuses_pair_checkpoint  (exit $status)"
  else
    echo "FAIL pair_restart/resolved_deck_refuses_pair_checkpoint: exit $status; $(grep -m1 -i error mixed2.nml.out | cut -c1-200)"
  fi
fi

# A run directory without a checkpoint (a run killed before its first one) cannot be continued.
mkdir -p empty && echo "&run name = 'needles' /" > empty/run.nml
deck empty none 100 .true. 0 > empty.nml
mpirun -np 1 "$AGGLO" empty.nml > empty.nml.out 2>&1; status=$?
if [ $status -ne 0 ] && grep -q "holds no complete and valid checkpoint to continue from" empty.nml.out \
   && [ ! -e empty/particles.h5 ]; then
  echo "PASS pair_restart/no_checkpoint_refused  (exit $status)"
else
  echo "FAIL pair_restart/no_checkpoint_refused: exit $status; $(grep -m1 -i error empty.nml.out | cut -c1-200)"
fi
