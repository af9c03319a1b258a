"""The study tools on synthetic batches of the FAKE pair-scene fixture (fake_pair_scene.py), whose
histories and outcomes the tests set: contact episodes, the history metrics of runs.csv, the
means, the illustrative-run rules (agglo-stats --illustrate), the paired comparison
(study_compare.py), the speed-accuracy analysis (speed_accuracy.py) and the batch costs
(batch_costs.py). The study scripts themselves are checked on the real decks through --list and
--slurm (the code merges their decks), and one tiny real batch of $AGGLO end to end."""
import csv
import json
import math
import os
import shutil

import h5py
import numpy as np
import pytest

from agglo_stats import contact_episodes, lever_arm
from conftest import AGGLO_STATS, REPO, run_tool
from fake_pair_scene import write_run
from speed_accuracy import pareto_front, spread_labels
from synthetic_fields import solenoidal_random_field, write_final_field

PYTHON = REPO / ".venv" / "bin" / "python"


def read_csv(path, delimiter=","):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle, delimiter=delimiter))


def edit_summary(directory, **first_collision):
    path = os.path.join(directory, "summary.json")
    with open(path) as handle:
        summary = json.load(handle)
    summary["first_collision"].update(first_collision)
    with open(path, "w") as handle:
        json.dump(summary, handle)
    return summary


# ---------------------------------------------------------------------------------------------
# Contact episodes
# ---------------------------------------------------------------------------------------------

def test_contact_episodes_counts_separations_between_collisions():
    time = np.linspace(0.0, 10.0, 101)
    gap = np.full(101, 1.0e-9)
    gap[(time > 3.0) & (time < 4.0)] = 50.0e-9          # one separation between t = 3 and 4
    events = [1.0, 2.0, 2.5, 5.0, 6.0]                    # 3 before it, 2 after: two episodes
    assert contact_episodes(events, time, gap, 10.0e-9) == 2
    gap[(time > 5.4) & (time < 5.6)] = 20.0e-9            # a second separation: three
    assert contact_episodes(events, time, gap, 10.0e-9) == 3
    assert contact_episodes([], time, gap, 10.0e-9) == 0
    assert contact_episodes([4.0], time, gap, 10.0e-9) == 1


def test_lever_arm_of_a_contact():
    """Two unit spheres touching off their centre line: the contact normal along x, the contact
    point 0.6 off the line through each centre along y: lever arm 0.6 r; a central contact 0."""
    r = 2.0
    time = np.array([0.0, 1.0, 2.0])
    centres = [np.tile([0.0, 0.0, 0.0], (3, 1)), np.tile([2.0 * 0.8 * r, 0.0, 0.0], (3, 1))]
    point = np.array([0.8 * r, 0.6 * r, 0.0])
    points = [np.tile(point, (3, 1)), np.tile(point + [1.0e-9, 0.0, 0.0], (3, 1))]
    assert lever_arm(time, 1.5, points, centres, r) == pytest.approx(0.6, rel=1e-9)
    points = [np.tile([r, 0.0, 0.0], (3, 1)), np.tile([r + 1.0e-9, 0.0, 0.0], (3, 1))]
    assert lever_arm(time, 1.5, points, centres, r) == pytest.approx(0.0, abs=1e-12)
    assert lever_arm(time, 1.5, [points[0], points[0]], centres, r) is None


# ---------------------------------------------------------------------------------------------
# agglo-stats: history metrics, means, illustrative runs
# ---------------------------------------------------------------------------------------------

def make_illustration_batch(root):
    """Disk runs: 1-2 plain agglomerated, 3 agglomerated after a separation (two episodes),
    4-5 rebounded with contacts away from the rim, 6 rebounded at 0.05 rad from the rim, 7
    rebounded and carried 100 um by a common drift of both particles. Summaries without
    contact_episodes (legacy): the table groups the events rows by the sampled gap."""
    directories = {}
    plan = ["agglomerated", "agglomerated", "agglomerated", "rebounded", "rebounded", "rebounded",
            "rebounded"]
    for seed, outcome in enumerate(plan, start=1):
        directory = os.path.join(root, f"run_{seed:04d}")
        write_run(directory, seed=seed, shape="disk", outcome=outcome, rows=200, legacy=True)
        directories[seed] = directory
        if outcome == "rebounded":
            edit_summary(directory, phi1=0.5, phi2=-0.4)
    with h5py.File(os.path.join(directories[3], "particles.h5"), "r+") as h5:
        time = h5["time"][:]
        contact = h5["events/time"][0]
        gap = h5["pair/gap"][:]
        late = time > contact + 0.2 * (time[-1] - contact)
        window = late & (time < contact + 0.3 * (time[-1] - contact))
        gap[window] = 60.0e-9                               # separated by 60 nm, then back
        h5["pair/gap"][...] = gap
        del h5["events/time"]
        h5["events/time"] = np.array([contact, contact + 0.5 * (time[-1] - contact)])
    edit_summary(directories[6], phi1=0.5 * math.pi + 0.05)
    with h5py.File(os.path.join(directories[2], "particles.h5"), "r+") as h5:
        approach = h5["pair/relative_velocity"][:]
        approach[1] = 0.5 * approach[0]
        h5["pair/relative_velocity"][...] = approach
    with h5py.File(os.path.join(directories[7], "particles.h5"), "r+") as h5:
        for k in (1, 2):
            velocity = h5[f"particle{k}/velocity"][:]
            velocity[:, 1] += 1.0e-2                       # 10 mm/s for 10 ms: 100 um
            h5[f"particle{k}/velocity"][...] = velocity
    return directories


