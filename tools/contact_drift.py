"""contact_drift: why a resolved pair with hydrodynamics_from = 'first_contact' moves faster after
its first contact than in vacuum, run by run against the 'none' batch on the same seeds.

For every run complete in both batches (same run name, same seed) it measures, from particles.h5,
summary.json, run.nml and bodies_loads.dat of the variant:
- the overshoot: the largest centre speed |v| of either particle (the max_particle_speed of
  agglo_stats) over the 'none' run's, when and on which particle it occurs (time after the first
  collision, and as a share of the time after it), and the pair's centre-of-mass speed
  |(v1 + v2) / 2| and relative speed |v2 - v1| at the end, over the start speed;
- the stabilisation drive: with &scene added_mass the resolved provider hands the particle step
  the load m a - F_dlvo with (m + M) a = F + M A + F_dlvo in each body frame
  (resolved_hydrodynamics.f90), so the DLVO force moves a body with the mass m + M while the
  contact impulses that balance it move it with m alone (particle_system.f90). Each body i then
  feels, besides the fluid's own reaction, D_i = (m R_i (m + M_i)^-1 R_i^T - 1) F_dlvo,i; two bodies
  whose added masses along the contact normal differ keep a net D = D_1 + D_2 while they are held
  in contact. drive_N is |mean D| over the rows after the first collision with the gap below
  EPISODE_FLOORS detection floors (in contact), drive_cos its cosine with the end's centre-of-mass
  velocity; the impulses over the time after the first collision of D (drive_impulse), of the sum of
  the felt hydrodynamic forces of particles.h5 (felt_impulse) and of the resolved momentum-balance
  forces of bodies_loads.dat (resolved_impulse), along the pair's momentum change, over that change;
- the reading it is compared with, the fluid carried at the first contact (last row before it):
  for the faster particle, face_on = |e . v| / |v| (e its symmetry axis), the potential-flow
  fluid momentum |R M R^T v| and the impulse the body gave the fluid before the contact
  (-integral of its resolved force, bodies_loads.dat), each over m |v|; and the first collision's
  normal velocity and its rebound ratio -v_after / v_before.
M = rho_f V diag(k_ax, k_tr, k_tr), Lamb, "Hydrodynamics" (1932), sec. 373 (as the code).

--held ROOT (any batch, no reference; with or without pairs of roots): the drive D_1 + D_2 on its
agglomerated pairs held in contact, median and largest, and its share of the felt hydrodynamic force.

Usage: .venv/bin/python tools/contact_drift.py NONE_ROOT VARIANT_ROOT [NONE_ROOT VARIANT_ROOT ...]
           [-o FILE.csv] [--figure DIR] [--label NAME ...] [--held ROOT ...]
Prints one summary line per pair of batches (runs above 1.01, median ratio, Spearman rank
correlations of the ratio with each quantity) and per --held root. Exit status: 0 done, 1
unusable input.
"""
import argparse
import csv
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from agglo_stats import EPISODE_FLOORS, BatchError, load_runs  # noqa: E402

OVERSHOOT = 1.01            # a ratio above this counts as an overshoot (the needles' largest)
COLUMNS = ("batch", "run", "seed", "shape", "outcome", "ratio", "max_particle", "max_after_contact_ms",
           "max_share_after_contact", "com_speed_end", "relative_speed_end", "contact_rows", "dlvo_N",
           "drive_N", "drive_cos", "drive_impulse", "felt_impulse", "resolved_impulse", "face_on",
           "added_mass_momentum", "fluid_impulse_before", "normal_velocity_before", "rebound")
CORRELATED = ("drive_N", "drive_impulse", "face_on", "added_mass_momentum", "fluid_impulse_before",
              "normal_velocity_before", "rebound")


def namelist_value(text, group, name):
    """The value of &group name in a resolved deck (run.nml), a float or an unquoted string;
    None when absent."""
    block = re.search(r"&" + group + r"\b(.*?)\n\s*/", text, re.I | re.S)
    if block is None:
        return None
    match = re.search(r"\b" + name + r"\s*=\s*([^,\n]+)", block.group(1), re.I)
    if match is None:
        return None
    value = match.group(1).strip().strip("'\"").strip()
    try:
        return float(value.replace("d", "e").replace("D", "e"))
    except ValueError:
        return value


