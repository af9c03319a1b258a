"""tools/montecarlo.sh with REAL runs of the built code ($AGGLO, set by tests/run_tests.sh) on a pair
deck of input/ at &scene fluid = 'none' with a short end time, in directories with spaces."""
import hashlib
import json
import os
import re
import signal
import subprocess
import time

import pytest

from agglo_stats import wilson_interval
from conftest import AGGLO_STATS, MONTECARLO, REPO, run_tool

# Short runs: past the first contact of the quiescent protocol (5 um closed at 0.875 mm/s takes
# 5.7 ms; docs/design.md) but shorter than the protocol's equal time after it.
END_TIME = "8.0e-3"


def montecarlo(agglo, deck, runs, seed, root, *extra):
    return run_tool([MONTECARLO, "--deck", deck, "--runs", runs, "--seed", seed, "--out", root,
                     "--agglo", agglo, "--set", f"run.end_time={END_TIME}", *extra], cwd=REPO)


def summary(root, index):
    with open(os.path.join(root, f"run_{index:04d}", "summary.json")) as handle:
        return json.load(handle)


def complete_runs(root, runs):
    return {i for i in range(1, runs + 1)
            if os.path.exists(os.path.join(root, f"run_{i:04d}", "summary.json"))
            and not os.path.exists(os.path.join(root, f"run_{i:04d}", "FAILED"))}


def remove_group(text, group):
    """The deck text without namelist group &group (quote- and comment-aware, like the code)."""
    out, i, n = [], 0, len(text)
    match = re.compile(rf"&{group}\b", re.I)
    while i < n:
        m = match.search(text, i)
        if not m:
            out.append(text[i:])
            break
        out.append(text[i:m.start()])
        j, quote, comment = m.end(), None, False
        while j < n:
            c = text[j]
            if comment:
                comment = c != "\n"
            elif quote:
                quote = None if c == quote else quote
            elif c in "'\"":
                quote = c
            elif c == "!":
                comment = True
            elif c == "/":
                break
            j += 1
        i = j + 1
    return "".join(out)


def group_count(text, group):
    """How many times &group opens in a deck: '&' outside quotes and '!' comments, line by line
    as the code's deck_check_groups scans."""
    count = 0
    for line in text.splitlines():
        quote = None
        for i, char in enumerate(line):
            if quote:
                quote = None if char == quote else quote
            elif char in "'\"":
                quote = char
            elif char == "!":
                break
            elif char == "&" and re.match(rf"&{group}\b", line[i:], re.I):
                count += 1
    return count


def resolved_value(run_nml, variable):
    """A variable's value text in run.nml (the resolved deck the code writes), quotes stripped."""
    m = re.search(rf"(?<![\w%]){variable}\s*=\s*(\"[^\"]*\"|'[^']*'|[^,\s/]+)", run_nml, re.I)
    assert m, f"{variable} not in run.nml"
    return m.group(1).strip("'\"").strip()


def test_help_describes_the_interface():
    result = run_tool([MONTECARLO, "--help"])
    assert result.returncode == 0
    for option in ("--deck", "--runs", "--seed", "--out", "--jobs", "--ranks", "--slurm", "--time", "--min-free",
                   "Resume"):
        assert option in result.stdout, option


def test_bad_arguments_are_refused(agglo, spaced_tmp):
    deck = spaced_tmp / "deck.nml"
    deck.write_text("&scene fluid = 'none' /\n")
    result = montecarlo(agglo, deck, "0", "1", spaced_tmp / "root")
    assert result.returncode == 2 and "--runs '0' is not allowed" in result.stderr
    result = montecarlo(agglo, spaced_tmp / "missing.nml", "2", "1", spaced_tmp / "root")
    assert result.returncode == 2 and "is not a readable file" in result.stderr
    result = montecarlo(agglo, deck, "2", "1", spaced_tmp / "root", "--set", "run.seed=4")
    assert result.returncode == 2 and "run.seed is not allowed" in result.stderr
    result = montecarlo(agglo, deck, "2", "1", spaced_tmp / "root", "--from-run", "3")
    assert result.returncode == 2 and "--from-run '3' is not allowed; allowed: an integer from 1 to --runs (2)" \
        in result.stderr
    result = montecarlo(agglo, deck, "2", "1", spaced_tmp / "root", "--min-free", "-1")
    assert result.returncode == 2 and "--min-free '-1' is not allowed; allowed: whole MiB >= 0" in result.stderr
    (spaced_tmp / "unrelated").mkdir()
    (spaced_tmp / "unrelated" / "notes.txt").write_text("x")
    result = montecarlo(agglo, deck, "2", "1", spaced_tmp / "unrelated")
    assert result.returncode == 2 and "holds no batch" in result.stderr


