"""tools/suspension-study.sh: its batches (--list), Slurm scripts, and a real local study sized down
to seconds (a 16^3 converged field, point spheres for 0.2 ms, a small ghost batch) that runs,
resumes, reports its status and ends in agglo-stats' suspension mode."""
import csv
import os
import re
import subprocess

import h5py

from conftest import REPO, run_tool
from synthetic_fields import solenoidal_random_field, write_final_field

STUDY = REPO / "tools" / "suspension-study.sh"
MPI_AS_ROOT = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}


def read_tsv(path):
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle, delimiter="\t"))


def workdir(spaced_tmp):
    """A directory of its own with the decks linked in: no converged field of the repository's
    output/ is seen."""
    work = spaced_tmp / "work"
    work.mkdir()
    (work / "input").symlink_to(REPO / "input")
    return work


def test_suspension_study_lists_its_batches(spaced_tmp):
    result = run_tool([STUDY, "--list"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    batches = [line.split()[:3] for line in result.stdout.splitlines() if not line.startswith("forced")]
    expected = [[f"{shape}-{rung}", "8", f"input/suspension_{shape}_{rung}.nml"]
                for rung in ("point", "resolved") for shape in ("needle", "disk", "sphere")]
    assert batches == expected + [["sphere-ghost", "8", "input/suspension_sphere_point.nml"]]
    ghost = next(line for line in result.stdout.splitlines() if line.startswith("sphere-ghost"))
    for text in ("suspension.ghost=.true.", "suspension.count=64", "suspension.radius=50e-6"):
        assert text in ghost
    result = run_tool([STUDY, "--list", "--grid", "72", "--end-time", "1e-3", "--runs", "3", "--bodies", "16",
                       "--ghost-runs", "0", "--shapes", "disk"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if not line.startswith("forced")]
    assert [line.split()[:2] for line in lines] == [["disk-point", "3"], ["disk-resolved", "3"]]
    for text in ("grid.nx=72", "run.end_time=1e-3", "suspension.count=16",
                 "fluid.init_file='output/hit_box_72/final_field.h5'"):
        assert all(text in line for line in lines), text
    # The published tables pin the paper's omission of the squeeze film; --lubrication models it.
    assert all("collision.lubrication=.false." in line for line in lines)
    result = run_tool([STUDY, "--list", "--lubrication", "--ghost-runs", "0", "--shapes", "disk"], cwd=REPO)
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if not line.startswith("forced")]
    assert lines and all("collision.lubrication=.true." in line for line in lines)
    for bad in (["--shapes", "cube"], ["--rungs", "stokes"], ["--runs", "0"], ["--end-time", "soon"],
                ["--grid", "-4"]):
        refused = run_tool([STUDY, "--list", *bad], cwd=REPO)
        assert refused.returncode == 2 and "not allowed" in refused.stderr, bad


def test_suspension_study_slurm_scripts(spaced_tmp):
    out = spaced_tmp / "slurm study"
    result = run_tool([STUDY, "--slurm", "-o", out, "--runs", "2", "--shapes", "sphere", "--ranks", "8",
                       "--time", "180", "--sbatch-option", "--partition=short"], cwd=workdir(spaced_tmp))
    assert result.returncode == 0, result.stderr + result.stdout
    submit = (out / "submit-all.sh").read_text()
    assert run_tool(["bash", "-n", out / "submit-all.sh"]).returncode == 0
    assert "field_128=$(sbatch --parsable" in submit
    for batch in ("sphere-point", "sphere-resolved", "sphere-ghost"):
        line = next(line for line in submit.splitlines() if f"{batch}/montecarlo.sbatch" in line)
        assert "--dependency=afterok:$field_128 " in line, batch
        script = (out / batch / "montecarlo.sbatch").read_text().splitlines()
        assert "#SBATCH --array=1-2" in script and "#SBATCH --time=180" in script
        assert "#SBATCH --partition=short" in script
    assert "#SBATCH --ntasks=8" in (out / "sphere-resolved" / "montecarlo.sbatch").read_text()
    assert re.search(r"^\s*ghost\s*=\s*\.true\.", (out / "sphere-ghost" / "batch.nml").read_text(), re.M | re.I)


def test_suspension_study_runs_resumes_and_analyses(spaced_tmp, agglo):
    out = spaced_tmp / "study"
    env = {**os.environ, **MPI_AS_ROOT}
    command = [STUDY, "-o", out, "--grid", "16", "--shapes", "sphere", "--rungs", "point", "--runs", "2",
               "--end-time", "2e-4", "--ghost-runs", "1", "--ghost-bodies", "8", "--ranks", "1", "-j", "2",
               "--launcher", "mpirun --oversubscribe"]
    work = workdir(spaced_tmp)

    def study(*extra):
        return subprocess.run([str(c) for c in command + list(extra)], cwd=work, env=env,
                              capture_output=True, text=True, timeout=600)
    first = study()
    assert first.returncode == 0, first.stderr + first.stdout
    assert (work / "output" / "hit_box_16" / "final_field.h5").exists()
    for batch, runs in (("sphere-point", 2), ("sphere-ghost", 1)):
        for i in range(1, runs + 1):
            assert '"scene": "suspension"' in (out / batch / f"run_{i:04d}" / "summary.json").read_text()
    # The ghost batch ran in ghost mode (the resolved deck the code wrote, run.nml).
    assert re.search(r"^\s*GHOST\s*=\s*T,", (out / "sphere-ghost" / "run_0001" / "run.nml").read_text(), re.M)
    for path in ("stats-point/suspension_table.csv", "stats-point/suspension.json",
                 "stats-collision/suspension_comparison.csv",
                 "stats-point/suspension_collision_rate.png", "stats-ghost/suspension_table.csv"):
        assert (out / path).exists(), path
    costs = read_tsv(out / "batch_costs.tsv")
    assert sorted((os.path.basename(r["batch"]), r["complete"]) for r in costs) == [
        ("sphere-ghost", "1"), ("sphere-point", "2")]
    second = study("--no-analysis")
    assert second.returncode == 0, second.stderr + second.stdout
    times = read_tsv(out / "batch_times.tsv")
    assert [(os.path.basename(r["batch"]), r["runs_run_by_this_call"]) for r in times
            if r["batch"].endswith(("point", "ghost"))] == [
        ("sphere-point", "2"), ("sphere-ghost", "1"), ("sphere-point", "0"), ("sphere-ghost", "0")]
    status = study("--status")
    assert status.returncode == 0 and "2 complete" in status.stdout and "1 complete" in status.stdout


def test_suspension_study_on_the_128_field_resampled(spaced_tmp):
    """--grid 16 --regrid-field: the batches start from the 128^3 field resampled onto 16^3
    (tools/regrid_field.py, made at once when the 128^3 field exists, also under --slurm) instead of
    a field converged on 16^3. A tiny synthetic base field (8^3, same box) stands in for the
    converged 128^3 one."""
    work, out = workdir(spaced_tmp), spaced_tmp / "regridded"
    (work / "output" / "hit_box_128").mkdir(parents=True)
    write_final_field(work / "output" / "hit_box_128" / "final_field.h5",
                      solenoidal_random_field((8, 8, 8), box=(1.0e-3, 1.0e-3, 1.0e-3)))
    command = [STUDY, "-o", out, "--grid", "16", "--regrid-field", "--shapes", "sphere", "--rungs", "point",
               "--runs", "1", "--ghost-runs", "0"]
    listed = run_tool(command + ["--list"], cwd=work)
    assert ("regridded field output/hit_box_128_on_16/final_field.h5: MISSING (tools/regrid_field.py: "
            "output/hit_box_128/final_field.h5 resampled onto 16^3, made first)") in listed.stdout
    result = run_tool(command + ["--slurm"], cwd=work)
    assert result.returncode == 0, result.stderr + result.stdout
    with h5py.File(work / "output" / "hit_box_128_on_16" / "final_field.h5", "r") as handle:
        assert list(handle["fluid/grid_shape"][()]) == [16, 16, 16]
    assert not (work / "output" / "hit_box_16").exists()
    assert "output/hit_box_128_on_16/final_field.h5" in (out / "sphere-point" / "batch.nml").read_text()
    submit = (out / "submit-all.sh").read_text()
    assert "dependency" not in submit and "sphere-point/montecarlo.sbatch" in submit
    refused = run_tool([STUDY, "--list", "--regrid-field"], cwd=REPO)
    assert refused.returncode == 2 and "--regrid-field needs --grid N" in refused.stderr
