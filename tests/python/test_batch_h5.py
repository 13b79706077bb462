"""zwidth.batch writing the HDF5 table (output=*.h5): the cells of `zwidth batch -o *.csv` on the
same units (through h5py, an independent reader, when it is installed), and a re-run through
Python resumes from the .h5 without running a unit."""
import csv
import math
import subprocess

import pytest

import zwidth
from zwidth import _batch

FLAGS = dict(delays=[2], b_points=20, window_length=512)


@pytest.fixture(scope="module")
def units(batch_logs):
    return batch_logs[:2] + batch_logs[-1:]


def test_python_batch_writes_the_commands_table_as_hdf5_and_resumes_from_it(units, exe, tmp_path, monkeypatch):
    cli = tmp_path / "cli.csv"
    rc = subprocess.run([exe, "batch", *units, "-o", str(cli), *_batch._flag_args(FLAGS)], capture_output=True).returncode
    assert rc == 4  # the corrupt log's row
    out = str(tmp_path / "py.h5")
    df = zwidth.batch(units, output=out, threads=2, **FLAGS)
    with open(out, "rb") as f:
        assert f.read(8) == b"\x89HDF\r\n\x1a\n"
    # The library's reader gives the command's CSV, byte for byte.
    assert zwidth._zwidth._read_batch_table(out) == cli.read_text()
    rows = list(csv.DictReader(open(cli, newline="")))
    statuses = df["status"].tolist() if hasattr(df, "columns") else [r["status"] for r in df]
    assert statuses == [r["status"] for r in rows] == ["ok", "ok", "input_error"]
    h5py = pytest.importorskip("h5py")
    with h5py.File(out, "r") as f:
        assert [c.decode() for c in f["columns"][:]] == list(rows[0])
        m = f["batch/m"]
        assert m.dtype.kind == "f" and list(f["empty/m"][:]) == [0, 0, 1]
        for i in (0, 1):
            assert float(m[i]) == float(rows[i]["m"])
        assert [s.decode() for s in f["batch/serial"][:]] == [r["serial"] for r in rows]
        assert math.isnan(float(m[2])) and rows[2]["m"] == ""
    # Resume through Python: every unit is in the .h5 table, none runs again.
    monkeypatch.setattr(_batch, "_unit_row", lambda *a: pytest.fail("a unit ran again"))
    zwidth.batch(units, output=out, **FLAGS)
    assert zwidth._zwidth._read_batch_table(out) == cli.read_text()
