#!/usr/bin/env python3
"""Throughput of a fleet (issue 28): units per second and memory for

  1. N separate `zwidth run --no-figures` processes, one after the other and two at a time;
  2. `zwidth batch --jobs 1` and `--jobs 2` (threads in one process);
  3. zwidth.batch (python/zwidth/_batch.py, units computed in-process: python/bind_batch.cc) on 2
     threads and on a dask.distributed LocalCluster of 2 worker processes (1 thread each), the
     cluster's start timed apart (the module is the one built beside ZWIDTH_EXE: build/python);

over the same N units, with the CPU time per unit (user + system of every process involved: on a
shared machine steadier than the wall time) and peak RSS per process (os.wait4's ru_maxrss: each `run`, each `batch`,
this Python process for the threads; for the cluster, each worker process's own peak, Python and
dask included).

Units: Table I simulated by `zwidth simulate` (white-noise torque, seeds 1..N, SECONDS s at 1 kHz),
the end-of-line recipe's flags (docs/fleet.md): --modes 2 --window-length 512 --delays 2,4.
Beside the times, the error: the largest relative difference of any number between the batch
table and the `run` folders' summary.json / model.json (0 expected: the same computation), whether
the threaded, cluster and batch tables are equal byte for byte, and the median K_CR^max at delay 2
against the design's (Table I's own, `zwidth boundary --summary`).

Usage: python3 bench/fleet_throughput.py ZWIDTH_EXE [UNITS=30] [SECONDS=4]
(from the source tree; needs python3-distributed for the cluster rows, skipped
without them). Prints a Markdown table; docs/fleet.md holds a measured one. Load on the machine
(os.getloadavg) is printed before and after: on a shared machine read the figures as upper bounds.
"""
import csv
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

FLAGS = ["--modes", "2", "--window-length", "512", "--delays", "2,4"]
KW = dict(modes=2, window_length=512, delays=[2, 4])


def cpu(ru):
    return ru.ru_utime + ru.ru_stime


def spawn(argv, **kw):
    """Runs argv; returns (wall s, peak RSS MiB, exit code, CPU s) of that one child (os.wait4)."""
    t = time.perf_counter()
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, **kw)
    _, status, ru = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    return time.perf_counter() - t, ru.ru_maxrss / 1024.0, p.returncode, cpu(ru)


