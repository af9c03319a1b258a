"""compare_outcomes: run-by-run comparison of two Monte-Carlo batches that share their seeds.

A sensitivity batch (one model parameter changed with montecarlo.sh --set) and its base batch were
started with the same base seed, so run_NNNN of both has the same seed and hence the same
orientations and approach direction (stream 3 of the seed, docs/theory.md "Pair scenes"). The
only difference between the two runs is the parameter: comparing outcomes run by run counts the
runs whose outcome the parameter changes, which the two rates alone cannot show (changes in both
directions cancel in a rate).

Usage (through the repository's venv, as tools/quiescent-study.sh does):
    .venv/bin/python tools/compare_outcomes.py BASE_ROOT VARIANT_ROOT [--label TEXT] [--csv FILE]
Prints: runs compared, runs whose outcome changed, the transition table base -> variant, and the
agglomeration rate of both with Wilson 95% intervals; then the seeds whose outcome changed, the
error of the first-contact normal speed of the variant against the base, (|v_n| - |v_n,base|) /
|v_n,base| over the runs that touch in both (signed median and range), and the median wall time of
a run of each (summary.json wall_time). With --csv, appends one row to FILE.
Exit status: 0 done, 1 unusable input (no common complete run, seeds that differ).
"""
import argparse
import csv
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from agglo_stats import OUTCOMES, BatchError, load_runs, wilson_interval  # noqa: E402

CSV_COLUMNS = ("label", "base", "variant", "runs", "changed", "changed_fraction",
               "base_agglomerated", "base_rate", "base_wilson_low", "base_wilson_high",
               "variant_agglomerated", "variant_rate", "variant_wilson_low", "variant_wilson_high",
               "transitions")


def runs_by_name(root):
    """{run directory name: summary} of the complete runs of one batch root."""
    complete, _skipped = load_runs([root])
    return {os.path.basename(run.directory): run.summary for run in complete}


def compare(base_root, variant_root):
    """(common run names, {(base outcome, variant outcome): count}, base runs, variant runs)."""
    base = runs_by_name(base_root)
    variant = runs_by_name(variant_root)
    common = sorted(set(base) & set(variant))
    if not common:
        raise BatchError(f"'{base_root}' and '{variant_root}' have no complete run in common")
    for name in common:
        if base[name]["seed"] != variant[name]["seed"]:
            raise BatchError(f"{name}: seed {base[name]['seed']} in '{base_root}' but "
                             f"{variant[name]['seed']} in '{variant_root}': not a paired comparison")
    transitions = {}
    for name in common:
        key = (base[name]["outcome"], variant[name]["outcome"])
        transitions[key] = transitions.get(key, 0) + 1
    return common, transitions, base, variant


def first_contact_errors(common, base, variant):
    """(|v_n| - |v_n,base|) / |v_n,base| of the first collision, for the runs that touch in both."""
    errors = []
    for name in common:
        first_base, first_variant = base[name].get("first_collision"), variant[name].get("first_collision")
        if not (first_base and first_variant):
            continue
        speed_base = abs(first_base["normal_velocity_before"])
        if speed_base > 0.0:
            errors.append((abs(first_variant["normal_velocity_before"]) - speed_base) / speed_base)
    return errors


def median_wall(common, runs):
    """The median wall_time of the runs as text ('unknown' when no summary has one)."""
    walls = [runs[name]["wall_time"] for name in common if isinstance(runs[name].get("wall_time"), (int, float))]
    return f"{statistics.median(walls):.1f} s" if walls else "unknown"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("base", help="base batch root")
    parser.add_argument("variant", help="batch root with one parameter changed, same base seed")
    parser.add_argument("--label", default="", help="name of the comparison in the output")
    parser.add_argument("--csv", help="append one summary row to this CSV file")
    arguments = parser.parse_args(argv)
    try:
        common, transitions, base, variant = compare(arguments.base, arguments.variant)
    except BatchError as error:
        print(f"compare_outcomes: {error}", file=sys.stderr)
        return 1
    runs = len(common)
    changed = sum(count for (before, after), count in transitions.items() if before != after)
    base_k = sum(1 for name in common if base[name]["outcome"] == "agglomerated")
    variant_k = sum(1 for name in common if variant[name]["outcome"] == "agglomerated")
    base_interval = wilson_interval(base_k, runs)
    variant_interval = wilson_interval(variant_k, runs)
    label = arguments.label or os.path.basename(os.path.normpath(arguments.variant))
    print(f"{label}: {runs} paired runs, {changed} changed outcome ({changed / runs:.1%})")
    print(f"  rate base    {base_k:4d}/{runs} = {base_k / runs:.3f}  "
          f"[{base_interval[0]:.3f}, {base_interval[1]:.3f}]")
    print(f"  rate variant {variant_k:4d}/{runs} = {variant_k / runs:.3f}  "
          f"[{variant_interval[0]:.3f}, {variant_interval[1]:.3f}]")
    print("  base -> variant: " + ", ".join(
        f"{before} -> {after}: {transitions[(before, after)]}"
        for before in OUTCOMES for after in OUTCOMES if (before, after) in transitions))
    changes = [f"{base[name]['seed']} {base[name]['outcome']} -> {variant[name]['outcome']}"
               for name in common if base[name]["outcome"] != variant[name]["outcome"]]
    print("  changed: " + ("; ".join(changes) if changes else "none"))
    errors = first_contact_errors(common, base, variant)
    if errors:
        print(f"  first-contact normal speed, variant against base: {statistics.median(errors):+.1%} "
              f"(signed median; {min(errors):+.1%} to {max(errors):+.1%}) over {len(errors)} runs touching in both")
    else:
        print("  first-contact normal speed, variant against base: no run touches in both")
    print(f"  wall per run (median): base {median_wall(common, base)}, variant {median_wall(common, variant)}")
    if arguments.csv:
        new_file = not os.path.exists(arguments.csv)
        with open(arguments.csv, "a", newline="") as handle:
            writer = csv.writer(handle)
            if new_file:
                writer.writerow(CSV_COLUMNS)
            writer.writerow((label, arguments.base, arguments.variant, runs, changed,
                             f"{changed / runs:.4f}",
                             base_k, f"{base_k / runs:.4f}", f"{base_interval[0]:.4f}",
                             f"{base_interval[1]:.4f}",
                             variant_k, f"{variant_k / runs:.4f}", f"{variant_interval[0]:.4f}",
                             f"{variant_interval[1]:.4f}",
                             "; ".join(f"{b}->{a}:{c}" for (b, a), c in sorted(transitions.items()))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
