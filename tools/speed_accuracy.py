"""speed_accuracy: error and cost of each knob variant against its reference setting.

Reads the manifest of tools/speed-accuracy-study.sh (a TSV with columns knob, variant, shape,
batch, reference: one row per knob variant and shape; batch is the batch root relative to the
manifest's directory, reference the variant name of the knob's reference setting). For every
row whose variant is not its reference, the variant batch is compared run by run with the
reference batch of the same shape on the seeds complete in both (tools/study_compare.py):

  outcome_agreement   share of the paired runs with the same outcome (Wilson 95% interval)
  vn_error            median over the runs that collided in both of
                      |v_n - v_n,ref| / |v_n,ref|, v_n the first-collision normal velocity
  chi_error           the same for chi_eta at the first collision
  vmax_error          median |v_max - v_max,ref| / v_max,ref, v_max the largest particle speed
                      (in most chaotic runs the speed at the start: fluid velocity plus approach)
  gap_error           the same for the smallest gap of the run (the closest approach; about the
                      contact distance in a run that touches): how well the approach through the
                      film is resolved, on every run, touching or not
  gap1ms_error        the same for the gap at 1 ms (agglo_stats GAP_SAMPLE_TIME): where the pair
                      is a third of the way through the protocol
  entry_error         the same for the time of entry into the DLVO range, over the runs that enter
                      it in both
  cost_run_s          median wall time of a run of the variant (summary.json wall_time, s)
  cost_per_ms_s       median wall seconds per simulated millisecond of the variant
  cost_ratio          cost_per_ms_s of the variant over that of its reference (< 1: cheaper)

The reference's own cost is given as well (the reference row, errors 0 by definition). A batch
whose root is absent is read from its run table TABLES/<batch>.csv when --tables names a folder
that has one (study_compare.py: the committed numbers per run of a study spanning sessions);
--save-tables DIR writes DIR/<batch>.csv for every batch root present. Writes
OUT/comparison.csv, OUT/speed_accuracy.md (a markdown table per knob) and OUT/pareto_<metric>.png
(error against cost per simulated ms, one panel per shape, each knob's variants labelled and the
non-dominated points joined). Usage:
    .venv/bin/python tools/speed_accuracy.py MANIFEST.tsv [-o OUT] [--tables DIR] [--save-tables DIR]
Exit status: 0 done (rows without complete runs are reported, not fatal), 1 unusable manifest.
"""
import argparse
import csv
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from agglo_stats import BatchError, wilson_interval  # noqa: E402
from study_compare import batch_runs, paired_runs, write_csv, write_run_table  # noqa: E402

MANIFEST_COLUMNS = ("knob", "variant", "shape", "batch", "reference")
METRICS = (("outcome_disagreement", "1 - outcome agreement"),
           ("vn_error", "first-collision normal velocity, median relative error"),
           ("chi_error", "chi_eta at the first collision, median relative error"),
           ("vmax_error", "maximum particle speed, median relative error"),
           ("gap_error", "smallest gap, median relative error"))
COLUMNS = ("knob", "variant", "shape", "reference", "paired_runs", "outcome_agreement",
           "agreement_low", "agreement_high", "vn_error", "vn_runs", "chi_error", "chi_runs",
           "vmax_error", "vmax_runs", "gap_error", "gap_runs", "gap1ms_error", "gap1ms_runs",
           "entry_error", "entry_runs", "cost_run_s", "cost_per_ms_s", "cost_ratio", "status")


class ManifestError(Exception):
    """A manifest that cannot be read."""


def read_manifest(path, tables=None):
    """Rows of the manifest, batch paths made absolute from the manifest's directory; a batch
    whose root is absent is its run table in the folder tables, when that has one."""
    try:
        with open(path, newline="") as handle:
            rows = list(csv.DictReader(handle, delimiter="\t"))
    except OSError as error:
        raise ManifestError(f"cannot read the manifest '{path}': {error}") from error
    if not rows:
        raise ManifestError(f"manifest '{path}' has no rows")
    missing = [c for c in MANIFEST_COLUMNS if c not in rows[0]]
    if missing:
        raise ManifestError(f"manifest '{path}' lacks the column(s) {', '.join(missing)}")
    base = os.path.dirname(os.path.abspath(path))
    for row in rows:
        row["batch"] = os.path.join(base, row["batch"])
        table = os.path.join(tables, os.path.basename(os.path.normpath(row["batch"])) + ".csv") if tables else None
        if table and not os.path.isdir(row["batch"]) and os.path.isfile(table):
            row["batch"] = table
    return rows


