"""agglo-stats' suspension mode on synthetic clusters.h5 / particles.h5 files with known answers:
mean sizes and their seed-to-seed intervals, fractal dimensions of lines (D = 1), square lattices
(D = 2) and a noisy power law, the psi distribution of random orientations, collision rates per
species pair and the size distribution at chosen times."""
import csv
import json
import math

import numpy as np
import pytest

from agglo_suspension import fractal_dimension, mean_interval, t_quantile
from conftest import AGGLO_STATS, run_tool
from synthetic_suspension import Row, gyration_full, line, square, write_particles, write_run

RADIUS = 50e-6
TIMES = [0.0, 1e-3, 2e-3, 3e-3]


def read_csv(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def test_t_quantiles_match_the_table():
    # Abramowitz & Stegun, Table 26.10 (Q = 0.025, two-sided 95%).
    for dof, expected in ((1, 12.706), (3, 3.182), (4, 2.776), (10, 2.228), (30, 2.042)):
        assert t_quantile(0.975, dof) == pytest.approx(expected, abs=1e-3)
    assert t_quantile(0.975, 10000) == pytest.approx(1.960, abs=1e-3)


def test_mean_interval_is_the_t_interval_of_the_seeds():
    values = [2.0, 3.0, 5.0, 6.0]            # mean 4, s = sqrt(10/3)
    mean, low, high = mean_interval(values)
    half = 3.182446305 * math.sqrt(10.0 / 3.0) / 2.0
    assert mean == pytest.approx(4.0) and low == pytest.approx(4.0 - half, rel=1e-6)
    assert high == pytest.approx(4.0 + half, rel=1e-6)
    assert mean_interval([7.0]) == (7.0, 7.0, 7.0)


def test_fractal_dimension_of_lines_and_square_lattices():
    sizes = np.arange(3, 41)
    radii = [gyration_full(line(n, RADIUS), RADIUS) for n in sizes]
    fit = fractal_dimension(sizes, radii)
    # Rg^2 = a^2 (4 (N^2 - 1)/12 + 3/5): slope 1 in log-log up to the finite-size terms (about 2%).
    assert fit["D"] == pytest.approx(1.0, abs=0.05) and fit["low"] < fit["D"] < fit["high"]
    sides = np.arange(2, 11)
    radii = [gyration_full(square(s, RADIUS), RADIUS) for s in sides]
    fit = fractal_dimension(sides ** 2, radii)
    assert fit["D"] == pytest.approx(2.0, abs=0.1) and fit["low"] < fit["D"] < fit["high"]


def test_fractal_dimension_of_a_noisy_power_law_and_its_interval():
    rng = np.random.default_rng(7)
    sizes = rng.integers(3, 200, 300)
    radii = RADIUS * sizes ** (1 / 2.5) * np.exp(rng.normal(0.0, 0.05, sizes.size))
    fit = fractal_dimension(sizes, radii)
    assert fit["low"] < 2.5 < fit["high"]
    assert fit["D"] == pytest.approx(2.5, abs=0.1) and fit["high"] - fit["low"] < 0.3
    assert math.isnan(fractal_dimension([3, 3, 3], [1.0, 1.1, 1.2])["D"])   # one size: no fit


def growth_batch(root, shape, finals, bodies=100):
    """Runs whose mean cluster size grows linearly to finals[k] over TIMES; the last row holds a
    line cluster of each size 3..8 (D = 1), a pair, and a percolating cluster with a huge Rg."""
    sizes = list(range(3, 9))
    radii = [gyration_full(line(n, RADIUS), RADIUS) for n in sizes]
    for k, final in enumerate(finals):
        mean = 1.0 + (final - 1.0) * np.asarray(TIMES) / TIMES[-1]
        rows = [Row(bodies)] * (len(TIMES) - 1) + [
            Row(bodies, sizes + [2, 40], radii + [10.0, 1.0], percolating=[0] * 7 + [1],
                psi=[0.1, 0.2, 0.3])]
        write_run(str(root / f"run_{k + 1:04d}"), TIMES, rows, shape=shape, seed=100 + k, mean_size=mean)


def test_batch_means_intervals_fractal_and_files(spaced_tmp):
    batch = spaced_tmp / "needle-point"
    finals = [2.0, 3.0, 5.0, 6.0]
    growth_batch(batch, "needle", finals)
    (batch / "run_0005").mkdir()                      # incomplete: deck, no summary.json
    (batch / "run_0005" / "deck.nml").write_text("&run /\n")
    out = spaced_tmp / "stats"
    result = run_tool([AGGLO_STATS, batch, "-o", out, "--times", "0,3e-3", "--snapshot-time", "3e-3"])
    assert result.returncode == 0, result.stderr + result.stdout
    assert "skipped 1 run(s) of 5" in result.stdout and "incomplete" in result.stdout
    (row,) = read_csv(out / "suspension_table.csv")
    assert row["group"] == "needle" and row["runs"] == "4"
    mean, low, high = mean_interval(finals)
    assert float(row["mean_size_number"]) == pytest.approx(mean)
    assert float(row["mean_size_number_low"]) == pytest.approx(low)
    assert float(row["mean_size_number_high"]) == pytest.approx(high)
    # The pair (size 2) and the percolating cluster are left out: the lines alone give D near 1.
    assert int(row["fractal_clusters"]) == 4 * 6
    assert float(row["fractal_dimension"]) == pytest.approx(1.0, abs=0.06)
    assert float(row["psi_mean"]) == pytest.approx(0.2)
    series = [r for r in read_csv(out / "suspension_timeseries.csv")]
    assert [float(r["time"]) for r in series] == TIMES
    assert float(series[2]["mean_size_number"]) == pytest.approx(1.0 + (mean - 1.0) * 2 / 3)
    sizes = read_csv(out / "suspension_sizes.csv")
    at_end = {int(r["size"]): int(r["count"]) for r in sizes if float(r["time"]) == pytest.approx(3e-3)}
    assert at_end == {1: 4 * (100 - 33 - 2 - 40), 2: 4, 3: 4, 4: 4, 5: 4, 6: 4, 7: 4, 8: 4, 40: 4}
    at_start = {int(r["size"]): int(r["count"]) for r in sizes if float(r["time"]) == 0.0}
    assert at_start == {1: 4 * 100}
    document = json.loads((out / "suspension.json").read_text())
    assert document["groups"]["needle"]["seeds"] == [100, 101, 102, 103]
    for stem in ("suspension_growth", "suspension_sizes", "suspension_gyration", "suspension_psi",
                 "suspension_collision_rate", "suspension_snapshot_needle"):
        assert (out / f"{stem}.png").stat().st_size > 0, stem


def test_psi_of_random_orientations_and_collision_rates(spaced_tmp):
    # psi = arccos(U), U uniform: the PDF sin(psi) of randomly oriented axes, mean 1 rad.
    rng = np.random.default_rng(3)
    psi = np.arccos(rng.uniform(0.0, 1.0, 4000))
    times = np.linspace(0.0, 2e-3, 5)
    volume = 1e-9
    rates = {"needle-needle": 2.0e12, "needle-disk": 5.0e11, "disk-disk": 1.0e12}
    counts = np.array([[round(rate * volume * t) for rate in rates.values()] for t in times])
    rows = [Row(10)] * 4 + [Row(10, [2], [1e-4], psi=psi)]
    write_run(str(spaced_tmp / "mixed" / "run_0001"), list(times), rows, shape="mixed",
              species=("needle", "disk"), counts=counts)
    out = spaced_tmp / "stats"
    result = run_tool([AGGLO_STATS, spaced_tmp / "mixed", "-o", out, "--no-figures"])
    assert result.returncode == 0, result.stderr + result.stdout
    document = json.loads((out / "suspension.json").read_text())
    group = document["groups"]["mixed"]
    # Standard error of the mean of 4000 samples: sqrt(pi - 3)/sqrt(4000) = 0.006.
    assert group["psi"]["mean"] == pytest.approx(1.0, abs=0.03)
    for name, rate in rates.items():
        assert group["collision_rate"][name]["mean"] == pytest.approx(rate, rel=1e-6), name
    assert "fractal" in group and group["fractal"]["D"] is None       # no cluster of >= 3 bodies
    assert group["collision_kernel"] is None     # several species: their counts are not in clusters.h5
    # Without --times the size distribution is the last row's: one pair and 8 single bodies.
    sizes = read_csv(out / "suspension_sizes.csv")
    assert {(float(r["time"]), int(r["size"]), int(r["count"])) for r in sizes} == {(2e-3, 1, 8), (2e-3, 2, 1)}


def test_point_and_resolved_compared_per_shape(spaced_tmp):
    growth_batch(spaced_tmp / "sphere-point", "sphere", [2.0, 2.0])
    growth_batch(spaced_tmp / "sphere-resolved", "sphere", [3.0, 3.0])
    out = spaced_tmp / "stats"
    result = run_tool([AGGLO_STATS, spaced_tmp / "sphere-point", spaced_tmp / "sphere-resolved",
                       "-o", out, "--group-by", "batch", "--compare", "point,resolved", "--no-figures"])
    assert result.returncode == 0, result.stderr + result.stdout
    rows = {r["quantity"]: r for r in read_csv(out / "suspension_comparison.csv")}
    assert float(rows["mean_size_number"]["point"]) == pytest.approx(2.0)
    assert float(rows["mean_size_number"]["resolved"]) == pytest.approx(3.0)
    assert float(rows["mean_size_number"]["ratio"]) == pytest.approx(1.5)
    assert rows["fractal_dimension"]["shape"] == "sphere"


def test_collision_kernel_and_the_efficiency_against_ghost_collisions(spaced_tmp):
    # 100 spheres in 1 mm^3: n = 1e11 per m^3, so the kernel is the rate / (n^2 / 2) = rate / 5e21.
    times = np.linspace(0.0, 1e-3, 3)
    for batch, rate in (("sphere-ghost", 4.0e12), ("sphere-point", 1.0e12)):
        for k in (1, 2):
            counts = np.array([[round(rate * 1e-9 * t)] for t in times])
            write_run(str(spaced_tmp / batch / f"run_{k:04d}"), list(times), [Row(100)] * 3, seed=k,
                      counts=counts)
    out = spaced_tmp / "stats"
    result = run_tool([AGGLO_STATS, spaced_tmp / "sphere-ghost", spaced_tmp / "sphere-point", "-o", out,
                       "--group-by", "batch", "--compare", "ghost,point", "--no-figures"])
    assert result.returncode == 0, result.stderr + result.stdout
    table = {row["group"]: row for row in read_csv(out / "suspension_table.csv")}
    assert float(table["sphere-ghost"]["collision_kernel"]) == pytest.approx(4.0e12 / 5e21, rel=1e-6)
    assert float(table["sphere-point"]["collision_kernel"]) == pytest.approx(1.0e12 / 5e21, rel=1e-6)
    rows = {r["quantity"]: r for r in read_csv(out / "suspension_comparison.csv")}
    assert float(rows["collision_kernel"]["ratio"]) == pytest.approx(0.25, rel=1e-6)   # the efficiency
    assert "collision kernel (m^3/s): 8e-10 [8e-10, 8e-10]" in result.stdout


def test_ghost_kernel_against_saffman_turner(spaced_tmp):
    # Spheres of r = 5 um, nu = 1e-6 m^2/s, dissipation rows 0.01 and 0.03 (mean 0.02): Saffman &
    # Turner (1956) give sqrt(8 pi / 15) (2 r)^3 sqrt(eps / nu) = 1.2965 x 1e-15 x 141.42 m^3/s. A
    # rate of 1.5 times that kernel times n^2 / 2 (n = 100 per mm^3) must come back as 1.5.
    reference = math.sqrt(8.0 * math.pi / 15.0) * (1.0e-5) ** 3 * math.sqrt(0.02 / 1.0e-6)
    times = np.linspace(0.0, 1e-3, 3)
    rate = 1.5 * reference * 0.5 * 1e11 ** 2
    for k in (1, 2):
        run = spaced_tmp / "sphere-ghost" / f"run_{k:04d}"
        counts = np.array([[rate * 1e-9 * t] for t in times])
        write_run(str(run), list(times), [Row(100)] * 3, seed=k, counts=counts)
        write_particles(str(run / "particles.h5"), list(times), np.zeros((3, 100, 3)), seed=k, radius=5e-6)
        (run / "run.nml").write_text("&fluid\n  viscosity = 1.0e-6\n/\n")
        (run / "fluid_statistics.dat").write_text("# step time dt kinetic_energy dissipation\n"
                                                  "0 0.0 0.0 1e-5 0.01\n100 1e-3 1e-5 1e-5 0.03\n")
    out = spaced_tmp / "stats"
    result = run_tool([AGGLO_STATS, spaced_tmp / "sphere-ghost", "-o", out, "--group-by", "batch", "--no-figures"])
    assert result.returncode == 0, result.stderr + result.stdout
    table = {row["group"]: row for row in read_csv(out / "suspension_table.csv")}
    assert float(table["sphere-ghost"]["kernel_over_saffman_turner"]) == pytest.approx(1.5, rel=1e-6)
    assert "kernel / Saffman-Turner: 1.500" in result.stdout


def test_suspension_options_are_refused_for_pair_batches(spaced_tmp):
    run = spaced_tmp / "pair" / "run_0001"
    run.mkdir(parents=True)
    (run / "summary.json").write_text(json.dumps({"outcome": "agglomerated"}))
    result = run_tool([AGGLO_STATS, spaced_tmp / "pair", "--times", "1e-3"])
    assert result.returncode == 1 and "options of suspension runs" in result.stderr
    result = run_tool([AGGLO_STATS, spaced_tmp / "pair", "--times", "soon"])
    assert result.returncode == 2 and "--times" in result.stderr
