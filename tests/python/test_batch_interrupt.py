"""zwidth.batch as `zwidth batch` runs: the unit folders record the Python call that made them (the
command records its argv); the rows finished so far are saved while the batch runs (the library's
BatchTableSaver, the command's), so a killed batch keeps them and a re-run resumes them; Ctrl-C stops
promptly, leaving a table of exactly the finished units (their folders written), resumable."""
import csv
import os
import signal
import subprocess
import sys
import textwrap
import time

import zwidth

FLAGS = dict(delays=[2], b_points=10, window_length=512, modes=0)  # ~10 ms a unit


def _env():
    return dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(zwidth.__file__)), PYTHONDONTWRITEBYTECODE="1")


def _manifest(tmp_path, log, n):
    """n units, each the same log under its own serial: a batch of n units at the cost of one log."""
    path = tmp_path / "units.csv"
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["serial", "path"])
        for i in range(n):
            w.writerow([f"SN{i:04d}", log])
    return path


def _rows(path):
    return list(csv.DictReader(open(path, newline="")))


def _child(manifest, out, folders=None):
    """A Python process running the batch: prints 'started' just before it, 'interrupted' on
    KeyboardInterrupt. Python's Ctrl-C handler is installed even when this test runs where SIGINT is
    ignored (a background job)."""
    extra = f", unit_folders={str(folders)!r}" if folders else ""
    script = textwrap.dedent(f"""
        import signal, sys, time, zwidth
        signal.signal(signal.SIGINT, signal.default_int_handler)
        print("started", flush=True)
        try:
            zwidth.batch(manifest={str(manifest)!r}, output={str(out)!r}, threads=1{extra}, **{FLAGS!r})
            print("finished", flush=True)
        except KeyboardInterrupt:
            print("interrupted", time.monotonic(), flush=True)
    """)
    return subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=_env())


def test_unit_folders_and_fleet_report_record_the_python_call(batch_logs, tmp_path):
    folders = tmp_path / "units"
    folders.mkdir()
    manifest, out, fleet = _manifest(tmp_path, batch_logs[0], 2), tmp_path / "t.csv", tmp_path / "fleet.html"
    zwidth.batch(manifest=manifest, output=str(out), threads=1, unit_folders=str(folders), fleet_report=str(fleet),
                 **FLAGS)
    # The call as typed, written here independently of zwidth._batch's formatting.
    call = (f"zwidth.batch(output={str(out)!r}, manifest={str(manifest)!r}, threads=1, unit_folders={str(folders)!r}, "
            f"fleet_report={str(fleet)!r}, delays=[2], b_points=10, window_length=512, modes=0)")
    escaped = {call.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace("'", e)
               for e in ("&#39;", "&#x27;", "&apos;", "'")}
    assert sorted(os.listdir(folders)) == ["SN0000", "SN0001"]
    for d in folders.iterdir():
        text = (d / "report.html").read_text()
        command = text.split("command: <code>", 1)[1].split("</code>", 1)[0]
        assert command in escaped, command
    assert any(e in fleet.read_text() for e in escaped)


def test_a_killed_batch_keeps_the_units_saved_while_it_ran(batch_logs, tmp_path):
    n = 400  # ~4 s of units: the first save (2 s, as the command's) comes before the end
    manifest, out = _manifest(tmp_path, batch_logs[0], n), tmp_path / "t.csv"
    p = _child(manifest, out)
    t0 = time.monotonic()
    while not out.exists() and p.poll() is None and time.monotonic() - t0 < 30:
        time.sleep(0.02)
    p.kill()  # SIGKILL: nothing of the batch runs after it
    p.communicate()
    assert out.exists(), "no table was saved while the batch ran"
    rows = _rows(out)
    assert 0 < len(rows) < n, len(rows)
    assert all(r["status"] == "ok" and r["input_hash"] for r in rows)
    assert not [f for f in os.listdir(tmp_path) if ".tmp" in f]  # the saves are atomic
    # A re-run takes every saved unit from the table (the same input hash) and computes the others.
    args = ["--manifest", str(manifest), "--output", str(out), *zwidth._batch._flag_args(FLAGS)]
    units = zwidth._zwidth._batch_units(args, "resume-check")
    resumed = {serial: row for serial, row in units if row is not None}
    assert set(resumed) == {r["serial"] for r in rows}
    assert all(resumed[r["serial"]]["m"] == r["m"] for r in rows)


def test_ctrl_c_stops_promptly_and_leaves_the_finished_units(batch_logs, tmp_path):
    n = 400
    manifest, out, folders = _manifest(tmp_path, batch_logs[0], n), tmp_path / "t.csv", tmp_path / "units"
    folders.mkdir()
    p = _child(manifest, out, folders)
    assert p.stdout.readline().strip() == "started"
    time.sleep(1.2)  # units running, before the first periodic save (2 s)
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=30)
    stopped = time.monotonic() - sent
    assert "interrupted" in stdout, (stdout, stderr)
    assert stopped < 1.5, stopped  # no unit started after Ctrl-C: the running one ends, the table is saved
    rows = _rows(out)
    assert 0 < len(rows) < n
    assert all(r["status"] == "ok" for r in rows)
    # The table holds exactly the finished units, each with its folder.
    assert {r["serial"] for r in rows} == set(os.listdir(folders))
    assert not [f for f in os.listdir(tmp_path) if ".tmp" in f]
    # Resumed: the interrupted table's units are not computed again.
    args = ["--manifest", str(manifest), "--output", str(out), "--unit-folders", str(folders),
            *zwidth._batch._flag_args(FLAGS)]
    units = zwidth._zwidth._batch_units(args, "resume-after-ctrl-c")
    assert sum(row is not None for _, row in units) == len(rows)