def relative_error(pairs, key):
    """(median relative error, count) of key over the pairs where both values exist and the
    reference is non-zero; (None, 0) when there is none."""
    errors = [abs(v[key] - r[key]) / abs(r[key]) for _name, _seed, r, v in pairs
              if r[key] is not None and v[key] is not None and r[key] != 0]
    return (statistics.median(errors), len(errors)) if errors else (None, 0)


def batch_cost(batch):
    """(median wall time of a run, median wall seconds per simulated ms) of a batch's complete
    runs (root or run table); (None, None) without any."""
    try:
        runs = [values for _seed, values in batch_runs(batch).values()]
    except BatchError:
        return None, None
    walls = [r["wall_time"] for r in runs]
    per_ms = [r["wall_time"] / (r["end_time"] * 1e3) for r in runs if r["end_time"] > 0]
    return (statistics.median(walls) if walls else None, statistics.median(per_ms) if per_ms else None)


def compare_row(row, reference_batch):
    """One COLUMNS row of a manifest row against its reference batch."""
    out = dict.fromkeys(COLUMNS, "")
    out.update(knob=row["knob"], variant=row["variant"], shape=row["shape"], reference=row["reference"])
    if not os.path.exists(row["batch"]):
        out["status"] = "not run"
        return out
    cost_run, cost_ms = batch_cost(row["batch"])
    out.update(cost_run_s=cost_run if cost_run is not None else "",
               cost_per_ms_s=cost_ms if cost_ms is not None else "")
    if row["variant"] == row["reference"]:
        out.update(status="reference", outcome_agreement=1.0, vn_error=0.0, chi_error=0.0, vmax_error=0.0,
                   gap_error=0.0, gap1ms_error=0.0, entry_error=0.0)
        return out
    if reference_batch is None or not os.path.exists(reference_batch):
        out["status"] = "reference not run"
        return out
    try:
        pairs = paired_runs(reference_batch, row["batch"])
    except BatchError as error:
        # The table is published: name the batches as the manifest does, not by this machine's paths.
        reason = str(error)
        for folder in {os.path.dirname(row["batch"]), os.path.dirname(reference_batch)} - {""}:
            reason = reason.replace(folder + os.sep, "")
        out["status"] = f"no comparison: {reason}"
        return out
    same = sum(r["outcome"] == v["outcome"] for _n, _s, r, v in pairs)
    low, high = wilson_interval(same, len(pairs))
    out.update(paired_runs=len(pairs), outcome_agreement=same / len(pairs), agreement_low=low,
               agreement_high=high, status="compared")
    for column, key in (("vn", "normal_velocity_before"), ("chi", "chi_eta"), ("vmax", "max_particle_speed"),
                        ("gap", "min_gap"), ("gap1ms", "gap_at_1ms"), ("entry", "range_entry_time")):
        error, count = relative_error(pairs, key)
        out[f"{column}_error"] = "" if error is None else error
        out[f"{column}_runs"] = count
    return out


def analyse(manifest_rows):
    """COLUMNS rows for every manifest row, in manifest order."""
    batches = {(row["shape"], row["variant"]): row["batch"] for row in manifest_rows}
    rows = [compare_row(row, batches.get((row["shape"], row["reference"]))) for row in manifest_rows]
    cost = {(row["shape"], row["variant"]): row["cost_per_ms_s"] for row in rows}
    for row in rows:
        reference = cost.get((row["shape"], row["reference"]), "")
        if row["cost_per_ms_s"] != "" and reference not in ("", 0, 0.0):
            row["cost_ratio"] = row["cost_per_ms_s"] / reference
    return rows


