"""tools/agglo-figure8 on synthetic run directories (a snapshot with a known staggered field and a
known pair in particles.h5, written here in the layout of docs/outputs.md):
- the sampled velocity on the plane equals the analytic field: each component linear in its own
  staggered coordinate and one other, so trilinear interpolation from the points where it lives
  is exact and a half-cell error in the staggering (G dx / 2) shows; the pair across the periodic boundary (minimum
  image); uniform flow gives the uniform magnitude;
- the plane contains both centres and the relative velocity; a head-on pair falls back to a lab axis;
- the outlines lie on the spheroids (their exact sections by the plane); poses come from the
  snapshot's bodies when it has them;
- the command writes a PNG (the latest snapshot by default, or --step / --time), and says why it
  cannot draw a run without particles.h5;
- the closest points: the numerical solve against contacts constructed exactly (a point of body 1
  and its normal, body 2 placed so that its support point in the opposite direction lies the gap
  away: for convex bodies that pair is the closest one), spheres, an overlap;
- a pair in contact (needles 1 nm apart, the contact far from the centres' plane) is drawn on the
  plane through both closest points and centre 1 (from particles.h5's closest points at the
  snapshot's time, or computed from the poses), with both closest points marked and the gap in the
  title; a distant pair keeps the plane through the centres.
"""
import subprocess
import sys

import h5py
import numpy as np
import pytest

from conftest import REPO
import agglo_figure8 as fig

TOOL = REPO / "tools" / "agglo-figure8"
BOX = np.array([1.0e-3, 0.8e-3, 1.2e-3])
SHAPE = (20, 16, 24)                      # nx, ny, nz
U0, V0, W0 = 1.0e-3, -2.0e-3, 0.5e-3      # m/s
G = 4.0                                   # 1/s, gradients of the linear parts


def position(index, offset, axis):
    """Where the 0-based index of a component with this offset (cells) lies along axis."""
    return (index + offset) * BOX[axis] / SHAPE[axis]


def linear_field():
    """u = U0 + G (x - lx/2) + G (z - lz/2), v = V0 + G (y - ly/2) + G (x - lx/2),
    w = W0 + G (z - lz/2) + G (y - ly/2) at their MAC points, stored [k, j, i] as the code writes
    them: each component varies along its own staggered direction, so a wrong offset shows."""
    nx, ny, nz = SHAPE
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    u = U0 + G * (position(i, 1.0, 0) - BOX[0] / 2) + G * (position(k, 0.5, 2) - BOX[2] / 2)
    v = V0 + G * (position(j, 1.0, 1) - BOX[1] / 2) + G * (position(i, 0.5, 0) - BOX[0] / 2)
    w = W0 + G * (position(k, 1.0, 2) - BOX[2] / 2) + G * (position(j, 0.5, 1) - BOX[1] / 2)
    return u, v, w


def analytic(points):
    x, y, z = (points[..., a] - BOX[a] / 2 for a in range(3))
    return np.stack([U0 + G * (x + z), V0 + G * (y + x), W0 + G * (z + y)], axis=-1)


def write_snapshot(run, step, time, fields, bodies=()):
    with h5py.File(run / f"fields_{step:010d}.h5", "w") as handle:
        for name, values in zip(("u", "v", "w"), fields):
            handle[f"fields/{name}"] = values
        handle["fields/pressure"] = np.zeros_like(fields[0])
        handle["time"] = time
        handle["step"] = np.int64(step)
        handle["grid/shape"] = np.array(SHAPE, dtype=np.int32)
        handle["grid/lengths"] = BOX
        handle["grid/spacing"] = BOX / np.array(SHAPE)
        handle["field_names"] = np.bytes_("u v w pressure")
        handle["field_locations"] = np.bytes_("x_face y_face z_face centre")
        for n, body in enumerate(bodies, start=1):
            handle[f"surfaces/body_{n}/centre"] = body["centre"]
            handle[f"surfaces/body_{n}/orientation"] = body["orientation"]
            handle[f"surfaces/body_{n}/semi_axes"] = np.array(body["semi_axes"])