def runs(zw, logs, out, parallel):
    """`zwidth run` per unit, `parallel` at once; (wall s, largest peak RSS MiB, CPU s of all)."""
    t = time.perf_counter()
    pending, peak, used = list(enumerate(logs)), 0.0, 0.0
    live = {}
    while pending or live:
        while pending and len(live) < parallel:
            i, log = pending.pop(0)
            p = subprocess.Popen([zw, "run", log, "-o", os.path.join(out, f"run{i}"), "--no-figures", "--force", *FLAGS],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            live[p.pid] = p
        pid, status, ru = os.wait4(-1, 0)
        if pid in live:
            if os.waitstatus_to_exitcode(status) != 0:
                sys.exit(f"zwidth run failed on a unit (exit {os.waitstatus_to_exitcode(status)})")
            del live[pid]
            peak = max(peak, ru.ru_maxrss / 1024.0)
            used += cpu(ru)
    return time.perf_counter() - t, peak, used


def run_error(table, logs, out):
    """Largest relative difference between the table's numbers and the run folders' (0: identical)."""
    rows = {r["serial"]: r for r in csv.DictReader(open(table, newline=""))}
    worst = 0.0
    for i, log in enumerate(logs):
        r = rows[log]
        summ = json.load(open(os.path.join(out, f"run{i}", "summary.json")))
        model = json.load(open(os.path.join(out, f"run{i}", "model.json")))
        plant = model.get("plant", model)
        pairs = [(r["m"], plant["m"]), (r["b"], plant["b"])]
        for e in summ["boundary"]:
            d = e["delay_samples"]
            pairs += [(r[f"d{d}_{k}"], e[k]) for k in ("K_cr_at_zero_B", "K_cr_max", "B_t", "B_max")]
        for cell, want in pairs:
            got, want = float(cell), float("nan") if want is None else float(want)
            if math.isnan(got) and math.isnan(want):
                continue
            worst = max(worst, abs(got - want) / max(abs(want), 1e-300))
    return worst


def main():
    zw = os.path.abspath(sys.argv[1])
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 30
    seconds = sys.argv[3] if len(sys.argv) > 3 else "4"
    src = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    model = os.path.join(src, "datasets/phantom/table1.json")
    lines = [f"load before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores"]
    rows = []  # (what, units, wall s, units/s, CPU s, peak RSS MiB)
    with tempfile.TemporaryDirectory(prefix="zwidth_fleet_bench_") as t:
        logs = []
        for s in range(1, n + 1):
            p = os.path.join(t, f"u{s:03d}.csv")
            subprocess.run([zw, "simulate", "--model", model, "-o", p, "--seconds", seconds, "--seed", str(s)],
                           check=True, capture_output=True)
            logs.append(p)
        subprocess.run([zw, "boundary", model, "--delays", "2", "-o", os.path.join(t, "design.csv"),
                        "--summary", os.path.join(t, "design.json")], check=True, capture_output=True)
        design = json.load(open(os.path.join(t, "design.json")))["delays"][0]["K_cr_max"]

        for parallel in (1, 2):
            wall, peak, used = runs(zw, logs, t, parallel)
            rows.append((f"{n} separate `zwidth run --no-figures`, {parallel} at a time", n, wall, n / wall, used, peak))
        tables = {}
        for jobs in (1, 2):
            table = os.path.join(t, f"batch{jobs}.csv")
            wall, peak, rc, used = spawn([zw, "batch", *logs, "-o", table, "--jobs", str(jobs), "--restart", *FLAGS])
            if rc != 0:
                sys.exit(f"zwidth batch exited {rc}")
            tables[f"batch --jobs {jobs}"] = open(table, "rb").read()
            rows.append((f"`zwidth batch --jobs {jobs}`", n, wall, n / wall, used, peak))
        error = run_error(os.path.join(t, "batch1.csv"), logs, t)
        kmax = statistics.median(float(r["d2_K_cr_max"]) for r in csv.DictReader(open(os.path.join(t, "batch1.csv"))))

        # The built module beside the executable (build/bin/zwidth -> build/python): its units are
        # computed in this process (python/bind_batch.cc); the cluster's workers import it too.
        pydir = os.path.join(os.path.dirname(os.path.dirname(zw)), "python")
        sys.path.insert(0, pydir)
        os.environ["PYTHONPATH"] = os.pathsep.join([pydir, os.environ.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        import zwidth._batch as zb
        threaded = os.path.join(t, "threads.csv")
        t0, c0 = time.perf_counter(), cpu(resource.getrusage(resource.RUSAGE_CHILDREN)) + cpu(resource.getrusage(resource.RUSAGE_SELF))
        zb.batch(logs, output=threaded, threads=2, **KW)
        wall = time.perf_counter() - t0
        used = cpu(resource.getrusage(resource.RUSAGE_CHILDREN)) + cpu(resource.getrusage(resource.RUSAGE_SELF)) - c0
        self_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        tables["zwidth.batch threads=2"] = open(threaded, "rb").read()
        rows.append(("`zwidth.batch`, 2 threads (units in this Python process)", n, wall, n / wall, used,
                     f"{self_peak:.0f} (this Python)"))
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError as e:
            lines.append(f"cluster: skipped ({e})")
        else:
            t0 = time.perf_counter()
            with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
                    Client(cluster) as client:
                start = time.perf_counter() - t0
                clustered = os.path.join(t, "cluster.csv")
                t0 = time.perf_counter()
                zb.batch(logs, output=clustered, client=client, **KW)
                wall = time.perf_counter() - t0

                def peak():  # the worker process's own: Python, dask, zwidth and the units it computed
                    import resource as r
                    me = r.getrusage(r.RUSAGE_SELF)
                    return me.ru_maxrss / 1024.0, me.ru_utime + me.ru_stime
                worker = list(client.run(peak).values())
                used = sum(c for _, c in worker)  # the workers' whole lives: their start and import included
            tables["zwidth.batch on the cluster"] = open(clustered, "rb").read()
            rows.append((f"`zwidth.batch`, LocalCluster of 2 workers (+ {start:.1f} s to start it)", n, wall, n / wall,
                         used, " and ".join(f"{w:.0f}" for w, _ in worker) + " (each worker)"))
        lines.append(f"load after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")

    print(f"Units: Table I simulated {seconds} s at 1 kHz (seeds 1..{n}), flags {' '.join(FLAGS)}\n")
    print("| what | units | wall | units/s | CPU per unit | peak RSS [MiB] |\n|---|---|---|---|---|---|")
    for what, units, wall, rate, used, peak in rows:
        print(f"| {what} | {units} | {wall:.2f} s | {rate:.2f} | {1000 * used / units:.0f} ms | "
              f"{peak if isinstance(peak, str) else f'{peak:.0f}'} |")
    ref = tables["batch --jobs 1"]
    same = [k for k, v in tables.items() if v == ref]
    print(f"\nerror: batch vs run, largest relative difference {error:.3g}; tables equal byte for byte: "
          f"{', '.join(same)} ({len(same)} of {len(tables)}); median K_CR^max at d = 2 {kmax:.4g} vs the design's "
          f"{design:.4g} ({100 * (kmax / design - 1):+.2f} %)")
    for line in lines:
        print(line)
    return 0 if len(same) == len(tables) and error == 0 else 1


if __name__ == "__main__":  # the cluster's workers are spawned: they import this file and must not run it
    sys.exit(main())