def test_history_metrics_means_and_illustrative_runs(spaced_tmp):
    root = spaced_tmp / "disks"
    make_illustration_batch(str(root))
    out = spaced_tmp / "stats"
    result = run_tool([AGGLO_STATS, root, "-o", out, "--illustrate"])
    assert result.returncode == 0, result.stderr
    runs = {row["run"]: row for row in read_csv(out / "runs.csv")}
    # Max particle speed: each fake particle moves at half the relative velocity (fixture).
    for name, row in runs.items():
        with h5py.File(root / name / "particles.h5", "r") as h5:
            speeds = np.linalg.norm(np.concatenate([h5["particle1/velocity"][:],
                                                    h5["particle2/velocity"][:]]), axis=1)
        assert float(row["max_particle_speed"]) == pytest.approx(speeds.max(), rel=1e-12)
    # The fixture's approach: 5 um closed by the contact at 5 ms (half its 10 ms), 1 mm/s.
    assert float(runs["run_0001"]["max_particle_speed"]) == pytest.approx(0.5 * 1.0e-3, rel=1e-9)
    assert runs["run_0003"]["contact_episodes"] == "2"
    assert runs["run_0001"]["contact_episodes"] == "1"
    assert float(runs["run_0007"]["carried_distance"]) == pytest.approx(1.0e-4, rel=1e-6)
    # Relative path: 5 um of approach, then the rebound at 0.4 mm/s for the remaining 5 ms.
    assert float(runs["run_0007"]["relative_path"]) == pytest.approx(5.0e-6 + 0.4e-3 * 5.0e-3, rel=0.02)
    # The smallest sampled gap and the approach the first sample interval keeps (fixture: a
    # constant 1 mm/s approach; run_0002 made to halve it at its second row).
    for name, row in runs.items():
        with h5py.File(root / name / "particles.h5", "r") as h5:
            assert float(row["min_gap"]) == pytest.approx(h5["pair/gap"][:].min(), rel=1e-12)
    assert float(runs["run_0001"]["early_approach_ratio"]) == pytest.approx(1.0, rel=1e-12)
    assert float(runs["run_0002"]["early_approach_ratio"]) == pytest.approx(0.5, rel=1e-12)
    # Means over every history row of the group.
    means = read_csv(out / "history_means.csv")[0]
    gaps = []
    for name in runs:
        with h5py.File(root / name / "particles.h5", "r") as h5:
            gaps.append(h5["pair/gap"][:])
    assert float(means["mean_gap"]) == pytest.approx(np.mean(np.concatenate(gaps)), rel=1e-12)
    # The rules pick the runs built for them.
    picks = {row["rule"]: row for row in read_csv(out / "illustrative.csv")}
    assert picks["successive_collisions"]["run"] == "run_0003"
    assert picks["edge_on_bounce"]["run"] == "run_0006"
    assert picks["edge_on_bounce"]["candidates"] == "1"
    assert picks["carried_together"]["run"] == "run_0007"
    for stem in ("illustrative_histories", "max_particle_speed_pdf"):
        assert (out / f"{stem}.png").stat().st_size > 1000


def test_no_qualifying_run_is_said(spaced_tmp):
    root = spaced_tmp / "spheres"
    for seed in (1, 2):
        write_run(str(root / f"run_{seed:04d}"), seed=seed, shape="sphere", outcome="rebounded", rows=40)
    result = run_tool([AGGLO_STATS, root, "-o", spaced_tmp / "s", "--illustrate", "--no-figures"])
    assert result.returncode == 0, result.stderr
    assert "illustrative sphere edge_on_bounce: no run qualifies" in result.stdout
    assert "illustrative sphere successive_collisions: no run qualifies" in result.stdout


# ---------------------------------------------------------------------------------------------
# Paired comparison and the speed-accuracy analysis
# ---------------------------------------------------------------------------------------------

def make_pair_of_batches(study, flips=(2, 5), speed_factor=1.1, runs=8):
    """reference and variant batches of the same seeds; the variant flips the outcome of the
    runs in flips and scales every first-collision normal velocity by speed_factor."""
    for name in ("disk-base", "disk-cheap"):
        for seed in range(1, runs + 1):
            outcome = "agglomerated" if seed % 2 else "rebounded"
            if name == "disk-cheap" and seed in flips:
                outcome = "rebounded" if outcome == "agglomerated" else "agglomerated"
            directory = os.path.join(study, name, f"run_{seed:04d}")
            summary = write_run(directory, seed=seed, shape="disk", outcome=outcome, rows=40)
            if name == "disk-cheap":
                edit_summary(directory, normal_velocity_before=speed_factor
                             * summary["first_collision"]["normal_velocity_before"])
        with open(os.path.join(study, name, "batch.conf"), "w") as handle:
            handle.write("base_seed=1\n")
    with open(os.path.join(study, "manifest.tsv"), "w") as handle:
        handle.write("knob\tvariant\tshape\tbatch\treference\n"
                     "demo\tbase\tdisk\tdisk-base\tbase\n"
                     "demo\tcheap\tdisk\tdisk-cheap\tbase\n"
                     "demo\tmissing\tdisk\tdisk-missing\tbase\n")


def test_study_compare_lists_every_paired_run(spaced_tmp):
    make_pair_of_batches(str(spaced_tmp))
    out = spaced_tmp / "transitions.csv"
    result = run_tool([PYTHON, REPO / "tools" / "study_compare.py", spaced_tmp / "disk-base",
                       spaced_tmp / "disk-cheap", "-o", out])
    assert result.returncode == 0, result.stderr
    rows = read_csv(out)
    assert len(rows) == 8
    assert sorted(int(row["seed"]) for row in rows if row["changed"] == "1") == [2, 5]
    assert "8 paired runs, 2 changed outcome" in result.stdout