@pytest.mark.parametrize("variant", ["without_run_and_output", "with_run_and_output"])
def test_run_decks_rewrite_run_and_output_groups(agglo, pair_deck, spaced_tmp, variant):
    base = remove_group(remove_group(open(pair_deck).read(), "run"), "output")
    if variant == "with_run_and_output":
        base += ("&run name = 'mine', ! a comment with seed = 5 / in it\n"
                 "     seed = 77, overwrite = .false.,\n"
                 f"     end_time = 1.0e-3, restart = .false. /\n"
                 "&output directory = 'somewhere/else', stats_interval = 3 /\n")
    deck = spaced_tmp / "base deck.nml"
    deck.write_text(base)
    root = spaced_tmp / "batch root"
    result = montecarlo(agglo, deck, "3", "40", root, "--slurm")
    assert result.returncode == 0, result.stderr
    text = (root / "run_0002" / "deck.nml").read_text()
    assert group_count(text, "run") == 1 and group_count(text, "output") == 1
    # The code itself reads the deck: run.nml (its resolved deck) names the run's identity.
    run = subprocess.run([agglo, str(root / "run_0002" / "deck.nml")], cwd=REPO,
                         capture_output=True, text=True, timeout=120)
    run_nml = (root / "run_0002" / "run.nml").read_text()
    assert resolved_value(run_nml, "name") == "run_0002", run.stdout + run.stderr
    assert int(resolved_value(run_nml, "seed")) == 41
    assert resolved_value(run_nml, "overwrite").upper() in ("T", ".TRUE.")
    assert resolved_value(run_nml, "restart").upper() in ("F", ".FALSE.")
    assert resolved_value(run_nml, "directory") == str(root / "run_0002")
    assert float(resolved_value(run_nml, "end_time")) == pytest.approx(float(END_TIME), rel=1e-12)
    if variant == "with_run_and_output":
        assert int(resolved_value(run_nml, "stats_interval")) == 3     # kept from the base deck


def test_another_base_deck_or_seed_is_refused(agglo, spaced_tmp):
    deck = spaced_tmp / "deck.nml"
    deck.write_text("&scene fluid = 'none', particles = 'pair' /\n")
    root = spaced_tmp / "root"
    assert montecarlo(agglo, deck, "2", "1", root, "--slurm").returncode == 0
    other = montecarlo(agglo, deck, "2", "1", root, "--slurm", "--set", "run.dt=1e-7")
    assert other.returncode == 2 and "another base deck" in other.stderr
    other = montecarlo(agglo, deck, "2", "9", root, "--slurm")
    assert other.returncode == 2 and "base seed 1, not 9" in other.stderr
    conf = (root / "batch.conf").read_text()
    digest = hashlib.sha256((root / "batch.nml").read_bytes()).hexdigest()
    assert "base_seed=1\n" in conf and f"deck_sha256={digest}\n" in conf
    assert "end_time = " + END_TIME in (root / "batch.nml").read_text()   # the --set is part of it


@pytest.fixture(scope="module")
def real_batch(pair_scene, tmp_path_factory):
    """A tiny batch of real runs: 4 runs, 2 at a time, seeds 101..104."""
    agglo, pair_deck = pair_scene
    root = tmp_path_factory.mktemp("real") / "tiny batch"
    result = montecarlo(agglo, pair_deck, "4", "101", root, "-j", "2")
    return root, result


def test_real_batch_completes_with_progress(real_batch):
    root, result = real_batch
    assert result.returncode == 0, result.stdout + result.stderr
    assert complete_runs(str(root), 4) == {1, 2, 3, 4}
    assert [summary(str(root), i)["seed"] for i in range(1, 5)] == [101, 102, 103, 104]
    assert [summary(str(root), i)["name"] for i in range(1, 5)] == [f"run_{i:04d}" for i in range(1, 5)]
    progress = [line for line in result.stdout.splitlines() if "| done" in line]
    assert len(progress) == 4 and "ETA" in progress[-1] and "remaining 0" in progress[-1]
    # The seed draws the orientations: four seeds give four different configurations.
    first_psi = {summary(str(root), i)["psi_final"] for i in range(1, 5)}
    assert len(first_psi) == 4


