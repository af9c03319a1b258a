"""tools/regrid_field.py: spectral resampling of a staggered (MAC) field onto another grid of the
same box, the discrete projection, the round trip, the file layout the code reads, and refusals.

The staggering is the code's (src/fluid/fluid_grid.f90): cell (i, j, k), 1-based, has its centre
at ((i - 1/2) dx, (j - 1/2) dy, (k - 1/2) dz); u(i, j, k) sits at (i dx, (j - 1/2) dy, (k - 1/2) dz),
v and w alike along y and z. A trigonometric polynomial whose modes lie inside both grids' bands
is its own interpolant on either grid, so its samples at the new positions are exact (to round-off)."""
import math

import h5py
import numpy as np
import pytest

from conftest import REPO, run_tool
from regrid_field import OFFSETS, discrete_divergence, kinetic_energy, project, regrid, resample
from synthetic_fields import BOX, solenoidal_random_field, write_final_field

PYTHON = REPO / ".venv" / "bin" / "python"
TOOL = REPO / "tools" / "regrid_field.py"
ROUND_OFF = 1e-12                       # relative to the field's largest value


def positions(shape, box, offsets):
    """The sample positions (x, y, z) of a field with the given offsets (in cells), 0-based arrays:
    sample a sits at (a + offset) h, which is i h for a face (offset 1, i = a + 1) and (i - 1/2) h
    for a centre (offset 1/2)."""
    axes = [(np.arange(n) + offset) * length / n for n, length, offset in zip(shape, box, offsets)]
    return np.meshgrid(*axes, indexing="ij")


def analytic(name, x, y, z, box):
    """u, v, w = curl A of a vector potential A with a few modes (|m| <= 2 per axis), and a scalar
    'pressure' of the same modes: continuous, solenoidal in the continuous sense, exact anywhere."""
    kx, ky, kz = (2.0 * math.pi / length for length in box)
    # A_x = 0.7 sin(ky y + 0.3) cos(2 kz z - 0.2) + 0.2 cos(kx x + 2 ky y)
    # A_y = 0.5 cos(2 kx x + 0.1) sin(kz z + 0.4) - 0.3 sin(kx x - kz z)
    # A_z = 0.9 sin(kx x + 0.5) sin(2 ky y - 0.6) + 0.1 cos(2 kx x + ky y + kz z)
    if name == "u":          # dA_z/dy - dA_y/dz
        return (1.8 * ky * np.sin(kx * x + 0.5) * np.cos(2 * ky * y - 0.6)
                - 0.1 * ky * np.sin(2 * kx * x + ky * y + kz * z)
                - 0.5 * kz * np.cos(2 * kx * x + 0.1) * np.cos(kz * z + 0.4) - 0.3 * kz * np.cos(kx * x - kz * z))
    if name == "v":          # dA_x/dz - dA_z/dx
        return (-1.4 * kz * np.sin(ky * y + 0.3) * np.sin(2 * kz * z - 0.2)
                - 0.9 * kx * np.cos(kx * x + 0.5) * np.sin(2 * ky * y - 0.6)
                + 0.2 * kx * np.sin(2 * kx * x + ky * y + kz * z))
    if name == "w":          # dA_y/dx - dA_x/dy
        return (-1.0 * kx * np.sin(2 * kx * x + 0.1) * np.sin(kz * z + 0.4) - 0.3 * kx * np.cos(kx * x - kz * z)
                - 0.7 * ky * np.cos(ky * y + 0.3) * np.cos(2 * kz * z - 0.2) + 0.4 * ky * np.sin(kx * x + 2 * ky * y))
    return np.sin(kx * x + 0.5) * np.cos(ky * y - kz * z) + 0.3 * np.cos(2 * kz * z + 0.7)


def vector_potential_field(shape, box):
    """analytic() sampled at each field's own staggered positions on the grid of shape."""
    return {name: analytic(name, *positions(shape, box, OFFSETS[name]), box) for name in ("u", "v", "w", "pressure")}


def largest(fields):
    return max(float(np.max(np.abs(fields[c]))) for c in "uvw")


