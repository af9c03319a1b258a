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

# Outcomes per shape of the fake batch: (agglomerated, rebounded, approached, no_contact).
PLANNED = {"needle": (3, 2, 1, 1), "disk": (4, 1, 0, 0), "sphere": (0, 3, 0, 0)}
CLASSES = ("agglomerated", "rebounded", "approached", "no_contact")


def make_fake_batch(root, planned=PLANNED, fluid="none", first_seed=1, legacy=False):
    seed = first_seed
    for shape, counts in planned.items():
        for outcome, count in zip(CLASSES, counts):
            for _ in range(count):
                write_run(os.path.join(root, f"run_{seed:04d}"), seed=seed, shape=shape,
                          outcome=outcome, fluid=fluid, rows=60, legacy=legacy)
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
    for shape, counts in PLANNED.items():
        row = rates[shape]
        runs = sum(counts)
        assert int(row["runs"]) == runs
        assert tuple(int(row[outcome]) for outcome in CLASSES) == counts
        # 'approached' (in the DLVO range, never touched, escaped) counts as not agglomerated.
        assert float(row["rate"]) == pytest.approx(counts[0] / runs, rel=1e-12)
        low, high = wilson_interval(counts[0], runs)
        assert float(row["wilson_low"]) == pytest.approx(low, rel=1e-12, abs=1e-15)
        assert float(row["wilson_high"]) == pytest.approx(high, rel=1e-12)
        assert row["ended_in_flight"] == "0"
    # The printed table carries the same numbers: needle 3 of 7 (Wilson 1927: [0.158, 0.750]).
    needle_line = next(line for line in result.stdout.splitlines() if line.startswith("needle"))
    assert needle_line.split()[1:7] == ["7", "3", "2", "1", "1", "0.429"]
    assert "[0.158, 0.750]" in needle_line


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


def test_old_summaries_are_read(spaced_tmp):
    """Summaries without contact_episodes, ended_in_flight, outcome_settled (and without
    'approached'): the same counts and rates; episodes from particles.h5, in flight unknown."""
    root = spaced_tmp / "old batch"
    old = {"needle": (3, 2, 0, 1), "disk": (1, 1, 0, 0)}
    total = make_fake_batch(str(root), old, legacy=True)
    result = run_tool([AGGLO_STATS, root, "--no-figures"])
    assert result.returncode == 0, result.stderr
    rates = {row["group"]: row for row in read_csv(root / "stats" / "rates.csv")}
    for shape, counts in old.items():
        assert tuple(int(rates[shape][outcome]) for outcome in CLASSES) == counts
        assert float(rates[shape]["rate"]) == pytest.approx(counts[0] / sum(counts), rel=1e-12)
        assert rates[shape]["ended_in_flight"] == "0"
    rows = read_csv(root / "stats" / "runs.csv")
    assert len(rows) == total
    for row in rows:
        assert row["ended_in_flight"] == ""
        assert row["contact_episodes"] == ("0" if row["outcome"] == "no_contact" else "1")


def test_summary_episodes_and_in_flight_are_used(spaced_tmp):
    """With contact_episodes in summary.json the table takes the code's count (one events row per
    episode), not the history's grouping; ended_in_flight runs are counted per group."""
    root = spaced_tmp / "batch"
    write_run(str(root / "run_0001"), seed=1, shape="needle", outcome="agglomerated", rows=60)
    write_run(str(root / "run_0002"), seed=2, shape="needle", outcome="approached", rows=60, in_flight=True)
    path = root / "run_0001" / "summary.json"
    summary = json.loads(path.read_text())
    summary["contact_episodes"] = 3
    path.write_text(json.dumps(summary))
    assert run_tool([AGGLO_STATS, root, "--no-figures"]).returncode == 0
    runs = {row["run"]: row for row in read_csv(root / "stats" / "runs.csv")}
    assert runs["run_0001"]["contact_episodes"] == "3"
    assert runs["run_0002"]["contact_episodes"] == "0" and runs["run_0002"]["ended_in_flight"] == "True"
    rate = read_csv(root / "stats" / "rates.csv")[0]
    assert (rate["agglomerated"], rate["approached"], rate["ended_in_flight"]) == ("1", "1", "1")


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
    make_fake_batch(str(spaced_tmp / "none"), {"needle": (2, 1, 0, 0)}, fluid="none")
    make_fake_batch(str(spaced_tmp / "stokes"), {"needle": (0, 0, 0, 3)}, fluid="stokes", first_seed=10)
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
    # The quiescent protocol at 'stokes' fidelity never touches (docs/physics.md section 7): 0 of n,
    # whose Wilson interval is [0, z^2/(n + z^2)] = [0, 0.56150] for n = 3.
    make_fake_batch(str(spaced_tmp), {"disk": (0, 0, 3)}, fluid="stokes")
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""                      # no plotting warnings about empty panels
    assert "[0.000, 0.561]" in result.stdout
    for stem in FIGURES:
        assert (spaced_tmp / "stats" / f"{stem}.png").stat().st_size > 5000, stem


def test_gap_at_1ms_and_dlvo_range_entry(spaced_tmp):
    """The grid study's two history metrics on a fake run whose gap closes linearly from 5 um at
    (5 um - 100 nm) / 5 ms (fake_pair_scene, 'approached'): the gap at 1 ms is that line's value
    (linear between rows, so exact to round-off), and the entry into the DLVO range is the first
    row at or below h_r = 60 / debye_kappa (docs/theory.md, "Run outcome": 182.4 nm for
    kappa = 3.29e8 1/m), or the van der Waals cut-off when that is wider; none without DLVO."""
    import math

    from agglo_stats import load_runs
    end_time, rows, gap0 = 1.0e-2, 200, 5.0e-6
    speed = (gap0 - 1.0e-7) / (0.5 * end_time)
    row_interval = end_time / (rows - 1)
    cases = {"kappa": (" DLVO=T,", 3.2894736842105263e8, 5.0e-9, 60.0 / 3.2894736842105263e8),
             "cutoff": (" DLVO=T,", 3.2894736842105263e8, 1.0e-6, 1.0e-6),
             "off": (" DLVO=F,", 3.2894736842105263e8, 5.0e-9, None)}
    for name, (switch, kappa, cutoff, reach) in cases.items():
        directory = spaced_tmp / name / "run_0001"
        directory.mkdir(parents=True)
        (directory / "run.nml").write_text(f"&SCENE\n FLUID=\"none\",\n{switch}\n /\n&DLVO\n "
                                           f"DEBYE_KAPPA=  {kappa!r}     ,\n VDW_CUTOFF=  {cutoff!r},\n /\n")
        write_run(str(directory), seed=1, outcome="approached", end_time=end_time, rows=rows)
        run = load_runs([str(spaced_tmp / name)])[0][0]
        metrics = run.metrics()
        assert metrics["gap_at_1ms"] == pytest.approx(gap0 - speed * 1.0e-3, rel=1e-12)
        if reach is None:
            assert run.dlvo_range is None and metrics["range_entry_time"] is None
            continue
        assert run.dlvo_range == pytest.approx(reach, rel=1e-14)
        first_row = math.ceil((gap0 - reach) / speed / row_interval)
        assert metrics["range_entry_time"] == pytest.approx(first_row * row_interval, rel=1e-12)