def added_mass_coefficients(axial, transverse):
    """[k_axial, k_transverse] of a spheroid in potential flow (Lamb 1932 sec. 373):
    k_i = alpha0_i / (2 - alpha0_i), alpha0_i = a b^2 alpha_i, from the closed forms of the
    ellipsoid integrals; a sphere has k = 1/2."""
    a, b = float(axial), float(transverse)
    if abs(a - b) <= 1e-9 * b:
        return [0.5, 0.5]
    d = b * b - a * a
    if a > b:
        c = math.sqrt(a * a - b * b)
        chi = math.log((a + c) / (a - c)) / c
    else:
        c = math.sqrt(d)
        chi = 2.0 * math.atan(c / a) / c
    alpha_transverse = (0.5 * chi - a / (b * b)) / d
    alpha_axial = 2.0 / (a * b * b) - 2.0 * alpha_transverse
    alpha0 = [a * b * b * alpha_axial, a * b * b * alpha_transverse]
    return [x / (2.0 - x) for x in alpha0]


def semi_axes(radius, aspect_ratio):
    """(axial, transverse) semi-axes of the spheroid of volume-equivalent radius and aspect ratio
    axial / transverse (summary.json's aspect_ratio: 0.2 for the disk, 5 for the needle)."""
    transverse = radius / aspect_ratio ** (1.0 / 3.0)
    return aspect_ratio * transverse, transverse


def rotation_matrices(quaternions):
    """R(q) body -> lab for rows of unit quaternions (w, x, y, z), as quaternion.f90."""
    import numpy as np
    w, x, y, z = (np.asarray(quaternions, float)[:, k] for k in range(4))
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def stabilisation_drive(force, quaternions, mass, added_mass):
    """Rows of D = (m R (m + M)^-1 R^T - 1) F: what the added-mass stabilisation adds to a body's
    felt load when the other force F is taken implicitly; added_mass = (M_ax, M_tr, M_tr) kg."""
    import numpy as np
    rotation = rotation_matrices(quaternions)
    body = np.einsum("nji,nj->ni", rotation, np.asarray(force, float))
    scaled = body * (mass / (mass + np.asarray(added_mass, float)))
    return np.einsum("nij,nj->ni", rotation, scaled) - np.asarray(force, float)


def spearman(x, y):
    """Spearman's rank correlation of two samples (average ranks for ties); nan below 3 pairs."""
    import numpy as np
    x, y = np.asarray(x, float), np.asarray(y, float)
    keep = np.isfinite(x) & np.isfinite(y)
    if np.count_nonzero(keep) < 3:
        return float("nan")

    def ranks(values):
        order = np.argsort(values, kind="mergesort")
        result = np.empty(values.size)
        result[order] = np.arange(values.size, dtype=float)
        for value in np.unique(values):
            tied = values == value
            result[tied] = result[tied].mean()
        return result
    rx, ry = ranks(x[keep]), ranks(y[keep])
    if rx.std() == 0.0 or ry.std() == 0.0:
        return float("nan")
    return float(np.corrcoef(rx, ry)[0, 1])


def _history(directory):
    import h5py
    import numpy as np
    with h5py.File(os.path.join(directory, "particles.h5"), "r") as h5:
        data = {"time": np.asarray(h5["time"][:], float), "gap": np.asarray(h5["pair/gap"][:], float)}
        for k in (1, 2):
            for name in ("velocity", "quaternion", "force_dlvo", "force_hydrodynamic"):
                data[f"{name}{k}"] = np.asarray(h5[f"particle{k}/{name}"][:], float)
        data["radius"] = float(np.asarray(h5["radius"][()])) if "radius" in h5 else float(h5.attrs["radius"])
    return data


def _resolved_loads(directory):
    """(time, body, force rows) of bodies_loads.dat; None without the file."""
    import numpy as np
    path = os.path.join(directory, "bodies_loads.dat")
    if not os.path.exists(path):
        return None
    table = np.loadtxt(path, usecols=(1, 2, 3, 4, 5), ndmin=2)
    return table[:, 0], table[:, 1].astype(int), table[:, 2:5]


def _integral(time, values):
    """Trapezoidal integral of rows of vectors over time."""
    import numpy as np
    if time.size < 2:
        return np.zeros(values.shape[1:])
    return np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(time)[:, None], axis=0)