def test_the_analytic_field_is_solenoidal():
    """The fixture's curl is right: sampled at common positions, its spectral divergence (exact for
    modes in the band) vanishes, so the resampling tests compare against a solenoidal field."""
    shape = (24, 20, 16)
    x, y, z = positions(shape, BOX, OFFSETS["pressure"])
    divergence = np.zeros(shape)
    for d, name in enumerate("uvw"):
        k = 2.0 * np.pi * np.fft.fftfreq(shape[d], BOX[d] / shape[d])
        spectrum = np.moveaxis(np.fft.fft(analytic(name, x, y, z, BOX), axis=d), d, -1) * 1j * k
        divergence += np.moveaxis(np.fft.ifft(spectrum, axis=-1).real, -1, d)
    fields = {name: analytic(name, x, y, z, BOX) for name in "uvw"}
    scale = largest(fields) * 2.0 * np.pi * max(shape[d] / BOX[d] for d in range(3))
    assert float(np.max(np.abs(divergence))) < ROUND_OFF * scale
    assert float(np.max(np.abs(fields["u"]))) > 0.1 * largest(fields)


@pytest.mark.parametrize("new_shape", [(36, 30, 25), (16, 12, 10), (24, 20, 16)])
def test_resampled_field_matches_the_analytic_one_at_the_new_positions(new_shape):
    """Each component at its own staggered positions on the new grid (finer, coarser, same, odd
    sizes): exact to round-off; a half-cell phase error would leave errors of order k h."""
    shape = (24, 20, 16)
    old, new = vector_potential_field(shape, BOX), vector_potential_field(new_shape, BOX)
    scale = largest(new)
    for name in ("u", "v", "w", "pressure"):
        resampled = resample(old[name], new_shape, OFFSETS[name])
        assert resampled.shape == new_shape
        error = float(np.max(np.abs(resampled - new[name])))
        assert error < ROUND_OFF * max(scale, float(np.max(np.abs(new[name])))), (name, error)


def test_resampling_with_the_wrong_staggering_is_detected():
    """The comparison above can fail: the u samples treated as centred are off by half a cell."""
    shape, new_shape = (24, 20, 16), (36, 30, 25)
    old, new = vector_potential_field(shape, BOX), vector_potential_field(new_shape, BOX)
    wrong = resample(old["u"], new_shape, OFFSETS["pressure"])
    assert float(np.max(np.abs(wrong - new["u"]))) > 1e-2 * largest(new)


def test_an_even_grids_nyquist_mode_becomes_its_real_cosine():
    """The samples (-1)^a of an 8-cell axis (u, at x = (a + 1) h) are cos(pi (x/h - 1)); on 12 cells
    the interpolant's samples are that cosine at the new positions, and 12 -> 8 gives them back."""
    n, m = 8, 12
    length = BOX[0]
    samples = np.tile(((-1.0) ** np.arange(n))[:, None, None], (1, 4, 4))
    up = resample(samples, (m, 4, 4), OFFSETS["u"])
    x = (np.arange(m) + 1.0) * length / m
    expected = np.cos(np.pi * (x / (length / n) - 1.0))
    assert np.max(np.abs(up[:, 0, 0] - expected)) < ROUND_OFF
    assert np.max(np.abs(resample(up, (n, 4, 4), OFFSETS["u"]) - samples)) < ROUND_OFF


@pytest.mark.parametrize("method", ["continuous", "discrete"])
def test_projection_leaves_a_round_off_divergence_and_keeps_the_mean(method):
    rng = np.random.default_rng(7)
    shape = (12, 10, 9)
    u, v, w = (rng.standard_normal(shape) + mean for mean in (0.3, -0.2, 0.1))
    cell = min(length / n for length, n in zip(BOX, shape))
    before = float(np.max(np.abs(discrete_divergence(u, v, w, BOX)))) * cell / largest({"u": u, "v": v, "w": w})
    assert before > 0.1                                # a random field is far from solenoidal
    pu, pv, pw = project(u, v, w, BOX, method)
    after = float(np.max(np.abs(discrete_divergence(pu, pv, pw, BOX)))) * cell / largest({"u": pu, "v": pv, "w": pw})
    assert after < ROUND_OFF
    for original, projected in ((u, pu), (v, pv), (w, pw)):
        assert abs(float(np.mean(projected)) - float(np.mean(original))) < ROUND_OFF
    # A solenoidal field is left alone (the projection is idempotent).
    again = project(pu, pv, pw, BOX, method)
    assert max(float(np.max(np.abs(a - b))) for a, b in zip(again, (pu, pv, pw))) < ROUND_OFF
    if method == "discrete":
        # The orthogonal projection removes the discrete gradient: never adds kinetic energy, and the
        # change has no discrete curl ((dv/dx - du/dy) on the cell edges).
        assert kinetic_energy(pu, pv, pw) <= kinetic_energy(u, v, w)
        du, dv = pu - u, pv - v
        curl = ((np.roll(dv, -1, axis=0) - dv) * shape[0] / BOX[0] - (np.roll(du, -1, axis=1) - du) * shape[1] / BOX[1])
        assert float(np.max(np.abs(curl))) * cell < ROUND_OFF * largest({"u": du, "v": dv, "w": pw - w})


