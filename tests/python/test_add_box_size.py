"""tools/add_box_size.py (launcher tools/add-box-size): the box lengths written into a field file
that lacks them, in the dataset the code reads (src/fluid/fluid_restart.f90: grid/lengths of a
field snapshot, fluid/box_length of a final field or checkpoint), nothing else changed; refusals
of a file that says another box, of a file without a field and of a malformed --box. The code's own
acceptance of the result is tested end to end in tests/decks/test_deck_limits.sh."""
import h5py
import numpy as np
import pytest

from conftest import REPO, run_tool

TOOL = REPO / "tools" / "add-box-size"


def field_file(path, layout):
    """A small field file without its box: a snapshot (fields/u, grid/shape) or a final field
    (fluid/u, fluid/grid_shape); returns the name of the box dataset the code reads for it."""
    values = np.arange(4 * 4 * 4, dtype=np.float64).reshape(4, 4, 4)
    with h5py.File(path, "w") as handle:
        if layout == "snapshot":
            handle.create_dataset("fields/u", data=values)
            handle.create_dataset("grid/shape", data=np.asarray([4, 4, 4], dtype=np.int32))
            return "grid/lengths"
        handle.create_dataset("fluid/u", data=values)
        handle.create_dataset("fluid/grid_shape", data=np.asarray([4, 4, 4], dtype=np.int32))
        return "fluid/box_length"


@pytest.mark.parametrize("layout", ["snapshot", "final_field"])
def test_box_written_where_the_code_reads_it(tmp_path, layout):
    path = tmp_path / f"{layout}.h5"
    name = field_file(path, layout)
    result = run_tool([TOOL, path, "--box", "7.0e-4", "8.0e-4", "6.99999999999999993E-004"])
    assert result.returncode == 0, result.stderr
    with h5py.File(path, "r") as handle:
        stored = np.asarray(handle[name][()])
        assert stored.dtype == np.float64 and stored.shape == (3,)
        # The text of the code's message reads back as the same double.
        assert stored.tolist() == [7.0e-4, 8.0e-4, 7.0e-4]
        assert np.array_equal(handle[f"{'fields' if layout == 'snapshot' else 'fluid'}/u"][()],
                              np.arange(64, dtype=np.float64).reshape(4, 4, 4))


def test_one_value_is_a_cube_and_a_second_call_writes_nothing(tmp_path):
    path = tmp_path / "cube.h5"
    name = field_file(path, "snapshot")
    assert run_tool([TOOL, path, "--box", "1e-3"]).returncode == 0
    again = run_tool([TOOL, path, "--box", "1e-3"])
    assert again.returncode == 0 and "nothing written" in again.stdout
    with h5py.File(path, "r") as handle:
        assert np.asarray(handle[name][()]).tolist() == [1e-3, 1e-3, 1e-3]


def test_another_box_is_refused_and_kept(tmp_path):
    path = tmp_path / "other.h5"
    name = field_file(path, "final_field")
    assert run_tool([TOOL, path, "--box", "1e-3"]).returncode == 0
    result = run_tool([TOOL, path, "--box", "2e-3"])
    assert result.returncode == 2 and "already says its box, fluid/box_length = 0.001 x 0.001 x 0.001" in result.stderr
    with h5py.File(path, "r") as handle:
        assert np.asarray(handle[name][()]).tolist() == [1e-3, 1e-3, 1e-3]


@pytest.mark.parametrize("box, reason", [(["1e-3", "1e-3"], "give L (a cube) or LX LY LZ"),
                                         (["0"], "each > 0"), (["nan"], "each > 0"), (["wide"], "not numbers")])
def test_malformed_box_refused(tmp_path, box, reason):
    path = tmp_path / "field.h5"
    field_file(path, "snapshot")
    result = run_tool([TOOL, path, "--box", *box])
    assert result.returncode == 2 and reason in result.stderr
    with h5py.File(path, "r") as handle:
        assert "grid/lengths" not in handle


def test_file_without_a_field_refused(tmp_path):
    path = tmp_path / "empty.h5"
    h5py.File(path, "w").close()
    result = run_tool([TOOL, path, "--box", "1e-3"])
    assert result.returncode == 2 and "holds no velocity field" in result.stderr
    missing = run_tool([TOOL, tmp_path / "missing.h5", "--box", "1e-3"])
    assert missing.returncode == 2 and "FILE" in missing.stderr
