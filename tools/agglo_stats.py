"""agglo-stats: agglomeration statistics and the paper's figures from Monte-Carlo batches.

Reads the run directories of one or more batches (tools/montecarlo.sh output roots, or any
directory whose sub-directories are runs), in the layout of the pair scenes' per-run outputs
(summary.json, particles.h5; docs/tools.md). Prints per group (shape, and fluid when batches of
several fluids are read) the number of runs, the outcomes and the agglomeration rate with its
Wilson score 95% interval; writes runs.csv (every run's summary), rates.csv and the figures.
Outcomes (docs/theory.md, "Run outcome"): agglomerated (bound), rebounded, approached (in the DLVO
range without touching, then escaped) and no_contact; every class but agglomerated counts as not
agglomerated. Summaries written before 'approached', contact_episodes and ended_in_flight existed
are read as they are (no run of theirs is 'approached'; episodes from particles.h5).
Suspension runs (clusters.h5; `--suspension`, or found by their files) are read by
agglo_suspension.py instead: cluster statistics per shape (docs/tools.md, "Suspension runs").
Run it through the launcher tools/agglo-stats (it picks the repository's .venv).
"""
import argparse
import csv
import json
import math
import os
import re
import sys

OUTCOMES = ("agglomerated", "rebounded", "approached", "no_contact")
# Two-sided 95% quantile of the standard normal distribution, Phi^{-1}(0.975).
Z_95 = 1.959963984540054
SUMMARY_KEYS = ("name", "seed", "shape", "aspect_ratio", "fluid", "outcome", "collisions",
                "first_collision", "max_vdw_force", "final_gap", "final_relative_velocity",
                "psi_final", "end_time", "steps", "wall_time")
FIRST_COLLISION_KEYS = ("time", "theta1", "phi1", "theta2", "phi2", "psi",
                        "normal_velocity_before", "normal_velocity_after")
RUN_MARKERS = ("summary.json", "run.nml", "deck.nml", "agglo.log", "particles.h5", "FAILED")
# Files of a resolved-fluid run (decaying or forced box, docs/outputs.md): not a pair scene.
FLUID_MARKERS = ("fields.xdmf", "fluid_statistics.dat", "flow_statistics.h5")
# A PDF estimated from fewer samples than this shows the noise of the sample more than the shape
# (each of 10 bins then holds about 3 samples, a relative error of about 1/sqrt(3) = 60%).
FEW_SAMPLES = 30
# &collision detection_floor when run.nml does not give it (the code's default, docs/decks.md).
DEFAULT_DETECTION_FLOOR = 1.0e-9
# "name = number" of a run.nml (the number as Fortran writes it, with an e or d exponent).
_NUMBER = r"\s*=\s*([-+0-9.]+(?:[eEdD][-+]?[0-9]+)?)"
_DETECTION_FLOOR = re.compile(r"detection_floor" + _NUMBER, re.I)
# The DLVO deck values of run.nml that set the range of the well (docs/theory.md, "Run outcome"):
# h_r = 60 Debye lengths, at least the van der Waals cut-off.
_DEBYE_KAPPA = re.compile(r"\bdebye_kappa" + _NUMBER, re.I)
_VDW_CUTOFF = re.compile(r"\bvdw_cutoff" + _NUMBER, re.I)
_DLVO_ON = re.compile(r"^\s*dlvo\s*=\s*\.?([tf])", re.I | re.M)
DLVO_RANGE_DEBYE_LENGTHS = 60.0
# The time of the gap the grid study compares between grids (s): a third of the chaotic
# protocol's 3 ms, when the pairs are still closing through the film.
GAP_SAMPLE_TIME = 1.0e-3


class BatchError(Exception):
    """A batch that cannot give statistics (empty, nothing complete, unreadable)."""


def wilson_interval(successes, trials, z=Z_95):
    """Wilson score interval for a binomial proportion (Wilson 1927, J. Am. Stat. Assoc. 22:209;
    Newcombe 1998, Stat. Med. 17:857, method 3):
        centre = (p + z^2/(2n)) / (1 + z^2/n),
        half   = z / (1 + z^2/n) * sqrt(p (1 - p)/n + z^2/(4 n^2)),   p = k/n.
    Unlike the Wald interval it stays inside [0, 1] and is usable at k = 0 or k = n."""
    if trials <= 0:
        raise ValueError("the Wilson interval needs at least one trial")
    if not 0 <= successes <= trials:
        raise ValueError(f"successes {successes} outside [0, {trials}]")
    p = successes / trials
    z2 = z * z
    denominator = 1.0 + z2 / trials
    centre = (p + z2 / (2.0 * trials)) / denominator
    half = z / denominator * math.sqrt(p * (1.0 - p) / trials + z2 / (4.0 * trials * trials))
    return max(0.0, centre - half), min(1.0, centre + half)


class Run:
    """One complete run: where it is, which batch, and its summary."""

    def __init__(self, directory, batch, summary):
        self.directory = directory
        self.batch = batch
        self.summary = summary
        self.group = ""
        self._metrics = None

    @property
    def label(self):
        return f"{os.path.basename(self.batch)}/{os.path.basename(self.directory)}"

    def metrics(self):
        """Quantities of the run's particles.h5 (HISTORY_METRICS; None each without the file),
        read once: max_particle_speed (m/s, largest |v| of either particle over the rows),
        chi_eta_first_collision (the row nearest the first collision), contact_episodes (see
        contact_episodes), carried_distance (m, path of the pair's midpoint, the integral of
        |v1 + v2| / 2 dt), close_fraction (share of the run time after the first collision with
        the gap below CLOSE_GAP_RADII radii; 0 without contact), relative_path (m, the integral
        of |v2 - v1| dt: how far the particles moved relative to each other), min_gap (m, the
        smallest sampled gap), early_approach_ratio (the normal relative velocity of the closest
        points at the second sampled row over the first, when both precede any collision and the
        pair approaches at the first: how much of the start's approach the first sample interval
        keeps), gap_at_1ms (m, the gap at GAP_SAMPLE_TIME, linear between rows; None for a shorter
        run), range_entry_time (s, the first row with the gap inside the DLVO range; None when never
        or without DLVO), radius (m)."""
        if self._metrics is None:
            self._metrics = history_metrics(self)
        return self._metrics

    @property
    def detection_floor(self):
        """&collision detection_floor (m) of the run, from its run.nml; the default without one."""
        try:
            with open(os.path.join(self.directory, "run.nml")) as handle:
                match = _DETECTION_FLOOR.search(handle.read())
        except OSError:
            match = None
        if match is None:
            return DEFAULT_DETECTION_FLOOR
        return _deck_number(match)

    @property
    def dlvo_range(self):
        """Range of the DLVO well h_r (m) of the run, from its run.nml (&dlvo debye_kappa and
        vdw_cutoff, as the code's dlvo_range); None without DLVO or without run.nml."""
        try:
            with open(os.path.join(self.directory, "run.nml")) as handle:
                text = handle.read()
        except OSError:
            return None
        on, kappa, cutoff = _DLVO_ON.search(text), _DEBYE_KAPPA.search(text), _VDW_CUTOFF.search(text)
        if on is None or on.group(1).lower() != "t" or kappa is None or cutoff is None:
            return None
        return max(DLVO_RANGE_DEBYE_LENGTHS / _deck_number(kappa), _deck_number(cutoff))


