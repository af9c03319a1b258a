"""study_compare: run-by-run comparison of two batches on the same seeds, with the numbers behind
each change of outcome.

Two batches of one study share their base seed, so run_NNNN of both has the same orientations,
approach direction and (chaotic protocol) pair centre: the runs differ only by the setting that
differs between the batches (fidelity, a numerical knob). For every run complete in both, one row:
the outcome in each, whether it changed, and the quantities that explain a change: the
first-collision normal velocity and chi_eta, psi, the number of contact episodes, the maximum
particle speed, the final gap, the wall time. compare_outcomes.py gives the transition counts;
this tool gives the runs. speed_accuracy.py uses paired_runs for its error metrics.

Usage: .venv/bin/python tools/study_compare.py REFERENCE_ROOT VARIANT_ROOT [-o FILE.csv]
Prints the runs whose outcome changed. Exit status: 0 done, 1 unusable input.
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from agglo_stats import BatchError, load_runs  # noqa: E402

PER_RUN = ("outcome", "collisions", "contact_episodes", "normal_velocity_before", "chi_eta",
           "psi", "lever_arm", "max_particle_speed", "min_gap", "early_approach_ratio", "final_gap",
           "wall_time", "end_time")
COLUMNS = ("run", "seed", "changed") + tuple(f"{side}_{key}" for key in PER_RUN
                                              for side in ("reference", "variant"))


def run_values(run):
    """The PER_RUN values of one run (None where the run has no such value: no contact, no
    particles.h5)."""
    first = run.summary["first_collision"] or {}
    metrics = run.metrics()
    return {"outcome": run.summary["outcome"], "collisions": run.summary["collisions"],
            "contact_episodes": metrics["contact_episodes"],
            "normal_velocity_before": first.get("normal_velocity_before"),
            "chi_eta": metrics["chi_eta_first_collision"], "psi": first.get("psi"),
            "lever_arm": metrics["lever_arm_first_collision"],
            "max_particle_speed": metrics["max_particle_speed"],
            "min_gap": metrics["min_gap"], "early_approach_ratio": metrics["early_approach_ratio"],
            "final_gap": run.summary["final_gap"], "wall_time": run.summary["wall_time"],
            "end_time": run.summary["end_time"]}


def paired_runs(reference_root, variant_root):
    """[(run name, seed, reference values, variant values)] of the runs complete in both batches,
    by run name. Raises BatchError when none is common or a pair's seeds differ."""
    reference = {os.path.basename(r.directory): r for r in load_runs([reference_root])[0]}
    variant = {os.path.basename(r.directory): r for r in load_runs([variant_root])[0]}
    common = sorted(set(reference) & set(variant))
    if not common:
        raise BatchError(f"'{reference_root}' and '{variant_root}' have no complete run in common")
    pairs = []
    for name in common:
        seed_a, seed_b = reference[name].summary["seed"], variant[name].summary["seed"]
        if seed_a != seed_b:
            raise BatchError(f"{name}: seed {seed_a} in '{reference_root}' but {seed_b} in "
                             f"'{variant_root}': not a paired comparison")
        pairs.append((name, seed_a, run_values(reference[name]), run_values(variant[name])))
    return pairs


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("reference", help="reference batch root")
    parser.add_argument("variant", help="batch root on the same base seed")
    parser.add_argument("-o", "--out", help="CSV file of every paired run")
    arguments = parser.parse_args(argv)
    try:
        pairs = paired_runs(arguments.reference, arguments.variant)
    except BatchError as error:
        print(f"study_compare: {error}", file=sys.stderr)
        return 1
    rows = []
    for name, seed, reference, variant in pairs:
        row = {"run": name, "seed": seed, "changed": int(reference["outcome"] != variant["outcome"])}
        for key in PER_RUN:
            row[f"reference_{key}"] = "" if reference[key] is None else reference[key]
            row[f"variant_{key}"] = "" if variant[key] is None else variant[key]
        rows.append(row)
    changed = [row for row in rows if row["changed"]]
    label = f"{os.path.basename(os.path.normpath(arguments.reference))} -> " \
            f"{os.path.basename(os.path.normpath(arguments.variant))}"
    print(f"{label}: {len(rows)} paired runs, {len(changed)} changed outcome")

    def show(value, scale=1.0):
        return "-" if value == "" else f"{value * scale:.3g}"
    for row in changed:
        print(f"  {row['run']} seed {row['seed']}: {row['reference_outcome']} -> {row['variant_outcome']}; "
              f"v_n before {show(row['reference_normal_velocity_before'], 1e3)} -> "
              f"{show(row['variant_normal_velocity_before'], 1e3)} mm/s, chi_eta "
              f"{show(row['reference_chi_eta'])} -> {show(row['variant_chi_eta'])}, episodes "
              f"{row['reference_contact_episodes']} -> {row['variant_contact_episodes']}")
    if arguments.out:
        with open(arguments.out + ".tmp", "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
        os.replace(arguments.out + ".tmp", arguments.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
