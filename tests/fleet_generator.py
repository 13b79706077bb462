#!/usr/bin/env python3
"""A simulated production line for zwidth batch (issue 28): a design (Table I), units with
manufacturing scatter, and a few with a defect. Each unit's model is the design's with every
parameter multiplied by exp(N(0, sigma)) (sigma: m 2 %, b 5 %, the modes' 1.5 %), seeded per unit, and
its log is `zwidth simulate` of that model (white-noise torque, its own seed). Defects:
  out_of_tolerance  m 40 % above the design (the m tolerance is +-15 %): must fail
  loose_part        an extra resonance/antiresonance pair at 160/150 rad/s (a loose part's mode)
  friction          Coulomb friction 0.02 N m at the motor (the torque's RMS is 0.03 N m)
  wrong_sign        the torque column negated (a motor wired the other way)
  truncated         the log cut to its first 40 lines (an interrupted recording)
Writes DIR/units.csv (serial,path), DIR/truth.csv (serial,kind,m,b) and DIR/design.json.
Usage: fleet_generator.py ZWIDTH DIR UNITS SECONDS [--defects N_EACH]
"""
import csv, json, math, os, random, subprocess, sys

DESIGN = {"m": 1.168e-3, "b": 0.00584, "modes": [{"omega": 479.166, "c": 83, "v": 417.612, "d": 80},
                                                 {"omega": 1159.31, "c": 352, "v": 546.626, "d": 90}],
          "delay_samples": 0, "sample_period_s": 0.001, "name": "design"}
KINDS = ["out_of_tolerance", "loose_part", "friction", "wrong_sign", "truncated"]


def unit_model(rng, kind):
    g = lambda s: math.exp(rng.gauss(0.0, s))
    m = dict(DESIGN, m=DESIGN["m"] * g(0.02), b=DESIGN["b"] * g(0.05), name=kind,
             modes=[{k: v * g(0.015) for k, v in md.items()} for md in DESIGN["modes"]])
    if kind == "out_of_tolerance":
        m["m"] = DESIGN["m"] * 1.4
    if kind == "loose_part":
        m["modes"] = [{"omega": 160.0, "c": 8.0, "v": 150.0, "d": 8.0}] + m["modes"]
    return m


def main():
    zw, out, n, seconds = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    each = int(sys.argv[sys.argv.index("--defects") + 1]) if "--defects" in sys.argv else 1
    os.makedirs(out, exist_ok=True)
    kinds = ["normal"] * n
    for k, kind in enumerate(KINDS):  # spread over the line
        for e in range(each):
            kinds[(7 + 37 * (k * each + e)) % n] = kind
    design = {"format": "zwidth-design", "format_version": 1, "name": "simulated line (Table I)",
              "model": DESIGN, "tolerances": [
                  {"parameter": "m", "relative": 0.15}, {"parameter": "b", "min": 0.002, "max": 0.02},
                  {"figure": "K_cr_max", "delay": 2, "relative": 0.25}]}
    json.dump(design, open(os.path.join(out, "design.json"), "w"), indent=1)
    with open(os.path.join(out, "units.csv"), "w", newline="") as u, open(os.path.join(out, "truth.csv"), "w", newline="") as t:
        uw, tw = csv.writer(u), csv.writer(t)
        uw.writerow(["serial", "path"]); tw.writerow(["serial", "kind", "m", "b"])
        for i, kind in enumerate(kinds):
            serial = f"SN{i:04d}"
            rng = random.Random(1000 + i)
            model = unit_model(rng, kind)
            mpath = os.path.join(out, serial + ".model.json")
            json.dump(model, open(mpath, "w"))
            log = os.path.join(out, serial + ".csv")
            args = [zw, "simulate", "--model", mpath, "-o", log, "--seconds", seconds, "--seed", str(i + 1)]
            if kind == "friction":
                args += ["--coulomb", "0.02"]
            subprocess.run(args, check=True, capture_output=True)
            if kind == "wrong_sign":
                rows = list(csv.reader(open(log)))
                for r in rows[1:]:
                    r[1] = repr(-float(r[1]))
                csv.writer(open(log, "w", newline="")).writerows(rows)
            if kind == "truncated":
                lines = open(log).read().splitlines()[:40]
                open(log, "w").write("\n".join(lines) + "\n")
            uw.writerow([serial, serial + ".csv"]); tw.writerow([serial, kind, model["m"], model["b"]])


if __name__ == "__main__":
    main()