def test_speed_accuracy_metrics_table_and_plots(spaced_tmp):
    make_pair_of_batches(str(spaced_tmp))
    out = spaced_tmp / "analysis"
    result = run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", spaced_tmp / "manifest.tsv", "-o", out])
    assert result.returncode == 0, result.stderr
    rows = {row["variant"]: row for row in read_csv(out / "comparison.csv")}
    cheap = rows["cheap"]
    assert cheap["status"] == "compared"
    assert int(cheap["paired_runs"]) == 8
    assert float(cheap["outcome_agreement"]) == pytest.approx(6 / 8, rel=1e-12)
    # Every run collided in both: the relative error of v_n is the factor's 0.1 on every run.
    assert int(cheap["vn_runs"]) == 8
    assert float(cheap["vn_error"]) == pytest.approx(0.1, rel=1e-9)
    # Fake runs: wall 0.01 s over 10 ms simulated -> 1e-3 s per simulated ms.
    assert float(cheap["cost_per_ms_s"]) == pytest.approx(1.0e-3, rel=1e-9)
    assert float(cheap["cost_ratio"]) == pytest.approx(1.0, rel=1e-9)      # same fake cost
    # The gap histories are the same in both batches but for the two flipped runs: every run has a
    # smallest gap, and the median error is that of the six identical runs.
    assert int(cheap["gap_runs"]) == 8
    assert float(cheap["gap_error"]) == 0.0
    # The same for the gap at 1 ms (every fake run lasts 10 ms); the fake decks have no &dlvo, so
    # no run enters a DLVO range and the entry time has no error to give.
    assert int(cheap["gap1ms_runs"]) == 8
    assert float(cheap["gap1ms_error"]) == 0.0
    assert int(cheap["entry_runs"]) == 0 and cheap["entry_error"] == ""
    assert rows["base"]["status"] == "reference"
    assert rows["missing"]["status"] == "not run"
    table = (out / "speed_accuracy.md").read_text()
    assert "| disk | cheap | base | 8 | 0.750 [" in table
    for metric in ("outcome_disagreement", "vn_error", "chi_error", "vmax_error", "gap_error"):
        assert (out / f"pareto_{metric}.png").stat().st_size > 1000


def test_speed_accuracy_names_a_batch_without_complete_runs_by_its_name(spaced_tmp):
    """A batch whose runs all stopped (the code refuses a too-thin disk at its start) is reported in
    the published table by its manifest name, not by the path of the machine that ran it."""
    make_pair_of_batches(str(spaced_tmp))
    refused = spaced_tmp / "disk-refused"
    (refused / "run_0001").mkdir(parents=True)
    (refused / "run_0001" / "agglo.log").write_text("error: the disk is too thin for this grid\n")
    (refused / "batch.conf").write_text("base_seed=1\n")
    with open(spaced_tmp / "manifest.tsv", "a") as handle:
        handle.write("demo\trefused\tdisk\tdisk-refused\tbase\n")
    out = spaced_tmp / "analysis"
    result = run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", spaced_tmp / "manifest.tsv", "-o", out,
                       "--no-figures"])
    assert result.returncode == 0, result.stderr
    status = {row["variant"]: row["status"] for row in read_csv(out / "comparison.csv")}["refused"]
    assert status.startswith("no comparison: no complete run in disk-refused:"), status
    assert str(spaced_tmp) not in (out / "speed_accuracy.md").read_text()


def test_run_tables_stand_for_their_batches(spaced_tmp):
    """A study spanning sessions keeps only each batch's run table (study_compare.py --table): the
    analysis read from the tables must give what it gives from the run directories, every value
    read back exactly (a float is written with all its digits), and a batch whose root is absent
    and whose table is missing stays 'not run'."""
    study = spaced_tmp / "study"
    make_pair_of_batches(str(study))
    tables = spaced_tmp / "tables"
    tables.mkdir()
    for name in ("disk-base", "disk-cheap"):
        result = run_tool([PYTHON, REPO / "tools" / "study_compare.py", "--table", study / name,
                           "-o", tables / f"{name}.csv"])
        assert result.returncode == 0, result.stderr
        assert "8 runs" in result.stdout
    from_dirs = spaced_tmp / "from-dirs"
    assert run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", study / "manifest.tsv", "-o", from_dirs,
                     "--no-figures"]).returncode == 0
    for name in ("disk-base", "disk-cheap"):
        (study / name).rename(spaced_tmp / f"{name}-gone")
    from_tables = spaced_tmp / "from-tables"
    result = run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", study / "manifest.tsv", "-o", from_tables,
                       "--no-figures", "--tables", tables])
    assert result.returncode == 0, result.stderr
    expected, got = read_csv(from_dirs / "comparison.csv"), read_csv(from_tables / "comparison.csv")
    assert got == expected
    assert {row["variant"]: row["status"] for row in got} == {"base": "reference", "cheap": "compared",
                                                             "missing": "not run"}
    # Without the tables the absent roots are 'not run'.
    result = run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", study / "manifest.tsv", "-o",
                       spaced_tmp / "none", "--no-figures"])
    assert {row["status"] for row in read_csv(spaced_tmp / "none" / "comparison.csv")} == {"not run"}


