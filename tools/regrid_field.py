"""regrid_field: a velocity field Agglo wrote, resampled spectrally onto another grid of the same box.

Reads a field file of the code (a final_field.h5 or a checkpoint: fluid/u, v, w, pressure,
grid_shape, box_length, time and forcing/state; or a field snapshot fields_<step>.h5: fields/u, v,
w, pressure, grid/shape, grid/lengths, time) and writes what &fluid init = 'file' reads on the new
grid: fluid/u, v, w, pressure, grid_shape, box_length, time, and forcing/state copied unchanged
(the Eswaran-Pope state holds the OU coefficients of the forced wavevectors, which are set by the
box and &forcing kappa_f_ratio alone, so it is the same on every grid; a snapshot has none).
A checkpoint's multistep history (explicit_old_*, dt_old, step, has_history) belongs to its grid
and is not written: a run started from a file begins its history afresh anyway.

Method (docs/studies/speed-accuracy.md, "Why the grid variants share one field"):
1. Each component is the trigonometric interpolant of its samples at its OWN staggered positions
   (src/fluid/fluid_grid.f90: u(i,j,k) at (i dx, (j-1/2) dy, (k-1/2) dz), v and w alike, the
   pressure at the cell centres), evaluated at the same kind of positions on the new grid: the
   Fourier coefficients carry the phase of the half-cell (or whole-cell) offset of each grid.
   Modes beyond the new grid's band are dropped (their energy is printed); an even old size's
   Nyquist mode is split evenly between +N/2 and -N/2 (the real cosine interpolant), so that
   128 -> 192 -> 128 returns every sample.
2. The velocity is made discretely divergence-free for the code's MAC divergence on the new grid,
   (u(i) - u(i-1))/dx + ..., whose Fourier symbol is sum_d 2i sin(k_d dx_d / 2)/dx_d on
   phase-aligned coefficients; the mean flow (k = 0) is kept. The default removes, per mode, a
   multiple of k (a gradient of the continuous interpolant: its vorticity is untouched, and the
   correction of a grid is undone exactly by the correction on the way back, so a round trip
   returns the field to round-off); --projection discrete removes the discrete gradient instead
   (the orthogonal projection the solver's own pressure step makes: the least change in the
   grid's kinetic energy). The two differ by far less than either changes the field.

Printed: the kinetic energy (1/2 the mean of u^2 + v^2 + w^2 over the cells, the code's
kinetic_energy) before and after resampling and after the projection, and the largest discrete
divergence relative to max|u|/dx before and after the projection.

Usage: .venv/bin/python tools/regrid_field.py INPUT.h5 --grid N [or NX NY NZ] -o OUTPUT.h5
           [--box L or LX LY LZ] [--projection continuous|discrete] [--force]
       .venv/bin/python tools/regrid_field.py INPUT.h5 --fingerprint
--fingerprint prints the SHA-256 of the field's content (grid, box, time, u, v, w, pressure and the
forcing state as stored, not the file's bytes, which carry HDF5 metadata): two files with the same
fingerprint start a deck on the same flow to the bit, so the results of runs started from them on
other machines or in other sessions may be compared run by run.
Exit status: 0 written (or printed), 2 refused (the argument and the reason named on stderr).
"""
import argparse
import hashlib
import os
import sys

import h5py
import numpy as np

# Offsets (in cells) of each staggered field's sample (i, j, k) from (i - 1, j - 1, k - 1) dx:
# the face component sits a whole cell along its own direction, half a cell along the others.
OFFSETS = {"u": (1.0, 0.5, 0.5), "v": (0.5, 1.0, 0.5), "w": (0.5, 0.5, 1.0), "pressure": (0.5, 0.5, 0.5)}
MIN_CELLS = 4
MAX_CELLS = 1290          # fluid_grid_t%cells_total is a default integer (src/fluid/fluid_grid.f90)
BOX_TOLERANCE = 1.0e-12   # relative, as src/fluid/fluid_restart.f90 (box_tolerance)


class Refusal(Exception):
    """Input the tool will not regrid: the message names the argument and the reason."""


# ------------------------------------------------------------------------------------------------
# Files
# ------------------------------------------------------------------------------------------------

