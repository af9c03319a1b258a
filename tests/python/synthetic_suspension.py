"""Synthetic suspension runs for the tests of agglo-stats' suspension mode: clusters.h5 in the
layout of docs/outputs.md ("clusters.h5") and particles.h5 in the suspension layout, written with
h5py from clusters of known geometry (lines, square lattices, power laws) so that the answers are
known."""
import json
import math
import os

import h5py
import numpy as np


def gyration_full(centres, radius):
    """Mass-weighted radius of gyration of equal spheres at centres, each sphere's own gyration
    (3/5 a^2) included: Rg^2 = mean |x - x_c|^2 + 3/5 a^2."""
    centres = np.asarray(centres, float)
    return math.sqrt(float(np.mean(np.sum((centres - centres.mean(axis=0)) ** 2, axis=1))) + 0.6 * radius ** 2)


def line(n, radius):
    """Centres of n touching spheres in a straight line (a cluster of fractal dimension 1)."""
    return np.array([[2.0 * radius * i, 0.0, 0.0] for i in range(n)])


def square(side, radius):
    """Centres of side x side touching spheres on a square lattice (fractal dimension 2)."""
    return np.array([[2.0 * radius * i, 2.0 * radius * j, 0.0] for i in range(side) for j in range(side)])


class Row:
    """One output row: clusters (sizes, radii of gyration, percolating flags), bonds (psi) and every
    body's cluster number; bodies is the total N (the clusters given plus single bodies)."""

    def __init__(self, bodies, sizes=(), radii=(), percolating=None, psi=(), centres=None):
        sizes = list(sizes)
        singles = bodies - sum(sizes)
        assert singles >= 0
        self.sizes = np.array(sizes + [1] * singles, int)
        self.radii = np.array(list(radii) + [0.0] * singles, float)
        flags = list(percolating) if percolating is not None else [0] * len(sizes)
        self.percolating = np.array(flags + [0] * singles, int)
        self.psi = np.asarray(psi, float)
        self.cluster = np.repeat(np.arange(1, self.sizes.size + 1), self.sizes)
        self.centres = np.zeros((self.sizes.size, 3)) if centres is None else np.asarray(centres, float)


def write_clusters(path, times, rows, species=("sphere",), box=(1e-3, 1e-3, 1e-3), counts=None,
                   mean_size=None, bonds=None):
    """clusters.h5 with the given rows; counts (T, P) cumulative collisions of the species pairs
    (i <= j in order); mean_size / bonds (T) replace the summary's mean_size_number / bonds."""
    n = rows[0].cluster.size
    with h5py.File(path, "w") as h5:
        h5.attrs["bodies"] = n
        h5.attrs["box_length"] = np.asarray(box, float)
        h5.attrs["species_names"] = [s.encode() for s in species]
        h5.attrs["bond_rule"] = "bound in the DLVO well: E = mu v_n^2/2 + U(h) < U_b, h <= h_r"
        h5["time"] = np.asarray(times, float)
        k = np.array([r.sizes.size for r in rows])
        b = np.array([r.psi.size for r in rows]) if bonds is None else np.asarray(bonds, int)
        h5["summary/clusters"] = k
        h5["summary/bonds"] = b
        h5["summary/mean_size_number"] = n / k if mean_size is None else np.asarray(mean_size, float)
        h5["summary/mean_size_weight"] = np.array([np.sum(r.sizes.astype(float) ** 2) / n for r in rows])
        h5["summary/largest"] = np.array([r.sizes.max() for r in rows])
        h5["summary/mean_coordination"] = 2.0 * b / n
        h5["summary/percolating"] = np.array([r.percolating.sum() for r in rows])
        h5["body/cluster"] = np.array([r.cluster for r in rows])
        h5["body/coordination"] = np.zeros((len(rows), n), int)
        h5["cluster/row_start"] = np.concatenate([[0], np.cumsum(k)])
        h5["cluster/size"] = np.concatenate([r.sizes for r in rows])
        h5["cluster/radius_of_gyration"] = np.concatenate([r.radii for r in rows])
        h5["cluster/radius_of_gyration_centres"] = np.concatenate([r.radii for r in rows])
        h5["cluster/gyration_eigenvalues"] = np.zeros((int(k.sum()), 3))
        h5["cluster/centre"] = np.concatenate([r.centres for r in rows])
        h5["cluster/percolating"] = np.concatenate([r.percolating for r in rows])
        bond_counts = np.array([r.psi.size for r in rows])
        h5["bond/row_start"] = np.concatenate([[0], np.cumsum(bond_counts)])
        h5["bond/pair"] = np.ones((int(bond_counts.sum()), 2), int) * np.array([1, 2])
        h5["bond/psi"] = np.concatenate([r.psi for r in rows])
        for name, shape in (("time", (0,)), ("kind", (0,)), ("pair", (0, 2)), ("theta", (0, 2)),
                            ("phi", (0, 2)), ("normal_speed", (0,)), ("gap", (0,))):
            h5[f"events/{name}"] = np.zeros(shape)
        pairs = [(i + 1, j + 1) for i in range(len(species)) for j in range(i, len(species))]
        h5["collisions/species_pairs"] = np.array(pairs, int)
        h5["collisions/count"] = np.zeros((len(rows), len(pairs)), int) if counts is None else np.asarray(counts)
        h5["collisions/volume"] = float(np.prod(box))


def write_particles(path, times, positions, shape="sphere", seed=1, radius=50e-6):
    """particles.h5 of a suspension: /time, /suspension/position (rows, 3 N), identity datasets."""
    positions = np.asarray(positions, float)
    rows, n = positions.shape[0], positions.shape[1]
    with h5py.File(path, "w") as h5:
        h5["time"] = np.asarray(times, float)
        h5["suspension/position"] = positions.reshape(rows, 3 * n)
        h5["suspension/velocity"] = np.zeros((rows, 3 * n))
        h5["bodies"] = n
        h5["shape"] = shape.encode()
        h5["seed"] = seed
        h5["radius"] = radius
        h5["aspect_ratio"] = 1.0
        h5["events/time"] = np.zeros(0)


def write_run(directory, times, rows, shape="sphere", seed=1, summary=True, **clusters):
    """A complete batch run: clusters.h5, particles.h5 (bodies on a line), deck.nml and the
    summary.json tools/montecarlo.sh writes for a suspension run."""
    os.makedirs(directory, exist_ok=True)
    write_clusters(os.path.join(directory, "clusters.h5"), times, rows, **clusters)
    n = rows[0].cluster.size
    positions = np.tile(np.linspace(1e-5, 9e-4, n)[None, :, None], (len(times), 1, 3))
    write_particles(os.path.join(directory, "particles.h5"), times, positions, shape=shape, seed=seed)
    with open(os.path.join(directory, "deck.nml"), "w") as handle:
        handle.write("&run seed = %d /\n" % seed)
    if summary:
        with open(os.path.join(directory, "summary.json"), "w") as handle:
            json.dump({"scene": "suspension", "complete": True, "seed": seed, "end_time": times[-1],
                       "wall_time": 1.0}, handle)