def _deck_number(match):
    """The number of a _NUMBER match of run.nml as a float."""
    return float(match.group(1).replace("d", "e").replace("D", "e"))


def is_fluid_run(directory):
    """A resolved-fluid run directory: fluid outputs and no pair-scene outputs."""
    def has(name):
        return os.path.exists(os.path.join(directory, name))
    return any(has(m) for m in FLUID_MARKERS) and not (has("summary.json") or has("particles.h5"))


HISTORY_METRICS = ("max_particle_speed", "chi_eta_first_collision", "lever_arm_first_collision",
                   "contact_episodes", "carried_distance", "relative_path", "close_fraction", "min_gap",
                   "early_approach_ratio", "gap_at_1ms", "range_entry_time", "radius")
# Between two collisions of one contact episode the gap stays below this many detection floors; a
# pair whose gap rises above it between two collisions has separated and come back (a new episode).
EPISODE_FLOORS = 10.0
# "Close" for the carried-together rule: a gap below this share of the volume-equivalent radius
# (5 um for the paper's 50 um particles: 2.5 times the chaotic protocol's initial gap).
CLOSE_GAP_RADII = 0.1


def contact_episodes(event_times, time, gap, threshold):
    """Number of contact episodes: collisions grouped so that two successive collisions belong to
    the same episode unless some sampled gap between them exceeds threshold. Sampled rows only:
    a separation shorter than the row interval is not seen."""
    import numpy as np
    events = np.sort(np.asarray(event_times, float))
    if events.size == 0:
        return 0
    above = np.asarray(time, float)[np.asarray(gap, float) > threshold]
    if above.size == 0 or events.size == 1:
        return 1
    index = np.searchsorted(above, events[:-1], side="right")
    separated = (index < above.size) & (above[np.minimum(index, above.size - 1)] < events[1:])
    return 1 + int(np.count_nonzero(separated))


def lever_arm(time, contact_time, points, centres, radius):
    """Mean over both particles of |(c_k - x_k) x n| / r at the last row before contact_time:
    the lever arm of the contact about each centre (c_k closest point, x_k centre, n the unit
    vector from c_1 to c_2, r the radius). 0 for a central contact, where the whole normal
    rebound goes into the centres' motion; large when the contact is far off the centre line and
    the rebound turns the bodies (1/m_eff = 1/m + (r x n)^2 / I). Positions are differences
    within one body, so the periodic wrap of the centres does not enter; None when undefined."""
    import numpy as np
    row = max(0, int(np.searchsorted(time, contact_time)) - 1)
    normal = points[1][row] - points[0][row]
    length = np.linalg.norm(normal)
    if not length > 0.0:
        return None
    normal = normal / length
    arms = [np.linalg.norm(np.cross(points[k][row] - centres[k][row], normal)) / radius for k in (0, 1)]
    return float(0.5 * (arms[0] + arms[1]))


def history_metrics(run):
    """The HISTORY_METRICS of one run from its particles.h5 (every value None without the file)."""
    import numpy as np
    values = dict.fromkeys(HISTORY_METRICS)
    path = os.path.join(run.directory, "particles.h5")
    if not os.path.exists(path):
        return values
    import h5py
    with h5py.File(path, "r") as h5:
        time = np.asarray(h5["time"][:], float)
        gap = np.asarray(h5["pair/gap"][:], float)
        v1 = np.asarray(h5["particle1/velocity"][:], float)
        v2 = np.asarray(h5["particle2/velocity"][:], float)
        chi = np.asarray(h5["pair/chi_eta"][:], float) if "pair/chi_eta" in h5 else None
        approach = (np.asarray(h5["pair/relative_velocity"][:], float) if "pair/relative_velocity" in h5
                    else None)
        points = ([np.asarray(h5[f"pair/closest_point{k}"][:], float) for k in (1, 2)]
                  if "pair/closest_point1" in h5 and "pair/closest_point2" in h5 else None)
        centres = [np.asarray(h5[f"particle{k}/position"][:], float) for k in (1, 2)]
        events = np.asarray(h5["events/time"][:], float) if "events/time" in h5 else np.empty(0)
        # /radius is a dataset in the code's files; an attribute in older or hand-made ones.
        radius = h5["radius"][()] if "radius" in h5 else h5.attrs.get("radius")
        radius = None if radius is None else float(np.asarray(radius))
    if time.size == 0:
        return values
    speeds = np.concatenate([np.linalg.norm(v1, axis=1), np.linalg.norm(v2, axis=1)])
    values["max_particle_speed"] = float(np.max(speeds))
    values["radius"] = radius
    first = run.summary["first_collision"]
    if first is not None and chi is not None and chi.size:
        values["chi_eta_first_collision"] = float(chi[np.argmin(np.abs(time - first["time"]))])
    if first is not None and radius is not None and points is not None:
        values["lever_arm_first_collision"] = lever_arm(time, first["time"], points, centres, radius)
    # The code's own count when the summary has it (one events row per episode); older files hold a
    # row per collision impulse, grouped here by the sampled gap.
    if run.summary.get("contact_episodes") is not None:
        values["contact_episodes"] = int(run.summary["contact_episodes"])
    else:
        values["contact_episodes"] = contact_episodes(events, time, gap, EPISODE_FLOORS * run.detection_floor)
    def path(speed):                      # trapezoidal integral of a speed over the rows
        return float(np.sum(0.5 * (speed[1:] + speed[:-1]) * np.diff(time)))
    values["carried_distance"] = path(np.linalg.norm(0.5 * (v1 + v2), axis=1))
    values["relative_path"] = path(np.linalg.norm(v2 - v1, axis=1))
    values["min_gap"] = float(np.min(gap))
    if time[-1] >= GAP_SAMPLE_TIME:
        values["gap_at_1ms"] = float(np.interp(GAP_SAMPLE_TIME, time, gap))
    reach = run.dlvo_range
    if reach is not None and np.any(gap <= reach):
        values["range_entry_time"] = float(time[np.argmax(gap <= reach)])
    if approach is not None and approach.size > 1 and approach[0] > 0.0 and \
            (events.size == 0 or events.min() > time[1]):
        values["early_approach_ratio"] = float(approach[1] / approach[0])
    values["close_fraction"] = 0.0
    if first is not None and radius is not None and time[-1] > first["time"]:
        after = time >= first["time"]
        dt = np.gradient(time[after]) if np.count_nonzero(after) > 1 else np.zeros(1)
        close = gap[after] < CLOSE_GAP_RADII * radius
        values["close_fraction"] = float(np.sum(dt[close]) / np.sum(dt)) if np.sum(dt) > 0 else 0.0
    return values


