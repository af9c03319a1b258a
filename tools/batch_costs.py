"""batch_costs: the cost of every Monte-Carlo batch under a study's output root.

For each batch root below STUDY (a directory with batch.conf, tools/montecarlo.sh), reads the
summary.json of its complete runs and writes one row: the batch, complete and failed runs, and the
sum, median and maximum of the runs' wall times (s, the code's own measure, summary.json
wall_time) with the median simulated time (ms) and wall seconds per simulated millisecond. A batch
continued from its run table (its runs of an earlier session in ROOT/earlier_runs.csv,
tools/study_compare.py) counts those rows as well. Works for local and Slurm batches alike
(batch_times.tsv only sees local calls).

Usage: .venv/bin/python tools/batch_costs.py STUDY [-o FILE.tsv]
"""
import argparse
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from agglo_stats import BatchError  # noqa: E402
from study_compare import EARLIER_RUNS, read_run_table  # noqa: E402

COLUMNS = ("batch", "complete", "failed", "wall_sum_s", "wall_median_s", "wall_max_s",
           "simulated_median_ms", "wall_per_simulated_ms_median_s")


def batch_roots(study):
    """Batch roots (directories holding batch.conf) at any depth below study, sorted."""
    roots = []
    for directory, subdirectories, files in os.walk(study):
        if "batch.conf" in files:
            roots.append(directory)
            subdirectories[:] = []          # runs live right below; no batch inside a batch
        else:
            subdirectories.sort()
    return sorted(roots)


def batch_cost(root):
    """The COLUMNS row of one batch root (numbers empty without a complete run)."""
    runs, walls, simulated, per_ms, failed, complete = [], [], [], [], 0, set()
    for entry in sorted(os.listdir(root)):
        run = os.path.join(root, entry)
        if not (entry.startswith("run_") and os.path.isdir(run)):
            continue
        if os.path.exists(os.path.join(run, "FAILED")):
            failed += 1
            continue
        try:
            with open(os.path.join(run, "summary.json")) as handle:
                summary = json.load(handle)
        except (OSError, ValueError):
            continue
        complete.add(entry)
        runs.append((float(summary["wall_time"]), float(summary["end_time"])))
    if os.path.isfile(os.path.join(root, EARLIER_RUNS)):
        runs += [(values["wall_time"], values["end_time"])
                 for name, (_seed, values) in read_run_table(os.path.join(root, EARLIER_RUNS)).items()
                 if name not in complete]
    for wall, end in runs:
        walls.append(wall)
        simulated.append(end * 1e3)
        if end > 0.0:
            per_ms.append(wall / (end * 1e3))
    row = {"batch": root, "complete": len(walls), "failed": failed}
    if walls:
        row.update(wall_sum_s=f"{sum(walls):.1f}", wall_median_s=f"{statistics.median(walls):.3g}",
                   wall_max_s=f"{max(walls):.3g}",
                   simulated_median_ms=f"{statistics.median(simulated):.4g}",
                   wall_per_simulated_ms_median_s=f"{statistics.median(per_ms):.4g}" if per_ms else "")
    return row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", help="output root of a study (batch roots below it)")
    parser.add_argument("-o", "--out", help="TSV file to write (default: print only)")
    arguments = parser.parse_args(argv)
    if not os.path.isdir(arguments.study):
        print(f"batch_costs: '{arguments.study}' is not a directory", file=sys.stderr)
        return 1
    try:
        rows = [batch_cost(root) for root in batch_roots(arguments.study)]
    except BatchError as error:
        print(f"batch_costs: {error}", file=sys.stderr)
        return 1
    lines = ["\t".join(COLUMNS)] + ["\t".join(str(row.get(c, "")) for c in COLUMNS) for row in rows]
    if arguments.out:
        with open(arguments.out + ".tmp", "w") as handle:
            handle.write("\n".join(lines) + "\n")
        os.replace(arguments.out + ".tmp", arguments.out)
    else:
        print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
