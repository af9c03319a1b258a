"""quiescent_capture: why a quiescent pair agglomerates or rebounds, from its first collision.

For every run with a collision in the given batches: the curvature factor chi_eta of Eq. 14 at
the last particles.h5 sample before the first collision (orientations barely change in the
stats_interval before it), the normal approach speed before and the rebound speed after the
first collision (summary.json), and the outcome. Figure `capture` (PNG and PDF in OUT):
rebound speed against chi_eta per group, coloured by outcome, with the escape line of the
head-on energy balance (docs/studies/results-quiescent.md):

    mu v_after^2 / 2 = chi_eta W_1   ->   v_escape(chi_eta) = sqrt(2 chi_eta W_1 / mu),

where W_1 is the DLVO energy gained by equal spheres (chi_eta = 1) between infinity and the
detection floor, measured from the sphere batch itself: W_1 = mu (v_before^2 - v_0^2) / 2 (the
sphere approach is head-on and conservative until contact). Also writes capture.csv.

Usage: .venv/bin/python tools/quiescent_capture.py -o OUT --sphere SPHERE_ROOT ROOT [ROOT ...]
"""
import argparse
import csv
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from agglo_stats import BatchError, load_runs  # noqa: E402

COLOURS = {"agglomerated": "tab:blue", "rebounded": "tab:red"}


def first_collision_rows(root):
    """[(shape, run name, chi_eta, v_before, v_after, outcome, collisions)] of one batch."""
    complete, _skipped = load_runs([root])
    rows = []
    for run in complete:
        first = run.summary["first_collision"]
        if first is None:
            continue
        with h5py.File(os.path.join(run.directory, "particles.h5"), "r") as handle:
            time = handle["time"][:]
            chi = handle["pair/chi_eta"][:]
        before = np.nonzero(time <= first["time"])[0]
        rows.append((run.summary["shape"], os.path.basename(run.directory), float(chi[before[-1]]),
                     first["normal_velocity_before"], -first["normal_velocity_after"],
                     run.summary["outcome"], run.summary["collisions"]))
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("roots", nargs="+", help="batch roots (fluid 'none')")
    parser.add_argument("--sphere", required=True, help="sphere batch root that measures W_1")
    parser.add_argument("--speed", type=float, default=0.875e-3, help="initial relative speed, m/s")
    parser.add_argument("-o", "--out", required=True, help="output directory")
    arguments = parser.parse_args(argv)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    try:
        sphere_runs, _ = load_runs([arguments.sphere])
        groups = [(os.path.basename(os.path.normpath(root)), first_collision_rows(root))
                  for root in arguments.roots]
    except BatchError as error:
        print(f"quiescent_capture: {error}", file=sys.stderr)
        return 1
    # Reduced mass of two equal bodies m: m/2; the sphere's mass from its radius and density is
    # not in summary.json, so W_1 / mu is what is measured, which is all the escape line needs.
    before = [run.summary["first_collision"]["normal_velocity_before"] for run in sphere_runs
              if run.summary["first_collision"] is not None]
    if not before:
        print("quiescent_capture: the sphere batch has no collision to measure W_1", file=sys.stderr)
        return 1
    w1_over_mu = 0.5 * (float(np.mean(before)) ** 2 - arguments.speed ** 2)
    print(f"W_1 / mu = {w1_over_mu:.4e} m^2/s^2 from {len(before)} sphere runs "
          f"(spread of v_before {np.std(before):.2e} m/s)")
    os.makedirs(arguments.out, exist_ok=True)
    with open(os.path.join(arguments.out, "capture.csv"), "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(("batch", "shape", "run", "chi_eta", "v_before", "v_after", "outcome", "collisions",
                         "escapes_head_on"))
        for batch, rows in groups:
            for shape, name, chi, v_before, v_after, outcome, collisions in rows:
                escapes = 0.5 * v_after ** 2 > chi * w1_over_mu
                writer.writerow((batch, shape, name, f"{chi:.5g}", f"{v_before:.6g}", f"{v_after:.6g}", outcome,
                                 collisions, int(escapes)))
    figure, axes = plt.subplots(1, len(groups), figsize=(4.2 * len(groups), 3.6), squeeze=False, sharey=True)
    for axis, (batch, rows) in zip(axes[0], groups):
        chis = [row[2] for row in rows]
        for outcome, colour in COLOURS.items():
            points = [(row[2], row[4] * 1e3) for row in rows if row[5] == outcome]
            if points:
                axis.scatter(*zip(*points), s=12, color=colour, label=f"{outcome} ({len(points)})")
        if chis:
            line = np.linspace(0.0, max(max(chis) * 1.05, 2.0), 200)
            axis.plot(line, np.sqrt(2.0 * line * w1_over_mu) * 1e3, "k--", lw=1,
                      label="head-on escape speed")
        axis.set_title(batch)
        axis.set_xlabel(r"$\chi_\eta$ at first contact (Eq. 14)")
        axis.legend(fontsize=7)
    axes[0][0].set_ylabel("rebound speed after first collision (mm/s)")
    figure.tight_layout()
    for extension in ("png", "pdf"):
        figure.savefig(os.path.join(arguments.out, f"capture.{extension}"), dpi=110)
    print(f"wrote capture.csv and capture.png/.pdf in {arguments.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
