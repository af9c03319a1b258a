"""agglo-figure8: the paper's Fig. 8 view of a run with a particle pair in the resolved fluid.

Draws, from one field snapshot of a run directory (docs/outputs.md), the fluid's velocity magnitude
on the plane through both particle centres, the exact sections of the two spheroids by that plane
(their outlines) and the in-plane velocity vectors; writes a PNG (matplotlib).

The plane contains the line between the centres (minimum image across the periodic box) and a
second direction: by default the pair's relative velocity (particles.h5), or a lab axis / vector
given with --second-direction; the part of it along the centre line is removed. In-plane axes:
s along the centre line (from particle 1 towards particle 2), t along the second direction,
both from the pair's midpoint.

The staggered velocity (u on x faces, v on y faces, w on z faces: docs/outputs.md, "Field
snapshots") is interpolated trilinearly from the points where each component lives, periodic in
all three directions, so no half-cell shift is made.

The pair's pose: the snapshot's own record of each body (/surfaces/body_<n>/centre, orientation,
semi_axes: written with the snapshot, exact at its time) when present, else the row of
particles.h5 nearest the snapshot's time; the relative velocity always from particles.h5 (nearest
row). Runs of prescribed bodies (no particles.h5) are drawn from the snapshot's poses through the
bodies given by --bodies, with a lab axis or a given second direction. Run it through the launcher tools/agglo-figure8 (it picks the repository's .venv).
"""
import argparse
import os
import re
import sys

import numpy as np

SNAPSHOT = re.compile(r"fields_([0-9]{10})\.h5")
# Where each velocity component lives, in cells from the box origin (MAC grid; index 0 of the
# stored array is the first value): u at (i+1, j+1/2, k+1/2), v at (i+1/2, j+1, k+1/2), w at
# (i+1/2, j+1/2, k+1) times (dx, dy, dz) for the 0-based index (i, j, k).
COMPONENT_OFFSETS = {"u": (1.0, 0.5, 0.5), "v": (0.5, 1.0, 0.5), "w": (0.5, 0.5, 1.0)}
LAB_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


class FigureError(Exception):
    """A run directory or a choice the figure cannot be drawn from (the message says why)."""


# ---------------------------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------------------------

def rotation_matrix(q):
    """R(q), body -> lab, for the unit quaternion q = (w, x, y, z) (src/particles/quaternion.f90)."""
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def semi_axes_of(radius, aspect_ratio):
    """(a, b) of the spheroid with volume-equivalent radius r and a/b = aspect ratio: a b^2 = r^3."""
    b = radius * aspect_ratio ** (-1.0 / 3.0)
    return aspect_ratio * b, b


def minimum_image(d, box):
    """The periodic image of the separation d closest to zero."""
    box = np.asarray(box, dtype=float)
    return d - box * np.round(np.asarray(d, dtype=float) / box)


class Plane:
    """The plane through both centres: origin (the pair's midpoint, not wrapped), unit vectors
    e1 (centre 1 -> centre 2) and e2, and where the centres lie in it (s = -+ distance / 2)."""

    def __init__(self, centre1, centre2, second, box):
        d = minimum_image(np.asarray(centre2, float) - np.asarray(centre1, float), box)
        distance = np.linalg.norm(d)
        if not distance > 0.0:
            raise FigureError("the two centres coincide: no plane through both")
        self.e1 = d / distance
        self.centre1 = np.asarray(centre1, dtype=float)
        self.centre2 = self.centre1 + d            # the image of centre 2 next to centre 1
        self.origin = self.centre1 + 0.5 * d
        self.distance = distance
        self.second_note = ""
        second = np.asarray(second, dtype=float)
        normal_part = second - np.dot(second, self.e1) * self.e1
        if not np.linalg.norm(normal_part) > 1.0e-3 * max(np.linalg.norm(second), 1.0e-300):
            # Along the centre line (a head-on approach of spheres): the lab axis most across it.
            axis = min(LAB_AXES, key=lambda name: abs(np.dot(LAB_AXES[name], self.e1)))
            second = np.array(LAB_AXES[axis])
            normal_part = second - np.dot(second, self.e1) * self.e1
            self.second_note = f"second direction along the centre line or unknown: lab {axis} used"
        self.e2 = normal_part / np.linalg.norm(normal_part)

    def points(self, s, t):
        """Lab-frame points (..., 3) of in-plane coordinates s, t (arrays of one shape)."""
        s = np.asarray(s, dtype=float)[..., None]
        t = np.asarray(t, dtype=float)[..., None]
        return self.origin + s * self.e1 + t * self.e2


