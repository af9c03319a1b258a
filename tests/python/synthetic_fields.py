"""Synthetic field files for the tests of tools/regrid_field.py and of the study scripts: a random
velocity made discretely divergence-free on its staggered grid (as a converged field of the code
is), written in the layout of the code's final_field.h5 (src/fluid/forcing_driver.f90,
forcing_driver_finish). A fixture, not a flow: the forcing state is a made-up word sequence."""
import h5py
import numpy as np

from regrid_field import project

BOX = (1.0e-3, 2.0e-3, 1.5e-3)          # m, deliberately not a cube


def solenoidal_random_field(shape, seed=3, box=BOX):
    """A random velocity on the grid, discretely divergence-free (as a converged field of the code
    is), with a random pressure: every Fourier mode including the Nyquist ones is populated."""
    rng = np.random.default_rng(seed)
    u, v, w = project(*(rng.standard_normal(shape) for _ in range(3)), box, "discrete")
    return {"u": u, "v": v, "w": w, "pressure": rng.standard_normal(shape), "shape": shape, "box": box,
            "time": 0.125, "forcing_state": np.arange(20, dtype=np.int64)}


def write_final_field(path, field):
    """field in the layout of the code's final_field.h5 (forcing_driver_finish): h5py's C order
    holds the Fortran (nx, ny, nz) arrays as [k, j, i]."""
    with h5py.File(path, "w") as handle:
        for name in ("u", "v", "w", "pressure"):
            handle.create_dataset(f"fluid/{name}", data=np.ascontiguousarray(field[name].T))
        handle.create_dataset("fluid/grid_shape", data=np.asarray(field["shape"], dtype=np.int32))
        handle.create_dataset("fluid/box_length", data=np.asarray(field["box"]))
        handle.create_dataset("fluid/time", data=field["time"])
        handle.create_dataset("forcing/state", data=field["forcing_state"])
