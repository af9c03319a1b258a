"""The suspension mode of agglo-stats: cluster statistics of suspension runs and batches.

Reads run directories of suspension runs (`&scene particles = 'suspension'`) that hold clusters.h5
(the bonds, clusters, events and collision counts; docs/outputs.md, "clusters.h5") and
particles.h5 (every body's state; docs/outputs.md), one run or the runs of one or more batches
(tools/montecarlo.sh output roots), and groups them by shape (the species' shape, `mixed` for
several species) or by batch. Per group it gives the mean cluster size and the number of bonds
against time with seed-to-seed 95% intervals (Student t over the runs), the cluster-size
distribution at chosen times, the radius of gyration against size with a fitted fractal dimension
and its 95% interval, the distribution of the angle psi between the axes of bonded neighbours, the
collision rate per unit volume per species pair, and a 3D snapshot coloured by cluster; the numbers
go into suspension_table.csv, suspension_timeseries.csv, suspension_sizes.csv and suspension.json.
Imported by agglo_stats.py (`agglo-stats --suspension`, or automatically when the runs hold
clusters.h5).
"""
import functools
import json
import math
import os

from agglo_stats import BatchError, _save, write_csv

CLUSTER_FILE = "clusters.h5"
PARTICLE_FILE = "particles.h5"
# Smallest cluster of the fractal fit: a pair has a radius of gyration fixed by the contact
# geometry alone (no scaling), three bodies are the first with a shape.
FRACTAL_MIN_SIZE = 3
SHAPE_ORDER = {"sphere": 0, "needle": 1, "disk": 2, "spheroid": 3, "mixed": 4}


