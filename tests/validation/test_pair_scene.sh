#!/usr/bin/env bash
# checks: 18
# Pair scenes run end to end with the built executable ($AGGLO) against analytic references.
set -u
AGGLO=${AGGLO:?AGGLO must point to the built executable}
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
PY=/usr/bin/python3; [ -x "$PY" ] || PY=python3

# run NAME RANKS DECK_TEXT: runs a deck in its own directory NAME (outputs in NAME/output/agglo)
run() {
  mkdir -p "$1" && printf '%s\n' "$3" > "$1/deck.nml"
  (cd "$1" && mpirun -np "$2" "$AGGLO" deck.nml > run.out 2>&1) \
    || { echo "FAIL $1: the run failed: $(grep -m1 'error' "$1/run.out")"; return 1; }
}
# value NAME KEY...: a value from the run's summary.json (nested keys allowed)
value() { "$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); [d:=d[k] for k in sys.argv[2:]]; print(repr(d))' \
  "$1/output/agglo/summary.json" "${@:2}"; }
# close NAME ACTUAL EXPECTED RELTOL: PASS/FAIL line
close() { "$PY" -c 'import sys; a,e,t=map(float,sys.argv[2:5]); ok=abs(a-e)<=t*abs(e); print(("PASS " if ok else "FAIL ")+sys.argv[1]+(": " if not ok else "  ")+f"actual {a:.10g} expected {e:.10g} rel tol {t:g}")' "$@"; }

common="&run seed = 3, dt = 2.0e-7, end_time = 0.02, progress_interval = 100000 /
&output stats_interval = 1000 /"

# 1. Vacuum, no DLVO, spheres head-on: contact after gap / v exactly (to one step), restitution exactly e.
#    Reference: kinematics; Poisson restitution for a head-on sphere collision (docs/physics.md section 6).
if run spheres_vacuum 1 "$common
&scene fluid = 'none', particles = 'pair', dlvo = .false. /
&pair shape = 'sphere', gap = 5.0e-6, relative_speed = 0.875e-3 /
&collision restitution = 0.4, detection_floor = 1.0e-9 /"; then
  close first_contact_time "$(value spheres_vacuum first_collision time)" "$(echo 'print((5e-6-1e-9)/0.875e-3)' | $PY)" 1e-4
  close head_on_restitution "$(value spheres_vacuum first_collision normal_velocity_after)" "$(echo 'print(-0.4*0.875e-3)' | $PY)" 1e-12
  close end_is_twice_first_collision "$(value spheres_vacuum end_time)" "$(echo "print(2*$(value spheres_vacuum first_collision time))" | $PY)" 1e-6
  [ "$(value spheres_vacuum outcome)" = "'rebounded'" ] && echo "PASS spheres_vacuum_rebound" || echo "FAIL spheres_vacuum_rebound: $(value spheres_vacuum outcome)"
fi

# 2. Stokes drag, spheres, no DLVO: each sphere decays with tau = m / (6 pi mu r) = 2 r^2 rho_p / (9 mu),
#    so the gap closes by v tau and the pair never touches (docs/physics.md section 7, energy scale).
if run spheres_stokes 1 "&run seed = 3, dt = 2.0e-7, end_time = 0.03, progress_interval = 100000 /
&output stats_interval = 1000 /
&scene fluid = 'stokes', particles = 'pair', dlvo = .false. /
&pair shape = 'sphere', gap = 5.0e-6, relative_speed = 0.875e-3 /"; then
  tau=$(echo 'print(2*(50e-6)**2*2710/(9*997*1e-6))' | $PY)
  expected_gap=$(echo "import math; print(5e-6 - 0.875e-3*$tau*(1-math.exp(-0.03/$tau)))" | $PY)
  close stokes_sphere_closing_distance "$(value spheres_stokes final_gap)" "$expected_gap" 1e-6
  [ "$(value spheres_stokes outcome)" = "'no_contact'" ] && echo "PASS stokes_no_contact" || echo "FAIL stokes_no_contact: $(value spheres_stokes outcome)"
fi

# 3. Paper decks run, are reproducible from the seed, and agree on 1 and 2 ranks.
for shape in needle disk; do
  deck="&run seed = 11, dt = 2.0e-7, end_time = 0.02, progress_interval = 100000 /
&output stats_interval = 1000 /
&scene fluid = 'none', particles = 'pair' /
&pair shape = '$shape', aspect_ratio = 5.0 /"
  run ${shape}_a 1 "$deck" && run ${shape}_b 2 "$deck" && {
    if cmp -s <(grep -v wall_time ${shape}_a/output/agglo/summary.json) <(grep -v wall_time ${shape}_b/output/agglo/summary.json); then
      echo "PASS ${shape}_same_result_1_and_2_ranks"; else echo "FAIL ${shape}_same_result_1_and_2_ranks: summaries differ"; fi
    o=$(value ${shape}_a outcome)
    case $o in "'agglomerated'"|"'rebounded'"|"'approached'"|"'no_contact'") echo "PASS ${shape}_outcome  ($o)";; *) echo "FAIL ${shape}_outcome: $o";; esac
    gap=$(value ${shape}_a final_gap)
    $PY -c "import sys; sys.exit(0 if $gap > -1e-9 else 1)" && echo "PASS ${shape}_no_unresolved_overlap  (final gap $gap m)" \
      || echo "FAIL ${shape}_no_unresolved_overlap: final gap $gap m"
  }
done

# 4. Extremes (aspect ratios 1, 1.0001, 20, 1/20; gaps down to 0.1 nm; dt 1e-9 to 1e-5 s):
#    every run completes (closest points converge or the run says why), no NaN, no overlap left.
#    The start must lie outside the detection distance max(floor, v dt) (the deck checks refuse a
#    start inside it: docs/decks.md, &pair gap): floor 0.05 nm; at dt = 1e-5 s, v dt = 8.75 nm.
for case in "sphere 1.0 1.0e-10 1.0e-9 2.0e-6" "spheroid 1.0001 1.0e-10 1.0e-7 2.0e-4" \
            "spheroid 20.0 1.0e-8 1.0e-5 2.0e-2" "spheroid 0.05 1.0e-8 1.0e-5 2.0e-2" \
            "spheroid 20.0 1.0e-10 1.0e-9 2.0e-6" "spheroid 0.05 2.0e-6 2.0e-7 2.0e-2"; do
  set -- $case
  name=extreme_${2}_${3}_${4}
  if run "$name" 1 "&run seed = 5, dt = $4, end_time = $5, progress_interval = 100000000 /
&output stats_interval = 100000 /
&scene fluid = 'stokes', particles = 'pair' /
&pair shape = '$1', aspect_ratio = $2, gap = $3, relative_speed = 0.875e-3 /
&collision detection_floor = 5.0e-11 /"; then
    gap=$(value "$name" final_gap); speed=$(value "$name" final_relative_velocity)
    if $PY -c "import math,sys; g,v=$gap,$speed; sys.exit(0 if math.isfinite(g) and math.isfinite(v) and g > -1e-9 else 1)"; then
      echo "PASS $name  (final gap $gap m, $(value "$name" collisions) collisions, $(value "$name" outcome))"
    else echo "FAIL $name: final gap $gap m, relative velocity $speed m/s"; fi
  fi
done
