"""Tests of tools/contact_drift.py: the added-mass coefficients against the closed forms of the
spheroid's potential-flow integrals, the stabilisation drive of a face-on and an edge-on disk held
in contact, and the run-by-run table on a hand-made pair of batches whose answer is known."""
import csv
import math
import os

import h5py
import numpy as np
import pytest

from conftest import REPO, run_tool
from contact_drift import added_mass_coefficients, semi_axes, spearman, stabilisation_drive
from fake_pair_scene import write_run

PYTHON = REPO / ".venv" / "bin" / "python"
FLUID_DENSITY, PARTICLE_DENSITY, RADIUS = 997.0, 2710.0, 5.0e-5
EDGE_ON = [math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]   # body x (the axis) along lab y


def closed_form_k(axial, transverse):
    """k_i = alpha0_i / (2 - alpha0_i) from the eccentricity forms of the integrals (Lamb 1932
    sec. 373; e.g. Korotkin, "Added masses of ship structures" (2009), table 2.2): oblate
    alpha0_ax = 2 / e^2 (1 - sqrt(1 - e^2) asin(e) / e), prolate alpha0_ax = 2 (1 - e^2) / e^3
    (atanh(e) - e); alpha0_tr = (2 - alpha0_ax) / 2 (the three sum to 2)."""
    if axial < transverse:
        e = math.sqrt(1.0 - (axial / transverse) ** 2)
        alpha_axial = 2.0 / e ** 2 * (1.0 - math.sqrt(1.0 - e * e) * math.asin(e) / e)
    else:
        e = math.sqrt(1.0 - (transverse / axial) ** 2)
        alpha_axial = 2.0 * (1.0 - e * e) / e ** 3 * (math.atanh(e) - e)
    alpha_transverse = 0.5 * (2.0 - alpha_axial)
    return [alpha_axial / (2.0 - alpha_axial), alpha_transverse / (2.0 - alpha_transverse)]


@pytest.mark.parametrize("aspect_ratio", [0.2, 0.5, 2.0, 5.0])
def test_added_mass_coefficients_match_closed_forms(aspect_ratio):
    axial, transverse = semi_axes(RADIUS, aspect_ratio)
    assert axial * transverse ** 2 == pytest.approx(RADIUS ** 3, rel=1e-12)
    assert added_mass_coefficients(axial, transverse) == pytest.approx(closed_form_k(axial, transverse), rel=1e-9)


def test_added_mass_of_sphere_and_thin_disk():
    assert added_mass_coefficients(RADIUS, RADIUS) == pytest.approx([0.5, 0.5], rel=1e-12)
    # A circular disk moving face-on carries (8/3) rho b^3 (Lamb 1932 sec. 108): k -> 2 b / (pi a).
    k = added_mass_coefficients(1.0e-3, 1.0)
    assert k[0] == pytest.approx(2.0 / (math.pi * 1.0e-3), rel=2e-3)


def test_stabilisation_drive_of_face_on_and_edge_on_disks():
    """A disk face-on to the contact normal x pulled by +F, an edge-on one by -F: the drive
    F (m / (m + M_ax) - m / (m + M_tr)) along x, -0.475 F for calcite disks in water."""
    axial, transverse = semi_axes(RADIUS, 0.2)
    volume = 4.0 / 3.0 * math.pi * RADIUS ** 3
    mass = PARTICLE_DENSITY * volume
    k = added_mass_coefficients(axial, transverse)
    added = FLUID_DENSITY * volume * np.array([k[0], k[1], k[1]])
    force = 9.0e-9
    first = stabilisation_drive([[force, 0.0, 0.0]], [[1.0, 0.0, 0.0, 0.0]], mass, added)[0]
    second = stabilisation_drive([[-force, 0.0, 0.0]], [EDGE_ON], mass, added)[0]
    expected = force * (mass / (mass + added[0]) - mass / (mass + added[1]))
    assert (first + second)[0] == pytest.approx(expected, rel=1e-12)
    assert expected / force == pytest.approx(-0.475, abs=1e-3)
    assert np.abs((first + second)[1:]).max() < 1e-12 * force
    # Equal added masses along the normal (both face-on): no net drive.
    same = stabilisation_drive([[-force, 0.0, 0.0]], [[1.0, 0.0, 0.0, 0.0]], mass, added)[0]
    assert np.abs(first + same).max() < 1e-12 * force


def test_spearman_ranks():
    assert spearman([1, 2, 3, 4], [10, 20, 30, 40]) == pytest.approx(1.0)
    assert spearman([1, 2, 3, 4], [4, 3, 2, 1]) == pytest.approx(-1.0)
    assert math.isnan(spearman([1, 2], [1, 2]))


