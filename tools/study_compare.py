"""study_compare: run-by-run comparison of two batches on the same seeds, with the numbers behind
each change of outcome.

Two batches of one study share their base seed, so run_NNNN of both has the same orientations,
approach direction and (chaotic protocol) pair centre: the runs differ only by the setting that
differs between the batches (fidelity, a numerical knob). For every run complete in both, one row:
the outcome in each, whether it changed, and the quantities that explain a change: the
first-collision normal velocity and chi_eta, psi, the number of contact episodes, the maximum
particle speed, the final gap, the wall time. compare_outcomes.py gives the transition counts;
this tool gives the runs. speed_accuracy.py uses paired_runs for its error metrics.

A batch is either a batch root of run directories or its run table: a CSV of one row per complete
run (RUN_TABLE_COLUMNS, written by write_run_table or `--table`), the few numbers per run a study
keeps once its raw runs are gone (the committed statistics of a study that spans sessions). A batch
root continued in a later session (tools/montecarlo.sh --from-run K) holds the run table of its runs
1..K-1 as ROOT/earlier_runs.csv: the batch is those rows and its complete run directories (a run
complete in both counts by its directory).

Usage: .venv/bin/python tools/study_compare.py REFERENCE VARIANT [-o FILE.csv]
       .venv/bin/python tools/study_compare.py --table BATCH_ROOT -o TABLE.csv
REFERENCE and VARIANT are batch roots or run tables (*.csv). Prints the runs whose outcome
changed. Exit status: 0 done, 1 unusable input.
"""
import argparse
import csv
import functools
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from agglo_stats import BatchError, load_runs  # noqa: E402

PER_RUN = ("outcome", "collisions", "contact_episodes", "normal_velocity_before", "chi_eta",
           "psi", "lever_arm", "max_particle_speed", "min_gap", "early_approach_ratio", "final_gap",
           "wall_time", "end_time", "gap_at_1ms", "range_entry_time")
# Columns a run table written before they existed lacks: read as None.
OPTIONAL_RUN_VALUES = ("gap_at_1ms", "range_entry_time")
COLUMNS = ("run", "seed", "changed") + tuple(f"{side}_{key}" for key in PER_RUN
                                              for side in ("reference", "variant"))
RUN_TABLE_COLUMNS = ("run", "seed") + PER_RUN
EARLIER_RUNS = "earlier_runs.csv"   # in a batch root: the run table of its runs of an earlier session
_TEXT_VALUES = ("outcome",)
_INTEGER_VALUES = ("collisions", "contact_episodes")


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
            "end_time": run.summary["end_time"], "gap_at_1ms": metrics["gap_at_1ms"],
            "range_entry_time": metrics["range_entry_time"]}


def is_run_table(batch):
    """Whether a batch is given as a run table (a .csv file) rather than a batch root."""
    return batch.endswith(".csv") and not os.path.isdir(batch)


def read_run_table(path):
    """{run name: (seed, PER_RUN values)} of a run table; an empty cell is None. Raises BatchError
    for a file that is not a run table."""
    def value(key, text):
        if text == "" or key in _TEXT_VALUES:
            return text or None
        return int(text) if key in _INTEGER_VALUES else float(text)
    try:
        with open(path, newline="") as handle:
            reader = csv.DictReader(handle)
            missing = [c for c in RUN_TABLE_COLUMNS
                       if c not in (reader.fieldnames or ()) and c not in OPTIONAL_RUN_VALUES]
            if missing:
                raise BatchError(f"run table '{path}' lacks the column(s) {', '.join(missing)}")
            runs = {row["run"]: (int(row["seed"]), {key: value(key, row.get(key) or "") for key in PER_RUN})
                    for row in reader}
    except (OSError, ValueError) as error:
        raise BatchError(f"run table '{path}' unreadable: {error}") from error
    if not runs:
        raise BatchError(f"run table '{path}' has no run")
    return runs


@functools.lru_cache(maxsize=None)
def batch_runs(batch):
    """{run name: (seed, PER_RUN values)} of the complete runs of a batch root (with the rows of its
    EARLIER_RUNS table, when it has one) or a run table; read once per process (the analysis asks for
    a batch's cost and for its pairs), not to be mutated."""
    if is_run_table(batch):
        return read_run_table(batch)
    earlier_table = os.path.join(batch, EARLIER_RUNS)
    earlier = read_run_table(earlier_table) if os.path.isfile(earlier_table) else {}
    try:
        here = {os.path.basename(r.directory): (r.summary["seed"], run_values(r)) for r in load_runs([batch])[0]}
    except BatchError:
        if not earlier:
            raise
        here = {}                     # a continued batch whose own runs have not completed yet
    return {**earlier, **here}


def write_csv(path, columns, rows):
    """rows (dicts) as a CSV file at path, written to path.tmp and renamed when complete."""
    with open(path + ".tmp", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    os.replace(path + ".tmp", path)


def write_run_table(batch, path):
    """Write the run table of a batch (root or table) to path; returns its run count."""
    runs = batch_runs(batch)
    write_csv(path, RUN_TABLE_COLUMNS,
              ({"run": name, "seed": seed, **{key: "" if values[key] is None else values[key] for key in PER_RUN}}
               for name, (seed, values) in sorted(runs.items())))
    return len(runs)


def paired_runs(reference_batch, variant_batch):
    """[(run name, seed, reference values, variant values)] of the runs complete in both batches
    (roots or run tables), by run name. Raises BatchError when none is common or a pair's seeds
    differ."""
    reference, variant = batch_runs(reference_batch), batch_runs(variant_batch)
    common = sorted(set(reference) & set(variant))
    if not common:
        raise BatchError(f"'{reference_batch}' and '{variant_batch}' have no complete run in common")
    pairs = []
    for name in common:
        (seed_a, values_a), (seed_b, values_b) = reference[name], variant[name]
        if seed_a != seed_b:
            raise BatchError(f"{name}: seed {seed_a} in '{reference_batch}' but {seed_b} in "
                             f"'{variant_batch}': not a paired comparison")
        pairs.append((name, seed_a, values_a, values_b))
    return pairs


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("reference", nargs="?", help="reference batch root or run table")
    parser.add_argument("variant", nargs="?", help="batch root or run table on the same base seed")
    parser.add_argument("-o", "--out", help="CSV file of every paired run (with --table: the run table)")
    parser.add_argument("--table", metavar="BATCH", help="write the run table of BATCH to --out instead")
    arguments = parser.parse_args(argv)
    if arguments.table:
        if not arguments.out or arguments.reference:
            parser.error("--table BATCH takes -o TABLE.csv and no other batch")
        try:
            count = write_run_table(arguments.table, arguments.out)
        except BatchError as error:
            print(f"study_compare: {error}", file=sys.stderr)
            return 1
        print(f"{arguments.out}: {count} runs of {arguments.table}")
        return 0
    if not arguments.variant:
        parser.error("give REFERENCE and VARIANT (or --table BATCH -o TABLE.csv)")
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
        write_csv(arguments.out, COLUMNS, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