def write_particles(run, times, centres, quaternions, velocities, radius=50.0e-6, aspect_ratio=0.2,
                    shape="disk", contact=None):
    """particles.h5 with the pair at rest in every row; contact = (gap, point1, point2) adds the
    /pair datasets (the same in every row)."""
    with h5py.File(run / "particles.h5", "w") as handle:
        handle["time"] = np.asarray(times, dtype=float)
        rows = len(times)
        for n in (0, 1):
            handle[f"particle{n + 1}/position"] = np.tile(centres[n], (rows, 1))
            handle[f"particle{n + 1}/quaternion"] = np.tile(quaternions[n], (rows, 1))
            handle[f"particle{n + 1}/velocity"] = np.tile(velocities[n], (rows, 1))
        if contact is not None:
            handle["pair/gap"] = np.full(rows, contact[0])
            handle["pair/closest_point1"] = np.tile(contact[1], (rows, 1))
            handle["pair/closest_point2"] = np.tile(contact[2], (rows, 1))
        handle["radius"] = radius
        handle["aspect_ratio"] = aspect_ratio
        handle["shape"] = np.bytes_(shape)
        handle["name"] = np.bytes_("synthetic")


def unit(q):
    q = np.asarray(q, dtype=float)
    return q / np.linalg.norm(q)


CENTRES = [np.array([0.40e-3, 0.35e-3, 0.60e-3]), np.array([0.55e-3, 0.42e-3, 0.62e-3])]
QUATERNIONS = [unit([0.9, 0.1, -0.3, 0.2]), unit([0.5, 0.5, 0.1, -0.4])]
VELOCITIES = [np.array([1.0e-3, 0.0, 0.0]), np.array([-1.0e-3, 0.5e-3, 0.3e-3])]


@pytest.fixture
def run(tmp_path):
    directory = tmp_path / "run with spaces"
    directory.mkdir()
    fields = linear_field()
    write_snapshot(directory, 0, 0.0, fields)
    write_snapshot(directory, 40, 2.0e-4, fields)
    write_particles(directory, [0.0, 1.0e-4, 2.0e-4], CENTRES, QUATERNIONS, VELOCITIES)
    return directory


def test_sampled_velocity_is_the_staggered_field(run):
    view = fig.plane_view(str(run), width=0.5e-3, resolution=41)
    plane = view["plane"]
    s_grid, t_grid = np.meshgrid(view["s"], view["t"])
    exact = np.linalg.norm(analytic(plane.points(s_grid, t_grid)), axis=-1)
    # The view stays clear of the periodic seams of the linear parts (where the field jumps).
    assert np.max(np.abs(view["magnitude"] - exact)) <= 1.0e-12 * np.max(exact)
    arrows = analytic(plane.points(view["arrow_s"], view["arrow_t"]))
    assert np.allclose(view["arrow_u"], arrows @ plane.e1, rtol=0, atol=1.0e-12 * np.max(exact))
    assert np.allclose(view["arrow_v"], arrows @ plane.e2, rtol=0, atol=1.0e-12 * np.max(exact))
    # A half-cell shift of one component (taking it at the cell centre) errs by G dx / 2,
    # 1e-4 m/s here: 1e8 times the tolerance.


def test_uniform_flow_and_pair_across_the_periodic_boundary(tmp_path):
    run = tmp_path / "wrapped"
    run.mkdir()
    nx, ny, nz = SHAPE
    fields = [np.full((nz, ny, nx), value) for value in (U0, V0, W0)]
    write_snapshot(run, 7, 1.0e-4, fields)
    centres = [np.array([0.97e-3, 0.40e-3, 1.15e-3]), np.array([0.05e-3, 0.42e-3, 0.03e-3])]
    write_particles(run, [1.0e-4], centres, QUATERNIONS, VELOCITIES)
    view = fig.plane_view(str(run), resolution=30, plane_choice="centres")   # the disks overlap
    plane = view["plane"]
    separation = np.array([0.08e-3, 0.02e-3, 0.08e-3])           # the minimum image
    assert plane.distance == pytest.approx(np.linalg.norm(separation), rel=1e-12)
    assert np.allclose(plane.e1, separation / np.linalg.norm(separation), rtol=0, atol=1e-12)
    assert np.max(np.abs(view["magnitude"] - np.linalg.norm([U0, V0, W0]))) <= 1e-15


def test_plane_holds_both_centres_and_the_relative_velocity(run):
    plane = fig.plane_view(str(run), resolution=5)["plane"]
    relative = VELOCITIES[1] - VELOCITIES[0]
    normal = np.cross(plane.e1, plane.e2)
    assert abs(np.dot(normal, relative)) <= 1e-12 * np.linalg.norm(relative)
    assert abs(np.dot(normal, CENTRES[1] - plane.origin)) <= 1e-15
    assert abs(np.dot(normal, CENTRES[0] - plane.origin)) <= 1e-15
    assert abs(np.dot(plane.e1, plane.e2)) <= 1e-15
    head_on = fig.Plane(CENTRES[0], CENTRES[1], CENTRES[1] - CENTRES[0], BOX)
    assert head_on.second_note and abs(np.dot(head_on.e1, head_on.e2)) <= 1e-15