def _check_summary(summary):
    """The reason a summary is unusable, or '' when it follows the agreed layout."""
    if not isinstance(summary, dict):
        return "summary.json is not a JSON object"
    missing = [key for key in SUMMARY_KEYS if key not in summary]
    if missing:
        return "summary.json lacks " + ", ".join(missing)
    if summary["outcome"] not in OUTCOMES:
        return f"summary.json outcome '{summary['outcome']}' is not one of {', '.join(OUTCOMES)}"
    first = summary["first_collision"]
    if first is not None:
        if not isinstance(first, dict) or any(key not in first for key in FIRST_COLLISION_KEYS):
            return "summary.json first_collision lacks some of " + ", ".join(FIRST_COLLISION_KEYS)
    return ""


def find_run_directories(root):
    """The run directories of a batch root: the root itself when it is a run, else its
    sub-directories that hold any run file (RUN_MARKERS)."""
    if not os.path.isdir(root):
        raise BatchError(f"batch root '{root}' is not a directory")
    markers = RUN_MARKERS + FLUID_MARKERS
    if any(os.path.exists(os.path.join(root, marker)) for marker in markers):
        return [root]
    runs = []
    for entry in sorted(os.listdir(root)):
        path = os.path.join(root, entry)
        if os.path.isdir(path) and any(os.path.exists(os.path.join(path, m)) for m in markers):
            runs.append(path)
    return runs


def load_runs(roots):
    """(complete runs, skipped [(directory, reason)]) of the batch roots.
    Raises BatchError for a root without runs, or when no run at all is complete."""
    complete, skipped = [], []
    for root in roots:
        directories = find_run_directories(root)
        if not directories:
            raise BatchError(f"batch root '{root}' holds no runs (no sub-directory with "
                             f"{', '.join(RUN_MARKERS)}): is it the output root of a batch?")
        for directory in directories:
            path = os.path.join(directory, "summary.json")
            if is_fluid_run(directory):
                skipped.append((directory, "a resolved-fluid run (" + ", ".join(
                    m for m in FLUID_MARKERS if os.path.exists(os.path.join(directory, m)))
                    + "), not a pair scene"))
                continue
            if os.path.exists(os.path.join(directory, "FAILED")):
                skipped.append((directory, "failed (see its FAILED file)"))
                continue
            if not os.path.exists(path):
                skipped.append((directory, "incomplete (no summary.json)"))
                continue
            try:
                with open(path) as handle:
                    summary = json.load(handle)
            except (OSError, ValueError) as error:
                skipped.append((directory, f"summary.json unreadable: {error}"))
                continue
            reason = _check_summary(summary)
            if reason:
                skipped.append((directory, reason))
                continue
            complete.append(Run(directory, root, summary))
    fluid = [directory for directory, reason in skipped if reason.startswith("a resolved-fluid run")]
    if not complete and fluid and len(fluid) == len(skipped):
        raise BatchError(
            f"{', '.join(fluid[:3])}{' ...' if len(fluid) > 3 else ''}: resolved-fluid run(s) "
            f"({', '.join(FLUID_MARKERS)}), not pair-scene runs; agglo-stats reads the summary.json "
            "and particles.h5 of pair scenes. A fluid run's time series is fluid_statistics.dat "
            "(and flow_statistics.h5 when forced); open fields.xdmf in ParaView (docs/outputs.md)")
    if not complete:
        raise BatchError(f"no complete run in {', '.join(roots)}: {len(skipped)} run(s), all "
                         "incomplete, failed or not pair scenes (a complete run has summary.json)")
    return complete, skipped


def assign_groups(runs, group_by):
    """Set run.group: by shape, by shape and fluid (the fluid only named when batches of
    several fluids are read), or by batch root. Returns the group names in a stable order."""
    fluids = {run.summary["fluid"] for run in runs}
    for run in runs:
        if group_by == "batch":
            run.group = os.path.basename(os.path.normpath(run.batch))
        elif group_by == "shape" or len(fluids) == 1:
            run.group = run.summary["shape"]
        else:
            run.group = f"{run.summary['shape']}/{run.summary['fluid']}"
    order = {"sphere": 0, "needle": 1, "disk": 2, "spheroid": 3}
    return sorted({run.group for run in runs}, key=lambda g: (order.get(g.split("/")[0], 9), g))


def ended_in_flight(summary):
    """True/False: the run ended with its outcome not settled (summary ended_in_flight, or not
    outcome_settled in summaries without it); None when the summary says neither."""
    if summary.get("ended_in_flight") is not None:
        return bool(summary["ended_in_flight"])
    if summary.get("outcome_settled") is not None:
        return not summary["outcome_settled"]
    return None


def rate_table(runs, groups):
    """Rows of rates.csv: per group the counts of every outcome, the agglomeration rate over all its
    runs (every other class counts as not agglomerated) and the runs that ended in flight."""
    rows = []
    for group in groups:
        members = [run for run in runs if run.group == group]
        counts = {outcome: sum(run.summary["outcome"] == outcome for run in members)
                  for outcome in OUTCOMES}
        low, high = wilson_interval(counts["agglomerated"], len(members))
        rows.append({"group": group,
                     "shape": ";".join(sorted({run.summary["shape"] for run in members})),
                     "fluid": ";".join(sorted({run.summary["fluid"] for run in members})),
                     "runs": len(members), **counts,
                     "rate": counts["agglomerated"] / len(members),
                     "wilson_low": low, "wilson_high": high,
                     "ended_in_flight": sum(ended_in_flight(run.summary) is True for run in members)})
    return rows