def _max_speed(directory):
    import h5py
    import numpy as np
    with h5py.File(os.path.join(directory, "particles.h5"), "r") as h5:
        return max(float(np.max(np.linalg.norm(h5[f"particle{k}/velocity"][:], axis=1))) for k in (1, 2))


def pair_drive(run, deck, h):
    """(m, (M_ax, M_tr, M_tr), rows of D_1 + D_2, rows in contact after the first collision) of a
    run with a first collision, from its run.nml text and _history; D is zero without the
    stabilisation (&scene added_mass)."""
    import numpy as np
    fluid_density = namelist_value(deck, "fluid", "density")
    particle_density = namelist_value(deck, "pair", "density")
    floor = namelist_value(deck, "collision", "detection_floor") or 1.0e-9
    stabilised = str(namelist_value(deck, "scene", "added_mass")).upper().startswith("T")
    axial, transverse = semi_axes(h["radius"], float(run.summary["aspect_ratio"]))
    volume = 4.0 / 3.0 * math.pi * h["radius"] ** 3
    mass = particle_density * volume
    k = added_mass_coefficients(axial, transverse)
    added = fluid_density * volume * np.array([k[0], k[1], k[1]])
    drive = np.zeros_like(h["force_dlvo1"])
    if stabilised:
        drive = sum(stabilisation_drive(h[f"force_dlvo{p}"], h[f"quaternion{p}"], mass, added) for p in (1, 2))
    contact = (h["time"] >= float(run.summary["first_collision"]["time"])) & (h["gap"] < EPISODE_FLOORS * floor)
    return mass, added, drive, contact


HELD_ROWS = 5               # an agglomerated run counts as held with at least this many rows in contact


def held_drive_line(root):
    """One line for the agglomerated runs of any batch held in contact for HELD_ROWS rows or more:
    median and largest |mean D| (nN) over their rows in contact, and the median of |mean D| over
    the mean |felt hydrodynamic force| per particle there."""
    import numpy as np
    drives, shares = [], []
    for run in load_runs([root])[0]:
        if run.summary["outcome"] != "agglomerated" or run.summary["first_collision"] is None:
            continue
        with open(os.path.join(run.directory, "run.nml")) as handle:
            deck = handle.read()
        h = _history(run.directory)
        _, _, drive, contact = pair_drive(run, deck, h)
        if np.count_nonzero(contact) < HELD_ROWS:
            continue
        size = float(np.linalg.norm(drive[contact].mean(axis=0)))
        felt = np.mean([np.linalg.norm(h[f"force_hydrodynamic{p}"][contact], axis=1).mean() for p in (1, 2)])
        drives.append(size)
        shares.append(size / felt if felt > 0 else float("nan"))
    if not drives:
        return f"{root}: no agglomerated run held in contact"
    return (f"{root}: {len(drives)} agglomerated runs held in contact, |D_1 + D_2| median "
            f"{np.median(drives) * 1e9:.3g} nN, largest {max(drives) * 1e9:.3g} nN, median "
            f"{np.nanmedian(shares):.2f} of the mean felt hydrodynamic force per particle")