def test_outlines_are_the_spheroid_sections(run):
    view = fig.plane_view(str(run), resolution=5)
    plane = view["plane"]
    a, b = fig.semi_axes_of(50.0e-6, 0.2)
    assert a * b * b == pytest.approx((50.0e-6) ** 3, rel=1e-12) and a / b == pytest.approx(0.2, rel=1e-12)
    for centre, q, outline in zip([plane.centre1, plane.centre2], QUATERNIONS, view["outlines"]):
        assert outline is not None
        points = plane.points(outline[0], outline[1]) - centre
        body = points @ fig.rotation_matrix(q)
        quadric = (body[:, 0] / a) ** 2 + (body[:, 1] / b) ** 2 + (body[:, 2] / b) ** 2
        assert np.max(np.abs(quadric - 1.0)) <= 1e-10
    # A plane that misses a spheroid has no outline.
    far = fig.Plane(CENTRES[0], CENTRES[1], [0.0, 0.0, 1.0], BOX)
    far.origin = far.origin + 10 * a * np.cross(far.e1, far.e2)
    assert fig.section_outline(far, CENTRES[0], QUATERNIONS[0], (a, b)) is None


def test_poses_from_the_snapshot_bodies(run):
    moved = [{"centre": CENTRES[0] + [0.0, 0.05e-3, 0.0], "orientation": QUATERNIONS[0], "semi_axes": (20e-6, 60e-6)},
             {"centre": CENTRES[1], "orientation": QUATERNIONS[1], "semi_axes": (20e-6, 60e-6)}]
    write_snapshot(run, 60, 3.0e-4, linear_field(), bodies=moved)
    view = fig.plane_view(str(run), resolution=5)
    assert view["pose_source"] == "snapshot" and view["snapshot"]["step"] == 60
    assert np.allclose(view["plane"].centre1, moved[0]["centre"], rtol=0, atol=1e-18)
    assert view["pair"]["time"] == pytest.approx(2.0e-4)      # the nearest particles.h5 row


def test_prescribed_bodies_without_particles_h5(tmp_path):
    run = tmp_path / "prescribed"
    run.mkdir()
    three = [{"centre": c, "orientation": q, "semi_axes": (80e-6, 40e-6)}
             for c, q in zip([CENTRES[0], np.array([0.7e-3, 0.5e-3, 0.9e-3]), CENTRES[1]], QUATERNIONS * 2)]
    write_snapshot(run, 12, 5.0e-5, linear_field(), bodies=three)
    view = fig.plane_view(str(run), resolution=5, chosen=(1, 3), plane_choice="centres")
    assert view["pair"] is None and view["pose_source"] == "snapshot"
    assert np.allclose(view["plane"].centre2, CENTRES[1], rtol=0, atol=1e-18)
    assert "lab" in view["plane"].second_note                  # no relative velocity: a lab axis
    out = subprocess.run([str(TOOL), str(run), "--bodies", "1,3", "-o", str(run / "b.png")],
                         capture_output=True, text=True)
    assert out.returncode == 0 and (run / "b.png").read_bytes()[:4] == b"\x89PNG", out.stderr
    wrong = subprocess.run([str(TOOL), str(run), "--bodies", "1,4"], capture_output=True, text=True)
    assert wrong.returncode == 1 and "has 3 bodies" in wrong.stderr


def test_command_writes_the_png(run, tmp_path):
    latest = subprocess.run([str(TOOL), str(run)], capture_output=True, text=True)
    assert latest.returncode == 0, latest.stderr
    png = run / "figure8_0000000040.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10000
    assert f"figure: {png}" in latest.stdout
    chosen = tmp_path / "chosen.png"
    by_time = subprocess.run([sys.executable, str(REPO / "tools" / "agglo_figure8.py"), str(run), "--time", "1e-5",
                              "--second-direction", "0,0,1", "--mask-bodies", "-o", str(chosen)],
                             capture_output=True, text=True)
    assert by_time.returncode == 0, by_time.stderr
    assert "fields_0000000000.h5" in by_time.stdout and chosen.read_bytes()[:4] == b"\x89PNG"


