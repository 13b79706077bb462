#!/usr/bin/env python3
"""A batch of logs: each log estimated, fitted and its Z-width computed, one row per log.

    python3 batch_of_logs.py TABLE.csv LOG [LOG ...]

Runs `zwidth batch` through zwidth.batch (each log computed in this process, on
the machine's cores; no executable needed) and prints, per log,
its status and K_CR at B = 0 for the loop delay 2. TABLE.csv is the batch's
table; run again with more logs, the ones already in it are not computed again.
"""
import sys

import zwidth


def main(argv):
    if len(argv) < 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    table = zwidth.batch(argv[2:], output=argv[1], delays=[2])
    rows = table.to_dict("records") if hasattr(table, "to_dict") else table
    failed = 0
    for r in rows:
        k = {key: v for key, v in r.items() if key.endswith("_K_cr_at_zero_B")}
        print(r["serial"], r["status"], " ".join(f"{key} {v}" for key, v in sorted(k.items())))
        failed += r["status"] != "ok"
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