def test_real_batch_rerun_skips_complete_runs(pair_scene, real_batch):
    agglo, pair_deck = pair_scene
    root, _ = real_batch
    stamps = {i: os.stat(root / f"run_{i:04d}" / "summary.json").st_mtime_ns for i in range(1, 5)}
    again = montecarlo(agglo, pair_deck, "4", "101", root, "-j", "2")
    assert again.returncode == 0 and "4 already complete, 0 to run" in again.stdout
    assert stamps == {i: os.stat(root / f"run_{i:04d}" / "summary.json").st_mtime_ns for i in range(1, 5)}


def test_real_batch_statistics(real_batch, tmp_path):
    root, _ = real_batch
    out = tmp_path / "stats out"
    result = run_tool([AGGLO_STATS, root, "-o", out])
    assert result.returncode == 0, result.stderr
    summaries = [summary(str(root), i) for i in range(1, 5)]
    rows = (out / "rates.csv").read_text().splitlines()
    assert len(rows) == 2                                   # header + the deck's one shape
    header, values = rows[0].split(","), rows[1].split(",")
    row = dict(zip(header, values))
    assert row["shape"] == summaries[0]["shape"] and int(row["runs"]) == 4
    for outcome in ("agglomerated", "rebounded", "approached", "no_contact"):
        assert int(row[outcome]) == sum(s["outcome"] == outcome for s in summaries), outcome
    low, high = wilson_interval(int(row["agglomerated"]), 4)
    assert float(row["wilson_low"]) == pytest.approx(low, abs=1e-15)
    assert float(row["wilson_high"]) == pytest.approx(high, rel=1e-12)
    assert len((out / "runs.csv").read_text().splitlines()) == 5
    for stem in ("separation_pdf", "relative_velocity_pdf", "max_vdw_force_pdf", "psi_pdf",
                 "collision_points_pdf", "histories"):
        assert (out / f"{stem}.png").stat().st_size > 5000 and (out / f"{stem}.pdf").exists(), stem


def test_from_run_runs_only_the_later_runs(pair_scene, spaced_tmp):
    """--from-run 3: runs 1-2 are kept elsewhere (a study's run table): only run 3 runs, with seed
    S+2, and the batch is complete without runs 1-2."""
    agglo, pair_deck = pair_scene
    root = spaced_tmp / "continued batch"
    result = montecarlo(agglo, pair_deck, "3", "40", root, "--from-run", "3")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "3 runs (runs 1-2 kept elsewhere, --from-run), 0 already complete, 1 to run" in result.stdout
    assert complete_runs(str(root), 3) == {3} and summary(str(root), 3)["seed"] == 42
    assert not (root / "run_0001").exists()
    status = montecarlo(agglo, pair_deck, "3", "40", root, "--from-run", "3", "--status")
    assert status.returncode == 0 and "1 complete, 0 failed, 0 not run" in status.stdout
    status = montecarlo(agglo, pair_deck, "3", "40", root, "--status")   # all three: two not run
    assert status.returncode == 1 and "1 complete, 0 failed, 2 not run" in status.stdout


def test_no_run_starts_without_free_space(pair_scene, spaced_tmp):
    """--min-free above what any file system has (2^40 MiB): no run starts (a full disk would fail
    every run as it writes), the call says why and ends with status 1; called again with room, the
    batch completes."""
    agglo, pair_deck = pair_scene
    root = spaced_tmp / "no room"
    result = montecarlo(agglo, pair_deck, "2", "7", root, "-j", "2", "--min-free", str(2**40))
    assert result.returncode == 1, result.stdout + result.stderr
    assert "MiB free on the file system of" in result.stdout and "no further run starts" in result.stdout
    assert "2 run(s) not started for want of free space (--min-free 1099511627776 MiB)" in result.stdout
    assert complete_runs(str(root), 2) == set() and not (root / "run_0001").exists()
    result = montecarlo(agglo, pair_deck, "2", "7", root, "-j", "2")
    assert result.returncode == 0, result.stdout + result.stderr
    assert complete_runs(str(root), 2) == {1, 2}