def test_refusals(run, tmp_path):
    (run / "particles.h5").unlink()
    missing = subprocess.run([str(TOOL), str(run)], capture_output=True, text=True)
    assert missing.returncode == 1 and "no particles.h5 and" in missing.stderr
    empty = tmp_path / "empty"
    empty.mkdir()
    none = subprocess.run([str(TOOL), str(empty)], capture_output=True, text=True)
    assert none.returncode == 1 and "no field snapshot" in none.stderr
    step = subprocess.run([str(TOOL), str(run), "--step", "5"], capture_output=True, text=True)
    assert step.returncode == 1 and "no snapshot of step 5" in step.stderr and "0 40" in step.stderr
    bad = subprocess.run([str(TOOL), str(run), "--second-direction", "0,0"], capture_output=True, text=True)
    assert bad.returncode != 0


# ---------------------------------------------------------------------------------------------
# Closest points and the plane through the contact
# ---------------------------------------------------------------------------------------------

NEEDLE = fig.semi_axes_of(50.0e-6, 5.0)      # (a, b) = (146 um, 29.2 um), the default deck's needles


def constructed_contact(centre1, q1, semi1, theta, phi, q2, semi2, gap):
    """A pair whose closest points are known exactly: p1 on body 1 at the parametric angles
    (theta from the symmetry axis, phi around it), n body 1's outward normal there, p2 = p1 + gap n,
    and body 2 (orientation q2) centred so that its support point in the direction -n is p2. Body 1
    lies in n . (x - p1) <= 0, body 2 in n . (x - p2) >= 0, so for gap > 0 no two points are nearer
    than the gap, and p1, p2 are that near. Returns p1, p2, n, centre 2."""
    a, b = semi1
    local = np.array([a * np.cos(theta), b * np.sin(theta) * np.cos(phi), b * np.sin(theta) * np.sin(phi)])
    rotation = fig.rotation_matrix(q1)
    p1 = np.asarray(centre1, dtype=float) + rotation @ local
    n = rotation @ (local / np.array([a * a, b * b, b * b]))
    n /= np.linalg.norm(n)
    p2 = p1 + gap * n
    q = fig.support_matrix(q2, semi2)
    return p1, p2, n, p2 + q @ n / np.sqrt(n @ q @ n)


def test_closest_points_of_constructed_contacts():
    rng = np.random.default_rng(8)
    centre1 = np.array([0.5e-3, 0.4e-3, 0.6e-3])
    for case in range(40):
        q1, q2 = unit(rng.normal(size=4)), unit(rng.normal(size=4))
        semi1 = NEEDLE if case % 2 == 0 else fig.semi_axes_of(50.0e-6, 0.2)     # needles, disks
        semi2 = NEEDLE if case % 4 < 2 else fig.semi_axes_of(50.0e-6, 0.2)
        gap = [1.0e-9, 5.0e-8, 2.0e-6, 4.0e-5][case % 4]
        theta, phi = np.arccos(rng.uniform(-1.0, 1.0)), rng.uniform(-np.pi, np.pi)
        p1, p2, n, centre2 = constructed_contact(centre1, q1, semi1, theta, phi, q2, semi2, gap)
        found = fig.closest_points(centre1, q1, semi1, centre2, q2, semi2)
        # The gap is stationary in the direction: it is found to round-off of the centre distance
        # (3e-4 m x 1e-16); the points move with the direction, to 1e-6 of the gap or 1e-15 m.
        assert found["gap"] == pytest.approx(gap, rel=1e-6, abs=1e-18), case
        assert np.linalg.norm(found["point1"] - p1) <= max(1e-6 * gap, 1e-15), case
        assert np.linalg.norm(found["point2"] - p2) <= max(1e-6 * gap, 1e-15), case
        assert np.linalg.norm(found["normal"] - n) <= 1e-6, case
        assert found["residual"] <= 1e-15
    spheres = fig.closest_points([0.0, 0.0, 0.0], [1, 0, 0, 0], (40e-6, 40e-6), [30e-6, 40e-6, 0.0],
                                 [0.6, 0.8, 0.0, 0.0], (40e-6, 40e-6))
    assert spheres["gap"] == pytest.approx(50e-6 - 80e-6, rel=1e-12)    # overlap: minus the depth
    assert np.allclose(spheres["point1"], [24e-6, 32e-6, 0.0], rtol=0, atol=1e-18)
    assert np.allclose(spheres["normal"], [0.6, 0.8, 0.0], rtol=0, atol=1e-14)