def section_outline(plane, centre, orientation, semi_axes, samples=361):
    """The section of the spheroid (centre, orientation, (a, b)) by the plane, as (s, t) arrays of
    a closed curve; None when the plane misses it. The spheroid is (x - c)^T M (x - c) = 1 with
    M = R diag(1/a^2, 1/b^2, 1/b^2) R^T; on the plane x = o + s e1 + t e2 this is the conic
    z^T A z + 2 B . z + C = 0, z = (s, t), A_ij = e_i M e_j, B_i = e_i M (o - c), C = (o-c) M (o-c) - 1,
    an ellipse with centre z0 = -A^-1 B and (z - z0)^T A (z - z0) = B . A^-1 B - C."""
    a, b = semi_axes
    rotation = rotation_matrix(orientation)
    m = rotation @ np.diag([1.0 / a ** 2, 1.0 / b ** 2, 1.0 / b ** 2]) @ rotation.T
    basis = np.stack([plane.e1, plane.e2])          # (2, 3)
    p0 = plane.origin - np.asarray(centre, dtype=float)
    big_a = basis @ m @ basis.T
    big_b = basis @ m @ p0
    big_c = p0 @ m @ p0 - 1.0
    z0 = -np.linalg.solve(big_a, big_b)
    level = big_b @ np.linalg.solve(big_a, big_b) - big_c
    if not level > 0.0:
        return None
    eigenvalues, eigenvectors = np.linalg.eigh(big_a)
    angle = np.linspace(0.0, 2.0 * np.pi, samples)
    local = np.stack([np.sqrt(level / eigenvalues[0]) * np.cos(angle),
                      np.sqrt(level / eigenvalues[1]) * np.sin(angle)])
    z = z0[:, None] + eigenvectors @ local
    return z[0], z[1]


def inside_spheroid(points, centre, orientation, semi_axes, box):
    """Points (..., 3) inside the spheroid or one of its periodic images (nearest image)."""
    a, b = semi_axes
    d = minimum_image(points - np.asarray(centre, dtype=float), box)
    body = d @ rotation_matrix(orientation)          # R^T d, row by row
    return (body[..., 0] / a) ** 2 + (body[..., 1] / b) ** 2 + (body[..., 2] / b) ** 2 < 1.0


# ---------------------------------------------------------------------------------------------
# Fields
# ---------------------------------------------------------------------------------------------

def interpolate_staggered(field, offset, spacing, points):
    """Trilinear, periodic interpolation of one stored component (h5py order [k, j, i], x
    fastest) whose value of 0-based index (i, j, k) lives at ((i + ox) dx, (j + oy) dy, (k + oz) dz),
    at lab points (..., 3). Exact for a field linear in each coordinate between its points."""
    shape_xyz = np.array(field.shape[::-1])          # nx, ny, nz
    f = points / np.asarray(spacing, dtype=float) - np.asarray(offset, dtype=float)
    low = np.floor(f).astype(np.int64)
    weight = f - low
    result = np.zeros(points.shape[:-1])
    for corner in range(8):
        shift = np.array([(corner >> 0) & 1, (corner >> 1) & 1, (corner >> 2) & 1])
        index = np.mod(low + shift, shape_xyz)
        w = np.prod(np.where(shift == 1, weight, 1.0 - weight), axis=-1)
        result += w * field[index[..., 2], index[..., 1], index[..., 0]]
    return result


def sample_velocity(snapshot, points):
    """The fluid velocity (..., 3) at lab points from a snapshot dictionary (read_snapshot)."""
    return np.stack([interpolate_staggered(snapshot["fields"][name], COMPONENT_OFFSETS[name],
                                           snapshot["spacing"], points) for name in ("u", "v", "w")], axis=-1)


