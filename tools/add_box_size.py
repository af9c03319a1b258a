"""add_box_size: write the box size into a field file of Agglo that does not hold it.

A field file (a field snapshot fields_<step>.h5: fields/u, v, w, grid/shape, grid/lengths; or a
final_field.h5 or a checkpoint: fluid/u, v, w, fluid/grid_shape, fluid/box_length) carries the box
lengths it was computed in, and the code refuses to start from a file whose box is not the deck's
&grid (src/fluid/fluid_restart.f90). Files written before the box was stored lack that dataset
and are refused with a message that names this tool. Given the box the file was computed in (the
&grid length_x, length_y, length_z of the run that wrote it: its run.nml), the tool adds
grid/lengths (snapshot) or fluid/box_length (final field, checkpoint) as 3 float64 values in m,
and changes nothing else. The box is the caller's word: nothing in the file can confirm it.

Usage: tools/add-box-size FILE.h5 --box L | LX LY LZ   (or .venv/bin/python tools/add_box_size.py ...)
Exit status: 0 written (or the file already holds exactly that box), 2 refused: a missing or
non-field file, a --box that is not 1 or 3 positive numbers, or a file that already says another
box (the message names it).
"""
import argparse
import sys

import h5py
import numpy as np

BOX_TOLERANCE = 1.0e-12   # relative, as src/fluid/fluid_restart.f90 (box_tolerance)


class Refusal(Exception):
    """A file or argument the tool will not write: the message names it and the reason."""


def box_lengths(values):
    """--box values as three positive lengths (m): one value is a cube."""
    try:
        lengths = [float(value) for value in values]
    except ValueError:
        raise Refusal(f"--box {' '.join(values)}: not numbers (m)") from None
    if len(lengths) == 1:
        lengths *= 3
    if len(lengths) != 3 or not all(np.isfinite(lengths)) or min(lengths) <= 0.0:
        raise Refusal(f"--box {' '.join(values)}: give L (a cube) or LX LY LZ, each > 0 (m)")
    return lengths


def add_box_size(path, lengths):
    """Write lengths into the field file at path; returns (dataset name, written: bool)."""
    try:
        handle = h5py.File(path, "r+")
    except OSError as error:
        raise Refusal(f"FILE '{path}': cannot open it for writing as an HDF5 file ({error})") from None
    with handle:
        if "fields/u" in handle:
            name = "grid/lengths"
        elif "fluid/u" in handle:
            name = "fluid/box_length"
        else:
            raise Refusal(f"FILE '{path}': holds no velocity field (expected fields/u of a field snapshot "
                          "or fluid/u of a final field or checkpoint)")
        if name in handle:
            stored = [float(x) for x in np.asarray(handle[name][()]).ravel()]
            if len(stored) == 3 and all(abs(a - b) <= BOX_TOLERANCE * abs(b) for a, b in zip(lengths, stored)):
                return name, False
            raise Refusal(f"FILE '{path}': already says its box, {name} = {' x '.join(f'{x:.17g}' for x in stored)} m; "
                          "the tool only adds a missing box")
        handle.create_dataset(name, data=np.asarray(lengths, dtype=np.float64))
    return name, True


def main(argv=None):
    parser = argparse.ArgumentParser(description="Write the box size into an Agglo field file that lacks it.")
    parser.add_argument("file", metavar="FILE.h5", help="field snapshot, final field or checkpoint")
    parser.add_argument("--box", nargs="+", metavar="L", required=True,
                        help="the box the file was computed in (m): L (a cube) or LX LY LZ")
    args = parser.parse_args(argv)
    try:
        lengths = box_lengths(args.box)
        name, written = add_box_size(args.file, lengths)
    except Refusal as refusal:
        print(f"add_box_size: {refusal}", file=sys.stderr)
        return 2
    box = " x ".join(f"{x:.17g}" for x in lengths)
    if written:
        print(f"add_box_size: {args.file}: {name} = {box} m written")
    else:
        print(f"add_box_size: {args.file}: already holds {name} = {box} m; nothing written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
