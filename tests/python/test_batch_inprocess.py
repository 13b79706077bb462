"""zwidth.batch computes its units in this process (python/bind_batch.cc), no zwidth executable
started: the table equals `zwidth batch`'s (the command run apart, the independent reference) byte
for byte on seeded `zwidth simulate` logs and a broken one, with specs, a manifest's per-unit
flag, the population's outlier columns; the GIL is released while a unit computes; a bad flag is
refused as the command refuses it; a resumed table computes nothing."""
import csv
import subprocess
import sys
import threading
import time

import pytest

import zwidth
from zwidth import _batch

FLAGS = dict(delays=[2, 4], b_points=20, window_length=512, modes=2, spec=["d2_K_cr_max>=30", "m<=2e-4"])


@pytest.fixture(scope="module")
def units(batch_logs):
    return batch_logs  # 5 ok units (the population's statistics run, analysis/population.h) and a broken one


def cli_table(exe, args, out):
    rc = subprocess.run([exe, "batch", *args, "-o", str(out)], capture_output=True, text=True).returncode
    assert rc == 4  # the broken log's row
    return out.read_text()


def no_process(*a, **k):
    raise AssertionError("zwidth.batch started a process")


def test_in_process_table_is_the_commands_byte_for_byte(units, exe, tmp_path, monkeypatch):
    ref = cli_table(exe, [*units, *_batch._flag_args(FLAGS)], tmp_path / "cli.csv")
    monkeypatch.setattr(subprocess, "Popen", no_process)
    for threads in (1, 2):
        out = tmp_path / f"py{threads}.csv"
        df = zwidth.batch(units, output=str(out), threads=threads, **FLAGS)
        assert out.read_text() == ref, f"threads={threads}"
    rows = list(csv.DictReader(open(tmp_path / "cli.csv", newline="")))
    assert [r["status"] for r in rows] == ["ok"] * 5 + ["input_error"]
    assert all(r["verdict"] in ("pass", "marginal", "fail") for r in rows[:5]) and rows[5]["verdict"] == "error"
    assert all(r["outlier"] in ("yes", "no") for r in rows[:5])
    assert df["status"].tolist() == [r["status"] for r in rows]


def test_manifest_units_with_their_own_flags_are_the_commands(units, exe, tmp_path, monkeypatch):
    manifest = tmp_path / "units.csv"
    with open(manifest, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["serial", "path", "output-scale"])
        w.writerow(["SN1", units[0], ""])
        w.writerow(["SN2", units[1], "2"])  # this unit's own log flag
        w.writerow(["SNX", units[-1], ""])
    flags = dict(delays=[2], b_points=20, window_length=512, modes=2)
    ref = cli_table(exe, ["--manifest", str(manifest), *_batch._flag_args(flags)], tmp_path / "cli.csv")
    monkeypatch.setattr(subprocess, "Popen", no_process)
    out = tmp_path / "py.csv"
    zwidth.batch(manifest=str(manifest), output=str(out), threads=2, **flags)
    assert out.read_text() == ref
    m = {r["serial"]: r["m"] for r in csv.DictReader(open(out, newline=""))}
    assert float(m["SN2"]) != float(m["SN1"])  # the scale reached that unit


def test_a_unit_releases_the_gil(units, tmp_path):
    args = [units[0], "--output", str(tmp_path / "t.csv"), *_batch._flag_args(dict(delays=[2], window_length=512))]
    zwidth._zwidth._batch_units(args, "gil")  # parsed before the thread starts

    def loops(until):  # this thread's Python loops while `until()` holds
        n = 0
        while until():
            n += 1
        return n
    t0 = time.perf_counter()
    alone = loops(lambda: time.perf_counter() - t0 < 0.2) / 0.2  # loops per second, no unit running
    result = {}
    def units_for_a_while():  # the unit again until 0.3 s have passed: long enough to tell on an idle machine
        while True:
            result["row"] = _batch._unit_row(args, "gil", 0, units[0], True)
            if time.perf_counter() - t0 > 0.3:
                return
    t = threading.Thread(target=units_for_a_while)
    t0 = time.perf_counter()
    t.start()
    beside = loops(t.is_alive)
    seconds = time.perf_counter() - t0
    t.join()
    assert result["row"]["status"] == "ok"
    # Holding the GIL, the unit would leave this thread about one switch interval (5 ms) of loops,
    # before it enters the library; released, this thread loops the whole time (on a shared machine
    # at a fraction of its speed alone: 22 % measured at load 6 on 2 cores).
    switch = sys.getswitchinterval()
    assert seconds > 20 * switch, f"the unit took {seconds:.3f} s: too short to tell"
    assert beside > 10 * switch * alone, f"{beside} loops beside the unit in {seconds:.3f} s, {alone:.0f}/s alone"


def test_bad_flag_is_refused_as_the_command_refuses_it(units, tmp_path):
    with pytest.raises(_batch.BatchError, match="--delays"):
        zwidth.batch(units[:1], output=str(tmp_path / "x.csv"), delays="two")
    with pytest.raises(_batch.BatchError, match="--no-such-flag|no_such_flag|no-such-flag"):
        zwidth.batch(units[:1], output=str(tmp_path / "x.csv"), no_such_flag=1)
    assert not (tmp_path / "x.csv").exists()


def test_resume_computes_nothing_and_a_changed_flag_computes_again(units, tmp_path, monkeypatch):
    out = str(tmp_path / "t.csv")
    flags = dict(delays=[2], b_points=20, window_length=512, modes=2)
    zwidth.batch(units[:2], output=out, threads=2, **flags)
    before = open(out).read()
    monkeypatch.setattr(_batch, "_unit_row", lambda *a: pytest.fail("a unit ran again"))
    zwidth.batch(units[:2], output=out, threads=2, **flags)
    assert open(out).read() == before
    ran = []
    monkeypatch.setattr(_batch, "_unit_row", lambda *a: ran.append(a[3]) or zwidth._zwidth._batch_unit(*a))
    zwidth.batch(units[:2], output=out, threads=2, **dict(flags, b_points=21))
    assert sorted(ran) == sorted(units[:2])