def read_field(path):
    """The field file at path as a dict: u, v, w (and pressure when stored) indexed [i, j, k]
    (the code's Fortran order; h5py sees [k, j, i]), shape (nx, ny, nz), box (m), time (s),
    forcing_state (int64 words or None), kind ('final field or checkpoint' | 'field snapshot'),
    dropped (names of grid-bound datasets that are not carried over)."""
    if not os.path.isfile(path):
        raise Refusal(f"INPUT '{path}': no such file")
    try:
        handle = h5py.File(path, "r")
    except OSError as error:
        raise Refusal(f"INPUT '{path}': not an HDF5 file ({error})") from None
    with handle:
        if "fluid/u" in handle:
            group, shape_name, box_name, time_name = "fluid/", "fluid/grid_shape", "fluid/box_length", "fluid/time"
            kind = "final field or checkpoint"
        elif "fields/u" in handle:
            group, shape_name, box_name, time_name = "fields/", "grid/shape", "grid/lengths", "time"
            kind = "field snapshot"
        else:
            raise Refusal(f"INPUT '{path}': holds no velocity field (expected fluid/u, v, w of a final "
                          "field or checkpoint, or fields/u, v, w of a field snapshot)")
        for name in (shape_name, box_name):
            if name not in handle:
                raise Refusal(f"INPUT '{path}': {name} is missing (written by an older Agglo?)")
        shape = tuple(int(n) for n in np.asarray(handle[shape_name][()]).ravel())
        box = tuple(float(x) for x in np.asarray(handle[box_name][()]).ravel())
        if len(shape) != 3 or len(box) != 3:
            raise Refusal(f"INPUT '{path}': {shape_name} and {box_name} must be 3-vectors")
        field = {"shape": shape, "box": box, "kind": kind,
                 "time": float(handle[time_name][()]) if time_name in handle else 0.0}
        names = ["u", "v", "w"] + (["pressure"] if group + "pressure" in handle else [])
        for name in names:
            data = handle[group + name]
            if data.shape != shape[::-1]:
                raise Refusal(f"INPUT '{path}': {group}{name} has shape {data.shape[::-1]} (Fortran order), "
                              f"{shape_name} says {shape}")
            field[name] = np.ascontiguousarray(np.asarray(data[()], dtype=np.float64).T)
        field["forcing_state"] = np.asarray(handle["forcing/state"][()]) if "forcing/state" in handle else None
        field["dropped"] = sorted(f"fluid/{name}" for name in ("explicit_old_u", "explicit_old_v", "explicit_old_w",
                                                               "dt_old", "step", "has_history")
                                  if f"fluid/{name}" in handle)
        own = ("fluid", "forcing", "fields", "grid", "time", "step", "field_names", "field_locations")
        field["dropped"] += sorted(name for name in handle.keys() if name not in own)
    return field


def write_field(path, field, source_shape):
    """field (read_field's layout on the new grid) into path in the final-field layout, written
    to path.tmp and renamed when complete (as the code does: never a torn file under its name)."""
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    temporary = path + ".tmp"
    with h5py.File(temporary, "w") as handle:
        for name in ("u", "v", "w", "pressure"):
            if name in field:
                handle.create_dataset(f"fluid/{name}", data=np.ascontiguousarray(field[name].T))
        handle.create_dataset("fluid/grid_shape", data=np.asarray(field["shape"], dtype=np.int32))
        handle.create_dataset("fluid/box_length", data=np.asarray(field["box"], dtype=np.float64))
        handle.create_dataset("fluid/time", data=np.float64(field["time"]))
        if field.get("forcing_state") is not None:
            handle.create_dataset("forcing/state", data=field["forcing_state"])
        handle.attrs["regridded_from_grid_shape"] = np.asarray(source_shape, dtype=np.int32)
        handle.attrs["regridded_by"] = "tools/regrid_field.py"
    os.replace(temporary, path)


def field_fingerprint(field):
    """SHA-256 (hex) of a read_field dict's content: shape, box, time, the velocity and pressure
    samples and the forcing state, each as little-endian bytes in the code's [i, j, k] order."""
    digest = hashlib.sha256()
    digest.update(np.asarray(field["shape"], dtype="<i8").tobytes())
    digest.update(np.asarray(field["box"] + (field["time"],), dtype="<f8").tobytes())
    for name in ("u", "v", "w", "pressure"):
        if name in field:
            digest.update(name.encode())
            digest.update(np.ascontiguousarray(field[name], dtype="<f8").tobytes())
    if field["forcing_state"] is not None:
        digest.update(b"forcing")
        digest.update(np.ascontiguousarray(field["forcing_state"], dtype="<i8").tobytes())
    return digest.hexdigest()


