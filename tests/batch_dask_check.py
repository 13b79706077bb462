"""zwidth.batch (python/zwidth/_batch.py) on threads, on a dask.distributed LocalCluster of two
worker processes, and `zwidth batch` itself: the same table, byte for byte, with the corrupt log's
row; then a resume through Python computes nothing.

Logs: `zwidth simulate` of Table I (8 s, seeds 1..3) and a corrupt text log.
The module is the built package's: each unit is computed in the process that runs it (the
extension's batch engine, python/bind_batch.cc); the workers import zwidth from PYTHONPATH and
start no executable (zwidth batch runs only to make the reference table).
Usage: batch_dask_check.py ZWIDTH SRC BUILD/python
"""
import os
import subprocess
import sys
import tempfile
import time

failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)


def read(path):
    with open(path, "rb") as f:
        return f.read()


def forbid_processes():
    """Run on each worker: starting any process (a zwidth executable) raises from then on."""
    import subprocess as sp

    def refuse(*a, **k):
        raise RuntimeError("a worker started a process")
    sp.Popen = refuse


def interrupt_on_the_cluster(zb, client, log, t):
    """Ctrl-C during a batch on the cluster, after its first periodic save (2 s): the table holds exactly
    the rows finished by then, all ok, each with its folder (a unit running on a worker when the interrupt
    came may still write its folder: it is not in the table, and the re-run computes it); a re-run on the
    cluster computes only the rest and keeps every saved row's own cells."""
    import csv
    import signal
    import threading
    from zwidth import _zwidth
    n = 1500  # the same log under n serials, ~10 ms a unit: the batch outlasts the interrupt
    manifest, out, folders = os.path.join(t, "units.csv"), os.path.join(t, "interrupted.csv"), os.path.join(t, "u")
    os.mkdir(folders)
    with open(manifest, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["serial", "path"])
        w.writerows([f"SN{i:04d}", log] for i in range(n))
    flags = dict(delays=[2], b_points=10, window_length=512, modes=0)
    saved_before = []

    def ctrl_c():  # once the first periodic save (2 s) has written the table, or at 60 s
        t_end = time.monotonic() + 60
        while not os.path.exists(out) and time.monotonic() < t_end:
            time.sleep(0.05)
        saved_before.append(os.path.exists(out))
        time.sleep(0.3)
        os.kill(os.getpid(), signal.SIGINT)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # also where ctest ignores SIGINT
    timer = threading.Thread(target=ctrl_c, daemon=True)
    interrupted, t0 = False, time.monotonic()
    try:
        timer.start()
        zb.batch(manifest=manifest, output=out, client=client, unit_folders=folders, **flags)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        timer.join()
        signal.signal(signal.SIGINT, previous)
    stopped = time.monotonic() - t0
    check(interrupted, f"Ctrl-C on a cluster batch raises KeyboardInterrupt ({stopped:.2f} s in)")
    check(saved_before == [True], "the cluster batch saved its table while it ran (before the interrupt)")
    rows = list(csv.DictReader(open(out, newline="")))
    check(0 < len(rows) < n and all(r["status"] == "ok" for r in rows),
          f"the interrupted table holds the {len(rows)} finished units of {n}, all ok")
    check({r["serial"] for r in rows} <= set(os.listdir(folders)), "every unit in the table has its folder")
    check(not [f for f in os.listdir(t) if ".tmp" in f], "no temporary file left by the interrupted batch")
    args = ["--manifest", manifest, "--output", out, "--unit-folders", folders, *zb._flag_args(flags)]
    resumed = sum(row is not None for _, row in _zwidth._batch_units(args, "cluster-resume-check"))
    check(resumed == len(rows), f"a re-run resumes exactly the saved units ({resumed} of {len(rows)})")
    before = {r["serial"]: r for r in rows}
    t_end = time.monotonic() + 30  # the cancelled tasks still running on the workers end
    while any(client.processing().values()) and time.monotonic() < t_end:
        time.sleep(0.05)
    zb.batch(manifest=manifest, output=out, client=client, unit_folders=folders, **flags)
    after = {r["serial"]: r for r in csv.DictReader(open(out, newline=""))}
    check(len(after) == n and all(r["status"] == "ok" for r in after.values()), "the re-run finishes every unit")
    # The population's columns are the whole batch's (a unit's outlier status among all, not among the
    # 130 saved); every other cell of a saved row is the unit's own and stays.
    population = {"outlier", "outlier_d2", "outlier_reasons"}
    changed = sorted({k for s, r in before.items() for k in r if after[s][k] != r[k]} - population)
    check(not changed, f"the re-run kept every saved row's own cells as they were (changed: {changed})")
    print(f"cluster interrupt: {len(rows)} of {n} units saved at the interrupt ({stopped:.2f} s in)")


