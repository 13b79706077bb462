"""zwidth.batch: `zwidth batch` from Python, on threads or on a dask.distributed cluster.

The request is `zwidth batch`'s: the keywords are its flags (the library's option table,
io/option_names.cc, else the keyword with dashes), parsed by the command's own declarations in
the compiled module (flags::ParseBatchRequest, below apps), so a bad flag is refused as the command refuses it
and a unit's input hash is the command's. Each unit is then computed in this process (or in a
worker's) by the batch engine, analysis::RunBatch on that unit, with the GIL released: its row of
text cells, its error as a row. Threads here, or the workers of a ``dask.distributed.Client``
(``client.map``; dask is the scheduler, zwidth does not bring one), run units side by side; a
worker needs only ``import zwidth`` and the logs at the paths given (a shared file system, or
localhost). The batch's end is the command's too (flags::FinishBatch): every unit resumed from its
row, the population's outlier columns, the table written by io::WriteBatchTable.
"""

import csv
import io
import os
import uuid
from concurrent.futures import ThreadPoolExecutor


class BatchError(RuntimeError):
    """zwidth batch refused the request (a bad flag, manifest or path): nothing was computed."""


def _flag_args(flags):
    """{'delays': [2, 4], 'window_length': 1024, 'allow_short': True, 'spec': ['m<=1', 'b<=2']}
    -> ['--delays', '2,4', '--window-length', '1024', '--allow-short', '--spec', 'm<=1', '--spec', 'b<=2']."""
    from . import _zwidth
    args = []
    for name, value in flags.items():
        flag = _zwidth._batch_flag(name)
        if value is True:
            args.append(flag)
        elif value is False or value is None:
            continue
        elif flag == "--spec" and isinstance(value, (list, tuple)):  # repeatable, one spec each
            for v in value:
                args += [flag, str(v)]
        elif isinstance(value, (list, tuple)):
            args += [flag, ",".join(str(v) for v in value)]
        else:
            args += [flag, str(value)]
    return args


def _unit_row(args, batch_id, index, serial, serial_thread=True, call=""):
    """Unit `index` of the batch computed here (a thread or a dask worker): its row, a dict of text cells."""
    from . import _zwidth
    return _zwidth._batch_unit(args, batch_id, index, serial, serial_thread, call)


def _call_text(logs, output, manifest, client, threads, flags):
    """The call as a readable line, what the unit folders and the fleet report record as their command:
    zwidth.batch(['a.csv', 'b.csv'], output='t.csv', threads=2, delays=[2, 4])."""
    parts = [repr(logs)] if logs is not None else []
    parts += [f"output={os.fspath(output)!r}"]
    if manifest is not None:
        parts.append(f"manifest={os.fspath(manifest)!r}")
    if client is not None:
        parts.append("client=<dask client>")
    if threads is not None:
        parts.append(f"threads={threads!r}")
    parts += [f"{k}={v!r}" for k, v in flags.items()]
    return "zwidth.batch(" + ", ".join(parts) + ")"


def _run_on_threads(args, batch_id, call, rows, todo, serials, threads):
    """The units `todo` on a pool of threads, the rows finished so far saved as the command saves them
    (the library's BatchTableSaver, every 2 s). Ctrl-C (KeyboardInterrupt): no unit is started after it,
    the running ones end, every finished row is saved at once (a resumable table whose rows are exactly
    the finished units, their folders written), and the KeyboardInterrupt goes on."""
    from concurrent.futures import FIRST_COMPLETED, wait
    from . import _zwidth
    workers = min(max(len(todo), 1), threads or os.cpu_count() or 1)
    serial_thread = workers > 1  # each unit's own work on its thread alone, as `zwidth batch --jobs`
    pool = ThreadPoolExecutor(max_workers=workers)
    futures = {pool.submit(_unit_row, args, batch_id, i, s, serial_thread, call): i for i, s in zip(todo, serials)}
    pending = set(futures)
    try:
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for f in finished:
                rows[futures[f]] = f.result()
            _zwidth._batch_progress(batch_id, rows)
    except BaseException:  # Ctrl-C, or an error of the saver or a unit's thread: the finished rows saved
        for f in pending:
            f.cancel()
        pool.shutdown(wait=True, cancel_futures=True)
        for f, i in futures.items():
            if f.done() and not f.cancelled() and f.exception() is None:
                rows[i] = f.result()
        _zwidth._batch_progress(batch_id, rows, now=True)
        raise
    finally:
        pool.shutdown(wait=True)