@functools.lru_cache(maxsize=None)
def t_quantile(probability, dof):
    """Quantile of Student's t distribution with dof degrees of freedom (dof >= 1), by bisection
    on its CDF, 1/2 + integral_0^t f(x) dx with f(x) = Gamma((v+1)/2) / (sqrt(v pi) Gamma(v/2))
    (1 + x^2/v)^(-(v+1)/2), the integral by composite Simpson (errors below 1e-9 for the
    quantiles used here). t_0.975 = 12.706 (dof 1), 2.776 (4), 2.228 (10) (Abramowitz & Stegun
    Table 26.10)."""
    if dof < 1:
        raise ValueError("the t distribution needs at least one degree of freedom")
    if not 0.5 <= probability < 1.0:
        raise ValueError("probability must be in [0.5, 1)")
    v = float(dof)
    log_norm = math.lgamma((v + 1) / 2) - math.lgamma(v / 2) - 0.5 * math.log(v * math.pi)

    def cdf(t):
        n = 4000
        h = t / n
        total = 0.0
        for i in range(n + 1):
            x = i * h
            f = math.exp(log_norm - (v + 1) / 2 * math.log1p(x * x / v))
            total += f * (1 if i in (0, n) else (4 if i % 2 else 2))
        return 0.5 + total * h / 3

    low, high = 0.0, 1.0
    while cdf(high) < probability:
        high *= 2.0
    for _ in range(60):
        middle = 0.5 * (low + high)
        if cdf(middle) < probability:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def mean_interval(values):
    """(mean, low, high) of the seed-to-seed 95% interval of the mean: mean -/+ t_{0.975, n-1}
    s / sqrt(n) (s the sample standard deviation over the runs); low = high = mean for one run."""
    import numpy as np
    values = np.asarray(values, float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return (math.nan, math.nan, math.nan)
    mean = float(np.mean(values))
    if values.size == 1:
        return (mean, mean, mean)
    half = t_quantile(0.975, values.size - 1) * float(np.std(values, ddof=1)) / math.sqrt(values.size)
    return (mean, mean - half, mean + half)


def fractal_dimension(sizes, radii):
    """Fractal dimension D of N = k (Rg / a)^D from clusters of sizes N and radii of gyration Rg:
    the least-squares line log Rg = c + b log N (the sizes are exact, the radii carry the scatter),
    D = 1/b, its 95% interval from b -/+ t_{0.975, m-2} SE(b) inverted (m clusters of at least two
    distinct sizes). Returns dict(D, low, high, slope, clusters); D nan when fewer than 3 clusters
    or one size only; high inf when the slope's interval reaches 0."""
    import numpy as np
    sizes = np.asarray(sizes, float)
    radii = np.asarray(radii, float)
    keep = (sizes > 0) & (radii > 0) & np.isfinite(radii)
    x, y = np.log(sizes[keep]), np.log(radii[keep])
    result = {"D": math.nan, "low": math.nan, "high": math.nan, "slope": math.nan, "clusters": int(x.size)}
    if x.size < 3 or np.ptp(x) == 0.0:
        return result
    xm, ym = x.mean(), y.mean()
    sxx = float(np.sum((x - xm) ** 2))
    slope = float(np.sum((x - xm) * (y - ym)) / sxx)
    residual = y - ym - slope * (x - xm)
    se = math.sqrt(float(np.sum(residual ** 2)) / (x.size - 2) / sxx)
    half = t_quantile(0.975, x.size - 2) * se
    low_slope, high_slope = slope - half, slope + half
    result.update(slope=slope, D=1.0 / slope if slope > 0 else math.nan,
                  low=1.0 / high_slope if high_slope > 0 else math.nan,
                  high=1.0 / low_slope if low_slope > 0 else math.inf)
    return result


def _text(value):
    """A string of an HDF5 dataset or attribute (bytes or str, fixed-length ones blank-padded)."""
    if hasattr(value, "tolist"):
        value = value.tolist()
    return (value.decode() if isinstance(value, bytes) else str(value)).strip()


def _names(value):
    """The species names of the species_names attribute (an array of strings, or one string)."""
    if isinstance(value, (str, bytes)) or getattr(value, "ndim", 1) == 0:
        return [_text(value)]
    return [_text(name) for name in value]


class SuspensionRun:
    """One suspension run: its directory, batch, clusters.h5 (read once) and particles.h5."""

    def __init__(self, directory, batch):
        self.directory = directory
        self.batch = batch
        self.group = ""
        self._clusters = None
        summary = os.path.join(directory, "summary.json")
        self.summary = {}
        if os.path.exists(summary):
            with open(summary) as handle:
                self.summary = json.load(handle)
        self.shape, self.seed, self.radius, self.bodies = self._identity()

    @property
    def label(self):
        return f"{os.path.basename(os.path.normpath(self.batch))}/{os.path.basename(self.directory)}"

    def path(self, name):
        return os.path.join(self.directory, name)

    def _identity(self):
        """(shape, seed, radius, bodies) from particles.h5, else the summary and clusters.h5;
        shape 'mixed' when clusters.h5 names several species."""
        import h5py
        shape, seed, radius, bodies = self.summary.get("shape"), self.summary.get("seed"), None, None
        if os.path.exists(self.path(PARTICLE_FILE)):
            with h5py.File(self.path(PARTICLE_FILE), "r") as h5:
                if "shape" in h5:
                    shape = _text(h5["shape"][()])
                if "seed" in h5:
                    seed = int(h5["seed"][()])
                if "radius" in h5:
                    radius = float(h5["radius"][()])
                if "bodies" in h5:
                    bodies = int(h5["bodies"][()])
        if os.path.exists(self.path(CLUSTER_FILE)):
            with h5py.File(self.path(CLUSTER_FILE), "r") as h5:
                names = _names(h5.attrs.get("species_names", []))
                if bodies is None and "bodies" in h5.attrs:
                    bodies = int(h5.attrs["bodies"])
                if len(names) > 1:
                    shape = "mixed"
                elif shape is None and names:
                    shape = names[0]
        return shape or "unknown", seed, radius, bodies

    def clusters(self):
        """The datasets of clusters.h5 as numpy arrays (dict by path), read once."""
        if self._clusters is None:
            import h5py
            import numpy as np
            data = {}
            with h5py.File(self.path(CLUSTER_FILE), "r") as h5:
                def visit(name, item):
                    if isinstance(item, h5py.Dataset):
                        data[name] = np.asarray(item[()])
                h5.visititems(visit)
                data["attrs"] = {key: h5.attrs[key] for key in h5.attrs}
            self._clusters = data
        return self._clusters

    @property
    def has_clusters(self):
        return os.path.exists(self.path(CLUSTER_FILE))

    def row_slice(self, group, row):
        """Slice of the entries of output row `row` in the ragged datasets of /group (cluster, bond)."""
        start = self.clusters()[f"{group}/row_start"]
        return slice(int(start[row]), int(start[row + 1]))


def _is_suspension_run(directory):
    return any(os.path.exists(os.path.join(directory, name)) for name in (CLUSTER_FILE, PARTICLE_FILE)) \
        and _summary_scene(directory) in (None, "suspension")


def _summary_scene(directory):
    """The scene of the run's summary.json: 'suspension', 'pair' (a summary with an outcome), or
    None (no summary, or one that names no scene)."""
    try:
        with open(os.path.join(directory, "summary.json")) as handle:
            summary = json.load(handle)
    except (OSError, ValueError):
        return None
    if "outcome" in summary and summary.get("scene") != "suspension":
        return "pair"
    return summary.get("scene")


def find_suspension_runs(root):
    """Run directories of a root: the root itself when it holds clusters.h5 or particles.h5 of a
    suspension, else its sub-directories that do."""
    if not os.path.isdir(root):
        raise BatchError(f"'{root}' is not a directory")
    if any(os.path.exists(os.path.join(root, name)) for name in (CLUSTER_FILE, PARTICLE_FILE, "summary.json")):
        return [root]
    return [os.path.join(root, entry) for entry in sorted(os.listdir(root))
            if os.path.isdir(os.path.join(root, entry))
            and any(os.path.exists(os.path.join(root, entry, name))
                    for name in (CLUSTER_FILE, PARTICLE_FILE, "summary.json", "FAILED", "deck.nml"))]


def _has_suspension_rows(directory):
    """Whether the directory's particles.h5 holds the suspension layout (/suspension)."""
    path = os.path.join(directory, PARTICLE_FILE)
    if not os.path.exists(path):
        return False
    import h5py
    try:
        with h5py.File(path, "r") as h5:
            return "suspension" in h5
    except OSError:
        return False


def looks_like_suspension(roots):
    """True when the first run found under the roots is a suspension run (clusters.h5, a
    summary.json whose scene is 'suspension', or particles.h5 in the suspension layout)."""
    for root in roots:
        try:
            directories = find_suspension_runs(root)
        except BatchError:
            continue
        for directory in directories:
            if os.path.exists(os.path.join(directory, CLUSTER_FILE)) or _summary_scene(directory) == "suspension":
                return True
            if os.path.exists(os.path.join(directory, "summary.json")):
                return False
            if _has_suspension_rows(directory):
                return True
    return False


def load_suspension_runs(roots):
    """(usable runs, skipped [(directory, reason)]). A run of a batch (deck.nml, written by
    tools/montecarlo.sh) is complete when its summary.json exists and no FAILED marker; a run
    directory of a single run needs only its output files. Runs without clusters.h5 count for the
    collision rate only (from particles.h5's events, one species assumed)."""
    usable, skipped = [], []
    for root in roots:
        directories = find_suspension_runs(root)
        if not directories:
            raise BatchError(f"'{root}' holds no suspension run (no clusters.h5 or particles.h5)")
        for directory in directories:
            if os.path.exists(os.path.join(directory, "FAILED")):
                skipped.append((directory, "failed (see its FAILED file)"))
            elif os.path.exists(os.path.join(directory, "deck.nml")) and \
                    not os.path.exists(os.path.join(directory, "summary.json")):
                skipped.append((directory, "incomplete (no summary.json)"))
            elif not _is_suspension_run(directory):
                skipped.append((directory, "not a suspension run"))
            else:
                try:
                    usable.append(SuspensionRun(directory, root))
                except (OSError, KeyError, ValueError) as error:
                    skipped.append((directory, f"unreadable: {error}"))
    if not usable:
        raise BatchError(f"no usable suspension run in {', '.join(roots)} ({len(skipped)} skipped)")
    return usable, skipped


def assign_suspension_groups(runs, group_by):
    """Set run.group (the shape, or the batch root's name) and return the groups in order."""
    for run in runs:
        run.group = os.path.basename(os.path.normpath(run.batch)) if group_by == "batch" else run.shape
    return sorted({run.group for run in runs},
                  key=lambda g: (SHAPE_ORDER.get(g.split("-")[0], 9), g))


# ----------------------------------------------------------------------------------------------
# Statistics
# ----------------------------------------------------------------------------------------------

def _common_time(members):
    """The time rows shared by the group's runs: the first run's rows up to the shortest run's end
    (the runs of one deck write the same rows)."""
    import numpy as np
    times = [np.asarray(run.clusters()["time"], float) for run in members]
    end = min(t[-1] for t in times if t.size) if any(t.size for t in times) else 0.0
    reference = max(times, key=len)
    return reference[reference <= end * (1 + 1e-12)]


def time_series(members, key):
    """(time, per-run values (runs, T)) of /summary/<key>, each run interpolated onto the group's
    common rows."""
    import numpy as np
    time = _common_time(members)
    values = np.array([np.interp(time, np.asarray(r.clusters()["time"], float),
                                 np.asarray(r.clusters()[f"summary/{key}"], float)) for r in members])
    return time, values


def nearest_row(run, time):
    import numpy as np
    return int(np.argmin(np.abs(np.asarray(run.clusters()["time"], float) - time)))


def size_distribution(members, time):
    """Sizes of every cluster of the group's runs at the row nearest `time`: (sizes, counts)."""
    import numpy as np
    pooled = []
    for run in members:
        rows = run.row_slice("cluster", nearest_row(run, time))
        pooled.append(np.asarray(run.clusters()["cluster/size"][rows], int))
    sizes = np.concatenate(pooled) if pooled else np.empty(0, int)
    values, counts = np.unique(sizes, return_counts=True)
    return values, counts


def gyration_sample(members, which="full"):
    """(sizes, radii) of the clusters of at least FRACTAL_MIN_SIZE bodies, not percolating, at the
    last row of each run; radii from /cluster/radius_of_gyration ('full', each body's own gyration
    included) or /cluster/radius_of_gyration_centres ('centres')."""
    import numpy as np
    dataset = "cluster/radius_of_gyration" if which == "full" else "cluster/radius_of_gyration_centres"
    sizes, radii = [], []
    for run in members:
        data = run.clusters()
        rows = run.row_slice("cluster", len(data["time"]) - 1)
        size = np.asarray(data["cluster/size"][rows], int)
        radius = np.asarray(data[dataset][rows], float)
        percolating = np.asarray(data["cluster/percolating"][rows], int) != 0
        keep = (size >= FRACTAL_MIN_SIZE) & ~percolating
        sizes.append(size[keep])
        radii.append(radius[keep])
    return (np.concatenate(sizes) if sizes else np.empty(0), np.concatenate(radii) if radii else np.empty(0))


def psi_sample(members):
    """psi (rad) of every bond of every row of the group's runs: the bonds weighted by the rows
    they last (a distribution over bonded time, not over bond formations)."""
    import numpy as np
    values = [np.asarray(run.clusters().get("bond/psi", np.empty(0)), float) for run in members]
    return np.concatenate(values) if values else np.empty(0)


def _box_volume(run):
    """Box volume (m^3) of a run without clusters.h5, from its run.nml &grid lengths."""
    import re
    try:
        with open(run.path("run.nml")) as handle:
            text = handle.read()
    except OSError:
        return None
    volume = 1.0
    for axis in "xyz":
        match = re.search(rf"length_{axis}\s*=\s*([-+0-9.]+(?:[eEdD][-+]?[0-9]+)?)", text, re.I)
        if match is None:
            return None
        volume *= float(match.group(1).replace("d", "e").replace("D", "e"))
    return volume


def collision_rates(run):
    """{species pair name: collisions per unit volume per second} of one run: the cumulative count's
    change over the run divided by the time span and the box volume (clusters.h5 /collisions), or,
    without clusters.h5, the particles.h5 events over the run's time (one species, named by the
    run's shape)."""
    import numpy as np
    if run.has_clusters:
        data = run.clusters()
        time = np.asarray(data["time"], float)
        counts = np.asarray(data["collisions/count"], float).reshape(time.size, -1)
        if time.size < 2 or counts.size == 0:
            return {}
        names = _names(data["attrs"].get("species_names", []))
        pairs = np.asarray(data["collisions/species_pairs"], int).reshape(-1, 2)
        volume = float(data["collisions/volume"])
        span = time[-1] - time[0]
        rates = {}
        for k, (first, second) in enumerate(pairs):
            name = "-".join(names[i - 1] if 0 < i <= len(names) else str(i) for i in (first, second))
            rates[name] = (counts[-1, k] - counts[0, k]) / span / volume
        return rates
    import h5py
    volume = _box_volume(run)
    with h5py.File(run.path(PARTICLE_FILE), "r") as h5:
        time = np.asarray(h5["time"][:], float)
        events = np.asarray(h5["events/time"][:], float) if "events/time" in h5 else np.empty(0)
    if volume is None or time.size < 2:
        return {}
    span = time[-1] - time[0]
    inside = np.count_nonzero((events > time[0]) & (events <= time[-1]))
    return {f"{run.shape}-{run.shape}": inside / span / volume}


def _deck_number(run, name):
    """The value of `name = number` in the run's run.nml (the first occurrence), else None."""
    import re
    try:
        with open(run.path("run.nml")) as handle:
            text = handle.read()
    except OSError:
        return None
    match = re.search(rf"\b{name}\s*=\s*([-+0-9.]+(?:[eEdD][-+]?[0-9]+)?)", text, re.I)
    return float(match.group(1).replace("d", "e").replace("D", "e")) if match else None


def saffman_turner_kernel(run):
    """Saffman & Turner's (1956) collision kernel of equal spheres that follow the flow, for the run's
    sphere radius r and flow: sqrt(8 pi / 15) (2 r)^3 sqrt(eps / nu) (m^3/s), eps the mean of the
    dissipation column of fluid_statistics.dat over the run, nu the deck's &fluid viscosity. None
    for other shapes or without a fluid."""
    import numpy as np
    if run.shape != "sphere" or not run.radius or not os.path.exists(run.path("fluid_statistics.dat")):
        return None
    viscosity = _deck_number(run, "viscosity")
    try:
        table = np.atleast_2d(np.loadtxt(run.path("fluid_statistics.dat"), comments="#"))
    except ValueError:
        return None
    if viscosity is None or table.size == 0 or table.shape[1] < 5:
        return None
    dissipation = float(np.mean(table[:, 4]))
    return math.sqrt(8.0 * math.pi / 15.0) * (2.0 * run.radius) ** 3 * math.sqrt(dissipation / viscosity)


def collision_kernel(run, rates):
    """Collision kernel (m^3/s) of a run of one species: the rate per unit volume over the pairs per
    unit volume, Gamma / (n^2 / 2) with n = N / V (Saffman & Turner 1956 define the rate so), the
    number that compares runs of different body counts and, ghost against real collisions, gives
    the collision efficiency. None for several species (clusters.h5 does not give each species'
    count) or without the body count."""
    if len(rates) != 1 or not run.bodies:
        return None
    if run.has_clusters:
        volume = float(run.clusters()["collisions/volume"])
    else:
        volume = _box_volume(run)
    if not volume:
        return None
    density = run.bodies / volume
    return next(iter(rates.values())) / (0.5 * density * density)


def group_statistics(members, times, rg_kind):
    """Every number of one group (JSON-ready) and the arrays its figures need."""
    import numpy as np
    clustered = [r for r in members if r.has_clusters]
    stats = {"runs": len(members), "runs_with_clusters": len(clustered),
             "seeds": sorted(r.seed for r in members if r.seed is not None)}
    arrays = {}
    if clustered:
        for key in ("mean_size_number", "mean_size_weight", "bonds", "largest", "clusters"):
            time, values = time_series(clustered, key)
            arrays[key] = (time, values)
            mean, low, high = (np.array(v) for v in zip(*(mean_interval(values[:, j])
                                                           for j in range(time.size))))
            arrays[key + "_band"] = (mean, low, high)
            stats[f"final_{key}"] = dict(zip(("mean", "low", "high"), mean_interval(values[:, -1])))
        stats["final_time"] = float(arrays["bonds"][0][-1]) if arrays["bonds"][0].size else math.nan
        stats["sizes"] = {}
        for t in times:
            values, counts = size_distribution(clustered, t)
            stats["sizes"][f"{t:g}"] = {"size": values.tolist(), "count": counts.tolist()}
        sizes, radii = gyration_sample(clustered, rg_kind)
        arrays["gyration"] = (sizes, radii)
        stats["fractal"] = fractal_dimension(sizes, radii)
        stats["fractal"]["radius_of_gyration"] = rg_kind
        psi = psi_sample(clustered)
        arrays["psi"] = psi
        stats["psi"] = {"bond_rows": int(psi.size),
                        "mean": float(np.mean(psi)) if psi.size else math.nan,
                        "median": float(np.median(psi)) if psi.size else math.nan}
    per_run = [collision_rates(r) for r in members]
    names = sorted({name for rates in per_run for name in rates})
    stats["collision_rate"] = {name: dict(zip(("mean", "low", "high"),
                                              mean_interval([rates.get(name, math.nan) for rates in per_run])))
                               for name in names}
    kernels = [collision_kernel(r, rates) for r, rates in zip(members, per_run)]
    kernels = [k for k in kernels if k is not None]
    stats["collision_kernel"] = dict(zip(("mean", "low", "high"), mean_interval(kernels))) \
        if kernels and len(names) == 1 else None
    # Ghost spheres that follow the flow against Saffman & Turner: each run's kernel over its own
    # reference (the runs' flows may differ in dissipation).
    ratios = []
    for run, rates in zip(members, per_run):
        kernel, reference = collision_kernel(run, rates), saffman_turner_kernel(run)
        if kernel is not None and reference:
            ratios.append(kernel / reference)
    stats["kernel_over_saffman_turner"] = dict(zip(("mean", "low", "high"), mean_interval(ratios))) \
        if ratios and len(names) == 1 else None
    return stats, arrays


# ----------------------------------------------------------------------------------------------
# Tables and figures
# ----------------------------------------------------------------------------------------------

TABLE_COLUMNS = ("group", "runs", "final_time",
                 "mean_size_number", "mean_size_number_low", "mean_size_number_high",
                 "mean_size_weight", "mean_size_weight_low", "mean_size_weight_high",
                 "bonds", "bonds_low", "bonds_high", "largest",
                 "fractal_dimension", "fractal_low", "fractal_high", "fractal_clusters",
                 "psi_mean", "psi_median", "psi_bond_rows", "collision_kernel", "collision_kernel_low",
                 "collision_kernel_high", "kernel_over_saffman_turner", "kernel_over_saffman_turner_low",
                 "kernel_over_saffman_turner_high", "collision_rates")


def table_row(group, stats):
    row = dict.fromkeys(TABLE_COLUMNS, "")
    row.update(group=group, runs=stats["runs"])
    if "final_bonds" in stats:
        row["final_time"] = stats["final_time"]
        for key in ("mean_size_number", "mean_size_weight", "bonds"):
            final = stats[f"final_{key}"]
            row.update({key: final["mean"], f"{key}_low": final["low"], f"{key}_high": final["high"]})
        row["largest"] = stats["final_largest"]["mean"]
        fractal = stats["fractal"]
        row.update(fractal_dimension=fractal["D"], fractal_low=fractal["low"], fractal_high=fractal["high"],
                   fractal_clusters=fractal["clusters"], psi_mean=stats["psi"]["mean"],
                   psi_median=stats["psi"]["median"], psi_bond_rows=stats["psi"]["bond_rows"])
    if stats.get("collision_kernel"):
        kernel = stats["collision_kernel"]
        row.update(collision_kernel=kernel["mean"], collision_kernel_low=kernel["low"],
                   collision_kernel_high=kernel["high"])
    if stats.get("kernel_over_saffman_turner"):
        ratio = stats["kernel_over_saffman_turner"]
        row.update(kernel_over_saffman_turner=ratio["mean"], kernel_over_saffman_turner_low=ratio["low"],
                   kernel_over_saffman_turner_high=ratio["high"])
    row["collision_rates"] = "; ".join(f"{name} {value['mean']:.6g} [{value['low']:.6g}, {value['high']:.6g}]"
                                       for name, value in stats["collision_rate"].items())
    return row


def _json_ready(value):
    if isinstance(value, dict):
        return {k: _json_ready(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_ready(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item"):
        return _json_ready(value.item())
    return value


def comparison_rows(table, rungs):
    """Rows of suspension_comparison.csv: for groups named SHAPE-RUNG (--group-by batch) the two
    rungs of each shape side by side (mean cluster size, bonds, fractal dimension, psi, collision
    kernel) with the ratio second / first."""
    first, second = rungs
    by_name = {row["group"]: row for row in table}
    shapes = sorted({name.rsplit("-", 1)[0] for name in by_name
                     if name.endswith(f"-{first}") or name.endswith(f"-{second}")},
                    key=lambda s: (SHAPE_ORDER.get(s, 9), s))
    rows = []
    for shape in shapes:
        a, b = by_name.get(f"{shape}-{first}"), by_name.get(f"{shape}-{second}")
        for quantity in ("mean_size_number", "mean_size_weight", "bonds", "fractal_dimension", "psi_mean",
                         "collision_kernel"):
            low = {"fractal_dimension": "fractal_low"}.get(quantity, f"{quantity}_low")
            high = {"fractal_dimension": "fractal_high"}.get(quantity, f"{quantity}_high")
            row = {"shape": shape, "quantity": quantity}
            for rung, source in ((first, a), (second, b)):
                row[rung] = "" if source is None else source[quantity]
                row[f"{rung}_low"] = "" if source is None or low not in source else source[low]
                row[f"{rung}_high"] = "" if source is None or high not in source else source[high]
            try:
                row["ratio"] = float(row[second]) / float(row[first])
            except (TypeError, ValueError, ZeroDivisionError):
                row["ratio"] = ""
            rows.append(row)
    return rows


def _figures(groups, results, runs, out, times, snapshot_time):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    import numpy as np
    written = []
    colours = {group: f"C{k % 10}" for k, group in enumerate(groups)}
    with_clusters = [g for g in groups if "bonds" in results[g][1]]

    # Mean cluster size and bonds against time, seed-to-seed 95% band.
    figure, axes = plt.subplots(1, 2, figsize=(11, 4))
    for group in with_clusters:
        arrays = results[group][1]
        runs_n = results[group][0]["runs_with_clusters"]
        for axis, key in ((axes[0], "mean_size_number"), (axes[1], "bonds")):
            time = arrays[key][0] * 1e3
            mean, low, high = arrays[key + "_band"]
            axis.plot(time, mean, color=colours[group], label=f"{group} ({runs_n} runs)")
            if runs_n > 1:
                axis.fill_between(time, low, high, color=colours[group], alpha=0.25, linewidth=0)
    axes[0].set_ylabel("mean cluster size N / K")
    axes[1].set_ylabel("bonds")
    for axis in axes:
        axis.set_xlabel("time (ms)")
        if with_clusters:
            axis.legend(fontsize=8)
    axes[0].set_title("Mean cluster size (band: t-based 95% over seeds)", fontsize=9)
    axes[1].set_title("Number of bonds (band: t-based 95% over seeds)", fontsize=9)
    figure.tight_layout()
    written += _save(figure, out, "suspension_growth")
    plt.close(figure)

    # Size distributions at the chosen times.
    if with_clusters and times:
        figure, axes = plt.subplots(1, len(times), figsize=(4.2 * len(times), 3.8), squeeze=False)
        for axis, t in zip(axes[0], times):
            for group in with_clusters:
                entry = results[group][0]["sizes"][f"{t:g}"]
                size, count = np.asarray(entry["size"]), np.asarray(entry["count"], float)
                if size.size:
                    axis.plot(size, count / count.sum(), "o-", color=colours[group], label=group, markersize=3)
            axis.set_xscale("log")
            axis.set_yscale("log")
            # Sizes are integers, often within a decade: labelled ticks at 1, 2, 5, 10, 20, ...
            axis.xaxis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
            axis.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
            axis.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            axis.set_xlabel("cluster size s")
            axis.set_title(f"t = {t * 1e3:g} ms", fontsize=9)
            if axis.get_legend_handles_labels()[0]:
                axis.legend(fontsize=8)
        axes[0][0].set_ylabel("fraction of clusters n_s / K")
        figure.tight_layout()
        written += _save(figure, out, "suspension_sizes")
        plt.close(figure)

    # Radius of gyration against size, fitted fractal dimension.
    figure, axis = plt.subplots(figsize=(5.5, 4.2))
    for group in with_clusters:
        sizes, radii = results[group][1]["gyration"]
        fractal = results[group][0]["fractal"]
        if sizes.size == 0:
            continue
        label = f"{group}: D = {fractal['D']:.2f} [{fractal['low']:.2f}, {fractal['high']:.2f}]" \
            if math.isfinite(fractal["D"]) else f"{group}: D not fitted ({sizes.size} clusters)"
        axis.loglog(sizes, radii * 1e6, "o", color=colours[group], markersize=3, label=label)
        if math.isfinite(fractal["slope"]):
            line = np.array([sizes.min(), sizes.max()], float)
            centre = np.exp(np.mean(np.log(radii)) + fractal["slope"] * (np.log(line) - np.mean(np.log(sizes))))
            axis.loglog(line, centre * 1e6, "-", color=colours[group])
    axis.set_xlabel("cluster size N")
    axis.set_ylabel("radius of gyration (um)")
    axis.set_title(f"Clusters of >= {FRACTAL_MIN_SIZE} bodies, not percolating, last row", fontsize=9)
    if axis.get_legend_handles_labels()[0]:
        axis.legend(fontsize=8)
    else:
        axis.text(0.5, 0.5, f"no cluster of >= {FRACTAL_MIN_SIZE} bodies", transform=axis.transAxes, ha="center")
    written += _save(figure, out, "suspension_gyration")
    plt.close(figure)

    # psi of bonded neighbours, with the isotropic reference sin(psi).
    figure, axis = plt.subplots(figsize=(5.5, 4.2))
    for group in with_clusters:
        psi = results[group][1]["psi"]
        if psi.size:
            density, edges = np.histogram(psi, bins=np.linspace(0, 0.5 * math.pi, 10), density=True)
            axis.stairs(density, edges, color=colours[group], label=f"{group} (n = {psi.size})")
    grid = np.linspace(0, 0.5 * math.pi, 100)
    axis.plot(grid, np.sin(grid), "k:", label="random orientations, sin psi")
    axis.set_xlabel("psi, angle between the axes of bonded neighbours (rad)")
    axis.set_ylabel("PDF")
    axis.legend(fontsize=8)
    written += _save(figure, out, "suspension_psi")
    plt.close(figure)

    # Collision rate per unit volume per species pair.
    figure, axis = plt.subplots(figsize=(6, 4))
    labels, means, errors = [], [], [[], []]
    for group in groups:
        for name, value in results[group][0]["collision_rate"].items():
            labels.append(f"{group}\n{name}")
            means.append(value["mean"])
            errors[0].append(value["mean"] - value["low"])
            errors[1].append(value["high"] - value["mean"])
    if labels:
        axis.bar(range(len(labels)), means, yerr=errors, color="C0", capsize=4)
        axis.set_xticks(range(len(labels)), labels, fontsize=7)
    axis.set_ylabel("collision rate (1 / (m^3 s))")
    axis.set_title("Collisions per unit volume and time (t-based 95% over seeds)", fontsize=9)
    written += _save(figure, out, "suspension_collision_rate")
    plt.close(figure)

    # 3D snapshot coloured by cluster: the first run of each group with clusters.h5.
    for group in with_clusters:
        run = next(r for r in runs if r.group == group and r.has_clusters)
        written += snapshot_figure(run, out, f"suspension_snapshot_{_safe(group)}", snapshot_time)
    return written


def _safe(name):
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)


def snapshot_figure(run, out, stem, time=None):
    """Body centres of a run at the particles.h5 row nearest `time` (default: the last), coloured
    by their cluster at the nearest clusters.h5 row; bodies without bonds grey."""
    import h5py
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    with h5py.File(run.path(PARTICLE_FILE), "r") as h5:
        ptime = np.asarray(h5["time"][:], float)
        row = len(ptime) - 1 if time is None else int(np.argmin(np.abs(ptime - time)))
        positions = np.asarray(h5["suspension/position"][row], float).reshape(-1, 3)
    data = run.clusters()
    crow = nearest_row(run, ptime[row])
    cluster = np.asarray(data["body/cluster"][crow], int)
    box = np.asarray(data["attrs"].get("box_length", np.ptp(positions, axis=0)), float)
    positions = np.mod(positions, box)
    sizes = np.bincount(cluster)
    figure = plt.figure(figsize=(6, 6))
    axis = figure.add_subplot(projection="3d")
    single = sizes[cluster] == 1
    axis.scatter(*(positions[single] * 1e3).T, color="0.7", s=12, label="single bodies")
    colours = plt.get_cmap("tab20")
    for k, number in enumerate(np.unique(cluster[~single])):
        members = cluster == number
        axis.scatter(*(positions[members] * 1e3).T, color=colours(k % 20), s=30)
    axis.set_xlabel("x (mm)")
    axis.set_ylabel("y (mm)")
    axis.set_zlabel("z (mm)")
    clustered = int(np.count_nonzero(~single))
    axis.set_title(f"{run.label}, t = {ptime[row] * 1e3:.3g} ms: {len(np.unique(cluster))} clusters, "
                   f"{clustered} bodies bonded", fontsize=9)
    paths = _save(figure, out, stem)
    plt.close(figure)
    return paths


def main(arguments):
    """The suspension mode of agglo-stats (arguments: agglo_stats' parsed options). Returns 0 or
    raises BatchError."""
    runs, skipped = load_suspension_runs(arguments.roots)
    group_by = "batch" if arguments.group_by == "batch" else "shape"
    groups = assign_suspension_groups(runs, group_by)
    out = arguments.out or os.path.join(arguments.roots[0], "stats")
    os.makedirs(out, exist_ok=True)
    times = list(arguments.times or [])
    if not times:      # the last row of every run (the nearest row to the latest end)
        ends = [float(r.clusters()["time"][-1]) for r in runs if r.has_clusters and len(r.clusters()["time"])]
        times = [max(ends)] if ends else []
    results = {group: group_statistics([r for r in runs if r.group == group], times, arguments.rg)
               for group in groups}
    table = [table_row(group, results[group][0]) for group in groups]
    write_csv(os.path.join(out, "suspension_table.csv"), TABLE_COLUMNS, table)
    series = []
    for group in groups:
        arrays = results[group][1]
        if "bonds" not in arrays:
            continue
        for j, t in enumerate(arrays["bonds"][0]):
            row = {"group": group, "time": t}
            for key in ("mean_size_number", "mean_size_weight", "bonds", "largest", "clusters"):
                mean, low, high = arrays[key + "_band"]
                row.update({key: mean[j], f"{key}_low": low[j], f"{key}_high": high[j]})
            series.append(row)
    series_columns = ("group", "time") + tuple(f"{k}{s}" for k in ("mean_size_number", "mean_size_weight",
                                                                   "bonds", "largest", "clusters")
                                               for s in ("", "_low", "_high"))
    write_csv(os.path.join(out, "suspension_timeseries.csv"), series_columns, series)
    sizes = [{"group": group, "time": t, "size": s, "count": c}
             for group in groups for t, entry in results[group][0].get("sizes", {}).items()
             for s, c in zip(entry["size"], entry["count"])]
    write_csv(os.path.join(out, "suspension_sizes.csv"), ("group", "time", "size", "count"), sizes)
    document = {"interval": "95%, Student t over the runs (seeds): mean -/+ t_{0.975,n-1} s/sqrt(n)",
                "fractal_fit": "log Rg = c + (1/D) log N over clusters of >= 3 bodies, not percolating, "
                               "last row of each run; 95% interval from the slope's t interval",
                "groups": {group: results[group][0] for group in groups},
                "runs": [{"run": r.label, "group": r.group, "shape": r.shape, "seed": r.seed,
                          "clusters_h5": r.has_clusters} for r in runs],
                "skipped": [{"run": d, "reason": reason} for d, reason in skipped]}
    if arguments.compare:
        rungs = tuple(arguments.compare.split(","))
        rows = comparison_rows(table, rungs)
        columns = ("shape", "quantity") + tuple(f"{r}{s}" for r in rungs for s in ("", "_low", "_high")) + ("ratio",)
        write_csv(os.path.join(out, "suspension_comparison.csv"), columns, rows)
        document["comparison"] = rows
        print_comparison(rows, rungs)
    with open(os.path.join(out, "suspension.json.tmp"), "w") as handle:
        json.dump(_json_ready(document), handle, indent=1)
    os.replace(os.path.join(out, "suspension.json.tmp"), os.path.join(out, "suspension.json"))
    print_table(table)
    bare = [r for r in runs if not r.has_clusters]
    if bare:
        print(f"note: {len(bare)} of {len(runs)} run(s) hold no clusters.h5 (a run without DLVO, or a "
              f"code without cluster output): collision rates only, from particles.h5's events")
    if skipped:
        print(f"skipped {len(skipped)} run(s) of {len(skipped) + len(runs)}:")
        for directory, reason in skipped[:20]:
            print(f"  {directory}: {reason}")
    print(f"wrote suspension_table.csv, suspension_timeseries.csv, suspension_sizes.csv and suspension.json in {out}")
    if not arguments.no_figures:
        written = _figures(groups, results, runs, out, times, arguments.snapshot_time)
        print(f"wrote {len(written)} figure files in {out}")
    return 0


def _show(value, form=".4g"):
    try:
        number = float(value)
    except (TypeError, ValueError):
        return "-"
    return format(number, form) if math.isfinite(number) else "-"


def print_table(table):
    width = max(12, max(len(row["group"]) for row in table))
    print(f"{'group':<{width}} {'runs':>4} {'t_end(ms)':>9}  {'N/K [95%]':<26} {'bonds [95%]':<26} "
          f"{'D [95%]':<22} {'psi mean':>8}")

    def triple(row, key, low, high, form=".4g"):
        return f"{_show(row[key], form)} [{_show(row[low], form)}, {_show(row[high], form)}]"
    for row in table:
        t_end = _show(row["final_time"] * 1e3) if row["final_time"] != "" else "-"
        print(f"{row['group']:<{width}} {row['runs']:>4} {t_end:>9}  "
              f"{triple(row, 'mean_size_number', 'mean_size_number_low', 'mean_size_number_high'):<26} "
              f"{triple(row, 'bonds', 'bonds_low', 'bonds_high'):<26} "
              f"{triple(row, 'fractal_dimension', 'fractal_low', 'fractal_high', '.3g'):<22} "
              f"{_show(row['psi_mean'], '.3f'):>8}")
        if row["collision_rates"]:
            print(f"{'':<{width}} collision rate (1/(m^3 s)): {row['collision_rates']}")
        if row["collision_kernel"] != "":
            print(f"{'':<{width}} collision kernel (m^3/s): "
                  f"{triple(row, 'collision_kernel', 'collision_kernel_low', 'collision_kernel_high')}")
        if row["kernel_over_saffman_turner"] != "":
            print(f"{'':<{width}} kernel / Saffman-Turner: "
                  f"{triple(row, 'kernel_over_saffman_turner', 'kernel_over_saffman_turner_low', 'kernel_over_saffman_turner_high', '.3f')}")


def print_comparison(rows, rungs):
    print(f"comparison {rungs[0]} -> {rungs[1]}:")
    for row in rows:
        print(f"  {row['shape']:<8} {row['quantity']:<17} {_show(row[rungs[0]]):>10} -> "
              f"{_show(row[rungs[1]]):>10}   ratio {_show(row['ratio'], '.3f')}")