# ---------------------------------------------------------------------------------------------
# Run directory
# ---------------------------------------------------------------------------------------------

def list_snapshots(run):
    """(step, file name) of the complete snapshots in the run directory, by step."""
    try:
        names = os.listdir(run)
    except OSError as error:
        raise FigureError(f"cannot read the run directory {run}: {error.strerror}") from error
    found = sorted((int(m.group(1)), name) for name in names if (m := SNAPSHOT.fullmatch(name)))
    if not found:
        raise FigureError(f"{run} holds no field snapshot fields_<step>.h5: is it a resolved run with "
                          "&output field_interval (or at least its start and end snapshots)?")
    return found


def choose_snapshot(run, step=None, time=None):
    """The snapshot file of the given step, the one nearest the given time, or the latest."""
    import h5py
    found = list_snapshots(run)
    if step is not None:
        for number, name in found:
            if number == step:
                return os.path.join(run, name)
        raise FigureError(f"no snapshot of step {step} in {run}; steps: "
                          + " ".join(str(n) for n, _ in found))
    if time is not None:
        def snapshot_time(name):
            with h5py.File(os.path.join(run, name), "r") as handle:
                return float(handle["time"][()])
        return os.path.join(run, min(found, key=lambda item: abs(snapshot_time(item[1]) - time))[1])
    return os.path.join(run, found[-1][1])


def read_snapshot(path):
    """The velocity components, grid, time and step of a snapshot, and its bodies' poses if any."""
    import h5py
    with h5py.File(path, "r") as handle:
        for name in ("u", "v", "w"):
            if f"fields/{name}" not in handle:
                raise FigureError(f"{path} has no /fields/{name}")
        snapshot = {
            "path": path,
            "time": float(handle["time"][()]),
            "step": int(handle["step"][()]),
            "lengths": np.array(handle["grid/lengths"][()], dtype=float),
            "fields": {name: np.array(handle[f"fields/{name}"][()]) for name in ("u", "v", "w")},
            "bodies": [],
        }
        snapshot["spacing"] = snapshot["lengths"] / np.array(handle["grid/shape"][()], dtype=float)
        n = 1
        while f"surfaces/body_{n}/centre" in handle:
            group = handle[f"surfaces/body_{n}"]
            snapshot["bodies"].append({"centre": np.array(group["centre"][()]),
                                       "orientation": np.array(group["orientation"][()]),
                                       "semi_axes": tuple(np.array(group["semi_axes"][()]))})
            n += 1
    return snapshot


def read_pair(run, time):
    """The pair at the row of particles.h5 nearest time: centres, orientations, velocities,
    semi-axes, shape, and the row's time; None without particles.h5 (prescribed bodies)."""
    import h5py
    path = os.path.join(run, "particles.h5")
    if not os.path.exists(path):
        return None
    with h5py.File(path, "r") as handle:
        times = np.array(handle["time"][()])
        if times.size == 0:
            raise FigureError(f"{path} has no rows yet")
        row = int(np.argmin(np.abs(times - time)))
        pair = {"time": float(times[row]), "row": row, "bodies": []}
        semi_axes = semi_axes_of(float(handle["radius"][()]), float(handle["aspect_ratio"][()]))
        shape = handle["shape"][()]
        pair["shape"] = shape.decode() if isinstance(shape, bytes) else str(shape)
        for n in (1, 2):
            group = handle[f"particle{n}"]
            pair["bodies"].append({"centre": np.array(group["position"][row]),
                                   "orientation": np.array(group["quaternion"][row]),
                                   "velocity": np.array(group["velocity"][row]),
                                   "semi_axes": semi_axes})
    return pair


def second_direction_of(choice, pair):
    """The plane's second direction: 'relative_velocity', a lab axis x|y|z, or 'a,b,c'. Without a
    pair in particles.h5 the relative velocity is unknown: zero (the plane then takes a lab axis)."""
    if choice == "relative_velocity":
        if pair is None:
            return np.zeros(3)
        return pair["bodies"][1]["velocity"] - pair["bodies"][0]["velocity"]
    if choice in LAB_AXES:
        return np.array(LAB_AXES[choice])
    try:
        vector = np.array([float(x) for x in choice.split(",")])
    except ValueError:
        vector = np.array([])
    if vector.size != 3 or not np.linalg.norm(vector) > 0.0:
        raise FigureError(f"--second-direction '{choice}': give relative_velocity, x, y, z or three "
                          "numbers a,b,c (not all zero)")
    return vector