def test_a_batch_continued_from_its_run_table_counts_both(spaced_tmp):
    """A batch continued in a later session (montecarlo.sh --from-run 5) holds runs 5-8 as directories
    and runs 1-4 as its earlier_runs.csv: the analysis and the saved table must be what the whole
    batch of directories gives; while none of its own runs is complete it is the earlier rows."""
    study = spaced_tmp / "study"
    make_pair_of_batches(str(study))
    whole = spaced_tmp / "whole"
    assert run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", study / "manifest.tsv", "-o", whole,
                     "--no-figures", "--save-tables", whole / "tables"]).returncode == 0
    table = read_csv(whole / "tables" / "disk-cheap.csv")
    assert run_tool([PYTHON, REPO / "tools" / "batch_costs.py", study, "-o", whole / "costs.tsv"]).returncode == 0
    with open(study / "disk-cheap" / "earlier_runs.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(table[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows(table[:4])
    for seed in range(1, 5):
        (study / "disk-cheap" / f"run_{seed:04d}").rename(spaced_tmp / f"gone_{seed}")
    continued = spaced_tmp / "continued"
    result = run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", study / "manifest.tsv", "-o", continued,
                       "--no-figures", "--save-tables", continued / "tables"])
    assert result.returncode == 0, result.stderr
    assert read_csv(continued / "comparison.csv") == read_csv(whole / "comparison.csv")
    assert read_csv(continued / "tables" / "disk-cheap.csv") == table
    assert run_tool([PYTHON, REPO / "tools" / "batch_costs.py", study, "-o", continued / "costs.tsv"]).returncode == 0
    assert read_csv(continued / "costs.tsv", "\t") == read_csv(whole / "costs.tsv", "\t")     # 8 runs each
    # Runs 5-8 not complete (FAILED): the batch is its four earlier runs, seeds 1-4.
    for seed in range(5, 9):
        (study / "disk-cheap" / f"run_{seed:04d}" / "FAILED").write_text("reason: test\n")
    result = run_tool([PYTHON, REPO / "tools" / "study_compare.py", study / "disk-base", study / "disk-cheap"])
    assert result.returncode == 0, result.stderr
    assert "4 paired runs, 1 changed outcome" in result.stdout       # seed 2 of the flips 2 and 5


def test_save_tables_writes_one_table_per_batch_present(spaced_tmp):
    make_pair_of_batches(str(spaced_tmp))
    saved = spaced_tmp / "saved"
    result = run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", spaced_tmp / "manifest.tsv", "-o",
                       spaced_tmp / "analysis", "--no-figures", "--save-tables", saved])
    assert result.returncode == 0, result.stderr
    assert sorted(path.name for path in saved.iterdir()) == ["disk-base.csv", "disk-cheap.csv"]
    rows = read_csv(saved / "disk-cheap.csv")
    assert [int(row["seed"]) for row in rows] == list(range(1, 9))
    # Odd seeds agglomerate; the variant flips seeds 2 and 5: agglomerated 1, 2, 3, 7.
    assert [int(row["seed"]) for row in rows if row["outcome"] == "agglomerated"] == [1, 2, 3, 7]


def test_a_run_table_without_its_columns_is_refused(spaced_tmp):
    table = spaced_tmp / "disk-base.csv"
    table.write_text("run,seed\nrun_0001,1\n")
    result = run_tool([PYTHON, REPO / "tools" / "study_compare.py", table, table])
    assert result.returncode == 1
    assert "lacks the column(s) outcome" in result.stderr


def test_pareto_front_keeps_the_non_dominated_points():
    points = [(1.0, 0.5), (2.0, 0.2), (3.0, 0.3), (4.0, 0.1), (0.5, 0.9), (2.0, 0.6)]
    assert pareto_front(points) == [4, 0, 1, 3]


def test_spread_labels_stacks_overlapping_labels_and_keeps_the_others():
    # Three labels at nearly one anchor (the resolved variants of nearly one cost and error) are
    # stacked a label height apart from the lowest (the third, at 6, moves up past 5 + 9 to
    # 6 + 2 x 9); a label far to the right and one far above stay put.
    anchors = [(10.0, 5.0), (10.0, 5.0), (12.0, 6.0), (200.0, 5.0), (11.0, 100.0)]
    placed = spread_labels(anchors, width=50.0, height=9.0)
    assert placed[3] == (200.0, 5.0) and placed[4] == (11.0, 100.0)    # the anchors, unchanged
    assert [y for x, y in placed[:3]] == pytest.approx([5.0, 14.0, 24.0], abs=1e-12)
    for k in range(len(placed)):
        for j in range(k):
            overlap = abs(placed[k][0] - placed[j][0]) < 50.0 and abs(placed[k][1] - placed[j][1]) < 9.0
            assert not overlap, (k, j)


def test_speed_accuracy_refuses_a_manifest_without_columns(spaced_tmp):
    manifest = spaced_tmp / "manifest.tsv"
    manifest.write_text("knob\tvariant\n grid\tbase\n")
    result = run_tool([PYTHON, REPO / "tools" / "speed_accuracy.py", manifest])
    assert result.returncode == 1
    assert "lacks the column(s) shape, batch, reference" in result.stderr


def test_batch_costs_sums_the_runs_wall_times(spaced_tmp):
    make_pair_of_batches(str(spaced_tmp))
    out = spaced_tmp / "costs.tsv"
    result = run_tool([PYTHON, REPO / "tools" / "batch_costs.py", spaced_tmp, "-o", out])
    assert result.returncode == 0, result.stderr
    rows = {os.path.basename(row["batch"]): row for row in read_csv(out, "\t")}
    assert sorted(rows) == ["disk-base", "disk-cheap"]
    assert int(rows["disk-base"]["complete"]) == 8
    assert float(rows["disk-base"]["wall_sum_s"]) == pytest.approx(0.08, abs=0.05)


# ---------------------------------------------------------------------------------------------
# The study scripts on the real decks
# ---------------------------------------------------------------------------------------------

