#!/usr/bin/env python3
"""A log to a model to its Z-width, with the zwidth Python module.

    python3 log_to_zwidth.py LOG MODEL_OUT.json [NUM_MODES]

LOG: a text, HDF5 or .mat log (time, input torque, output angle). Prints the
fit's verdict and, per loop delay, K_CR at B = 0, the largest K_CR and the
largest stable B; writes the model file the CLI reads (zwidth boundary ...).
"""
import sys

import zwidth


def main(argv):
    if len(argv) < 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    modes = int(argv[3]) if len(argv) > 3 else 2
    log = zwidth.read_log(argv[1])
    frf = zwidth.estimate(log)
    res = zwidth.fit(frf, modes=modes)
    print(res)
    model = res.model
    model.save(argv[2])
    for d in (1, 2):
        s = zwidth.ZWidth(model, period_s=log.period_s, delay_samples=d).summary()
        print(f"delay {d}: K_cr_at_zero_B {s['K_cr_at_zero_B']:.9g} K_cr_max {s['K_cr_max']:.9g} "
              f"B_max {s['B_max']:.9g}")
    return 0 if res.quality == "good" else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