def test_round_trip_to_a_finer_grid_and_back_returns_the_field():
    """128 -> 192 -> 128 in miniature (the same 2 : 3 ratio, 32 -> 48 -> 32): every sample back to
    round-off with the default projection, although each leg changed the field by its projection.
    The orthogonal (discrete) projection is not undone on the way back: the test can tell them apart."""
    field = solenoidal_random_field((32, 32, 32))
    scale = largest(field)
    finer, report = regrid(field, (48, 48, 48))
    assert report["max_change_by_projection"] > 1e-3 * scale     # the fine grid's projection did act
    back, _ = regrid(finer, (32, 32, 32))
    for name in ("u", "v", "w", "pressure"):
        assert float(np.max(np.abs(back[name] - field[name]))) < ROUND_OFF * scale, name
    finer, _ = regrid(field, (48, 48, 48), "discrete")
    back, _ = regrid(finer, (32, 32, 32), "discrete")
    assert max(float(np.max(np.abs(back[c] - field[c]))) for c in "uvw") > 1e-4 * scale


def test_command_line_round_trip_and_layout(spaced_tmp):
    field = solenoidal_random_field((16, 12, 10))
    source, middle, back = spaced_tmp / "field.h5", spaced_tmp / "on 24" / "final_field.h5", spaced_tmp / "back.h5"
    write_final_field(source, field)
    result = run_tool([PYTHON, TOOL, source, "--grid", "24", "18", "15", "-o", middle, "--box", "1e-3", "2e-3", "1.5e-3"])
    assert result.returncode == 0, result.stderr
    assert "max|div| dx / max|u|" in result.stdout and "forcing/state: copied" in result.stdout
    with h5py.File(middle, "r") as handle:
        assert list(handle["fluid/grid_shape"][()]) == [24, 18, 15]
        assert handle["fluid/grid_shape"].dtype == np.int32
        assert handle["fluid/u"].shape == (15, 18, 24)                   # Fortran (24, 18, 15)
        assert handle["fluid/time"][()] == pytest.approx(0.125, rel=1e-15)
        assert list(handle["fluid/box_length"][()]) == pytest.approx(list(BOX), rel=1e-15)
        assert list(handle["forcing/state"][()]) == list(range(20))
    assert not list(spaced_tmp.glob("**/*.tmp"))
    result = run_tool([PYTHON, TOOL, middle, "--grid", "16", "12", "10", "-o", back])
    assert result.returncode == 0, result.stderr
    with h5py.File(back, "r") as handle:
        for name in ("u", "v", "w", "pressure"):
            error = float(np.max(np.abs(handle[f"fluid/{name}"][()].T - field[name])))
            assert error < ROUND_OFF * largest(field), name


def refusal(arguments):
    result = run_tool([PYTHON, TOOL] + [str(a) for a in arguments])
    assert result.returncode == 2, result.stdout + result.stderr
    return result.stderr


def test_refusals_name_the_argument(spaced_tmp):
    field = solenoidal_random_field((8, 8, 8))
    source, target = spaced_tmp / "field.h5", spaced_tmp / "out.h5"
    write_final_field(source, field)
    assert "--grid 3: 3 cells is outside 4 .. 1290" in refusal([source, "--grid", "3", "-o", target])
    assert "--grid 0" in refusal([source, "--grid", "0", "-o", target])
    assert "is not a whole number" in refusal([source, "--grid", "9.5", "-o", target])
    assert "give N (an N^3 grid) or NX NY NZ" in refusal([source, "--grid", "16", "16", "-o", target])
    assert "2000 cells is outside" in refusal([source, "--grid", "2000", "-o", target])
    assert "no such file" in refusal([spaced_tmp / "missing.h5", "--grid", "16", "-o", target])
    assert "regridding keeps the box" in refusal([source, "--grid", "16", "-o", target, "--box", "2e-3"])
    assert "is the INPUT itself" in refusal([source, "--grid", "16", "-o", source, "--force"])
    not_a_field = spaced_tmp / "other.h5"
    with h5py.File(not_a_field, "w") as handle:
        handle.create_dataset("something", data=1.0)
    assert "holds no velocity field" in refusal([not_a_field, "--grid", "16", "-o", target])
    assert not target.exists()
    # An existing output is kept unless --force.
    target.write_text("earlier")
    assert "exists" in refusal([source, "--grid", "16", "-o", target])
    assert target.read_text() == "earlier"
    result = run_tool([PYTHON, TOOL, source, "--grid", "16", "-o", target, "--force"])
    assert result.returncode == 0, result.stderr
    with h5py.File(target, "r") as handle:
        assert list(handle["fluid/grid_shape"][()]) == [16, 16, 16]