RUN_COLUMNS = ("batch", "run", "group", "name", "seed", "shape", "aspect_ratio", "fluid", "outcome",
               "collisions", "first_collision_time", "theta1", "phi1", "theta2", "phi2", "psi",
               "normal_velocity_before", "normal_velocity_after", "max_vdw_force", "final_gap",
               "final_relative_velocity", "psi_final", "end_time", "steps", "wall_time",
               "max_particle_speed", "chi_eta_first_collision", "lever_arm_first_collision",
               "contact_episodes", "carried_distance", "relative_path", "close_fraction", "min_gap",
               "early_approach_ratio", "gap_at_1ms", "range_entry_time", "ended_in_flight")


def run_row(run):
    """One runs.csv row; the first-collision columns are empty for a run without contact."""
    s = run.summary
    first = s["first_collision"] or {}
    row = {"batch": run.batch, "run": os.path.basename(run.directory), "group": run.group}
    for key in ("name", "seed", "shape", "aspect_ratio", "fluid", "outcome", "collisions",
                "max_vdw_force", "final_gap", "final_relative_velocity", "psi_final",
                "end_time", "steps", "wall_time"):
        row[key] = s[key]
    row["first_collision_time"] = first.get("time", "")
    for key in FIRST_COLLISION_KEYS[1:]:
        row[key] = first.get(key, "")
    metrics = run.metrics()
    for key in HISTORY_METRICS[:-1]:
        row[key] = "" if metrics[key] is None else metrics[key]
    in_flight = ended_in_flight(s)
    row["ended_in_flight"] = "" if in_flight is None else in_flight
    return row