NEEDLE_Q1 = unit([0.9, 0.2, -0.3, 0.25])
NEEDLE_Q2 = unit([0.3, -0.7, 0.5, 0.4])
NEEDLE_C1 = np.array([0.45e-3, 0.40e-3, 0.62e-3])
# Near the tip of needle 1 (0.35 rad from its axis): a side-by-side contact whose point is far from
# the plane through both centres and their relative velocity.
NEEDLE_P1, NEEDLE_P2, NEEDLE_N, NEEDLE_C2 = constructed_contact(NEEDLE_C1, NEEDLE_Q1, NEEDLE, 0.35, 1.1,
                                                                NEEDLE_Q2, NEEDLE, 1.0e-9)


@pytest.fixture(params=["stored", "computed"])
def needles_in_contact(request, tmp_path):
    """Needles 1 nm apart; particles.h5 with the closest points at the snapshot's time ('stored')
    or without /pair datasets ('computed': the tool solves for them)."""
    run = tmp_path / f"needles {request.param}"
    run.mkdir()
    write_snapshot(run, 40, 2.0e-4, linear_field())
    contact = (1.0e-9, NEEDLE_P1, NEEDLE_P2) if request.param == "stored" else None
    write_particles(run, [0.0, 2.0e-4], [NEEDLE_C1, NEEDLE_C2], [NEEDLE_Q1, NEEDLE_Q2], VELOCITIES,
                    aspect_ratio=5.0, shape="needle", contact=contact)
    return run, request.param


def test_contact_plane_holds_both_closest_points_and_a_centre(needles_in_contact):
    run, source = needles_in_contact
    view = fig.plane_view(str(run), resolution=5)
    plane, contact = view["plane"], view["contact"]
    assert plane.kind == "contact" and plane.through == "centre 1"
    assert ("particles.h5" in contact["source"]) == (source == "stored")
    assert contact["gap"] == pytest.approx(1.0e-9, rel=1e-6)
    for point in (NEEDLE_P1, NEEDLE_P2, NEEDLE_C1):
        assert abs(plane.coordinates(point)[2]) <= 1e-15       # m: on the plane
    assert abs(np.dot(plane.e1, plane.e2)) <= 1e-15 and np.dot(plane.e1, NEEDLE_N) == pytest.approx(1.0, abs=1e-12)
    # The closest points sit at the view's origin, 1 nm apart along s; their markers' coordinates.
    for (s, t), point in zip(view["markers"], (NEEDLE_P1, NEEDLE_P2)):
        assert (s, t) == pytest.approx(plane.coordinates(point)[:2], abs=1e-15)
    assert view["markers"][1][0] - view["markers"][0][0] == pytest.approx(1.0e-9, rel=1e-6)
    # The outlines are the sections by this plane: both touch the origin.
    for outline in view["outlines"]:
        assert outline is not None and np.min(np.hypot(outline[0], outline[1])) <= 1.0e-6
    # The plane through both centres misses the contact by micrometres: the picture this replaces.
    centres = fig.plane_view(str(run), resolution=5, plane_choice="centres")["plane"]
    assert centres.kind == "centres" and abs(centres.coordinates(NEEDLE_P1)[2]) > 5.0e-6


def test_markers_and_gap_in_the_title(needles_in_contact, tmp_path):
    run, _ = needles_in_contact
    view = fig.plane_view(str(run), resolution=20, vectors=5)
    figure = fig.render(view)
    axes = figure.axes[0]
    marked = {line.get_label(): (line.get_marker(), line.get_xdata()[0], line.get_ydata()[0])
              for line in axes.get_lines() if line.get_marker() not in (None, "None", "")}
    for n in (1, 2):
        marker, s, t = marked[f"closest point {n}"]
        assert (s, t) == pytest.approx(np.array(view["markers"][n - 1]) * 1.0e6, abs=1e-9)    # um
    assert marked["closest point 1"][0] != marked["closest point 2"][0]
    assert "gap 1 nm" in axes.get_title() and "plane through the closest points" in axes.get_title()
    import matplotlib.pyplot as plt
    plt.close(figure)
    out = subprocess.run([str(TOOL), str(run), "-o", str(tmp_path / "n.png")], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "gap 1 nm (1e-09 m)" in out.stdout and "plane through the closest points and centre 1" in out.stdout


def test_distant_pair_keeps_the_centre_plane(run):
    view = fig.plane_view(str(run), resolution=5)
    a, b = fig.semi_axes_of(50.0e-6, 0.2)
    assert view["contact"]["gap"] > a                          # farther than the thinnest semi-axis
    assert view["plane"].kind == "centres" and view["markers"] is None
    figure = fig.render(view)
    assert f"gap {view['contact']['gap'] * 1e6:.3g} um" in figure.axes[0].get_title()
    import matplotlib.pyplot as plt
    plt.close(figure)