def analyse_run(run, reference_max_speed):
    """The COLUMNS of one variant run (module header) given the 'none' run's max particle speed."""
    import numpy as np
    with open(os.path.join(run.directory, "run.nml")) as handle:
        deck = handle.read()
    h = _history(run.directory)
    time = h["time"]
    if run.summary["first_collision"] is None:
        raise BatchError(f"{run.directory}: no collision, nothing after a first contact to analyse")
    speeds = np.stack([np.linalg.norm(h["velocity1"], axis=1), np.linalg.norm(h["velocity2"], axis=1)])
    particle, row = np.unravel_index(int(np.argmax(speeds)), speeds.shape)
    start_speed = float(np.max(speeds[:, 0]))
    row_values = {"batch": os.path.basename(os.path.dirname(run.directory)), "run": os.path.basename(run.directory),
                  "seed": run.summary["seed"], "shape": run.summary["shape"], "outcome": run.summary["outcome"],
                  "ratio": float(speeds.max() / reference_max_speed), "max_particle": int(particle) + 1}
    first = run.summary["first_collision"]
    t1 = float(first["time"])
    after = time >= t1
    row_values["max_after_contact_ms"] = (time[row] - t1) * 1e3
    row_values["max_share_after_contact"] = (time[row] - t1) / max(time[-1] - t1, 1e-300)
    com = 0.5 * (h["velocity1"] + h["velocity2"])
    row_values["com_speed_end"] = float(np.linalg.norm(com[-1]) / start_speed)
    row_values["relative_speed_end"] = float(np.linalg.norm(h["velocity2"][-1] - h["velocity1"][-1]) / start_speed)

    mass, added, drive, contact = pair_drive(run, deck, h)
    row_values["contact_rows"] = int(np.count_nonzero(contact))
    if np.any(contact):
        row_values["dlvo_N"] = float(np.mean(np.linalg.norm(h["force_dlvo1"][contact], axis=1)))
        mean_drive = drive[contact].mean(axis=0)
        row_values["drive_N"] = float(np.linalg.norm(mean_drive))
        end_com = com[-1]
        denominator = np.linalg.norm(mean_drive) * np.linalg.norm(end_com)
        row_values["drive_cos"] = float(mean_drive @ end_com / denominator) if denominator > 0 else float("nan")
    change = 2.0 * mass * (com[-1] - com[np.argmax(after)])
    size = np.linalg.norm(change)
    if size > 0:
        direction = change / size
        felt = h["force_hydrodynamic1"] + h["force_hydrodynamic2"]
        row_values["drive_impulse"] = float(_integral(time[after], drive[after]) @ direction / size)
        row_values["felt_impulse"] = float(_integral(time[after], felt[after]) @ direction / size)
    loads = _resolved_loads(run.directory)
    if loads is not None and size > 0:
        load_time, body, force = loads
        total = force[body == 1] + force[body == 2]
        late = load_time[body == 1] >= t1
        row_values["resolved_impulse"] = float(_integral(load_time[body == 1][late], total[late]) @ direction / size)

    before = max(int(np.searchsorted(time, t1)) - 1, 0)
    p = row_values["max_particle"]
    velocity = h[f"velocity{p}"][before]
    speed = np.linalg.norm(velocity)
    rotation = rotation_matrices(h[f"quaternion{p}"][before:before + 1])[0]
    row_values["face_on"] = float(abs(rotation[:, 0] @ velocity) / speed)
    row_values["added_mass_momentum"] = float(np.linalg.norm(rotation @ (added * (rotation.T @ velocity)))
                                              / (mass * speed))
    if loads is not None:
        load_time, body, force = loads
        early = (body == p) & (load_time <= t1)
        row_values["fluid_impulse_before"] = float(np.linalg.norm(_integral(load_time[early], force[early]))
                                                   / (mass * speed))
    row_values["normal_velocity_before"] = float(first["normal_velocity_before"])
    row_values["rebound"] = float(-first["normal_velocity_after"] / first["normal_velocity_before"])
    return row_values


def analyse_batches(reference_root, variant_root):
    """Rows of every run complete in both batches with a first collision in the variant, by run name
    (two run directories: that pair, whatever their names). Raises BatchError when none is common
    or has a collision, or a pair's seeds differ."""
    reference = {os.path.basename(r.directory): r for r in load_runs([reference_root])[0]}
    variant = {os.path.basename(r.directory): r for r in load_runs([variant_root])[0]}
    if (len(reference) == len(variant) == 1 and os.path.exists(os.path.join(reference_root, "summary.json"))
            and os.path.exists(os.path.join(variant_root, "summary.json"))):
        variant = {next(iter(reference)): next(iter(variant.values()))}
    common = sorted(set(reference) & set(variant))
    if not common:
        raise BatchError(f"'{reference_root}' and '{variant_root}' have no complete run in common")
    rows = []
    for name in common:
        if reference[name].summary["seed"] != variant[name].summary["seed"]:
            raise BatchError(f"{name}: seeds {reference[name].summary['seed']} and "
                             f"{variant[name].summary['seed']} differ: not a paired comparison")
        if variant[name].summary["first_collision"] is not None:     # no contact: nothing to explain
            rows.append(analyse_run(variant[name], _max_speed(reference[name].directory)))
    if not rows:
        raise BatchError(f"'{variant_root}': no run with a first collision")
    return rows