def _run_on_client(client, args, batch_id, call, rows, todo, serials):
    """The units `todo` as tasks of a dask.distributed `client`, each row taken as its task ends and the rows
    finished so far saved as on threads (every 2 s; a killed batch resumes them). Ctrl-C (KeyboardInterrupt):
    the tasks not finished are cancelled, every finished row is saved at once, and the KeyboardInterrupt goes
    on; so does an error of the cluster (a worker lost past dask's retries), after the same save. A task
    already running on a worker cannot be stopped there (dask cancels its result, not its thread): such a
    unit may still write its folder, but it is not in the table, so a re-run computes it again (its folder
    replaced)."""
    from distributed import as_completed
    from . import _zwidth
    n = len(todo)
    futures = client.map(_unit_row, [args] * n, [batch_id] * n, todo, serials, [True] * n, [call] * n, pure=False)
    index = {f.key: i for f, i in zip(futures, todo)}
    try:
        for f in as_completed(futures):
            rows[index[f.key]] = f.result()
            _zwidth._batch_progress(batch_id, rows)
    except BaseException:
        try:
            client.cancel([f for f in futures if not f.done()])
            for f in futures:
                if f.status == "finished" and rows[index[f.key]] is None:
                    rows[index[f.key]] = f.result(timeout=10)
        except Exception:  # the scheduler gone: the rows taken so far are saved, the first error raised
            pass
        finally:
            _zwidth._batch_progress(batch_id, rows, now=True)
        raise


def _table_text(path):
    """The table at `path` as CSV text, read by the library (io::ReadBatchTable: CSV or HDF5, its rule)."""
    from . import _zwidth
    return _zwidth._read_batch_table(os.fspath(path))


def batch(logs=None, *, output, manifest=None, client=None, threads=None, **flags):
    """Runs `zwidth batch` over `logs` (paths or globs) or a `manifest` CSV into the table `output`
    (CSV, or HDF5 when it ends .h5/.hdf5, as the command writes it), each unit in this process
    (or on the client's workers) through the library.

    flags: the command's flags as keywords (delays=[2, 4], window_length=1024, reference="table1",
    spec=["m<=2e-4"], population="pop.csv", restart=True, ...).
    client: a dask.distributed.Client; the units then run as its tasks (the workers import zwidth).
    Else on `threads` threads (default: the cores); a unit releases the GIL while it computes.
    Returns the table: a pandas DataFrame when pandas imports, else a list of dicts of text cells.
    A unit that fails is a row with status and error; a bad request raises BatchError.
    An existing `output` of an earlier batch is resumed (its units with the same inputs are not run).
    """
    from . import _zwidth
    if (logs is None) == (manifest is None):
        raise BatchError("batch takes logs (paths or globs) or manifest=units.csv, not both and not neither")
    if isinstance(logs, (str, os.PathLike)):
        logs = [logs]
    if "jobs" in flags:
        raise BatchError("jobs: zwidth.batch runs units on threads=N or a dask client=, not --jobs")
    args = ["--manifest", os.fspath(manifest)] if manifest else [os.fspath(a) for a in logs]
    args += ["--output", os.fspath(output), *_flag_args(flags)]
    batch_id = uuid.uuid4().hex  # a worker parses this request once
    call = _call_text(logs, output, manifest, client, threads, flags)
    try:
        units = _zwidth._batch_units(args, batch_id, call)  # (serial, the previous table's row or None)
    except _zwidth.InputError as e:
        raise BatchError(str(e)) from None
    rows = [row for _, row in units]  # a unit resumed from the table at `output`: its row; else None
    todo = [i for i, row in enumerate(rows) if row is None]
    serials = [units[i][0] for i in todo]
    if client is not None:
        _run_on_client(client, args, batch_id, call, rows, todo, serials)
    else:
        _run_on_threads(args, batch_id, call, rows, todo, serials, threads)
    text = _zwidth._batch_finish(args, batch_id, rows, call)
    try:
        import pandas
        return pandas.read_csv(io.StringIO(text), dtype={"serial": str, "input_hash": str, "logs": str})
    except ImportError:
        return list(csv.DictReader(io.StringIO(text)))
