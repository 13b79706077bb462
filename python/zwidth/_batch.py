"""zwidth.batch: `zwidth batch` from Python, on threads or on a dask.distributed cluster.

Each unit is one ``zwidth batch`` process (an argument vector, never a shell)
that writes that unit's row; the rows are then merged by ``zwidth batch`` itself
over all the units, which finds every unit done with the same inputs and options
(its resume) and writes the table in its own column order. So the table is the
command's, whatever ran the units: threads here, or the workers of a
``dask.distributed.Client`` (``client.map``; dask is the scheduler, zwidth does
not bring one). The workers need the zwidth executable and read the logs at the
paths given (a shared file system, or localhost).
"""

import csv
import io
import os
import shutil
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor


class BatchError(RuntimeError):
    """zwidth batch refused the request (a bad flag, manifest or path): nothing was computed."""


def _flag_args(flags):
    """{'delays': [2, 4], 'window_length': 1024, 'allow_short': True} -> ['--delays', '2,4', ...]."""
    args = []
    for name, value in flags.items():
        flag = "--" + name.replace("_", "-")
        if value is True:
            args.append(flag)
        elif value is False or value is None:
            continue
        elif isinstance(value, (list, tuple)):
            args += [flag, ",".join(str(v) for v in value)]
        else:
            args += [flag, str(value)]
    return args


def _run(exe, args):
    p = subprocess.run([exe, "batch", *args], capture_output=True, text=True)
    if p.returncode not in (0, 4):  # 4: some unit failed, its row says why
        raise BatchError(p.stderr.strip() or f"zwidth batch exited {p.returncode}")
    return p


def _unit_row(exe, unit, args):
    """One unit in its own `zwidth batch` (--jobs 1): its table's text. Runs on a thread or a dask worker."""
    with tempfile.TemporaryDirectory(prefix="zwidth_unit_") as d:
        table = os.path.join(d, "row.csv")
        if isinstance(unit, dict):  # a manifest row: serial, path and log flags
            manifest = os.path.join(d, "unit.csv")
            with open(manifest, "w", newline="") as f:
                w = csv.writer(f)
                w.writerow(list(unit))
                w.writerow(list(unit.values()))
            _run(exe, ["--manifest", manifest, "-o", table, "--jobs", "1", *args])
        else:
            _run(exe, [unit, "-o", table, "--jobs", "1", *args])
        with open(table, newline="") as f:
            return f.read()


def _table_text(path):
    """The table at `path` as CSV text, read by the library (io::ReadBatchTable: CSV or HDF5, its rule)."""
    from . import _zwidth
    return _zwidth._read_batch_table(os.fspath(path))


def _manifest_units(manifest):
    folder = os.path.dirname(os.path.abspath(manifest))
    with open(manifest, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:  # as zwidth reads it: a relative path from the manifest's folder
        if "path" in r and r["path"] and not os.path.isabs(r["path"]):
            r["path"] = os.path.join(folder, r["path"])
    return rows


def batch(logs=None, *, output, manifest=None, client=None, threads=None, zwidth=None, **flags):
    """Runs `zwidth batch` over `logs` (paths or globs) or a `manifest` CSV into the table `output`
    (CSV, or HDF5 when it ends .h5/.hdf5, as the command writes it).

    flags: run's flags as keywords (delays=[2, 4], window_length=1024, reference="table1", ...).
    client: a dask.distributed.Client; the units then run as its tasks. Else on `threads`
    threads (default: the cores; each unit is a process, so the GIL is not held).
    zwidth: the executable (default: $ZWIDTH_EXE, else `zwidth` on PATH).
    Returns the table: a pandas DataFrame when pandas imports, else a list of dicts of text cells.
    A unit that fails is a row with status and error; a bad request raises BatchError.
    An existing `output` of an earlier batch is resumed (its units with the same inputs are not run).
    """
    exe = zwidth or os.environ.get("ZWIDTH_EXE") or shutil.which("zwidth")
    if not exe:
        raise BatchError("no zwidth executable: pass zwidth='/path/to/zwidth' or set ZWIDTH_EXE")
    if (logs is None) == (manifest is None):
        raise BatchError("batch takes logs (paths or globs) or manifest=units.csv, not both and not neither")
    args = _flag_args(flags)
    if isinstance(logs, str):
        logs = [logs]
    whole = ["--manifest", manifest] if manifest else list(logs)
    # The units as zwidth names them (a glob expanded in name order, as zwidth does).
    if manifest:
        units = _manifest_units(manifest)
    else:
        import glob as _glob
        units = []
        for a in logs:
            units += sorted(_glob.glob(a)) if any(c in a for c in "*?[") else [a]
    # Resume: units in an earlier table are left to zwidth's merge, which takes a row whose
    # inputs hash the same and computes again (on this machine) one whose log or options changed.
    done, earlier = set(), None
    if os.path.exists(output):
        earlier = _table_text(output)
        done = {r["serial"] for r in csv.DictReader(io.StringIO(earlier))}
    todo = [u for u in units if (u["serial"] if isinstance(u, dict) else u) not in done]
    if client is not None:
        texts = client.gather(client.map(_unit_row, [exe] * len(todo), todo, [args] * len(todo), pure=False))
    else:
        with ThreadPoolExecutor(max_workers=threads or os.cpu_count() or 1) as pool:
            texts = list(pool.map(lambda u: _unit_row(exe, u, args), todo))
    # The rows, with those of the earlier table, as the table zwidth resumes from.
    rows, columns = [], []
    sources = [earlier] if done else []
    for text in sources + texts:
        for r in csv.DictReader(io.StringIO(text)):
            rows.append(r)
            columns += [c for c in r if c not in columns]
    merged = io.StringIO()
    w = csv.DictWriter(merged, fieldnames=columns, restval="", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    # Written by the library (io::WriteBatchTable: HDF5 or CSV by its rule, atomically).
    from . import _zwidth
    _zwidth._write_batch_table(os.fspath(output), merged.getvalue())
    _run(exe, [*whole, "-o", output, *args])  # every unit resumed: zwidth writes the table
    text = _table_text(output)
    try:
        import pandas
        return pandas.read_csv(io.StringIO(text), dtype={"serial": str, "input_hash": str, "logs": str})
    except ImportError:
        return list(csv.DictReader(io.StringIO(text)))