def test_the_code_starts_from_a_regridded_forced_field(spaced_tmp, agglo):
    """End to end: a forced field of the code (input/hit_box.nml at 16^3, a few steps from rest),
    regridded to 24^3, is read by &fluid init = 'file' with its forcing state (&forcing
    initial_state = 'field'): at step 0 the code sees the tool's kinetic energy and a round-off
    divergence, and the power input <f.u> after one tiny step (1e-8 s, so that the two grids'
    different truncation errors of one step stay below 1e-7) equals that on 16^3: the forced modes
    lie far inside both bands and f is the same, so f . u averages to the same value."""
    base = ["input/hit_box.nml", "--set", "run.dt_mode='fixed'", "--set", "run.dt=2.0e-4",
            "--set", "forcing.statistics_interval=1", "--set", "output.stats_interval=1",
            "--set", "output.field_interval=0.0", "--set", "output.checkpoint_interval=0"]
    def grid(n):
        return ["--set", f"grid.nx={n}", "--set", f"grid.ny={n}", "--set", f"grid.nz={n}"]
    def run(name, *extra):
        result = run_tool([agglo] + base + list(extra) + ["--set", f"run.name='{name}'",
                          "--set", f"output.directory='{spaced_tmp / name}'"], cwd=REPO)
        assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
        return spaced_tmp / name
    forced = run("forced16", *grid(16), "--set", "run.end_time=2.0e-3")
    regridded = spaced_tmp / "on24.h5"
    result = run_tool([PYTHON, TOOL, forced / "final_field.h5", "--grid", "24", "-o", regridded])
    assert result.returncode == 0, result.stderr
    start = ["--set", "fluid.init='file'", "--set", "run.dt=1.0e-8", "--set", "run.end_time=1.0e-8"]
    on16 = run("from16", *grid(16), *start, "--set", f"fluid.init_file='{forced / 'final_field.h5'}'")
    on24 = run("from24", *grid(24), *start, "--set", f"fluid.init_file='{regridded}'")
    with h5py.File(regridded, "r") as handle:
        energy = kinetic_energy(*(handle[f"fluid/{c}"][()] for c in "uvw"))
        speed = max(float(np.max(np.abs(handle[f"fluid/{c}"][()]))) for c in "uvw")
    rows = [line.split() for line in (on24 / "fluid_statistics.dat").read_text().splitlines()
            if not line.startswith("#")]
    step0 = rows[0]
    assert int(step0[0]) == 0
    assert float(step0[3]) == pytest.approx(energy, rel=1e-12)
    assert float(step0[5]) * (1.0e-3 / 24) / speed < 1e-12               # max_divergence (1/s)
    power = {}
    for name, directory in (("16", on16), ("24", on24)):
        with h5py.File(directory / "flow_statistics.h5", "r") as handle:
            power[name] = float(handle["power_input"][0])
    assert power["16"] != 0.0
    assert power["24"] == pytest.approx(power["16"], rel=1e-6)


def test_fingerprint_sees_the_content_not_the_file(spaced_tmp):
    """Two files of the same field have one fingerprint (the content is hashed, not the file's
    bytes); one ulp in one sample, or another forcing state, gives another."""
    field = solenoidal_random_field((8, 6, 4))
    first, second, changed = (spaced_tmp / f"{name}.h5" for name in ("first", "second", "changed"))
    write_final_field(first, field)
    write_final_field(second, field)

    def fingerprint(path):
        result = run_tool([PYTHON, TOOL, path, "--fingerprint"])
        assert result.returncode == 0, result.stderr
        digest, name = result.stdout.rstrip("\n").split("  ", 1)
        assert len(digest) == 64 and name == str(path)
        return digest
    reference = fingerprint(first)
    assert fingerprint(second) == reference
    field["v"][3, 2, 1] = np.nextafter(field["v"][3, 2, 1], np.inf)
    write_final_field(changed, field)
    assert fingerprint(changed) != reference
    field["v"][3, 2, 1] = np.nextafter(field["v"][3, 2, 1], -np.inf)
    field["forcing_state"] = field["forcing_state"] + 1
    write_final_field(changed, field)
    assert fingerprint(changed) != reference
