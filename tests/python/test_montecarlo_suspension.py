"""tools/montecarlo.sh with REAL suspension runs of the built code ($AGGLO): the fast deck
input/suspension_sphere_none.nml (no fluid) shortened to 1 ms, in directories with spaces. A
suspension run has no pair outcome; the batch writes its summary.json, resumes, reports its status,
runs Slurm tasks and feeds agglo-stats' suspension mode."""
import json
import math
import os
import subprocess

import h5py
import numpy as np

from conftest import AGGLO_STATS, MONTECARLO, REPO, run_tool

DECK = REPO / "input" / "suspension_sphere_none.nml"
END_TIME = "1.0e-3"


def montecarlo(agglo, runs, seed, root, *extra):
    return run_tool([MONTECARLO, "--deck", DECK, "--runs", runs, "--seed", seed, "--out", root,
                     "--agglo", agglo, "--set", f"run.end_time={END_TIME}", *extra], cwd=REPO)


def summary(root, index):
    return json.loads((root / f"run_{index:04d}" / "summary.json").read_text())


def first_positions(directory):
    with h5py.File(directory / "particles.h5", "r") as h5:
        return np.asarray(h5["suspension/position"][0])


def test_suspension_batch_completes_resumes_and_feeds_the_statistics(agglo, spaced_tmp):
    root = spaced_tmp / "suspension batch"
    result = montecarlo(agglo, "2", "5", root, "-j", "2")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "all 2 runs complete" in result.stdout
    for index, seed in ((1, 5), (2, 6)):
        s = summary(root, index)
        assert s["scene"] == "suspension" and s["complete"] is True
        assert s["name"] == f"run_{index:04d}" and s["seed"] == seed
        assert s["end_time"] == float(END_TIME) and s["wall_time"] > 0.0
        assert s["clusters"] == (root / f"run_{index:04d}" / "clusters.h5").exists()
    # Seeds place the bodies: the two runs differ, and run 1 is the deck's own run at seed 5.
    assert not np.array_equal(first_positions(root / "run_0001"), first_positions(root / "run_0002"))
    direct = spaced_tmp / "direct"
    single = run_tool([agglo, DECK, "--set", "run.seed=5", "--set", f"run.end_time={END_TIME}",
                       "--set", f"output.directory='{direct}'"], cwd=REPO)
    assert single.returncode == 0, single.stderr
    assert np.array_equal(first_positions(direct), first_positions(root / "run_0001"))
    # Resume: complete runs are kept as they are.
    stamp = os.stat(root / "run_0001" / "summary.json").st_mtime_ns
    again = montecarlo(agglo, "2", "5", root)
    assert again.returncode == 0 and "2 already complete, 0 to run" in again.stdout
    assert os.stat(root / "run_0001" / "summary.json").st_mtime_ns == stamp
    # A summary that says the run is not complete makes it so.
    text = (root / "run_0002" / "summary.json").read_text()
    (root / "run_0002" / "summary.json").write_text(text.replace('"complete": true', '"complete": false'))
    status = montecarlo(agglo, "2", "5", root, "--status")
    assert status.returncode == 1 and "1 complete, 0 failed, 1 not run or incomplete" in status.stdout
    rerun = montecarlo(agglo, "2", "5", root)
    assert rerun.returncode == 0 and "1 already complete, 1 to run" in rerun.stdout
    assert summary(root, 2)["complete"] is True
    stats = run_tool([AGGLO_STATS, root, "-o", spaced_tmp / "stats", "--no-figures"])
    assert stats.returncode == 0, stats.stderr + stats.stdout
    document = json.loads((spaced_tmp / "stats" / "suspension.json").read_text())
    assert document["groups"]["sphere"]["runs"] == 2 and document["groups"]["sphere"]["seeds"] == [5, 6]
    # Every run collided within 1 ms at 5% by volume (docs/scenes.md: about 60 collisions in 20 ms).
    rate = document["groups"]["sphere"]["collision_rate"]["sphere-sphere"]["mean"]
    assert rate > 0.0


def test_suspension_slurm_task_writes_the_summary(agglo, spaced_tmp):
    root = spaced_tmp / "slurm suspension"
    result = montecarlo(agglo, "2", "11", root, "--slurm", "--launcher", "mpirun --oversubscribe")
    assert result.returncode == 0, result.stderr
    script = root / "montecarlo.sbatch"
    assert "#SBATCH --array=1-2" in script.read_text().splitlines()
    env = {**os.environ, "SLURM_ARRAY_TASK_ID": "2", "OMPI_ALLOW_RUN_AS_ROOT": "1",
           "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}
    task = subprocess.run(["bash", str(script)], env=env, capture_output=True, text=True, timeout=300)
    assert task.returncode == 0, (root / "run_0002" / "stdout.log").read_text()
    s = summary(root, 2)
    assert s["scene"] == "suspension" and s["seed"] == 12 and isinstance(s["wall_time"], (int, float))
    again = montecarlo(agglo, "2", "11", root, "--slurm")
    assert again.returncode == 0 and "#SBATCH --array=1" in script.read_text().splitlines()


def test_ghost_collision_kernel_of_the_vacuum_suspension_is_the_kinetic_one(agglo, spaced_tmp):
    """Ghost spheres in vacuum keep their Maxwellian start velocities (each component normal with
    sigma = velocity_rms, docs/theory.md "Suspension placement"; ghosts pass through each other),
    so their collision kernel is the hard-sphere gas's (Chapman & Cowling 1970, ch. 5):
    Z / (n^2/2) = pi d^2 <|v_rel|>, <|v_rel|> = sqrt(2) sqrt(8/pi) sigma = 4 sigma / sqrt(pi).
    d = 100 um, sigma = 10 mm/s: 7.09e-10 m^3/s. Four runs of 20 ms (about 250 encounters, a
    Poisson error of 6%), the kernel from agglo-stats' suspension mode."""
    root = spaced_tmp / "ghost batch"
    result = run_tool([MONTECARLO, "--deck", DECK, "--runs", "4", "--seed", "1", "--out", root, "--agglo", agglo,
                       "-j", "2", "--set", "suspension.ghost=.true."], cwd=REPO)
    assert result.returncode == 0, result.stdout + result.stderr
    stats = run_tool([AGGLO_STATS, root, "-o", spaced_tmp / "stats", "--no-figures"])
    assert stats.returncode == 0, stats.stderr + stats.stdout
    kernel = json.loads((spaced_tmp / "stats" / "suspension.json").read_text())["groups"]["sphere"]["collision_kernel"]
    theory = math.pi * (100e-6) ** 2 * 4.0 * 0.01 / math.sqrt(math.pi)
    assert kernel["low"] < theory < kernel["high"], (kernel, theory)
    assert abs(kernel["mean"] / theory - 1.0) < 0.2, (kernel, theory)