def write_drifting_run(directory, seed, added_mass, drift):
    """A disk pair held in contact after t1 = 5 ms under DLVO +-F along x (disk 1 face-on, disk 2
    edge-on), its centre of mass drifting at drift(t) along x; run.nml with the groups the tool reads."""
    write_run(directory, seed=seed, shape="disk", outcome="agglomerated", fluid="resolved_resolved")
    rows, t1, speed, force = 101, 5.0e-3, 4.375e-4, 9.0e-9
    time = np.linspace(0.0, 1.0e-2, rows)
    after = time >= t1
    com = np.zeros((rows, 3))
    com[:, 0] = np.where(after, drift(time - t1), 0.0)
    relative = np.zeros((rows, 3))
    relative[:, 0] = np.where(after, 0.0, speed)          # +-speed before the contact, held after
    with h5py.File(os.path.join(directory, "particles.h5"), "w") as h5:
        h5["time"] = time
        h5["radius"] = RADIUS
        h5["pair/gap"] = np.where(after, 1.0e-9, 5.0e-6 - 2 * speed * time)
        for k, sign, quaternion in ((1, 1.0, [1.0, 0.0, 0.0, 0.0]), (2, -1.0, EDGE_ON)):
            h5[f"particle{k}/velocity"] = com + sign * relative
            h5[f"particle{k}/quaternion"] = np.tile(quaternion, (rows, 1))
            dlvo = np.zeros((rows, 3))
            dlvo[after, 0] = sign * force
            h5[f"particle{k}/force_dlvo"] = dlvo
            h5[f"particle{k}/force_hydrodynamic"] = np.zeros((rows, 3))
    with open(os.path.join(directory, "run.nml"), "w") as handle:
        handle.write(f"&RUN\n NAME='{os.path.basename(directory)}',\n SEED={seed},\n /\n"
                     f"&SCENE\n FLUID=\"resolved\",\n ADDED_MASS={'T' if added_mass else 'F'},\n /\n"
                     f"&FLUID\n DENSITY=  {FLUID_DENSITY},\n /\n&PAIR\n SHAPE=\"disk\",\n"
                     f" DENSITY=  {PARTICLE_DENSITY},\n /\n&COLLISION\n DETECTION_FLOOR=  1.0E-009,\n /\n")
    path = os.path.join(directory, "summary.json")
    import json
    with open(path) as handle:
        summary = json.load(handle)
    summary["first_collision"].update(time=t1, normal_velocity_before=2 * speed, normal_velocity_after=-0.8 * speed)
    with open(path, "w") as handle:
        json.dump(summary, handle)


def test_contact_drift_table_and_figure(spaced_tmp):
    for seed in (1, 2):
        name = f"run_{seed:04d}"
        write_run(str(spaced_tmp / "none" / name), seed=seed, shape="disk", outcome="agglomerated")
    write_drifting_run(str(spaced_tmp / "resolved" / "run_0001"), 1, True, lambda t: -0.2 * t)
    write_drifting_run(str(spaced_tmp / "resolved" / "run_0002"), 2, False, lambda t: 0.0 * t)
    out = spaced_tmp / "drift.csv"                   # 6 significant digits
    result = run_tool([PYTHON, REPO / "tools" / "contact_drift.py", spaced_tmp / "none", spaced_tmp / "resolved",
                       "--label", "disks", "-o", out, "--figure", spaced_tmp / "figures"])
    assert result.returncode == 0, result.stderr
    with open(out, newline="") as handle:
        rows = {row["run"]: row for row in csv.DictReader(handle)}
    none_speed = 0.5 * 5.0e-6 / 5.0e-3              # fake_pair_scene: 5 um closed in half of 10 ms
    drifting, still = rows["run_0001"], rows["run_0002"]
    # 0.2 m/s^2 for 5 ms: 1 mm/s at the end, the largest speed of the run, on its last row.
    assert float(drifting["ratio"]) == pytest.approx(1.0e-3 / none_speed, rel=1e-5)
    assert float(drifting["max_share_after_contact"]) == pytest.approx(1.0, abs=1e-5)
    assert float(drifting["com_speed_end"]) == pytest.approx(1.0e-3 / 4.375e-4, rel=1e-5)
    volume = 4.0 / 3.0 * math.pi * RADIUS ** 3
    mass = PARTICLE_DENSITY * volume
    k = added_mass_coefficients(*semi_axes(RADIUS, 0.2))
    added = FLUID_DENSITY * volume * np.array(k)
    expected = 9.0e-9 * (mass / (mass + added[1]) - mass / (mass + added[0]))
    assert float(drifting["drive_N"]) == pytest.approx(expected, rel=1e-5)
    assert float(drifting["drive_cos"]) == pytest.approx(1.0, abs=1e-5)   # drift and drive both along -x
    assert float(drifting["rebound"]) == pytest.approx(0.4, rel=1e-5)
    assert float(drifting["face_on"]) == pytest.approx(1.0, abs=1e-5)      # disk 1 moves along its axis
    assert float(drifting["added_mass_momentum"]) == pytest.approx(added[0] / mass, rel=1e-5)
    assert float(still["drive_N"]) == 0.0                                  # no stabilisation, no drive
    assert float(still["ratio"]) == pytest.approx(4.375e-4 / none_speed, rel=1e-5)   # its approach
    assert "disks: 2 runs, 1 above 1.01" in result.stdout
    assert (spaced_tmp / "figures" / "contact_drift_scatter.png").stat().st_size > 1000


def test_contact_drift_refuses_unpaired_roots(spaced_tmp):
    write_run(str(spaced_tmp / "none" / "run_0001"), seed=1, shape="disk", outcome="agglomerated")
    result = run_tool([PYTHON, REPO / "tools" / "contact_drift.py", spaced_tmp / "none"])
    assert result.returncode == 1
    assert "pairs" in result.stderr


def test_contact_drift_held_drive_of_any_batch(spaced_tmp):
    """--held needs no reference: the drift fixture's drive, and a stabilised batch of one run."""
    write_drifting_run(str(spaced_tmp / "resolved" / "run_0001"), 1, True, lambda t: -0.2 * t)
    result = run_tool([PYTHON, REPO / "tools" / "contact_drift.py", "--held", spaced_tmp / "resolved"])
    assert result.returncode == 0, result.stderr
    volume = 4.0 / 3.0 * math.pi * RADIUS ** 3
    mass = PARTICLE_DENSITY * volume
    k = added_mass_coefficients(*semi_axes(RADIUS, 0.2))
    expected = 9.0e-9 * (mass / (mass + FLUID_DENSITY * volume * k[1]) - mass / (mass + FLUID_DENSITY * volume * k[0]))
    assert "1 agglomerated runs held in contact" in result.stdout
    assert f"median {expected * 1e9:.3g} nN" in result.stdout