# ---------------------------------------------------------------------------------------------
# The figure
# ---------------------------------------------------------------------------------------------

def plane_view(run, step=None, time=None, second="relative_velocity", width=None, resolution=240,
               vectors=21, mask_bodies=False, chosen=(1, 2)):
    """Everything the figure shows, as arrays (the tests check them): the chosen snapshot, the
    plane, s and t axes (m), |u| and the in-plane components on the grid, the outlines.
    chosen: the two bodies (1-based) the plane goes through."""
    snapshot = read_snapshot(choose_snapshot(run, step, time))
    pair = read_pair(run, snapshot["time"])
    if len(set(chosen)) != 2 or min(chosen) < 1:
        raise FigureError(f"--bodies {chosen[0]},{chosen[1]}: two different body numbers from 1")
    if snapshot["bodies"]:
        if max(chosen) > len(snapshot["bodies"]):
            raise FigureError(f"--bodies {chosen[0]},{chosen[1]}: {os.path.basename(snapshot['path'])} "
                              f"has {len(snapshot['bodies'])} bodies")
        bodies = [snapshot["bodies"][n - 1] for n in chosen]
        pose_source = "snapshot"
    elif pair is None:
        raise FigureError(f"{run} has no particles.h5 and {os.path.basename(snapshot['path'])} no bodies' "
                          "poses (/surfaces): no particles to draw the plane through")
    elif max(chosen) > 2:
        raise FigureError(f"--bodies {chosen[0]},{chosen[1]}: particles.h5 holds a pair (bodies 1 and 2)")
    else:
        bodies = [pair["bodies"][n - 1] for n in chosen]
        pose_source = "particles.h5"
    if pair is not None and tuple(chosen) == (2, 1):
        pair = dict(pair, bodies=pair["bodies"][::-1])   # the relative velocity of the chosen order
    box = snapshot["lengths"]
    plane = Plane(bodies[0]["centre"], bodies[1]["centre"], second_direction_of(second, pair), box)
    extent = max(max(body["semi_axes"]) for body in bodies)
    if width is None:   # both bodies and about one body length of fluid around them
        width = min(plane.distance + 6.0 * extent, float(np.min(box)))
    half = 0.5 * width
    s = np.linspace(-half, half, resolution)
    s_grid, t_grid = np.meshgrid(s, s)
    velocity = sample_velocity(snapshot, plane.points(s_grid, t_grid))
    magnitude = np.linalg.norm(velocity, axis=-1)
    if mask_bodies:
        points = plane.points(s_grid, t_grid)
        inside = np.zeros(magnitude.shape, dtype=bool)
        for body in bodies:
            inside |= inside_spheroid(points, body["centre"], body["orientation"], body["semi_axes"], box)
        magnitude = np.ma.masked_where(inside, magnitude)
    s_arrows = np.linspace(-half, half, vectors)
    sa, ta = np.meshgrid(s_arrows, s_arrows)
    arrows = sample_velocity(snapshot, plane.points(sa, ta))
    centres = [plane.centre1, plane.centre2]
    outlines = [section_outline(plane, centre, body["orientation"], body["semi_axes"])
                for centre, body in zip(centres, bodies)]
    return {"snapshot": snapshot, "pair": pair, "plane": plane, "pose_source": pose_source,
            "s": s, "t": s, "magnitude": magnitude,
            "arrow_s": sa, "arrow_t": ta, "arrow_u": arrows @ plane.e1, "arrow_v": arrows @ plane.e2,
            "outlines": outlines, "width": width, "chosen": tuple(chosen)}