def test_study_scripts_list_their_batches():
    result = run_tool([REPO / "tools" / "quiescent-resolved-study.sh", "--list"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    names = [line.split()[0] for line in result.stdout.splitlines() if not line.startswith("forced")]
    assert names == ["needle-none", "needle-stokes-first_contact", "disk-none", "disk-stokes-first_contact",
                     "needle-resolved-start", "needle-resolved-first_contact", "disk-resolved-start",
                     "disk-resolved-first_contact"]
    result = run_tool([REPO / "tools" / "chaotic-study.sh", "--list"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    batches = [line.split()[:2] for line in result.stdout.splitlines() if not line.startswith("forced")]
    assert batches == [[f"{shape}-{rung}", runs] for rung, runs in (("resolved", "60"), ("point", "120"))
                       for shape in ("needle", "disk", "sphere")]
    result = run_tool([REPO / "tools" / "near-contact-study.sh", "--list", "--point-runs", "20",
                       "--resolved-runs", "8", "--shapes", "needle disk"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    lines = [line.split() for line in result.stdout.splitlines() if not line.startswith("forced")]
    assert [line[:2] for line in lines] == [[f"{shape}-{rung}-{model}", runs]
                                            for rung, runs in (("point", "20"), ("resolved", "8"))
                                            for shape in ("needle", "disk") for model in ("omission", "lubrication")]
    assert all(("collision.lubrication=.true." in line) == line[0].endswith("lubrication") for line in lines)
    assert all(("collision.lubrication=.false." in line) == line[0].endswith("omission") for line in lines)
    # The variants of the lubricated batch: one more batch per shape and variant, the model on.
    result = run_tool([REPO / "tools" / "near-contact-study.sh", "--list", "--rungs", "point", "--point-runs", "20",
                       "--shapes", "disk", "--roughness", "1e-10 1e-8", "--tangential", "--noise",
                       "--variant-runs", "10"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    lines = [line.split() for line in result.stdout.splitlines() if not line.startswith("forced")]
    assert [line[:2] for line in lines] == [["disk-point-omission", "20"], ["disk-point-lubrication", "20"],
                                            ["disk-point-lubrication-roughness1e-10", "10"],
                                            ["disk-point-lubrication-roughness1e-8", "10"],
                                            ["disk-point-lubrication-tangential", "10"],
                                            ["disk-point-lubrication-noise", "10"]]
    assert all("collision.lubrication=.true." in line for line in lines[1:])
    assert "collision.lubrication_roughness=1e-10" in lines[2]
    assert "collision.lubrication_tangential=.true." in lines[4] and "pair.gap=2.000000000002e-6" in lines[5]
    result = run_tool([REPO / "tools" / "near-contact-study.sh", "--list", "--roughness", "1nm"], cwd=REPO)
    assert result.returncode == 2 and "'1nm' is not a gap in m" in result.stderr
    # The speed-accuracy knobs omit the squeeze film (the published tables), or model it with --lubrication.
    for flag, value in (([], ".false."), (["--lubrication"], ".true.")):
        result = run_tool([REPO / "tools" / "speed-accuracy-study.sh", "--list", "--shapes", "disk", "--knobs",
                           "grid fidelity", "--no-reuse", "--no-tables"] + flag, cwd=REPO)
        assert result.returncode == 0, result.stderr
        lines = [line for line in result.stdout.splitlines() if line.startswith("disk-")]
        assert len(lines) >= 5 and all(f"collision.lubrication={value}" in line for line in lines)
        # The disk is 3.28 cells thick at 96^3 (docs/theory.md, "Thin bodies"): the code refuses the
        # deck, and the study leaves the batch out with the code's reason instead of failing its runs.
        assert not any(line.startswith("disk-grid96") for line in lines)
        assert ("batch disk-grid96: not run: the code refuses its deck: deck: &pair radius = 5.00000E-05 "
                "(disk 3.28 cells thin on this grid)") in result.stdout
    result = run_tool([REPO / "tools" / "speed-accuracy-study.sh", "--list", "--shapes", "disk",
                       "--knobs", "diffusion substep"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    assert "disk-cn5" in result.stdout and "run.dt=2.4e-05" in result.stdout
    assert "scene.particle_substeps=120" in result.stdout
    assert "disk-dt2.4e-6" in result.stdout and "run.dt=2.4e-6" in result.stdout
    assert "disk-substep2.4e-6" in result.stdout and "scene.particle_substeps=2" in result.stdout


def test_study_slurm_scripts_and_forced_field_dependency(spaced_tmp):
    out = spaced_tmp / "sa"
    # Run from a directory of its own (the decks linked in), so that no forced field computed in the
    # repository's output/ hides the one this test expects the script to schedule.
    work = spaced_tmp / "work"
    work.mkdir()
    (work / "input").symlink_to(REPO / "input")
    result = run_tool([REPO / "tools" / "speed-accuracy-study.sh", "--slurm", "-o", out, "-N", "2",
                       "--shapes", "needle", "--knobs", "grid", "--runs-256", "0",
                       "--sbatch-option", "--partition=short"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    submit = (out / "submit-all.sh").read_text()
    assert run_tool(["bash", "-n", out / "submit-all.sh"]).returncode == 0
    # One converged field, the base decks' 128^3 one; no field is converged on another grid.
    field = out / "slurm" / "forced_field_hit_box_128.sbatch"
    text = field.read_text()
    assert "#SBATCH --partition=short" in text and "grid.nx=128" in text
    assert run_tool(["bash", "-n", field]).returncode == 0
    assert sorted(path.name for path in (out / "slurm").glob("forced_field_*")) == ["forced_field_hit_box_128.sbatch"]
    # The 96^3 and 192^3 fields are that field resampled, by a one-task job after the field's job.
    regrid = out / "slurm" / "regrid_field_hit_box_128_on_96.sbatch"
    text = regrid.read_text()
    assert "#SBATCH --ntasks=1" in text and "#SBATCH --partition=short" in text
    assert "regrid_field.py output/hit_box_128/final_field.h5 --grid 96 -o output/hit_box_128_on_96/final_field.h5" in text
    assert run_tool(["bash", "-n", regrid]).returncode == 0
    assert "field_128=$(sbatch --parsable" in submit
    assert "field_128_on_96=$(sbatch --parsable --dependency=afterok:$field_128 " in submit
    assert "field_128_on_192=$(sbatch --parsable --dependency=afterok:$field_128 " in submit
    # Each grid batch waits for its own field; the batch script is montecarlo.sh's.
    assert "--dependency=afterok:$field_128_on_96" in submit and "needle-grid96/montecarlo.sbatch" in submit
    assert submit.index("field_128=") < submit.index("field_128_on_96=") < submit.index("needle-grid96/montecarlo")
    base_line = next(line for line in submit.splitlines() if "needle-base/montecarlo.sbatch" in line)
    assert "--dependency=afterok:$field_128 " in base_line
    batch = (out / "needle-grid96" / "montecarlo.sbatch").read_text()
    assert "#SBATCH --array=1-2" in batch and "#SBATCH --ntasks=2" in batch
    assert "#SBATCH --partition=short" in batch
    assert "output/hit_box_128_on_96/final_field.h5" in (out / "needle-grid96" / "batch.nml").read_text()
    manifest = read_csv(out / "manifest.tsv", "\t")
    assert [(row["variant"], row["reference"]) for row in manifest] == [
        ("grid96", "grid192"), ("base", "grid192"), ("grid192", "grid192")]


def test_study_regrids_an_existing_base_field_at_once(spaced_tmp):
    """With the base decks' field present, the grid variants' fields are made when the script
    runs (tools/regrid_field.py, seconds), also under --slurm: the batch then waits for nothing.
    A tiny synthetic base field (8^3, same box) stands in for the converged 128^3 one."""
    work, out = spaced_tmp / "work", spaced_tmp / "sa"
    (work / "output" / "hit_box_128").mkdir(parents=True)
    (work / "input").symlink_to(REPO / "input")
    field = solenoidal_random_field((8, 8, 8), box=(1.0e-3, 1.0e-3, 1.0e-3))
    write_final_field(work / "output" / "hit_box_128" / "final_field.h5", field)
    command = [REPO / "tools" / "speed-accuracy-study.sh", "-o", out, "-N", "2", "--shapes", "needle",
               "--knobs", "grid", "--runs-256", "0"]
    listed = run_tool(command + ["--list"], cwd=work)
    assert listed.returncode == 0, listed.stderr
    assert ("regridded field output/hit_box_128_on_96/final_field.h5: MISSING (tools/regrid_field.py: "
            "output/hit_box_128/final_field.h5 resampled onto 96^3, made first)") in listed.stdout
    assert "forced field output/hit_box_128/final_field.h5: present" in listed.stdout
    result = run_tool(command + ["--slurm", "--only", "^needle-grid96$"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    regridded = work / "output" / "hit_box_128_on_96" / "final_field.h5"
    with h5py.File(regridded, "r") as handle:
        assert list(handle["fluid/grid_shape"][()]) == [96, 96, 96]
        assert list(handle["forcing/state"][()]) == list(field["forcing_state"])
    submit = (out / "submit-all.sh").read_text()
    assert "dependency" not in submit and "needle-grid96/montecarlo.sbatch" in submit
    assert not list((out / "slurm").glob("*.sbatch"))
    times = read_csv(out / "batch_times.tsv", "\t")
    assert [(row["batch"], row["status"]) for row in times] == [("regrid_field_hit_box_128_on_96", "0")]
    # Made once: a second call finds it (and never overwrites it).
    before = regridded.stat().st_mtime_ns
    listed = run_tool(command + ["--list"], cwd=work)
    assert "regridded field output/hit_box_128_on_96/final_field.h5: present" in listed.stdout
    assert regridded.stat().st_mtime_ns == before


def test_study_skips_tabled_batches_only_on_the_same_field(spaced_tmp, agglo):
    """A batch whose committed run table has its runs is not scheduled again, the others are; a
    table computed from another base field (another fingerprint in FIELD), or with no base field
    here, does not stand for its batch. A tiny synthetic base field stands in for the converged
    128^3 one."""
    work, out, tables = spaced_tmp / "work", spaced_tmp / "sa", spaced_tmp / "tables"
    (work / "output" / "hit_box_128").mkdir(parents=True)
    (work / "input").symlink_to(REPO / "input")
    base_field = work / "output" / "hit_box_128" / "final_field.h5"
    write_final_field(base_field, solenoidal_random_field((8, 8, 8), box=(1.0e-3, 1.0e-3, 1.0e-3)))
    tables.mkdir()
    from study_compare import RUN_TABLE_COLUMNS
    (tables / "disk-base.csv").write_text(",".join(RUN_TABLE_COLUMNS) + "\n" + "run_0001,1001\nrun_0002,1002\n")
    deck = run_tool([agglo, "input/chaotic_disk_resolved.nml", "--set", "output.field_interval=0.0", "--set",
                     "collision.lubrication=.false.", "--print-deck"],
                    cwd=REPO)
    assert deck.returncode == 0, deck.stderr
    (tables / "disk-base.nml").write_text(deck.stdout)
    fingerprint = run_tool([PYTHON, REPO / "tools" / "regrid_field.py", base_field, "--fingerprint"])
    assert fingerprint.returncode == 0, fingerprint.stderr
    (tables / "FIELD").write_text(fingerprint.stdout)
    command = [REPO / "tools" / "speed-accuracy-study.sh", "-o", out, "-N", "2", "--shapes", "disk",
               "--knobs", "noise", "--tables", tables, "--slurm"]
    result = run_tool(command, cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert f"batch disk-base: from its run table {tables}/disk-base.csv (2 runs), not run" in result.stdout
    submit = (out / "submit-all.sh").read_text()
    assert "disk-perturbed/montecarlo.sbatch" in submit and "disk-base" not in submit
    # Three runs asked for: the 2-run table no longer stands for the batch; the batch continues
    # after its two tabled runs (run 3 alone in the array) and keeps them as earlier_runs.csv.
    result = run_tool(command[:3] + ["-N", "3"] + command[5:], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert "disk-base/montecarlo.sbatch" in (out / "submit-all.sh").read_text()
    assert f"batch disk-base: runs 1-2 from its run table {tables}/disk-base.csv, runs 3-3 here" in result.stdout
    assert "#SBATCH --array=3\n" in (out / "disk-base" / "montecarlo.sbatch").read_text()
    assert (out / "disk-base" / "earlier_runs.csv").read_text() == (tables / "disk-base.csv").read_text()
    # A continued call stopped before it kept the table (its root holds none of runs 1-2) continues
    # when called again; a root that holds one of runs 1-2 was begun here from run 1 and does not.
    (out / "disk-base" / "earlier_runs.csv").unlink()
    result = run_tool(command[:3] + ["-N", "3"] + command[5:], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert "runs 3-3 here" in result.stdout
    assert "#SBATCH --array=3\n" in (out / "disk-base" / "montecarlo.sbatch").read_text()
    assert (out / "disk-base" / "earlier_runs.csv").read_text() == (tables / "disk-base.csv").read_text()
    (out / "disk-base" / "earlier_runs.csv").unlink()
    (out / "disk-base" / "run_0002").mkdir()
    result = run_tool(command[:3] + ["-N", "3"] + command[5:], cwd=work)
    assert "runs 3-3 here" not in result.stdout
    assert not (out / "disk-base" / "earlier_runs.csv").exists()
    # A table that is not runs 1..M of the batch (run 2 missing) does not continue it.
    gapped = spaced_tmp / "gapped-tables"
    shutil.copytree(tables, gapped)
    (gapped / "disk-base.csv").write_text(",".join(RUN_TABLE_COLUMNS) + "\n" + "run_0001,1001\nrun_0003,1003\n")
    result = run_tool(command[:3] + ["-N", "3"] + command[5:9] + ["--tables", gapped, "--slurm", "-o",
                                                                   spaced_tmp / "gapped"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert "runs 1-2 from its run table" not in result.stdout
    assert "#SBATCH --array=1-3" in (spaced_tmp / "gapped" / "disk-base" / "montecarlo.sbatch").read_text()
    assert not (spaced_tmp / "gapped" / "disk-base" / "earlier_runs.csv").exists()
    # Runs from another base seed, or of another deck, do not stand for the batch either.
    result = run_tool(command + ["-o", spaced_tmp / "seed", "--seed", "2001"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert "disk-base/montecarlo.sbatch" in (spaced_tmp / "seed" / "submit-all.sh").read_text()
    (tables / "disk-base.nml").write_text(deck.stdout.replace("field_interval = 0.0", "field_interval = 1.0"))
    result = run_tool(command + ["-o", spaced_tmp / "deck"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert "disk-base/montecarlo.sbatch" in (spaced_tmp / "deck" / "submit-all.sh").read_text()
    (tables / "disk-base.nml").write_text(deck.stdout)
    # Another field: the table is not used (both fingerprints named) and the batch runs here.
    (tables / "FIELD").write_text("0" * 64 + "  output/hit_box_128/final_field.h5\n")
    result = run_tool(command + ["-o", spaced_tmp / "other"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert "computed from a base field with fingerprint " + "0" * 64 in result.stdout
    assert fingerprint.stdout.split()[0] in result.stdout
    assert "disk-base/montecarlo.sbatch" in (spaced_tmp / "other" / "submit-all.sh").read_text()
    # No base field here: likewise, said once.
    base_field.unlink()
    (tables / "FIELD").write_text(fingerprint.stdout)
    result = run_tool(command + ["-o", spaced_tmp / "nofield"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    assert result.stdout.count("final_field.h5 is missing: the tables of batches that start from it are not used") == 1
    assert "disk-base/montecarlo.sbatch" in (spaced_tmp / "nofield" / "submit-all.sh").read_text()


def test_study_without_a_usable_base_field_schedules_no_grid_batch(spaced_tmp):
    """A base field that tools/regrid_field.py cannot read: the study says so, exits 1, and writes
    no Slurm script for the batches that would start from the missing resampled field."""
    work, out = spaced_tmp / "work", spaced_tmp / "sa"
    (work / "output" / "hit_box_128").mkdir(parents=True)
    (work / "input").symlink_to(REPO / "input")
    (work / "output" / "hit_box_128" / "final_field.h5").write_text("not a field\n")
    result = run_tool([REPO / "tools" / "speed-accuracy-study.sh", "-o", out, "-N", "2", "--shapes", "needle",
                       "--knobs", "grid", "--runs-256", "0", "--slurm", "--only", "grid96"], cwd=work)
    assert result.returncode == 1, result.stderr + result.stdout
    assert "regridded field output/hit_box_128_on_96/final_field.h5 failed" in result.stderr
    assert "not an HDF5 file" in (out / "regrid_field_hit_box_128_on_96.log").read_text()
    assert not (out / "needle-grid96" / "montecarlo.sbatch").exists()
    assert not (work / "output" / "hit_box_128_on_96").exists()


def test_study_runs_resumes_and_records_costs(spaced_tmp, agglo, monkeypatch):
    out = spaced_tmp / "q"
    published = spaced_tmp / "published"
    monkeypatch.setenv("AGGLO_STUDY_PUBLISH_DIR", str(published))
    command = [REPO / "tools" / "quiescent-resolved-study.sh", "-o", out, "--only", "^needle-none$",
               "--cheap-runs", "2", "-j", "2"]
    # What an earlier session (another output root, gone) published: kept, the batch's row replaced.
    published.mkdir()
    costs_header = "batch\tcomplete\tfailed\twall_sum_s\twall_median_s\twall_max_s\tsimulated_median_ms\t" \
                   "wall_per_simulated_ms_median_s\n"
    (published / "batch_costs.tsv").write_text(costs_header + "disk-old\t3\t0\t9.0\t3\t3\t3\t1\n"
                                               + "needle-none\t1\t0\t1.0\t1\t1\t3\t0.3\n")
    old_time = "disk-old\t3\t1\t3\t9.5\t0\t2026-01-01T00:00:00+00:00\n"
    (published / "batch_times.tsv").write_text("batch\truns\tjobs\truns_run_by_this_call\twall_seconds\tstatus\t"
                                               "date\n" + old_time)
    first = run_tool(command + ["--publish"], cwd=REPO)
    assert first.returncode == 0, first.stderr + first.stdout
    second = run_tool(command, cwd=REPO)
    assert second.returncode == 0, second.stderr + second.stdout
    # The end checkpoint every pair-scene run writes is pruned from complete runs; the analysis'
    # inputs stay.
    assert not list(out.glob("needle-none/run_*/checkpoints/checkpoint_*.h5"))
    assert len(list(out.glob("needle-none/run_*/particles.h5"))) == 2
    times = read_csv(out / "batch_times.tsv", "\t")
    assert [row["runs_run_by_this_call"] for row in times] == ["2", "0"]
    costs = read_csv(out / "batch_costs.tsv", "\t")
    assert [(os.path.basename(row["batch"]), row["complete"]) for row in costs] == [("needle-none", "2")]
    status = run_tool(command + ["--status"], cwd=REPO)
    assert status.returncode == 0 and "2 complete" in status.stdout
    assert (out / "stats-all" / "rates.csv").exists()
    # --publish: the tables without the output root in their paths, no runs.csv.
    costs_published = (published / "batch_costs.tsv").read_text()
    assert "needle-none\t2\t" in costs_published and str(out) not in costs_published
    assert [line.split("\t")[0] for line in costs_published.splitlines()] == ["batch", "disk-old", "needle-none"]
    times_published = (published / "batch_times.tsv").read_text().splitlines()
    assert times_published[1] == old_time.strip() and times_published[2].startswith("needle-none\t2\t")
    assert len(times_published) == 3
    assert (published / "stats-all_rates.csv").exists()
    assert not list(published.glob("*runs.csv"))


def test_study_reuses_the_runs_of_an_identical_batch(spaced_tmp, agglo):
    """--reuse-from: the complete runs of a batch with the same base deck and seed are hard-linked
    in and not run again; a batch of another deck takes nothing from it."""
    first, second = spaced_tmp / "first", spaced_tmp / "second"
    command = [REPO / "tools" / "speed-accuracy-study.sh", "--knobs", "fidelity", "--shapes", "disk",
               "--no-analysis", "--no-tables"]      # not the committed run tables of docs/
    result = run_tool(command + ["-o", first, "-N", "2", "--no-reuse", "--only", "^disk-none$"], cwd=REPO)
    assert result.returncode == 0, result.stderr + result.stdout
    result = run_tool(command + ["-o", second, "-N", "3", "--reuse-from", first, "--only", "^disk-(none|stokes)$"],
                      cwd=REPO)
    assert result.returncode == 0, result.stderr + result.stdout
    reused = [line for line in result.stdout.splitlines() if "reused" in line]
    assert reused == [f"== batch {second}/disk-none: 2 complete runs reused from {first}/disk-none (same deck and seeds)"]
    times = read_csv(second / "batch_times.tsv", "\t")
    assert [(os.path.basename(row["batch"]), row["runs_run_by_this_call"]) for row in times] == [
        ("disk-stokes", "3"), ("disk-none", "1")]
    for run in ("run_0001", "run_0002"):
        assert os.path.samefile(first / "disk-none" / run / "summary.json", second / "disk-none" / run / "summary.json")
    assert (second / "disk-none" / "run_0003" / "summary.json").exists()
    assert not (first / "disk-none" / "run_0003").exists()


def test_compare_outcomes_names_the_changed_seeds_and_the_first_contact_error(spaced_tmp):
    """compare_outcomes.py: the seeds whose outcome changed, the signed error of the first-contact
    normal speed over the runs that touch in both (median and range), the median wall per run."""
    plan = {1: ("agglomerated", 1.0e-3, "rebounded", 1.2e-3), 2: ("agglomerated", 2.0e-3, "agglomerated", 2.2e-3),
            3: ("agglomerated", 1.0e-3, "approached", None), 4: ("rebounded", 4.0e-3, "rebounded", 3.6e-3)}
    for seed, (base_outcome, base_speed, variant_outcome, variant_speed) in plan.items():
        for batch, outcome, speed, wall in (("base", base_outcome, base_speed, 10.0 + seed),
                                            ("variant", variant_outcome, variant_speed, 20.0 + seed)):
            directory = spaced_tmp / batch / f"run_{seed:04d}"
            write_run(directory, seed, outcome=outcome)
            with open(directory / "summary.json") as handle:
                summary = json.load(handle)
            if speed is not None:
                summary["first_collision"]["normal_velocity_before"] = speed
            summary["wall_time"] = wall
            with open(directory / "summary.json", "w") as handle:
                json.dump(summary, handle)
    result = run_tool([PYTHON, REPO / "tools" / "compare_outcomes.py", spaced_tmp / "base", spaced_tmp / "variant"])
    assert result.returncode == 0, result.stderr
    assert "changed: 1 agglomerated -> rebounded; 3 agglomerated -> approached" in result.stdout
    # +20%, +10%, -10%: seed 3 does not touch in the variant.
    assert ("first-contact normal speed, variant against base: +10.0% (signed median; -10.0% to +20.0%) "
            "over 3 runs touching in both") in result.stdout
    assert "wall per run (median): base 12.5 s, variant 22.5 s" in result.stdout
