"""tools/agglo-stats on batches written by the FAKE pair-scene fixture (fake_pair_scene.py), whose
outcomes are set by the test: exact counts, rates, CSV contents, figure files, error messages.
The same tool on REAL runs of $AGGLO is tested in test_montecarlo.py."""
import csv
import json
import os

import pytest

from agglo_stats import wilson_interval
from conftest import AGGLO_STATS, run_tool
from fake_pair_scene import write_run

FIGURES = ("separation_pdf", "relative_velocity_pdf", "max_vdw_force_pdf", "psi_pdf",
           "collision_points_pdf", "histories")

# Outcomes per shape of the fake batch: (agglomerated, rebounded, no_contact).
PLANNED = {"needle": (3, 2, 1), "disk": (4, 1, 0), "sphere": (0, 3, 0)}


def make_fake_batch(root, planned=PLANNED, fluid="none", first_seed=1):
    seed = first_seed
    for shape, counts in planned.items():
        for outcome, count in zip(("agglomerated", "rebounded", "no_contact"), counts):
            for _ in range(count):
                write_run(os.path.join(root, f"run_{seed:04d}"), seed=seed, shape=shape,
                          outcome=outcome, fluid=fluid, rows=60)
                seed += 1
    return seed - first_seed


def read_csv(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def test_counts_rates_and_wilson_interval(spaced_tmp):
    root = spaced_tmp / "fake batch"
    make_fake_batch(str(root))
    result = run_tool([AGGLO_STATS, root, "--no-figures"])
    assert result.returncode == 0, result.stderr
    rates = {row["group"]: row for row in read_csv(root / "stats" / "rates.csv")}
    assert sorted(rates) == sorted(PLANNED)
    for shape, (agglomerated, rebounded, no_contact) in PLANNED.items():
        row = rates[shape]
        runs = agglomerated + rebounded + no_contact
        assert (int(row["runs"]), int(row["agglomerated"]), int(row["rebounded"]),
                int(row["no_contact"])) == (runs, agglomerated, rebounded, no_contact)
        assert float(row["rate"]) == pytest.approx(agglomerated / runs, rel=1e-12)
        low, high = wilson_interval(agglomerated, runs)
        assert float(row["wilson_low"]) == pytest.approx(low, rel=1e-12, abs=1e-15)
        assert float(row["wilson_high"]) == pytest.approx(high, rel=1e-12)
    # The printed table carries the same numbers: needle 3 of 6, Wilson [0.188, 0.812].
    needle_line = next(line for line in result.stdout.splitlines() if line.startswith("needle"))
    assert needle_line.split()[1:6] == ["6", "3", "2", "1", "0.500"]
    assert "[0.188, 0.812]" in needle_line


def test_csv_has_every_run(spaced_tmp):
    root = spaced_tmp / "batch"
    total = make_fake_batch(str(root))
    assert run_tool([AGGLO_STATS, root, "--no-figures"]).returncode == 0
    rows = read_csv(root / "stats" / "runs.csv")
    assert len(rows) == total
    assert [int(row["seed"]) for row in rows] == list(range(1, total + 1))
    for row in rows:
        with open(root / row["run"] / "summary.json") as handle:
            summary = json.load(handle)
        assert row["outcome"] == summary["outcome"] and row["shape"] == summary["shape"]
        assert float(row["max_vdw_force"]) == summary["max_vdw_force"]
        if summary["first_collision"] is None:
            assert row["theta1"] == "" and row["psi"] == ""
        else:
            assert float(row["psi"]) == summary["first_collision"]["psi"]
            assert float(row["phi2"]) == summary["first_collision"]["phi2"]


def test_figures_are_written(spaced_tmp):
    root = spaced_tmp / "batch"
    make_fake_batch(str(root))
    out = spaced_tmp / "figures out"
    result = run_tool([AGGLO_STATS, root, "-o", out, "--history", "run_0001", "--history", "run_0012"])
    assert result.returncode == 0, result.stderr
    for stem in FIGURES:
        png = out / f"{stem}.png"
        pdf = out / f"{stem}.pdf"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", stem
        assert pdf.read_bytes()[:5] == b"%PDF-", stem
        assert png.stat().st_size > 5000, f"{stem}.png looks empty"


def test_two_fluids_are_compared_and_batches_merged(spaced_tmp):
    make_fake_batch(str(spaced_tmp / "none"), {"needle": (2, 1, 0)}, fluid="none")
    make_fake_batch(str(spaced_tmp / "stokes"), {"needle": (0, 0, 3)}, fluid="stokes", first_seed=10)
    out = spaced_tmp / "stats"
    assert run_tool([AGGLO_STATS, spaced_tmp / "none", spaced_tmp / "stokes", "-o", out,
                     "--no-figures"]).returncode == 0
    rates = {row["group"]: row for row in read_csv(out / "rates.csv")}
    assert sorted(rates) == ["needle/none", "needle/stokes"]
    assert rates["needle/stokes"]["no_contact"] == "3" and rates["needle/none"]["agglomerated"] == "2"
    assert run_tool([AGGLO_STATS, spaced_tmp / "none", spaced_tmp / "stokes", "-o", out,
                     "--no-figures", "--group-by", "shape"]).returncode == 0
    assert [row["runs"] for row in read_csv(out / "rates.csv")] == ["6"]


def test_empty_batch_is_refused_with_a_clear_message(spaced_tmp):
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 1
    assert "holds no runs" in result.stderr and str(spaced_tmp) in result.stderr


def test_batch_without_a_complete_run_is_refused(spaced_tmp):
    for k in (1, 2):
        run = spaced_tmp / f"run_{k:04d}"
        run.mkdir()
        (run / "deck.nml").write_text("&run /\n")
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 1
    assert "no complete run" in result.stderr and "2 run(s)" in result.stderr


def test_partial_batch_reports_the_skipped_runs(spaced_tmp):
    make_fake_batch(str(spaced_tmp), {"disk": (2, 2, 0)})
    os.remove(spaced_tmp / "run_0002" / "summary.json")          # as a killed run leaves it
    (spaced_tmp / "run_0003" / "FAILED").write_text("reason: exit status 2\n")
    (spaced_tmp / "run_0005").mkdir()
    (spaced_tmp / "run_0005" / "summary.json").write_text("{\"name\": \"run_0005\"")  # truncated
    result = run_tool([AGGLO_STATS, spaced_tmp, "--no-figures"])
    assert result.returncode == 0, result.stderr
    assert "skipped 3 run(s) of 5" in result.stdout
    assert "run_0002: incomplete (no summary.json)" in result.stdout
    assert "run_0003: failed" in result.stdout and "run_0005: summary.json unreadable" in result.stdout
    assert len(read_csv(spaced_tmp / "stats" / "runs.csv")) == 2


def test_batch_without_any_contact_still_gives_rates_and_figures(spaced_tmp):
    # The quiescent protocol at 'stokes' fidelity never touches (physics.md section 7): 0 of n,
    # whose Wilson interval is [0, z^2/(n + z^2)] = [0, 0.56150] for n = 3.
    make_fake_batch(str(spaced_tmp), {"disk": (0, 0, 3)}, fluid="stokes")
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""                      # no plotting warnings about empty panels
    assert "[0.000, 0.561]" in result.stdout
    for stem in FIGURES:
        assert (spaced_tmp / "stats" / f"{stem}.png").stat().st_size > 5000, stem