def _format(value, form):
    return "–" if value == "" or value is None else format(value, form)


def markdown(rows):
    """The table of speed_accuracy.md: one section per knob."""
    lines = []
    for knob in dict.fromkeys(row["knob"] for row in rows):
        lines += [f"### {knob}", "",
                  "| shape | variant | reference | paired runs | outcome agreement [Wilson 95%] | "
                  "v_n error | chi_eta error | v_max error | min gap error | gap at 1 ms error | "
                  "DLVO range entry time error | wall s / run | wall s / simulated ms | cost / reference | status |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for row in (r for r in rows if r["knob"] == knob):
            agreement = _format(row["outcome_agreement"], ".3f")
            if row["agreement_low"] != "":
                agreement += f" [{row['agreement_low']:.3f}, {row['agreement_high']:.3f}]"
            lines.append(f"| {row['shape']} | {row['variant']} | {row['reference']} | "
                         f"{row['paired_runs'] or '–'} | {agreement} | {_format(row['vn_error'], '.3g')} | "
                         f"{_format(row['chi_error'], '.3g')} | {_format(row['vmax_error'], '.3g')} | "
                         f"{_format(row['gap_error'], '.3g')} | {_format(row['gap1ms_error'], '.3g')} | "
                         f"{_format(row['entry_error'], '.3g')} ({row['entry_runs'] or 0}) | "
                         f"{_format(row['cost_run_s'], '.3g')} | {_format(row['cost_per_ms_s'], '.3g')} | "
                         f"{_format(row['cost_ratio'], '.3g')} | {row['status']} |")
        lines.append("")
    return "\n".join(lines)


def pareto_front(points):
    """Indices of the non-dominated points (cost, error), both to be minimised, by rising cost."""
    order = sorted(range(len(points)), key=lambda k: (points[k][0], points[k][1]))
    front, best = [], math.inf
    for k in order:
        if points[k][1] < best:
            front.append(k)
            best = points[k][1]
    return front


def spread_labels(anchors, width, height):
    """Label positions (display units) near their points' anchors that do not overlap: a label is
    width x height, placed at its anchor and, while it overlaps one already placed, moved up by
    height. Labels are placed by rising anchor (y, then x). Returns the positions in the anchors'
    order."""
    placed = [None] * len(anchors)
    done = []
    for k in sorted(range(len(anchors)), key=lambda k: (anchors[k][1], anchors[k][0])):
        x, y = anchors[k]
        while any(abs(x - px) < width and abs(y - py) < height for px, py in done):
            y += height
        placed[k] = (x, y)
        done.append((x, y))
    return placed


def pareto_plots(rows, directory):
    """One PNG per metric: error against wall seconds per simulated ms, a panel per shape.
    Returns the files written.

    The error axis is linear below 1e-4 and logarithmic above (the errors span round-off to
    several hundred per cent), so a zero error (the references) sits on the axis' foot; the
    outcome disagreement, a multiple of 1/runs, is linear. A reference shared by several knobs is
    drawn once; labels that would overlap are stacked."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    shapes = list(dict.fromkeys(row["shape"] for row in rows))
    knobs = list(dict.fromkeys(row["knob"] for row in rows))
    references = {(row["shape"], row["reference"]) for row in rows}
    written = []
    for metric, description in METRICS:
        figure, axes = plt.subplots(1, len(shapes), figsize=(5.5 * len(shapes), 5), squeeze=False)
        for axis, shape in zip(axes[0], shapes):
            points, names, drawn = [], [], set()
            for row in rows:
                is_reference = row["variant"] == row["reference"]
                key = row["variant"] if is_reference else (row["knob"], row["variant"])
                if row["shape"] != shape or row["cost_per_ms_s"] == "" or key in drawn:
                    continue
                if metric == "outcome_disagreement":
                    error = "" if row["outcome_agreement"] == "" else 1.0 - row["outcome_agreement"]
                else:
                    error = row[metric]
                if error == "":
                    continue
                drawn.add(key)
                knob = "reference" if is_reference else row["knob"]
                colour = "k" if is_reference else f"C{knobs.index(row['knob']) % 10}"
                axis.scatter(row["cost_per_ms_s"], error, color=colour, s=18, zorder=2,
                             marker="s" if is_reference else "o",
                             label=knob if knob not in axis.get_legend_handles_labels()[1] else None)
                points.append((row["cost_per_ms_s"], error))
                # A reference that is also a variant of another knob (the base against grid192).
                names.append(row["variant"] if is_reference or (shape, row["variant"]) not in references
                             else f"{row['variant']} (vs {row['reference']})")
            if points:
                front = pareto_front(points)
                axis.plot([points[k][0] for k in front], [points[k][1] for k in front], color="0.5",
                          linewidth=0.8, zorder=1)
                axis.set_xscale("log")
                if metric == "outcome_disagreement":     # multiples of 1/runs: linear
                    axis.set_ylim(bottom=-0.02, top=1.05)
                else:
                    axis.set_yscale("symlog", linthresh=1.0e-4, linscale=0.3)
                    axis.set_ylim(bottom=0.0, top=max(1.0, 2.0 * max(p[1] for p in points)))
                axis.legend(fontsize=6, loc="best")
                figure.canvas.draw()
                to_display, to_data = axis.transData, axis.transData.inverted()
                anchors = [tuple(to_display.transform(point) + (4.0, 2.0)) for point in points]
                # Display units of the 100-dpi figure: a 6-point label is 8 px high, 55 px wide for most names.
                for name, position in zip(names, spread_labels(anchors, 55.0, 9.0)):
                    axis.annotate(name, to_data.transform(position), fontsize=6, va="bottom")
            else:
                axis.text(0.5, 0.5, "no compared batch yet", transform=axis.transAxes, ha="center",
                          va="center", color="0.4")
            axis.set_title(shape)
            axis.set_xlabel("wall s per simulated ms (median run)")
        axes[0][0].set_ylabel(description if metric == "outcome_disagreement"
                              else description + "\n(axis linear below 1e-4)")
        figure.tight_layout()
        path = os.path.join(directory, f"pareto_{metric}.png")
        figure.savefig(path, dpi=150)
        plt.close(figure)
        written.append(path)
    return written


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("manifest", help="manifest.tsv of tools/speed-accuracy-study.sh")
    parser.add_argument("-o", "--out", help="output directory (default: analysis/ next to the manifest)")
    parser.add_argument("--no-figures", action="store_true", help="only comparison.csv and the table")
    parser.add_argument("--tables", metavar="DIR", help="run tables <batch>.csv of the batches whose root is absent")
    parser.add_argument("--save-tables", metavar="DIR", help="write DIR/<batch>.csv for every batch root present")
    arguments = parser.parse_args(argv)
    try:
        manifest = read_manifest(arguments.manifest, arguments.tables)
    except ManifestError as error:
        print(f"speed_accuracy: {error}", file=sys.stderr)
        return 1
    if arguments.save_tables:
        os.makedirs(arguments.save_tables, exist_ok=True)
        for batch in dict.fromkeys(row["batch"] for row in manifest if os.path.isdir(row["batch"])):
            path = os.path.join(arguments.save_tables, os.path.basename(os.path.normpath(batch)) + ".csv")
            try:
                print(f"run table {path}: {write_run_table(batch, path)} runs")
            except BatchError as error:
                print(f"speed_accuracy: no run table of '{batch}': {error}", file=sys.stderr)
    out = arguments.out or os.path.join(os.path.dirname(os.path.abspath(arguments.manifest)), "analysis")
    os.makedirs(out, exist_ok=True)
    rows = analyse(manifest)
    write_csv(os.path.join(out, "comparison.csv"), COLUMNS, rows)
    table = markdown(rows)
    with open(os.path.join(out, "speed_accuracy.md"), "w") as handle:
        handle.write(table + "\n")
    print(table)
    if not arguments.no_figures:
        written = pareto_plots(rows, out)
        print(f"wrote {len(written)} Pareto plots in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
