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
  cannot draw a run without particles.h5.
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


def write_particles(run, times, centres, quaternions, velocities, radius=50.0e-6, aspect_ratio=0.2):
    with h5py.File(run / "particles.h5", "w") as handle:
        handle["time"] = np.asarray(times, dtype=float)
        for n in (0, 1):
            rows = len(times)
            handle[f"particle{n + 1}/position"] = np.tile(centres[n], (rows, 1))
            handle[f"particle{n + 1}/quaternion"] = np.tile(quaternions[n], (rows, 1))
            handle[f"particle{n + 1}/velocity"] = np.tile(velocities[n], (rows, 1))
        handle["radius"] = radius
        handle["aspect_ratio"] = aspect_ratio
        handle["shape"] = np.bytes_("disk")
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
    view = fig.plane_view(str(run), resolution=30)
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
    view = fig.plane_view(str(run), resolution=5, chosen=(1, 3))
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