def main():
    zw, src, pydir = sys.argv[1], sys.argv[2], sys.argv[3]
    sys.path.insert(0, pydir)
    try:
        import zwidth._batch as zb
    except ImportError as e:  # a build without the Python module
        print(f"skip: the zwidth module in {pydir} does not import ({e})")
        sys.exit(77)

    with tempfile.TemporaryDirectory() as t:
        model = os.path.join(src, "datasets/phantom/table1.json")
        logs = []
        for s in (1, 2, 3):
            p = os.path.join(t, f"u{s}.csv")
            subprocess.run([zw, "simulate", "--model", model, "-o", p, "--seconds", "8", "--seed", str(s)],
                           check=True, capture_output=True)
            logs.append(p)
        bad = os.path.join(t, "bad.csv")
        with open(bad, "w") as f:
            f.write("t,torque,position\n0,1,2\n0.001,x,y\n")
        logs.append(bad)
        flags = dict(delays=[2, 4], b_points=20, window_length=1024)

        cli = os.path.join(t, "cli.csv")
        rc = subprocess.run([zw, "batch", *logs, "-o", cli, *zb._flag_args(flags)], capture_output=True).returncode
        check(rc == 4, f"zwidth batch with a corrupt log exits 4 (got {rc})")

        t0 = time.monotonic()
        threaded = os.path.join(t, "threads.csv")
        df = zb.batch(logs, output=threaded, threads=2, **flags)
        t_threads = time.monotonic() - t0
        check(read(threaded) == read(cli), "zwidth.batch on threads: the table of zwidth batch, byte for byte")
        rows = df.to_dict("records") if hasattr(df, "to_dict") else df
        status = {r["serial"]: r["status"] for r in rows}
        check(status[bad] == "input_error" and sum(v == "ok" for v in status.values()) == 3, f"statuses {status}")

        from dask.distributed import Client, LocalCluster
        # The spawned workers import zwidth as any worker would: from their PYTHONPATH.
        os.environ["PYTHONPATH"] = os.pathsep.join([pydir, os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        t0 = time.monotonic()
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
                Client(cluster) as client:
            t_start = time.monotonic() - t0
            client.run(forbid_processes)  # a unit that started a process would fail its row
            t0 = time.monotonic()
            clustered = os.path.join(t, "cluster.csv")
            zb.batch(logs, output=clustered, client=client, **flags)
            t_cluster = time.monotonic() - t0
            pids = set(client.run(os.getpid).values())
            interrupt_on_the_cluster(zb, client, logs[0], t)
        check(len(pids) == 2 and os.getpid() not in pids, f"two worker processes ({len(pids)})")
        check(read(clustered) == read(cli), "zwidth.batch on a 2-worker LocalCluster: the same table, byte for byte")

        # Resume through Python: nothing to run, the table unchanged.
        t0 = time.monotonic()
        zb.batch(logs, output=clustered, **flags)
        check(read(clustered) == read(cli), "a resumed zwidth.batch leaves the table as it was")
        print(f"4 units: threads {t_threads:.2f} s, cluster {t_cluster:.2f} s (+ {t_start:.2f} s to start it), "
              f"resume {time.monotonic() - t0:.2f} s")

        try:
            zb.batch(logs, output=os.path.join(t, "x.csv"), delays="two")
            check(False, "a bad flag raises BatchError")
        except zb.BatchError as e:
            check("--delays" in str(e), f"a bad flag raises BatchError: {str(e)[:100]}")

    print(f"batch_dask: {len(failures)} failed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":  # the workers are spawned: they import this file and must not run it
    main()