def test_resume_after_the_batch_is_killed_mid_way(pair_scene, spaced_tmp):
    agglo, pair_deck = pair_scene
    root = spaced_tmp / "killed batch"
    command = [str(MONTECARLO), "--deck", pair_deck, "--runs", "3", "--seed", "7", "--out", str(root),
               "--agglo", agglo, "--set", f"run.end_time={END_TIME}", "-j", "1"]
    driver = subprocess.Popen(command, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    # The code has started run 2: agglo.log is opened after run.nml is written (io/run_directory),
    # so waiting for it leaves no window in which the kill lands between the two.
    started = root / "run_0002" / "agglo.log"
    deadline = time.time() + 120
    while not started.exists() and driver.poll() is None and time.time() < deadline:
        time.sleep(0.002)
    driver.send_signal(signal.SIGTERM)
    output, _ = driver.communicate(timeout=60)
    assert driver.returncode == 130, output             # interrupted, not finished
    assert "interrupted" in output
    before = complete_runs(str(root), 3)
    # Run 1 had finished; run 2 was killed mid-way: the code had started it (run.nml, agglo.log)
    # and it had not finished (no summary.json). A run of this deck takes ~0.3 s of wall time.
    assert 1 in before and 2 not in before and 3 not in before, output
    assert (root / "run_0002" / "agglo.log").exists()
    stamps = {i: os.stat(root / f"run_{i:04d}" / "summary.json").st_mtime_ns for i in before}
    time.sleep(1.0)
    assert complete_runs(str(root), 3) == before, "a run went on after its batch was stopped"
    resumed = montecarlo(agglo, pair_deck, "3", "7", root, "-j", "1")
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert f"{len(before)} already complete, {3 - len(before)} to run" in resumed.stdout
    assert complete_runs(str(root), 3) == {1, 2, 3}
    assert stamps == {i: os.stat(root / f"run_{i:04d}" / "summary.json").st_mtime_ns for i in before}


def test_failing_run_is_reported_and_the_others_complete(pair_scene, spaced_tmp):
    agglo, pair_deck = pair_scene
    # Seeds 2147483646..2147483648: the third leaves the code's 32-bit integer, so the code
    # refuses that deck (a namelist read error on &run) while runs 1 and 2 are fine.
    root = spaced_tmp / "failing batch"
    result = montecarlo(agglo, pair_deck, "3", "2147483646", root, "-j", "2")
    assert result.returncode == 1, result.stdout + result.stderr
    assert "run_0003 FAILED" in result.stdout
    assert complete_runs(str(root), 3) == {1, 2}
    failed = (root / "run_0003" / "FAILED").read_text()
    assert "exit status" in failed and "stdout.log" in failed
    assert "&run" in (root / "run_0003" / "stdout.log").read_text()
    assert (root / "failed.txt").read_text().startswith("run_0003\t")
    status = montecarlo(agglo, pair_deck, "3", "2147483646", root, "--status")
    assert status.returncode == 1 and "2 complete, 1 failed" in status.stdout
    stats = run_tool([AGGLO_STATS, root, "--no-figures"])
    assert stats.returncode == 0 and "skipped 1 run(s) of 3" in stats.stdout


def test_slurm_script_is_generated_and_runs_a_task(pair_scene, spaced_tmp):
    agglo, pair_deck = pair_scene
    root = spaced_tmp / "slurm batch"
    result = montecarlo(agglo, pair_deck, "3", "5", root, "--slurm", "-j", "2", "--ranks", "2",
                        "--time", "30", "--sbatch-option", "--partition=debug")
    assert result.returncode == 0, result.stderr
    script = root / "montecarlo.sbatch"
    assert subprocess.run(["bash", "-n", str(script)]).returncode == 0
    text = script.read_text()
    for line in ("#SBATCH --array=1-3%2", "#SBATCH --ntasks=2", "#SBATCH --time=30",
                 "#SBATCH --partition=debug"):
        assert line in text.splitlines(), line
    # Run array task 2 here as Slurm would (one rank, mpirun standing in for srun).
    local = montecarlo(agglo, pair_deck, "3", "5", root, "--slurm", "--launcher", "mpirun --oversubscribe")
    assert local.returncode == 0
    env = {**os.environ, "SLURM_ARRAY_TASK_ID": "2", "OMPI_ALLOW_RUN_AS_ROOT": "1",
           "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    task = subprocess.run(["bash", str(script)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert task.returncode == 0, (root / "run_0002" / "stdout.log").read_text()
    assert complete_runs(str(root), 3) == {2}
    again = montecarlo(agglo, pair_deck, "3", "5", root, "--slurm")
    assert "#SBATCH --array=1,3" in script.read_text().splitlines()
    assert again.returncode == 0