def write_csv(path, columns, rows):
    with open(path + ".tmp", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    os.replace(path + ".tmp", path)


# ----------------------------------------------------------------------------------------------
# Figures
# ----------------------------------------------------------------------------------------------

def _histories(run):
    """(time, gap, relative velocity) arrays of a run's particles.h5, or None when absent."""
    import h5py
    import numpy as np
    path = os.path.join(run.directory, "particles.h5")
    if not os.path.exists(path):
        return None
    with h5py.File(path, "r") as h5:
        return (np.asarray(h5["time"][:]), np.asarray(h5["pair/gap"][:]),
                np.asarray(h5["pair/relative_velocity"][:]))


def _save(figure, directory, stem):
    paths = []
    for extension in ("png", "pdf"):
        path = os.path.join(directory, f"{stem}.{extension}")
        figure.savefig(path, dpi=150 if extension == "png" else None, bbox_inches="tight")
        paths.append(path)
    return paths


def _pdf_line(axis, values, bins, label, log_bins=False, color=None, style="-"):
    """Plot a normalised histogram (an estimate of the PDF) as a step line."""
    import numpy as np
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return 0
    if log_bins:
        # Density per unit log10 of the quantity, drawn against the quantity on a log axis.
        density, edges = np.histogram(np.log10(values), bins=np.log10(bins), density=True)
        edges = 10.0 ** edges
    else:
        density, edges = np.histogram(values, bins=bins, density=True)
    axis.stairs(density, edges, label=f"{label} (n = {values.size})", color=color, linestyle=style)
    return values.size


class FewSamples:
    """The PDF lines drawn from fewer than FEW_SAMPLES samples: each such panel gets a visible
    note, and messages() gives one line per figure for the user (main prints them)."""

    def __init__(self):
        self._by_figure = {}
        self._pending = []

    def count(self, axis, figure_stem, panel, label, n):
        if 0 < n < FEW_SAMPLES:
            self._pending.append((axis, f"{label} n = {n}"))
            name = f"{panel} {label}" if panel else label
            self._by_figure.setdefault(figure_stem, []).append(f"{name} {n}")

    def annotate(self):
        """Write the note on every panel counted since the last call."""
        notes = {}
        for axis, text in self._pending:
            notes.setdefault(id(axis), (axis, []))[1].append(text)
        for axis, texts in notes.values():
            axis.text(0.02, 0.98, f"few samples (< {FEW_SAMPLES}): " + "; ".join(texts),
                      transform=axis.transAxes, ha="left", va="top", fontsize=6, color="C3",
                      bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none", "pad": 1.0})
        self._pending = []

    def messages(self):
        return [f"{stem}: {len(items)} PDF(s) from fewer than {FEW_SAMPLES} samples show the "
                f"sample's noise more than a shape: {', '.join(items)}"
                for stem, items in self._by_figure.items()]


def label_log_ends(axis, which="x"):
    """Label both ends of a log axis: major ticks at its two limits, plus the decades between
    that are not crowding an end (matplotlib alone may label one decade, or none, of a range
    spanning less than two). Returns the tick values."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter
    target = axis.xaxis if which == "x" else axis.yaxis
    limits = axis.get_xlim() if which == "x" else axis.get_ylim()
    low, high = sorted(limits)
    if not (low > 0.0 and high > low and math.isfinite(high)):
        return []
    first, last = math.log10(low), math.log10(high)
    # Room one label takes, as a share of the axis: about 14% of a 6-inch-wide x axis for a label
    # like 5.91e-10, about 6% of a 4-inch-tall y axis.
    room = (0.14 if which == "x" else 0.06) * (last - first)
    decades = [k for k in range(math.ceil(first), math.floor(last) + 1)
               if k - first > room and last - k > room]
    stride = max(1, math.ceil(room))                       # inner labels at least room apart
    ticks = [low] + [10.0 ** k for k in decades[::stride]] + [high]
    (axis.set_xlim if which == "x" else axis.set_ylim)(*limits)
    target.set_major_locator(FixedLocator(ticks))
    target.set_major_formatter(FuncFormatter(lambda value, _: f"{value:.3g}"))
    target.set_minor_formatter(NullFormatter())
    return ticks


def mark_detection_floor(axis, floors, gaps):
    """A dashed line at each collision detection floor with the share of the gap samples within
    10% of it (pairs in contact sit at the floor: the PDF's tallest peak is that, not a physical
    separation). Returns one description per floor."""
    import numpy as np
    every = np.concatenate([np.asarray(g, float) for g in gaps]) if gaps else np.empty(0)
    every = every[np.isfinite(every) & (every > 0.0)]
    notes = []
    for floor in floors:
        near = np.mean((every >= floor / 1.1) & (every <= floor * 1.1)) * 100.0 if every.size else 0.0
        text = f"detection floor {floor * 1e9:.3g} nm: {near:.0f}% of the samples within 10%"
        axis.axvline(floor, color="k", linestyle="--", linewidth=0.8, label=text)
        axis.axvspan(floor / 1.1, floor * 1.1, color="0.85", zorder=0)
        notes.append(text)
    return notes


def _legend_or_note(axis, note="no data"):
    """A legend when something was drawn, else a note in the middle of the empty axis."""
    if axis.get_legend_handles_labels()[0]:
        axis.legend(fontsize=7)
    else:
        axis.text(0.5, 0.5, note, transform=axis.transAxes, ha="center", va="center", color="0.4")


def _log_bins(values, count=40):
    import numpy as np
    positive = np.concatenate([np.asarray(v, float)[np.asarray(v, float) > 0] for v in values])
    if positive.size == 0:
        return None
    low, high = positive.min(), positive.max()
    if high <= low:
        low, high = low / 2.0, high * 2.0
    return np.logspace(np.log10(low), np.log10(high), count + 1)


def make_figures(runs, groups, directory, history_runs, notes=None):
    """Write every figure as PNG and PDF into directory; returns the paths written. notes (a
    list), when given, receives what the user should know about the figures (small samples, the
    detection floor)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    colours = {group: f"C{k % 10}" for k, group in enumerate(groups)}
    outcome_style = {"agglomerated": ("C3", "-"), "rebounded": ("C0", "--"),
                     "approached": ("C2", "-."), "no_contact": ("C7", ":")}
    written = []
    few = FewSamples()

    # 1-2. PDFs of surface separation and relative velocity over the runs' histories.
    histories = {group: [] for group in groups}
    for run in runs:
        history = _histories(run)
        if history is not None:
            histories[run.group].append(history)
    gaps = {g: np.concatenate([h[1] for h in histories[g]]) if histories[g] else np.empty(0)
            for g in groups}
    velocities = {g: np.concatenate([h[2] for h in histories[g]]) if histories[g] else np.empty(0)
                  for g in groups}
    figure, axis = plt.subplots(figsize=(6, 4))
    bins = _log_bins(list(gaps.values()))
    for group in groups:
        if bins is None or gaps[group].size == 0:
            continue
        overlap = np.mean(gaps[group] <= 0.0) * 100.0
        n = _pdf_line(axis, gaps[group][gaps[group] > 0.0], bins,
                      f"{group}, mean {np.mean(gaps[group]):.3g} m, overlap {overlap:.1f}% of samples",
                      log_bins=True, color=colours[group])
        few.count(axis, "separation_pdf", "", group, n)
    floor_notes = []
    if bins is not None:
        floor_notes = mark_detection_floor(axis, sorted({run.detection_floor for run in runs}),
                                           [gaps[group] for group in groups])
    axis.set_xscale("log")
    axis.set_xlabel("surface separation h (m)")
    axis.set_ylabel("PDF of log10 h")
    axis.set_title("Surface separation over the runs' histories")
    _legend_or_note(axis, "no particles.h5 histories")
    label_log_ends(axis, "x")
    few.annotate()
    written += _save(figure, directory, "separation_pdf")
    plt.close(figure)

    figure, axis = plt.subplots(figsize=(6, 4))
    every = np.concatenate(list(velocities.values())) * 1.0e3
    if every.size:
        bins = np.linspace(every.min(), every.max() if every.max() > every.min() else every.min() + 1, 61)
        for group in groups:
            mean = np.mean(velocities[group]) * 1.0e3 if velocities[group].size else float("nan")
            n = _pdf_line(axis, velocities[group] * 1.0e3, bins, f"{group}, mean {mean:.3g} mm/s",
                          color=colours[group])
            few.count(axis, "relative_velocity_pdf", "", group, n)
    axis.set_yscale("log")
    axis.set_xlabel("normal relative velocity of the closest points (mm/s, > 0 approaching)")
    axis.set_ylabel("PDF (s/mm)")
    axis.set_title("Relative velocity over the runs' histories")
    _legend_or_note(axis, "no particles.h5 histories")
    label_log_ends(axis, "y")
    few.annotate()
    written += _save(figure, directory, "relative_velocity_pdf")
    plt.close(figure)

    # 3. PDF of the maximum van der Waals force of each run.
    forces = {g: np.array([r.summary["max_vdw_force"] for r in runs if r.group == g], float)
              for g in groups}
    figure, axis = plt.subplots(figsize=(6, 4))
    bins = _log_bins(list(forces.values()), count=20)
    if bins is not None:
        for group in groups:
            n = _pdf_line(axis, forces[group][forces[group] > 0.0], bins, group, log_bins=True,
                          color=colours[group])
            few.count(axis, "max_vdw_force_pdf", "", group, n)
    axis.set_xscale("log")
    axis.set_xlabel("maximum van der Waals force of a run (N)")
    axis.set_ylabel("PDF of log10 F")
    axis.set_title("Maximum van der Waals force")
    _legend_or_note(axis, "no positive force")
    label_log_ends(axis, "x")
    few.annotate()
    written += _save(figure, directory, "max_vdw_force_pdf")
    plt.close(figure)

    # 3b. PDF of each run's maximum particle speed (how strongly the flow accelerates each shape).
    speeds = {g: np.array([r.metrics()["max_particle_speed"] for r in runs if r.group == g
                           and r.metrics()["max_particle_speed"] is not None], float) * 1.0e3
              for g in groups}
    figure, axis = plt.subplots(figsize=(6, 4))
    every = np.concatenate(list(speeds.values())) if speeds else np.empty(0)
    if every.size:
        bins = np.linspace(0.0, every.max() * 1.05 if every.max() > 0 else 1.0, 21)
        for group in groups:
            label = f"{group}, mean {np.mean(speeds[group]):.3g} mm/s" if speeds[group].size else group
            n = _pdf_line(axis, speeds[group], bins, label, color=colours[group])
            few.count(axis, "max_particle_speed_pdf", "", group, n)
    axis.set_xlabel("maximum particle speed of a run, either particle (mm/s)")
    axis.set_ylabel("PDF (s/mm)")
    axis.set_title("Maximum particle speed")
    _legend_or_note(axis, "no particles.h5 histories")
    few.annotate()
    written += _save(figure, directory, "max_particle_speed_pdf")
    plt.close(figure)

    # 4. PDFs of psi at the first collision, agglomerated vs rebounded, one panel per group.
    figure, axes = plt.subplots(1, len(groups), figsize=(4 * len(groups), 3.6), squeeze=False)
    bins = np.linspace(0.0, 0.5 * math.pi, 10)
    for axis, group in zip(axes[0], groups):
        for outcome in ("agglomerated", "rebounded"):
            psi = [r.summary["first_collision"]["psi"] for r in runs
                   if r.group == group and r.summary["outcome"] == outcome
                   and r.summary["first_collision"] is not None]
            colour, style = outcome_style[outcome]
            n = _pdf_line(axis, psi, bins, outcome, color=colour, style=style)
            few.count(axis, "psi_pdf", group, outcome, n)
        axis.set_title(group)
        axis.set_xlabel("psi at the first collision (rad)")
        axis.set_xlim(0.0, 0.5 * math.pi)
        _legend_or_note(axis, "no collision in this group")
    axes[0][0].set_ylabel("PDF (1/rad)")
    figure.suptitle("Angle between the symmetry axes at contact")
    few.annotate()
    written += _save(figure, directory, "psi_pdf")
    plt.close(figure)

    # 5. PDFs of the collision points (theta, phi) on each surface, split by outcome.
    figure, axes = plt.subplots(len(groups), 2, figsize=(9, 3.2 * len(groups)), squeeze=False)
    for row, group in enumerate(groups):
        for column, (angle, bins) in enumerate((("theta", np.linspace(0.0, math.pi, 13)),
                                                ("phi", np.linspace(-math.pi, math.pi, 25)))):
            axis = axes[row][column]
            for outcome in ("agglomerated", "rebounded"):
                values = []
                for r in runs:
                    first = r.summary["first_collision"]
                    if r.group == group and r.summary["outcome"] == outcome and first is not None:
                        values += [first[angle + "1"], first[angle + "2"]]
                colour, style = outcome_style[outcome]
                n = _pdf_line(axis, values, bins, outcome, color=colour, style=style)
                few.count(axis, "collision_points_pdf", f"{group} {angle}", outcome, n)
            axis.set_xlabel(f"{angle} of the first collision point (rad), both particles")
            axis.set_ylabel(f"{group}: PDF (1/rad)")
            _legend_or_note(axis, "no collision in this group")
    figure.suptitle("Collision points on the unrotated spheroid surfaces")
    figure.tight_layout()
    few.annotate()
    written += _save(figure, directory, "collision_points_pdf")
    plt.close(figure)

    # 6. Time histories of chosen runs.
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    all_gaps = []
    for k, run in enumerate(history_runs):
        history = _histories(run)
        if history is None:
            continue
        time, gap, velocity = history
        label = f"{run.label} ({run.group}, {run.summary['outcome']})"
        top.plot(time * 1e3, gap, color=f"C{k % 10}", label=label)
        bottom.plot(time * 1e3, velocity * 1e3, color=f"C{k % 10}")
        all_gaps.append(gap)
    # Gaps spanning decades (contact at nanometres) need a log-like axis; a narrow positive range
    # (pairs that never touch) reads better on a linear one, where symlog would show no ticks.
    gaps_seen = np.concatenate(all_gaps) if all_gaps else np.empty(0)
    if gaps_seen.size and gaps_seen.min() > 0 and gaps_seen.max() < 10 * gaps_seen.min():
        top.set_yscale("linear")
    else:
        top.set_yscale("symlog", linthresh=1.0e-9)
    top.set_ylabel("surface separation h (m)")
    _legend_or_note(top, "no particles.h5 in the chosen runs")
    bottom.set_ylabel("relative velocity (mm/s)")
    bottom.set_xlabel("time (ms)")
    top.set_title("Histories of chosen runs")
    written += _save(figure, directory, "histories")
    plt.close(figure)
    if notes is not None:
        notes += [f"separation_pdf: {text}" for text in floor_notes]
        notes += [f"warning: {text}" for text in few.messages()]
    return written


MEAN_COLUMNS = ("group", "runs", "samples", "mean_gap", "mean_relative_velocity",
                "mean_abs_relative_velocity", "mean_max_particle_speed", "median_max_particle_speed")


def history_means(runs, groups):
    """Rows of history_means.csv: per group the means over every history row of its runs (the
    samples the separation and relative-velocity PDFs are drawn from; SI units) and the mean and
    median of the runs' maximum particle speed."""
    import numpy as np
    rows = []
    for group in groups:
        members = [r for r in runs if r.group == group]
        histories = [h for h in (_histories(r) for r in members) if h is not None]
        gaps = np.concatenate([h[1] for h in histories]) if histories else np.empty(0)
        velocities = np.concatenate([h[2] for h in histories]) if histories else np.empty(0)
        speeds = np.array([r.metrics()["max_particle_speed"] for r in members
                           if r.metrics()["max_particle_speed"] is not None], float)

        def mean(values):
            return float(np.mean(values)) if values.size else ""
        rows.append({"group": group, "runs": len(members), "samples": int(gaps.size),
                     "mean_gap": mean(gaps), "mean_relative_velocity": mean(velocities),
                     "mean_abs_relative_velocity": mean(np.abs(velocities)),
                     "mean_max_particle_speed": mean(speeds),
                     "median_max_particle_speed": float(np.median(speeds)) if speeds.size else ""})
    return rows


# Rules that pick the illustrative runs of a group (docs/tools.md, "Illustrative runs"):
# name, what it shows, and whether a run qualifies / its score (larger is better).
EDGE_TOLERANCE = 0.15          # rad: a contact point this close to the rim (disk) or tip (needle)


def _edge_distance(shape, phi):
    """Distance (rad) of the parametric angle phi from the shape's edge: the rim of a disk
    (|phi| = pi/2, the equator of the oblate spheroid), the tips of a needle (phi = 0, +-pi);
    None for a sphere (no edge)."""
    if shape == "disk":
        return abs(abs(phi) - 0.5 * math.pi)
    if shape == "needle":
        return min(abs(phi), math.pi - abs(phi))
    return None


def _successive_collisions(run):
    """Agglomerated after at least two contact episodes; score: the episodes."""
    episodes = run.metrics()["contact_episodes"]
    if run.summary["outcome"] != "agglomerated" or episodes is None or episodes < 2:
        return None
    return float(episodes)


# The carried-together rule: the pair's midpoint travels at least this many radii (10 um for the
# paper's particles, about the path of the flow at u_rms over 1.3 ms), and farther than the
# particles move relative to each other: the pair moves as one, with the flow.
CARRIED_RADII = 0.2


def _carried_together(run):
    """Collided, not agglomerated, carried (midpoint path >= CARRIED_RADII radii and >= the
    relative path) and close after the first collision; score: the share of the time after it
    with the gap below CLOSE_GAP_RADII radii."""
    metrics = run.metrics()
    if run.summary["outcome"] == "agglomerated" or run.summary["first_collision"] is None:
        return None
    if metrics["radius"] is None or metrics["carried_distance"] is None:
        return None
    if (metrics["carried_distance"] < CARRIED_RADII * metrics["radius"]
            or metrics["carried_distance"] < metrics["relative_path"]):
        return None
    return metrics["close_fraction"] or None


def _edge_on_bounce(run):
    """Rebounded with one contact episode, the first contact within EDGE_TOLERANCE of the edge of
    at least one particle; score: minus that distance (the nearest the edge wins)."""
    first = run.summary["first_collision"]
    if run.summary["outcome"] != "rebounded" or first is None or run.metrics()["contact_episodes"] != 1:
        return None
    distances = [_edge_distance(run.summary["shape"], first[k]) for k in ("phi1", "phi2")]
    distances = [d for d in distances if d is not None]
    if not distances or min(distances) > EDGE_TOLERANCE:
        return None
    return -min(distances)


ILLUSTRATION_RULES = (
    ("successive_collisions", "agglomerated by successive collisions", _successive_collisions),
    ("carried_together", "stays close, carried by the same eddy", _carried_together),
    ("edge_on_bounce", "edge-on bounce", _edge_on_bounce))
ILLUSTRATION_COLUMNS = ("group", "rule", "run", "batch", "seed", "outcome", "collisions",
                        "contact_episodes", "score", "candidates")


def choose_illustrative_runs(runs, groups):
    """Per group and rule the best-scoring run (ties: the lowest seed), as rows of
    illustrative.csv (run empty when no run of the group qualifies) and the chosen runs."""
    rows, chosen = [], []
    for group in groups:
        members = sorted((r for r in runs if r.group == group), key=lambda r: r.summary["seed"])
        for rule, _description, score_of in ILLUSTRATION_RULES:
            scored = [(score_of(r), r) for r in members]
            scored = [(score, r) for score, r in scored if score is not None]
            row = dict.fromkeys(ILLUSTRATION_COLUMNS, "")
            row.update(group=group, rule=rule, candidates=len(scored))
            if scored:
                best = max(score for score, _ in scored)
                run = next(r for score, r in scored if score == best)
                row.update(run=os.path.basename(run.directory), batch=run.batch, seed=run.summary["seed"],
                           outcome=run.summary["outcome"], collisions=run.summary["collisions"],
                           contact_episodes=run.metrics()["contact_episodes"], score=best)
                chosen.append((rule, run))
            rows.append(row)
    return rows, chosen


def illustrative_figure(chosen, directory):
    """Gap (symmetric log) and normal relative velocity against time of the illustrative runs,
    one column per rule; returns the files written."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(2, len(ILLUSTRATION_RULES), figsize=(4.2 * len(ILLUSTRATION_RULES), 6),
                                sharex="col", squeeze=False)
    for column, (rule, description, _score) in enumerate(ILLUSTRATION_RULES):
        top, bottom = axes[0][column], axes[1][column]
        for k, run in enumerate(r for name, r in chosen if name == rule):
            history = _histories(run)
            if history is None:
                continue
            time, gap, velocity = history
            label = f"{run.label} ({run.group}, {run.summary['outcome']})"
            top.plot(time * 1e3, gap, color=f"C{k % 10}", label=label)
            bottom.plot(time * 1e3, velocity * 1e3, color=f"C{k % 10}")
        top.set_yscale("symlog", linthresh=1.0e-9)
        top.set_title(description, fontsize=9)
        _legend_or_note(top, "no run qualifies")
        bottom.set_xlabel("time (ms)")
    axes[0][0].set_ylabel("surface separation h (m)")
    axes[1][0].set_ylabel("normal relative velocity (mm/s)")
    figure.tight_layout()
    paths = _save(figure, directory, "illustrative_histories")
    plt.close(figure)
    return paths


def choose_history_runs(runs, groups, requested):
    """The runs named by --history (run directories or names), else per group the first
    agglomerated and the first rebounded run (the first run when the group has neither)."""
    if requested:
        chosen = []
        for wanted in requested:
            path = os.path.realpath(wanted)
            matches = [r for r in runs if os.path.realpath(r.directory) == path
                       or os.path.basename(r.directory) == wanted or r.label == wanted]
            if not matches:
                raise BatchError(f"--history '{wanted}' is not a complete run of these batches")
            chosen.append(matches[0])
        return chosen
    chosen = []
    for group in groups:
        members = [r for r in runs if r.group == group]
        picked = [next((r for r in members if r.summary["outcome"] == outcome), None)
                  for outcome in ("agglomerated", "rebounded")]
        picked = [r for r in picked if r is not None] or members[:1]
        chosen += picked
    return chosen


def print_rates(rows, stream):
    width = max(12, max(len(row["group"]) for row in rows))
    stream.write(f"{'group':<{width}} {'runs':>5} {'agglomerated':>12} {'rebounded':>9} "
                 f"{'approached':>10} {'no_contact':>10} {'rate':>6}  Wilson 95% interval"
                 f"   in flight\n")
    for row in rows:
        stream.write(f"{row['group']:<{width}} {row['runs']:>5} {row['agglomerated']:>12} "
                     f"{row['rebounded']:>9} {row['approached']:>10} {row['no_contact']:>10} "
                     f"{row['rate']:>6.3f}  [{row['wilson_low']:.3f}, {row['wilson_high']:.3f}]"
                     f"   {row['ended_in_flight']:>9}\n")


def print_means(rows, stream):
    width = max(12, max(len(row["group"]) for row in rows))
    stream.write(f"{'group':<{width}} {'mean gap (m)':>13} {'mean v_rel (mm/s)':>18} "
                 f"{'mean max speed (mm/s)':>22}\n")
    for row in rows:
        def show(value, scale=1.0, form=".4g"):
            return "-" if value == "" else format(value * scale, form)
        stream.write(f"{row['group']:<{width}} {show(row['mean_gap']):>13} "
                     f"{show(row['mean_relative_velocity'], 1e3):>18} "
                     f"{show(row['mean_max_particle_speed'], 1e3):>22}\n")


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        prog="agglo-stats",
        description="Agglomeration statistics and figures of Agglo Monte-Carlo batches "
                    "(output roots of tools/montecarlo.sh). Prints per group the runs, outcomes "
                    "and the agglomeration rate (agglomerated / runs) with its Wilson score 95% "
                    "interval; writes runs.csv, rates.csv and the figures (PNG and PDF).",
        epilog="Runs without summary.json (incomplete) or with a FAILED marker are skipped and "
               "counted. Suspension runs (clusters.h5) get the cluster statistics instead (their options "
               "above; docs/tools.md, 'Suspension runs'). "
               "Exit status: 0 done, 1 no usable run or unreadable input, 2 usage.")
    parser.add_argument("roots", nargs="+", metavar="BATCH",
                        help="batch output root (or a single run directory); several are merged")
    parser.add_argument("-o", "--out", metavar="DIR",
                        help="where the CSV files and figures go (default: BATCH/stats of the first)")
    parser.add_argument("--group-by", choices=("shape", "shape+fluid", "batch"), default="shape+fluid",
                        help="groups compared in the table and figures (default shape+fluid: the "
                             "fluid is named only when the batches hold several fluids)")
    parser.add_argument("--history", action="append", metavar="RUN", default=[],
                        help="run (directory, or name like run_0007) whose time history is drawn; "
                             "repeatable (default: first agglomerated and rebounded run per group)")
    parser.add_argument("--illustrate", action="store_true",
                        help="pick illustrative runs per group by rule (agglomerated by successive "
                             "collisions, carried together by the flow, edge-on bounce): "
                             "illustrative.csv and the figure illustrative_histories")
    parser.add_argument("--no-figures", action="store_true", help="only the table and CSV files")
    suspension = parser.add_argument_group(
        "suspension runs", "runs of &scene particles = 'suspension' (clusters.h5 and particles.h5; "
        "chosen automatically when the runs hold clusters.h5): cluster statistics per shape "
        "(--group-by shape, the default for them) or per batch (--group-by batch)")
    suspension.add_argument("--suspension", action="store_true",
                            help="read the batches as suspension runs (cluster statistics)")
    suspension.add_argument("--times", type=_times, metavar="T1,T2,...",
                            help="simulated times (s) of the cluster-size distributions, e.g. 1e-3,3e-3 "
                                 "(each the nearest output row; default: the last row)")
    suspension.add_argument("--snapshot-time", type=float, metavar="T",
                            help="simulated time (s) of the 3D snapshot coloured by cluster (default: the "
                                 "last particles.h5 row)")
    suspension.add_argument("--rg", choices=("full", "centres"), default="full",
                            help="radius of gyration of the fractal fit: 'full' (each body's own "
                                 "gyration included, the default) or 'centres' (the centres alone)")
    suspension.add_argument("--compare", metavar="RUNG_A,RUNG_B",
                            help="with --group-by batch and batches named SHAPE-RUNG: the two rungs "
                                 "side by side per shape (suspension_comparison.csv), e.g. point,resolved")
    return parser.parse_args(argv)


def _times(text):
    """--times: comma-separated non-negative simulated times (s)."""
    try:
        values = [float(value) for value in text.split(",") if value.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a comma-separated list of times (s)")
    if not values or any(not math.isfinite(v) or v < 0 for v in values):
        raise argparse.ArgumentTypeError(f"'{text}': times must be finite and >= 0 (s)")
    return values


def main(argv=None):
    arguments = parse_arguments(sys.argv[1:] if argv is None else argv)
    import agglo_suspension
    # Run as a script this module is __main__, and agglo_suspension imports it again as agglo_stats:
    # its BatchError is then another class.
    batch_errors = (BatchError, agglo_suspension.BatchError)
    try:
        if arguments.suspension or agglo_suspension.looks_like_suspension(arguments.roots):
            return agglo_suspension.main(arguments)
        if arguments.compare or arguments.times or arguments.snapshot_time is not None:
            raise BatchError("--times, --snapshot-time and --compare are options of suspension runs "
                             "(clusters.h5); these batches are pair scenes")
        runs, skipped = load_runs(arguments.roots)
        groups = assign_groups(runs, arguments.group_by)
        rows = rate_table(runs, groups)
        out = arguments.out or os.path.join(arguments.roots[0], "stats")
        os.makedirs(out, exist_ok=True)
        print_rates(rows, sys.stdout)
        if skipped:
            print(f"skipped {len(skipped)} run(s) of {len(skipped) + len(runs)}:")
            for directory, reason in skipped[:20]:
                print(f"  {directory}: {reason}")
            if len(skipped) > 20:
                print(f"  ... and {len(skipped) - 20} more")
        write_csv(os.path.join(out, "runs.csv"), RUN_COLUMNS, [run_row(run) for run in runs])
        write_csv(os.path.join(out, "rates.csv"), tuple(rows[0].keys()), rows)
        print(f"wrote {os.path.join(out, 'runs.csv')} ({len(runs)} runs) and {os.path.join(out, 'rates.csv')}")
        means = history_means(runs, groups)
        write_csv(os.path.join(out, "history_means.csv"), MEAN_COLUMNS, means)
        print_means(means, sys.stdout)
        if arguments.illustrate:
            rows, chosen = choose_illustrative_runs(runs, groups)
            write_csv(os.path.join(out, "illustrative.csv"), ILLUSTRATION_COLUMNS, rows)
            for row in rows:
                print(f"illustrative {row['group']} {row['rule']}: "
                      + (f"{row['run']} (seed {row['seed']}, score {row['score']:.4g}, "
                         f"{row['candidates']} candidates)" if row["run"] else "no run qualifies"))
            if not arguments.no_figures:
                illustrative_figure(chosen, out)
        if not arguments.no_figures:
            history_runs = choose_history_runs(runs, groups, arguments.history)
            notes = []
            written = make_figures(runs, groups, out, history_runs, notes)
            for note in notes:
                print(note)
            print(f"wrote {len(written)} figure files in {out}")
    except batch_errors as error:
        sys.stderr.write(f"agglo-stats: error: {error}\n")
        return 1
    except (OSError, KeyError) as error:
        sys.stderr.write(f"agglo-stats: error: cannot read the batch: {error}\n")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