# ------------------------------------------------------------------------------------------------
# Spectral resampling and the discrete projection
# ------------------------------------------------------------------------------------------------

def _resample_axis(array, axis, new_size, offset):
    """array (complex) along axis, sampled at (a + offset) h for a = 0 .. n-1 (h = L/n), as its
    trigonometric interpolant sampled at (b + offset) L/new_size, b = 0 .. new_size-1."""
    n = array.shape[axis]
    if n == new_size:
        return array
    spectrum = np.moveaxis(np.fft.fft(array, axis=axis), axis, 0) / n
    out = np.zeros((new_size,) + spectrum.shape[1:], dtype=complex)
    # (source index, signed mode, weight): every mode below the old Nyquist, and an even size's
    # Nyquist split evenly between +n/2 and -n/2 (the interpolant's real cosine).
    entries = [(index, index if index < n / 2 else index - n, 1.0) for index in range(n) if 2 * index != n]
    if n % 2 == 0:
        entries += [(n // 2, n // 2, 0.5), (n // 2, -n // 2, 0.5)]
    for index, mode, weight in entries:
        if 2 * abs(mode) > new_size:
            continue                                    # beyond the new band: truncated
        # continuous coefficient c_m = F_m e^{-2 pi i m offset / n}, sampled at the new positions
        phase = np.exp(2j * np.pi * mode * offset * (1.0 / new_size - 1.0 / n))
        out[mode % new_size] += weight * phase * spectrum[index]
    return np.moveaxis(np.fft.ifft(out * new_size, axis=0), 0, axis)


def resample(array, new_shape, offsets):
    """A real periodic field sampled at (index + offsets) cells, resampled onto new_shape cells of
    the same box at the same relative positions (offsets per axis, in cells of each grid)."""
    result = array.astype(complex)
    for axis in range(3):
        result = _resample_axis(result, axis, new_shape[axis], offsets[axis])
    return result.real.copy()


def _wavenumbers(shape, box):
    """Signed wavenumbers (1/m) and the angles theta = k h of the rfftn layout, broadcastable."""
    waves, angles = [], []
    for axis, (n, length) in enumerate(zip(shape, box)):
        modes = np.fft.rfftfreq(n, 1.0 / n) if axis == 2 else np.fft.fftfreq(n, 1.0 / n)
        view = [1, 1, 1]
        view[axis] = modes.size
        waves.append((2.0 * np.pi * modes / length).reshape(view))
        angles.append((2.0 * np.pi * modes / n).reshape(view))
    return waves, angles


def discrete_divergence(u, v, w, box):
    """The code's MAC divergence at the cell centres, (u(i) - u(i-1))/dx + ... (periodic)."""
    nx, ny, nz = u.shape
    return ((u - np.roll(u, 1, axis=0)) * (nx / box[0]) + (v - np.roll(v, 1, axis=1)) * (ny / box[1])
            + (w - np.roll(w, 1, axis=2)) * (nz / box[2]))


def project(u, v, w, box, method="continuous"):
    """(u, v, w) made discretely divergence-free on their grid (MAC divergence), the mean kept.
    Per mode, the array spectra U_d get U_d - alpha e_d exp(i theta_d / 2) with alpha chosen so
    that sum_d (1 - exp(-i theta_d)) U_d / h_d = 0: e = k (continuous: a gradient of the
    interpolant, exactly undone on the way back) or e = 2 sin(theta / 2) / h (discrete: the
    orthogonal projection, the least change in kinetic energy)."""
    shape = u.shape
    spectra = [np.fft.rfftn(component) for component in (u, v, w)]
    waves, angles = _wavenumbers(shape, box)
    steps = [length / n for n, length in zip(shape, box)]
    divergence = sum((1.0 - np.exp(-1j * angles[d])) / steps[d] * spectra[d] for d in range(3))
    if method == "continuous":
        directions = waves
    elif method == "discrete":
        directions = [2.0 * np.sin(angles[d] / 2.0) / steps[d] for d in range(3)]
    else:
        raise ValueError(f"unknown projection '{method}'")
    # sum_d 2i sin(theta_d/2)/h_d e_d: i times a positive number except at k = 0 (sin(theta/2) and
    # e_d have the sign of k_d for |theta| <= pi), so alpha is well defined
    symbol = sum(2j * np.sin(angles[d] / 2.0) / steps[d] * directions[d] for d in range(3))
    symbol[0, 0, 0] = 1.0
    alpha = divergence / symbol
    alpha[0, 0, 0] = 0.0                                    # the mean flow is kept
    return tuple(np.fft.irfftn(spectra[d] - alpha * directions[d] * np.exp(0.5j * angles[d]), s=shape,
                                 axes=(0, 1, 2)) for d in range(3))


def kinetic_energy(u, v, w):
    """1/2 the mean of u^2 + v^2 + w^2 over the cells (the code's kinetic_energy, m^2/s^2)."""
    return 0.5 * float(np.mean(u * u) + np.mean(v * v) + np.mean(w * w))


def relative_divergence(u, v, w, box):
    """max |div u| (1/s) times the smallest cell size over max |u_d|: the divergence relative to
    the largest speed over one cell."""
    speed = max(float(np.max(np.abs(c))) for c in (u, v, w))
    cell = min(length / n for length, n in zip(box, u.shape))
    divergence = float(np.max(np.abs(discrete_divergence(u, v, w, box))))
    return divergence * cell / speed if speed > 0.0 else 0.0


def truncated_energy_fraction(field, new_shape):
    """The fraction of the kinetic energy in the Fourier modes of the input beyond the new grid's
    band (|m_d| > new_d / 2 along some axis): what truncation to a coarser grid removes."""
    shape = field["shape"]
    modes = [np.abs(np.fft.fftfreq(n, 1.0 / n)).reshape([-1 if a == axis else 1 for a in range(3)])
             for axis, n in enumerate(shape)]
    outside = (2 * modes[0] > new_shape[0]) | (2 * modes[1] > new_shape[1]) | (2 * modes[2] > new_shape[2])
    removed = total = 0.0
    for name in "uvw":
        power = np.abs(np.fft.fftn(field[name])) ** 2
        removed += float(np.sum(power[np.broadcast_to(outside, power.shape)]))
        total += float(np.sum(power))
    return removed / total if total > 0.0 else 0.0


def regrid(field, new_shape, method="continuous"):
    """read_field's dict on new_shape (resampled, then projected), and a report dict of the
    energies and divergences."""
    box = field["box"]
    out = {key: field[key] for key in ("box", "time", "forcing_state")}
    out["shape"] = tuple(new_shape)
    report = {"energy_source": kinetic_energy(field["u"], field["v"], field["w"]),
              "divergence_source": relative_divergence(field["u"], field["v"], field["w"], box),
              "truncated_fraction": truncated_energy_fraction(field, new_shape)}
    resampled = {name: resample(field[name], new_shape, OFFSETS[name])
                 for name in ("u", "v", "w", "pressure") if name in field}
    report["energy_resampled"] = kinetic_energy(resampled["u"], resampled["v"], resampled["w"])
    report["divergence_resampled"] = relative_divergence(resampled["u"], resampled["v"], resampled["w"], box)
    out["u"], out["v"], out["w"] = project(resampled["u"], resampled["v"], resampled["w"], box, method)
    if "pressure" in resampled:
        out["pressure"] = resampled["pressure"]
    report["energy_projected"] = kinetic_energy(out["u"], out["v"], out["w"])
    report["divergence_projected"] = relative_divergence(out["u"], out["v"], out["w"], box)
    report["max_change_by_projection"] = max(float(np.max(np.abs(out[c] - resampled[c]))) for c in "uvw")
    report["max_speed"] = max(float(np.max(np.abs(out[c]))) for c in "uvw")
    return out, report


# ------------------------------------------------------------------------------------------------
# Command line
# ------------------------------------------------------------------------------------------------

def _grid(values):
    if len(values) not in (1, 3):
        raise Refusal(f"--grid {' '.join(values)}: give N (an N^3 grid) or NX NY NZ")
    cells = []
    for value in values:
        try:
            number = int(value)
        except ValueError:
            raise Refusal(f"--grid {' '.join(values)}: '{value}' is not a whole number of cells") from None
        if not MIN_CELLS <= number <= MAX_CELLS:
            raise Refusal(f"--grid {' '.join(values)}: {number} cells is outside {MIN_CELLS} .. {MAX_CELLS}")
        cells.append(number)
    return tuple(cells * 3 if len(cells) == 1 else cells)


def _box(values, source_box):
    if values is None:
        return
    if len(values) not in (1, 3):
        raise Refusal(f"--box {' '.join(values)}: give L (a cube) or LX LY LZ in m")
    try:
        lengths = [float(value) for value in values]
    except ValueError:
        raise Refusal(f"--box {' '.join(values)}: not numbers (m)") from None
    lengths = lengths * 3 if len(lengths) == 1 else lengths
    if any(abs(a - b) > BOX_TOLERANCE * abs(b) for a, b in zip(lengths, source_box)):
        raise Refusal(f"--box {' '.join(values)}: the input's box is {' x '.join(f'{x:g}' for x in source_box)} m; "
                      "regridding keeps the box (a field in another box is another flow)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="Method and output: see the module docstring (tools/regrid_field.py).")
    parser.add_argument("input", help="final_field.h5, a checkpoint or a field snapshot written by Agglo")
    parser.add_argument("--grid", nargs="+", metavar="N", help="N (N^3) or NX NY NZ cells")
    parser.add_argument("-o", "--output", help="the regridded field (final-field layout)")
    parser.add_argument("--box", nargs="+", metavar="L", help="the box (m) the caller expects: refused if the "
                                                              "input's differs")
    parser.add_argument("--projection", choices=("continuous", "discrete"), default="continuous",
                        help="remove k (default: exact round trips) or the discrete gradient (orthogonal)")
    parser.add_argument("--force", action="store_true", help="replace an existing OUTPUT")
    parser.add_argument("--fingerprint", action="store_true", help="print the SHA-256 of INPUT's field content "
                                                                   "and write nothing")
    args = parser.parse_args(argv)
    if args.fingerprint:
        try:
            print(f"{field_fingerprint(read_field(args.input))}  {args.input}")
        except Refusal as refusal:
            print(f"regrid_field: {refusal}", file=sys.stderr)
            return 2
        return 0
    if args.grid is None or args.output is None:
        parser.error("--grid and -o are required (or --fingerprint)")
    try:
        new_shape = _grid(args.grid)
        if os.path.exists(args.output) and os.path.exists(args.input) and os.path.samefile(args.output, args.input):
            raise Refusal(f"-o '{args.output}': is the INPUT itself")
        if os.path.exists(args.output) and not args.force:
            raise Refusal(f"-o '{args.output}': exists (an earlier field is never replaced without --force)")
        field = read_field(args.input)
        _box(args.box, field["box"])
    except Refusal as refusal:
        print(f"regrid_field: {refusal}", file=sys.stderr)
        return 2
    out, report = regrid(field, new_shape, args.projection)
    write_field(args.output, out, field["shape"])
    grid = " x ".join(str(n) for n in field["shape"])
    print(f"source: {args.input} ({field['kind']}), {grid} cells, box {' x '.join(f'{x:g}' for x in field['box'])} m, "
          f"t = {field['time']:.6g} s")
    print(f"  kinetic energy {report['energy_source']:.10e} m^2/s^2, max|div| dx / max|u| = "
          f"{report['divergence_source']:.3e}")
    change = report["energy_resampled"] / report["energy_source"] - 1.0
    print(f"resampled to {' x '.join(str(n) for n in new_shape)}: kinetic energy {report['energy_resampled']:.10e} "
          f"(changed by {change:+.3e}); energy in the modes beyond the new band: "
          f"{report['truncated_fraction']:.3e} of the total; max|div| dx / max|u| = {report['divergence_resampled']:.3e}")
    change = report["energy_projected"] / report["energy_resampled"] - 1.0
    print(f"projected ({args.projection}): kinetic energy {report['energy_projected']:.10e} (changed by {change:+.3e}), "
          f"max|div| dx / max|u| = {report['divergence_projected']:.3e}, largest change of a velocity sample "
          f"{report['max_change_by_projection'] / report['max_speed']:.3e} max|u|")
    if field["forcing_state"] is None:
        print("note: the input has no forcing/state (a field snapshot or an unforced run): a forced deck needs "
              "&forcing initial_state = 'stationary' to start from it")
    else:
        print(f"forcing/state: copied ({field['forcing_state'].size} words; grid-independent)")
    if "pressure" not in out:
        print("note: the input has no pressure; none written (the code then starts from p = 0)")
    if field["dropped"]:
        print(f"not carried over (bound to the old grid or not fluid state): {', '.join(field['dropped'])}")
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
