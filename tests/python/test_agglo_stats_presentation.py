"""What agglo-stats tells its user besides the rates: the collision detection floor on the
separation PDF, labels at both ends of log axes, warnings on PDFs from fewer than 30 samples, and
a resolved-fluid run named as such instead of "all incomplete or failed". Batches from the FAKE
pair-scene fixture (fake_pair_scene.py); the resolved-fluid case also on a REAL run of $AGGLO."""
import re

import h5py
import numpy as np
import pytest

from agglo_stats import FEW_SAMPLES, label_log_ends
from conftest import AGGLO_STATS, run_tool
from test_agglo_stats import make_fake_batch


def floor_share(root, floor):
    """Percentage of the positive gap samples of every run under root within 10% of floor."""
    gaps = []
    for path in sorted(root.glob("run_*/particles.h5")):
        with h5py.File(path, "r") as h5:
            gaps.append(np.asarray(h5["pair/gap"][:]))
    every = np.concatenate(gaps)
    every = every[every > 0.0]
    return np.mean((every >= floor / 1.1) & (every <= floor * 1.1)) * 100.0


def test_separation_pdf_marks_the_default_detection_floor(spaced_tmp):
    make_fake_batch(str(spaced_tmp), {"disk": (4, 1, 0, 0)})
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 0, result.stderr
    share = floor_share(spaced_tmp, 1.0e-9)
    assert share > 0.0                   # the fake bound pairs sit at 1-3 nm: the mark means something
    assert f"separation_pdf: detection floor 1 nm: {share:.0f}% of the samples within 10%" in result.stdout


def test_detection_floor_read_from_each_run_nml(spaced_tmp):
    # run.nml as the code writes it (upper case, padded); the fixture keeps an existing run.nml.
    for seed in (1, 2, 3):
        run = spaced_tmp / f"run_{seed:04d}"
        run.mkdir()
        floor = "2.0000000000000000E-009" if seed < 3 else "5.0000000000000001E-010"
        (run / "run.nml").write_text(f"&RUN\n NAME=\"run_{seed:04d}\",\n /\n&COLLISION\n"
                                     f" DETECTION_FLOOR=  {floor}     ,\n /\n")
    make_fake_batch(str(spaced_tmp), {"needle": (3, 0, 0, 0)})
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 0, result.stderr
    marks = re.findall(r"detection floor (\S+) nm", result.stdout)
    assert marks == ["0.5", "2"], result.stdout


def test_few_samples_are_warned_per_figure(spaced_tmp):
    make_fake_batch(str(spaced_tmp), {"needle": (3, 2, 0, 1)})
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 0, result.stderr
    warnings = [line for line in result.stdout.splitlines() if line.startswith("warning: ")]
    assert any(line.startswith(f"warning: psi_pdf: 2 PDF(s) from fewer than {FEW_SAMPLES} samples")
               and "agglomerated 3" in line and "rebounded 2" in line for line in warnings), warnings
    assert any(line.startswith("warning: max_vdw_force_pdf:") and "needle 6" in line for line in warnings)
    # 6 runs x 60 history rows: the separation PDF has enough samples.
    assert not any("separation_pdf" in line for line in warnings)


def test_no_warning_from_30_samples_on(spaced_tmp):
    make_fake_batch(str(spaced_tmp), {"disk": (FEW_SAMPLES, 0, 0, 0)})
    result = run_tool([AGGLO_STATS, spaced_tmp])
    assert result.returncode == 0, result.stderr
    assert "warning:" not in result.stdout, result.stdout


@pytest.mark.parametrize("which, low, high", [("x", 5.91e-10, 7.69e-6), ("x", 2.0e-9, 5.0e-9),
                                              ("y", 3.95, 23.2), ("x", 1.0e-30, 1.0e-10)])
def test_log_axis_labelled_at_both_ends(which, low, high):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axis = plt.subplots()
    (axis.set_xscale if which == "x" else axis.set_yscale)("log")
    (axis.set_xlim if which == "x" else axis.set_ylim)(low, high)
    ticks = label_log_ends(axis, which)
    target = axis.xaxis if which == "x" else axis.yaxis
    formatter = target.get_major_formatter()
    labels = [formatter(value, k) for k, value in enumerate(target.get_major_locator()())]
    plt.close(figure)
    assert ticks[0] == low and ticks[-1] == high           # the limits as set, read back
    assert labels[0] == f"{low:.3g}" and labels[-1] == f"{high:.3g}", labels
    assert len(labels) <= 10                                # 20 decades are thinned, not crowded


def write_fake_fluid_run(directory):
    directory.mkdir(parents=True)
    (directory / "run.nml").write_text("&RUN\n NAME=\"box\",\n /\n&SCENE\n FLUID=\"resolved\",\n /\n")
    (directory / "agglo.log").write_text("Agglo\n")
    (directory / "fields.xdmf").write_text("<Xdmf/>\n")
    (directory / "fluid_statistics.dat").write_text("# step time\n")


def test_resolved_fluid_run_is_named(spaced_tmp):
    write_fake_fluid_run(spaced_tmp / "output" / "box")
    for root in (spaced_tmp / "output" / "box", spaced_tmp / "output"):   # the run, or its parent
        result = run_tool([AGGLO_STATS, root])
        assert result.returncode == 1
        assert "resolved-fluid run" in result.stderr and "not pair-scene runs" in result.stderr, result.stderr
        assert "fluid_statistics.dat" in result.stderr and "incomplete" not in result.stderr


def test_resolved_fluid_run_beside_pair_runs_is_skipped_by_name(spaced_tmp):
    make_fake_batch(str(spaced_tmp), {"disk": (1, 1, 0, 0)})
    write_fake_fluid_run(spaced_tmp / "box")
    result = run_tool([AGGLO_STATS, spaced_tmp, "--no-figures"])
    assert result.returncode == 0, result.stderr
    assert "skipped 1 run(s) of 3" in result.stdout
    assert "box: a resolved-fluid run (fields.xdmf, fluid_statistics.dat), not a pair scene" in result.stdout


def test_real_resolved_fluid_run_is_named(agglo, tmp_path):
    deck = tmp_path / "box.nml"
    deck.write_text("&run name = 'box', end_time = 1.0e-3, dt = 1.0e-5, max_steps = 3 /\n"
                    "&scene fluid = 'resolved' /\n"
                    "&grid nx = 8, ny = 8, nz = 8, length_x = 1.0e-3, length_y = 1.0e-3, length_z = 1.0e-3 /\n"
                    "&fluid init = 'random', init_amplitude = 0.01 /\n"
                    "&output field_interval = 1.0e-5 /\n")
    run = run_tool(["mpirun", "-np", "1", agglo, deck.name], cwd=tmp_path)
    assert run.returncode == 0, run.stdout + run.stderr
    result = run_tool([AGGLO_STATS, tmp_path / "output" / "box"])
    assert result.returncode == 1
    assert "resolved-fluid run" in result.stderr and "incomplete" not in result.stderr, result.stderr