def summary_line(label, rows):
    """One line: runs, overshoots, median and largest ratio, Spearman rho of the ratio with
    CORRELATED."""
    import numpy as np
    ratios = np.array([r["ratio"] for r in rows], float)
    parts = [f"{label}: {len(rows)} runs, {int(np.sum(ratios > OVERSHOOT))} above {OVERSHOOT}",
             f"median ratio {np.median(ratios):.3f}, largest {ratios.max():.3f}"]
    com = [r.get("com_speed_end", float("nan")) for r in rows]
    if len(rows) < 3:
        return ", ".join(parts + [f"centre-of-mass speed at the end / start speed {com[0]:.3g}"])
    for key in CORRELATED:
        values = [r.get(key, float("nan")) for r in rows]
        parts.append(f"rho({key}) {spearman(ratios, values):+.2f}")
    drive = [r.get("drive_N", float("nan")) for r in rows]
    parts.append(f"centre-of-mass speed at the end / start speed {np.nanmin(com):.3g} to {np.nanmax(com):.3g}, "
                 f"rho(drive_N) {spearman(com, drive):+.2f}")
    return ", ".join(parts)


def scatter_figure(groups, directory):
    """contact_drift_scatter.png, one colour per batch: the ratio against the potential-flow fluid
    momentum at the first contact and against the stabilisation drive, and the centre-of-mass
    speed at the end against the drive."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    figure, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for (label, rows), colour in zip(groups, ("C0", "C1", "C2", "C3")):
        def column(key):
            return np.array([r.get(key, np.nan) for r in rows], float)
        ratio, drive = column("ratio"), column("drive_N") * 1e9
        axes[0].scatter(column("added_mass_momentum"), ratio, s=14, color=colour, label=label)
        axes[1].scatter(drive, ratio, s=14, color=colour, label=label)
        axes[2].scatter(drive, column("com_speed_end"), s=14, color=colour, label=label)
    axes[0].set_xlabel("fluid momentum |M v| / (m |v|), faster particle, first contact")
    axes[1].set_xlabel("net stabilisation drive |D1 + D2| in contact (nN)")
    axes[2].set_xlabel("net stabilisation drive |D1 + D2| in contact (nN)")
    axes[0].set_ylabel("max particle speed / 'none' run's")
    axes[1].set_ylabel("max particle speed / 'none' run's")
    axes[2].set_ylabel("pair's centre-of-mass speed at the end / start speed")
    for axis in axes:
        axis.axhline(1.0, color="0.6", lw=0.8)
        axis.legend(fontsize=8)
    figure.suptitle("Speed after the first contact ('first_contact', resolved): what it follows")
    figure.tight_layout()
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, "contact_drift_scatter.png")
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("roots", nargs="*", help="pairs of batch roots: NONE_ROOT VARIANT_ROOT ...")
    parser.add_argument("--held", action="append", default=[], metavar="ROOT",
                        help="any batch: the drive on its agglomerated pairs held in contact (no reference)")
    parser.add_argument("--label", action="append", help="a name per pair (default: the variant's directory)")
    parser.add_argument("-o", "--out", help="CSV of every run")
    parser.add_argument("--figure", help="directory of the scatter figure")
    arguments = parser.parse_args(argv)
    try:
        for root in arguments.held:
            print(held_drive_line(root))
    except (BatchError, OSError, KeyError) as error:
        print(f"contact_drift: {error}", file=sys.stderr)
        return 1
    if not arguments.roots and arguments.held:
        return 0
    if not arguments.roots or len(arguments.roots) % 2:
        print("contact_drift: the roots come in pairs: NONE_ROOT VARIANT_ROOT", file=sys.stderr)
        return 1
    pairs = list(zip(arguments.roots[0::2], arguments.roots[1::2]))
    labels = arguments.label or [os.path.basename(os.path.normpath(v)) for _, v in pairs]
    if len(labels) != len(pairs):
        print(f"contact_drift: {len(labels)} --label for {len(pairs)} pairs of roots", file=sys.stderr)
        return 1
    groups = []
    try:
        for label, (reference, variant) in zip(labels, pairs):
            groups.append((label, analyse_batches(reference, variant)))
    except (BatchError, OSError, KeyError) as error:
        print(f"contact_drift: {error}", file=sys.stderr)
        return 1
    for label, rows in groups:
        print(summary_line(label, rows))
    if arguments.out:
        with open(arguments.out, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=COLUMNS, restval="")
            writer.writeheader()
            for _, rows in groups:
                for row in rows:
                    writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})
    if arguments.figure:
        print(f"figure: {scatter_figure(groups, arguments.figure)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