def draw(view, output, title=None, dpi=150):
    """Write the PNG of a plane_view."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    um, mm_s = 1.0e6, 1.0e3
    figure, axes = plt.subplots(figsize=(6.4, 5.4), constrained_layout=True)
    image = axes.pcolormesh(view["s"] * um, view["t"] * um, view["magnitude"] * mm_s, shading="auto",
                            cmap="viridis")
    figure.colorbar(image, ax=axes, label="|u| (mm/s)")
    axes.quiver(view["arrow_s"] * um, view["arrow_t"] * um, view["arrow_u"], view["arrow_v"],
                color="white", alpha=0.8, pivot="mid")
    for n, outline in enumerate(view["outlines"], start=1):
        if outline is not None:
            axes.plot(outline[0] * um, outline[1] * um, color="black", linewidth=1.5)
            axes.fill(outline[0] * um, outline[1] * um, color="lightgrey", alpha=0.35)
    axes.set_aspect("equal")
    axes.set_xlabel("s along the centre line (um)")
    axes.set_ylabel("t in the plane (um)")
    snapshot, pair = view["snapshot"], view["pair"]
    what = f"{pair['shape']} pair" if pair is not None else "bodies {} and {}".format(*view["chosen"])
    axes.set_title(title or f"{what}, t = {snapshot['time']:.4g} s (step {snapshot['step']})", fontsize=10)
    figure.savefig(output, dpi=dpi)
    plt.close(figure)


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="agglo-figure8",
        description="The paper's Fig. 8 view of a run: velocity magnitude on the plane through both "
                    "particle centres, the particle outlines and in-plane vectors (PNG).")
    parser.add_argument("run", help="run directory (fields_<step>.h5 and particles.h5)")
    choice = parser.add_mutually_exclusive_group()
    choice.add_argument("--step", type=int, help="the snapshot of this step (default: the latest)")
    choice.add_argument("--time", type=float, help="the snapshot nearest this time (s)")
    parser.add_argument("--second-direction", default="relative_velocity",
                        help="the plane's second direction: relative_velocity (default), x, y, z or a,b,c")
    parser.add_argument("--width", type=float, help="side of the square view (m); default: the pair "
                        "and about one body length around it")
    parser.add_argument("--resolution", type=int, default=240, help="samples along each side (240)")
    parser.add_argument("--vectors", type=int, default=21, help="arrows along each side (21)")
    parser.add_argument("--bodies", default="1,2",
                        help="the two bodies the plane goes through, i,j (default 1,2; prescribed bodies)")
    parser.add_argument("--mask-bodies", action="store_true", help="leave the bodies' interiors blank")
    parser.add_argument("--dpi", type=int, default=150, help="PNG resolution (150 dots per inch, 6.4 x 5.4 in)")
    parser.add_argument("-o", "--output", help="PNG to write (default RUN/figure8_<step>.png)")
    args = parser.parse_args(argv)
    if args.resolution < 2 or args.vectors < 2 or args.dpi < 10:
        parser.error("--resolution and --vectors must be at least 2, --dpi at least 10")
    if args.width is not None and not args.width > 0.0:
        parser.error("--width must be positive")
    if not re.fullmatch(r"[0-9]+,[0-9]+", args.bodies):
        parser.error("--bodies takes two body numbers i,j")
    chosen = tuple(int(n) for n in args.bodies.split(","))
    try:
        view = plane_view(args.run, args.step, args.time, args.second_direction, args.width,
                          args.resolution, args.vectors, args.mask_bodies, chosen)
        output = args.output or os.path.join(args.run, f"figure8_{view['snapshot']['step']:010d}.png")
        draw(view, output, dpi=args.dpi)
    except FigureError as error:
        print(f"agglo-figure8: {error}", file=sys.stderr)
        return 1
    snapshot, pair, plane = view["snapshot"], view["pair"], view["plane"]
    row = f", particles.h5 row at t = {pair['time']:.6g} s" if pair is not None else ", no particles.h5"
    print(f"snapshot {os.path.basename(snapshot['path'])} (t = {snapshot['time']:.6g} s); bodies "
          f"{chosen[0]} and {chosen[1]} from {view['pose_source']}{row}")
    if plane.second_note:
        print(plane.second_note)
    print(f"centre distance {plane.distance:.4g} m; |u| on the plane {np.min(view['magnitude']):.4g} .. "
          f"{np.max(view['magnitude']):.4g} m/s")
    print(f"figure: {output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
