"""agglo-figure8: the paper's Fig. 8 view of a run with a particle pair in the resolved fluid.

Draws, from one field snapshot of a run directory (docs/outputs.md), the fluid's velocity magnitude
on a plane through the pair, the exact sections of the two spheroids by that plane (their
outlines), the in-plane velocity vectors and, near contact, the closest points; the title gives the
gap. Writes a PNG (matplotlib).

Near contact (gap below the smallest semi-axis; --plane contact) the plane goes through both
closest points and centre 1: s along the contact normal, t towards the centre, from the closest
points' midpoint. Otherwise (--plane centres) it contains the line between the centres (minimum
image across the periodic box) and a second direction: by default the pair's relative velocity
(particles.h5), or a lab axis / vector given with --second-direction; the part of it along the
centre line is removed. In-plane axes: s along the centre line (from particle 1 towards
particle 2), t along the second direction, both from the pair's midpoint. The closest points and
gap are particles.h5's when its row is at the snapshot's time, else solved from the poses
(closest_points).

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
        self.kind = "centres"
        self.through = "both centres"

    @classmethod
    def through_contact(cls, centre1, centre2, point1, point2, normal, second, box):
        """The plane through both closest points and a centre: origin the closest points' midpoint,
        e1 the contact normal (body 1 towards body 2; point 2 = point 1 + gap e1), e2 towards
        centre 1 across the normal (centre 2 when centre 1 is on the normal line, e.g. spheres;
        the second direction when both are, as for a sphere pair). centre2, point1 and point2 are
        the images next to centre1 (minimum image)."""
        plane = cls(centre1, centre2, second, box)       # centres, distance, fallback direction
        point1 = np.asarray(point1, dtype=float)
        point2 = np.asarray(point2, dtype=float)
        e1 = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
        plane.origin = 0.5 * (point1 + point2)
        plane.e1 = e1
        plane.kind = "contact"
        plane.second_note = ""
        for name, centre in (("centre 1", plane.centre1), ("centre 2", plane.centre2)):
            r = centre - plane.origin
            across = r - np.dot(r, e1) * e1
            if np.linalg.norm(across) > 1.0e-6 * max(np.linalg.norm(r), 1.0e-300):
                plane.e2 = across / np.linalg.norm(across)
                plane.through = name
                return plane
        second = np.asarray(second, dtype=float)
        across = second - np.dot(second, e1) * e1
        if not np.linalg.norm(across) > 1.0e-3 * max(np.linalg.norm(second), 1.0e-300):
            axis = min(LAB_AXES, key=lambda name: abs(np.dot(LAB_AXES[name], e1)))
            across = np.array(LAB_AXES[axis]) - np.dot(LAB_AXES[axis], e1) * e1
            plane.second_note = f"both centres on the contact normal, second direction along it or unknown: lab {axis} used"
        plane.e2 = across / np.linalg.norm(across)
        plane.through = "both centres"
        return plane

    def coordinates(self, point):
        """In-plane coordinates (s, t) of a lab point, and its distance from the plane."""
        r = np.asarray(point, dtype=float) - self.origin
        return float(r @ self.e1), float(r @ self.e2), float(r @ np.cross(self.e1, self.e2))

    def points(self, s, t):
        """Lab-frame points (..., 3) of in-plane coordinates s, t (arrays of one shape)."""
        s = np.asarray(s, dtype=float)[..., None]
        t = np.asarray(t, dtype=float)[..., None]
        return self.origin + s * self.e1 + t * self.e2


def support_matrix(orientation, semi_axes):
    """Q = R diag(a^2, b^2, b^2) R^T: the spheroid's support function about its centre is
    h(n) = sqrt(n^T Q n) and its support point in the direction n is c + Q n / h(n)."""
    a, b = semi_axes
    rotation = rotation_matrix(orientation)
    return rotation @ np.diag([a * a, b * b, b * b]) @ rotation.T


def closest_points(centre1, orientation1, semi_axes1, centre2, orientation2, semi_axes2,
                   directions=4000, iterations=60):
    """The closest points of two spheroids (centre 2 given as the image next to centre 1).

    Separating-axis form of the minimum distance of two convex bodies: the signed gap is the
    maximum over unit vectors n of F(n) = n . (c2 - c1) - h1(n) - h2(n) (h the support functions,
    support_matrix; h2(-n) = h2(n) by symmetry), the closest points are the support points
    x1 = c1 + Q1 n / h1 and x2 = c2 - Q2 n / h2, and at the maximum x2 - x1 = gap n: n is the
    common normal, from body 1 towards body 2. For separated bodies F is the dual of the convex
    distance problem (a local maximum on the sphere with F > 0 is the global one); for overlapping
    ones the maximum is minus the depth of the shortest separating translation. The maximum is
    found from the best of a Fibonacci set of directions by Newton's method on the sphere.
    Returns a dictionary gap (m), point1, point2, normal, residual (|x2 - x1 - gap n|, m)."""
    c1 = np.asarray(centre1, dtype=float)
    d = np.asarray(centre2, dtype=float) - c1
    q1 = support_matrix(orientation1, semi_axes1)
    q2 = support_matrix(orientation2, semi_axes2)

    def value(n):    # F for one or many directions (..., 3)
        return (n @ d - np.sqrt(np.einsum("...i,ij,...j->...", n, q1, n))
                - np.sqrt(np.einsum("...i,ij,...j->...", n, q2, n)))

    k = np.arange(directions) + 0.5
    polar = np.arccos(1.0 - 2.0 * k / directions)
    azimuth = np.pi * (1.0 + 5.0 ** 0.5) * k
    candidates = np.stack([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth),
                           np.cos(polar)], axis=-1)
    if np.linalg.norm(d) > 0.0:
        candidates = np.vstack([candidates, d / np.linalg.norm(d)])
    n = candidates[int(np.argmax(value(candidates)))]
    scale = np.linalg.norm(d) + max(semi_axes1) + max(semi_axes2)
    for _ in range(iterations):
        h1, h2 = np.sqrt(n @ q1 @ n), np.sqrt(n @ q2 @ n)
        y1, y2 = q1 @ n / h1, q2 @ n / h2
        f = n @ d - h1 - h2
        gradient = d - y1 - y2 - f * n            # the tangential part (F is homogeneous of degree 1)
        if np.linalg.norm(gradient) <= 1.0e-15 * scale:
            break
        helper = np.eye(3)[int(np.argmin(np.abs(n)))]
        ea = np.cross(n, helper)
        ea /= np.linalg.norm(ea)
        basis = np.stack([ea, np.cross(n, ea)], axis=1)        # (3, 2), tangent to the sphere at n
        hessian = -(q1 / h1 - np.outer(y1, y1) / h1) - (q2 / h2 - np.outer(y2, y2) / h2)
        reduced = basis.T @ hessian @ basis - f * np.eye(2)  # the Hessian of F on the sphere
        slope = basis.T @ gradient
        if np.all(np.linalg.eigvalsh(reduced) < 0.0):
            step = -np.linalg.solve(reduced, slope)
        else:                                                # not concave here: steepest ascent
            step = slope / max(np.linalg.norm(slope) / 1.0e-2, 1.0)
        for _ in range(60):                                  # backtrack until F does not decrease
            trial = n + basis @ step
            trial /= np.linalg.norm(trial)
            if value(trial) >= f:
                break
            step = 0.5 * step
        else:
            break
        n = trial
    h1, h2 = np.sqrt(n @ q1 @ n), np.sqrt(n @ q2 @ n)
    point1, point2 = c1 + q1 @ n / h1, c1 + d - q2 @ n / h2
    gap = float(n @ d - h1 - h2)
    return {"gap": gap, "point1": point1, "point2": point2, "normal": n,
            "residual": float(np.linalg.norm(point2 - point1 - gap * n))}


def surface_normal(point, centre, orientation, semi_axes):
    """The outward unit normal of the spheroid at (or nearest) the surface point: M (x - c)."""
    a, b = semi_axes
    rotation = rotation_matrix(orientation)
    m = rotation @ np.diag([1.0 / a ** 2, 1.0 / b ** 2, 1.0 / b ** 2]) @ rotation.T
    g = m @ (np.asarray(point, dtype=float) - np.asarray(centre, dtype=float))
    return g / np.linalg.norm(g)


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
        if all(f"pair/{name}" in handle for name in ("gap", "closest_point1", "closest_point2")):
            pair["contact"] = {"gap": float(handle["pair/gap"][row]),
                               "point1": np.array(handle["pair/closest_point1"][row]),
                               "point2": np.array(handle["pair/closest_point2"][row])}
    return pair


def contact_of(bodies, centres, pair, snapshot, chosen, box):
    """The closest points, gap and contact normal of the drawn bodies at the snapshot's poses
    (centres: the drawn images): particles.h5's /pair/closest_point1, closest_point2 and gap when
    its row is at the snapshot's time (each point kept at its offset from its body's centre in that
    row, so the images match), else computed from the poses (closest_points). Also says which."""
    stored = pair.get("contact") if pair is not None else None
    same_time = pair is not None and abs(pair["time"] - snapshot["time"]) <= 1.0e-9 * max(abs(snapshot["time"]), 1.0e-12)
    if stored is not None and same_time and set(chosen) == {1, 2}:
        row_centres = [pair["bodies"][0]["centre"], pair["bodies"][1]["centre"]]
        if tuple(chosen) == (2, 1):
            row_centres = row_centres[::-1]   # pair was reordered to the chosen order
        points = [stored["point1"], stored["point2"]] if tuple(chosen) == (1, 2) else [stored["point2"], stored["point1"]]
        placed = [centre + minimum_image(point - row, box) for centre, point, row in zip(centres, points, row_centres)]
        normal = surface_normal(placed[0], centres[0], bodies[0]["orientation"], bodies[0]["semi_axes"])
        return {"gap": stored["gap"], "point1": placed[0], "point2": placed[1], "normal": normal,
                "source": f"particles.h5 row at t = {pair['time']:.6g} s"}
    found = closest_points(centres[0], bodies[0]["orientation"], bodies[0]["semi_axes"],
                           centres[1], bodies[1]["orientation"], bodies[1]["semi_axes"])
    found["source"] = "computed from the poses"
    return found


def gap_text(gap):
    """The gap for the title, in nm below 1 um, else in um."""
    if abs(gap) < 1.0e-6:
        text = f"gap {gap * 1.0e9:.3g} nm"
    else:
        text = f"gap {gap * 1.0e6:.3g} um"
    return text + (" (overlap)" if gap < 0.0 else "")


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

PLANES = ("auto", "contact", "centres")


def plane_view(run, step=None, time=None, second="relative_velocity", width=None, resolution=240,
               vectors=21, mask_bodies=False, chosen=(1, 2), plane_choice="auto"):
    """Everything the figure shows, as arrays (the tests check them): the chosen snapshot, the
    plane, s and t axes (m), |u| and the in-plane components on the grid, the outlines, the
    contact (closest points, gap, normal) and the closest points' in-plane coordinates when the
    plane holds them. chosen: the two bodies (1-based) drawn. plane_choice: 'centres' (through
    both centres), 'contact' (through both closest points and a centre), or 'auto': 'contact' when
    the gap is below the smallest semi-axis of the two bodies (in contact or near it)."""
    if plane_choice not in PLANES:
        raise FigureError(f"--plane {plane_choice}: give one of {', '.join(PLANES)}")
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
    direction = second_direction_of(second, pair)
    plane = Plane(bodies[0]["centre"], bodies[1]["centre"], direction, box)
    contact = contact_of(bodies, [plane.centre1, plane.centre2], pair, snapshot, chosen, box)
    near = min(min(body["semi_axes"]) for body in bodies)
    if plane_choice == "contact" or (plane_choice == "auto" and contact["gap"] < near):
        plane = Plane.through_contact(plane.centre1, plane.centre2, contact["point1"], contact["point2"],
                                      contact["normal"], direction, box)
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
    markers = None
    if plane.kind == "contact":
        markers = [plane.coordinates(contact["point1"])[:2], plane.coordinates(contact["point2"])[:2]]
    return {"snapshot": snapshot, "pair": pair, "plane": plane, "pose_source": pose_source,
            "contact": contact, "markers": markers, "s": s, "t": s, "magnitude": magnitude,
            "arrow_s": sa, "arrow_t": ta, "arrow_u": arrows @ plane.e1, "arrow_v": arrows @ plane.e2,
            "outlines": outlines, "width": width, "chosen": tuple(chosen)}


def draw(view, output, title=None, dpi=150):
    """Write the PNG of a plane_view."""
    import matplotlib.pyplot as plt
    figure = render(view, title)
    figure.savefig(output, dpi=dpi)
    plt.close(figure)


def render(view, title=None):
    """The matplotlib figure of a plane_view (its one axes holds the picture)."""
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
    if view["markers"] is not None:    # the closest points: a gap of nm is far below a pixel
        for (s, t), marker, label in zip(view["markers"], ("o", "x"), ("closest point 1", "closest point 2")):
            axes.plot(s * um, t * um, marker=marker, color="red", markersize=9, markerfacecolor="none",
                      markeredgewidth=1.5, linestyle="none", label=label)
        axes.legend(loc="upper right", fontsize=7, framealpha=0.7)
    axes.set_aspect("equal")
    plane = view["plane"]
    if plane.kind == "contact":
        axes.set_xlabel("s along the contact normal (um)")
        axes.set_ylabel(f"t towards {plane.through} (um)" if plane.through != "both centres" else "t in the plane (um)")
    else:
        axes.set_xlabel("s along the centre line (um)")
        axes.set_ylabel("t in the plane (um)")
    snapshot, pair = view["snapshot"], view["pair"]
    what = f"{pair['shape']} pair" if pair is not None else "bodies {} and {}".format(*view["chosen"])
    through = "plane through the closest points" if plane.kind == "contact" else "plane through the centres"
    axes.set_title(title or f"{what}, t = {snapshot['time']:.4g} s (step {snapshot['step']}), "
                            f"{gap_text(view['contact']['gap'])}\n{through}", fontsize=10)
    return figure


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
    parser.add_argument("--plane", choices=PLANES, default="auto",
                        help="centres: through both centres; contact: through both closest points and a "
                             "centre; auto (default): contact when the gap is below the smallest semi-axis")
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
                          args.resolution, args.vectors, args.mask_bodies, chosen, args.plane)
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
    contact = view["contact"]
    print(f"{gap_text(contact['gap'])} ({contact['gap']:.6g} m), closest points {contact['source']}; plane through "
          + ("the closest points and " + plane.through if plane.kind == "contact" else "both centres"))
    print(f"centre distance {plane.distance:.4g} m; |u| on the plane {np.min(view['magnitude']):.4g} .. "
          f"{np.max(view['magnitude']):.4g} m/s")
    print(f"figure: {output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
