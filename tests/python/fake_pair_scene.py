"""FAKE stand-in for the pair scene of build/agglo: a fixture, never a physics model.

It writes a run directory exactly in the layout of "Per-run outputs of the pair scenes"
(run.nml, agglo.log, particles.h5, summary.json; docs/tools.md lists the fields) with made-up but
self-consistent histories: a straight approach, a first collision, then either a bound pair or a
rebound; or an approach into the DLVO range without contact, then a retreat ('approached'); or an
approach that stops short of the range ('no_contact'). legacy=True writes the summary.json of the
code before contact episodes: no contact_episodes, ended_in_flight, outcome_settled, end_rule. The statistics tests (test_agglo_stats.py) use it to build batches whose outcomes are
known exactly (counts, Wilson interval, CSV, figures), independent of the real code's physics.
Every test of tools/montecarlo.sh and of statistics on real runs uses $AGGLO instead.

Use: write_run(directory, seed=..., shape=..., outcome=...).
"""
import json
import math
import os

import h5py
import numpy as np

ASPECT_RATIO = {"sphere": 1.0, "needle": 5.0, "disk": 0.2, "spheroid": 2.0}
AGGLOMERATION_PROBABILITY = {"sphere": 0.2, "needle": 0.4, "disk": 0.7, "spheroid": 0.5}


def _history(rng, outcome, end_time, rows):
    """Gap and normal relative velocity of a head-on approach at 0.875 mm/s from 5 um."""
    time_axis = np.linspace(0.0, end_time, rows)
    gap0, speed = 5.0e-6, 8.75e-4
    if outcome == "no_contact":              # closes a fifth of the gap, never touches
        contact_time, speed = 2.0 * end_time, 0.2 * gap0 / end_time
    elif outcome == "approached":            # to 100 nm (inside the 182 nm range) at mid-run, then back
        contact_time = 0.5 * end_time
        speed = (gap0 - 1.0e-7) / contact_time
    else:                                    # contact within the first half of the run
        contact_time = min(gap0 / speed, 0.5 * end_time)
        speed = gap0 / contact_time
    gap = gap0 - speed * time_axis
    velocity = np.full(rows, speed)
    after = time_axis > contact_time
    if outcome == "agglomerated":
        gap[after] = 2.0e-9 * (1.0 + 0.5 * np.sin(1.0e5 * time_axis[after]))
        velocity[after] = 1.0e-6 * np.cos(1.0e5 * time_axis[after])
    elif outcome == "rebounded":
        gap[after] = 0.4 * speed * (time_axis[after] - contact_time) + 1.0e-9
        velocity[after] = -0.4 * speed
    elif outcome == "approached":
        gap[after] = 1.0e-7 + 0.4 * speed * (time_axis[after] - contact_time)
        velocity[after] = -0.4 * speed
    return time_axis, gap, velocity, contact_time, speed


def write_run(directory, seed, shape="needle", outcome=None, fluid="none", name=None,
              end_time=1.0e-2, rows=200, radius=5.0e-5, legacy=False, in_flight=False):
    """Write a complete fake run into directory (created); returns the summary dict."""
    rng = np.random.default_rng(seed)
    if outcome is None:
        if rng.random() < AGGLOMERATION_PROBABILITY[shape]:
            outcome = "agglomerated"
        else:
            outcome = "rebounded"
    os.makedirs(directory, exist_ok=True)
    name = name or os.path.basename(os.path.normpath(directory))
    if not os.path.exists(os.path.join(directory, "run.nml")):
        with open(os.path.join(directory, "run.nml"), "w") as handle:
            handle.write(f"&run name = '{name}', seed = {seed} /\n&scene fluid = '{fluid}' /\n")
        with open(os.path.join(directory, "agglo.log"), "w") as handle:
            handle.write(f"fake pair scene: {name}\n")
    time_axis, gap, velocity, contact_time, speed = _history(rng, outcome, end_time, rows)
    theta = rng.uniform(0.0, math.pi, 2)
    phi = rng.uniform(-math.pi, math.pi, 2)
    psi_first = float(np.arccos(rng.uniform(0.0, 1.0)))   # uniform axes: cos(psi) ~ U[0, 1]
    vdw = 2.23e-20 * radius / (12.0 * np.maximum(np.abs(gap), 5.0e-9) ** 2)
    with h5py.File(os.path.join(directory, "particles.h5.tmp"), "w") as h5:
        h5["time"] = time_axis
        for k, sign in ((1, -1.0), (2, 1.0)):
            group = h5.create_group(f"particle{k}")
            position = np.zeros((rows, 3))
            position[:, 0] = 0.5e-3 + sign * (radius + 0.5 * gap)
            group["position"] = position
            group["quaternion"] = np.tile([1.0, 0.0, 0.0, 0.0], (rows, 1))
            vel = np.zeros((rows, 3))
            vel[:, 0] = -sign * 0.5 * velocity
            group["velocity"] = vel
            group["angular_velocity"] = np.zeros((rows, 3))
            for load in ("force", "torque"):
                for part in ("hydrodynamic", "dlvo", "collision"):
                    group[f"{load}_{part}"] = np.zeros((rows, 3))
        pair = h5.create_group("pair")
        pair["gap"] = gap
        pair["closest_point1"] = np.zeros((rows, 3))
        pair["closest_point2"] = np.zeros((rows, 3))
        pair["chi_eta"] = np.ones(rows)
        pair["relative_velocity"] = velocity
        pair["vdw_force"] = vdw
        events = h5.create_group("events")
        collided = outcome in ("agglomerated", "rebounded")
        count = 1 if collided else 0
        events["time"] = np.full(count, contact_time)
        events["theta1"] = np.full(count, theta[0])
        events["phi1"] = np.full(count, phi[0])
        events["theta2"] = np.full(count, theta[1])
        events["phi2"] = np.full(count, phi[1])
        events["normal_velocity_before"] = np.full(count, speed)
        events["normal_velocity_after"] = np.full(count, -0.4 * speed)
        events["psi"] = np.full(count, psi_first)
        for key, value in (("shape", shape), ("aspect_ratio", ASPECT_RATIO[shape]),
                           ("radius", radius), ("fluid", fluid), ("seed", seed)):
            h5.attrs[key] = value
    os.replace(os.path.join(directory, "particles.h5.tmp"), os.path.join(directory, "particles.h5"))
    first = None
    if collided:
        first = {"time": contact_time, "theta1": theta[0], "phi1": phi[0], "theta2": theta[1],
                 "phi2": phi[1], "psi": psi_first, "normal_velocity_before": speed,
                 "normal_velocity_after": -0.4 * speed}
    summary = {"name": name, "seed": int(seed), "shape": shape, "aspect_ratio": ASPECT_RATIO[shape],
               "fluid": fluid, "outcome": outcome, "collisions": 0 if first is None else 1,
               "first_collision": first, "max_vdw_force": float(vdw.max()),
               "final_gap": float(gap[-1]), "final_relative_velocity": float(velocity[-1]),
               "psi_final": psi_first, "end_time": end_time, "steps": rows - 1, "wall_time": 0.01}
    if not legacy:
        summary.update(outcome_settled=not in_flight, ended_in_flight=in_flight, end_rule="settled",
                       contact_episodes=count)
    with open(os.path.join(directory, "summary.json.tmp"), "w") as handle:
        json.dump(summary, handle)
    os.replace(os.path.join(directory, "summary.json.tmp"), os.path.join(directory, "summary.json"))
    return summary
