"""estimator='robust' (issue 23 item 2): the robust method of a periodic excitation through the Python
module and the CLI, on logs made here. Each realisation's input is `zwidth excite --kind multisine
--random-phases --seed S` (lines 1..200 Hz, 1 Hz apart, 6 periods of 1000 samples at 1 kHz); the
output is computed here in numpy: a resonant second-order filter (poles 0.98 e^{+-j 2 pi 50/1000}),
then either nothing (linear) or a static cubic y + 0.5 y^3 / std(y)^2 (a nonlinear device), plus
white noise of 1e-3 std(y) (seeded). The reference: the distortion variance against the noise
variance of the same estimate (a linear device's distortion is a chance fluctuation about 0), and
the CLI's response file against the module's to the last digit (two callers of one function)."""
import csv

import numpy as np
import pytest

import zwidth

PERIOD, PERIODS, M = 1000, 6, 4


def _device(u, cubic, rng):
    a1, a2 = 2 * 0.98 * np.cos(2 * np.pi * 50 / 1000), -0.98 ** 2
    y = np.zeros_like(u)
    for t in range(2, len(u)):
        y[t] = a1 * y[t - 1] + a2 * y[t - 2] + u[t - 1]
    s = np.std(y)
    if cubic:
        y = y + 0.5 * y ** 3 / s ** 2
    return y + 1e-3 * s * rng.standard_normal(len(y))


def _logs(cli, d, cubic):
    rng = np.random.default_rng(7)
    paths = []
    for m in range(M):
        ex = d / f"u{m}.txt"
        cli("excite", "--kind", "multisine", "--random-phases", "--seed", 10 + m, "--seconds", PERIODS,
            "--fmin", 1, "--fmax", 200, "--rms", 0.03, "-o", ex)
        u = np.loadtxt(ex, skiprows=2)
        assert len(u) == PERIODS * PERIOD
        y = _device(u, cubic, rng)
        p = d / f"log{m}.csv"
        with open(p, "w") as f:
            f.write("t,torque,position\n")
            for k in range(len(u)):
                f.write(f"{k / 1000:.17g},{u[k]:.17g},{y[k]:.17g}\n")
        paths.append(str(p))
    return paths


def _median_ratio(r):
    return float(np.median(np.asarray(r.distortion_var) / np.asarray(r.noise_var)))


@pytest.mark.parametrize("cubic", [False, True])
def test_robust_tells_distortion_from_noise_as_the_cli(cli, tmp_path, cubic):
    paths = _logs(cli, tmp_path, cubic)
    r = zwidth.estimate_logs(paths, estimator="robust", period_samples=PERIOD, transient_periods=1)
    assert r.estimator == "robust"
    assert len(r.f_hz) == 200 and len(r.noise_var) == 200 and len(r.distortion_var) == 200
    if cubic:
        assert _median_ratio(r) > 10
    else:
        assert _median_ratio(r) < 1
    out = tmp_path / "frf.csv"
    cli("estimate", *paths, "--estimator", "robust", "--period-samples", PERIOD, "--transient-periods", 1,
        "-o", out)
    with open(out) as f:
        rows = list(csv.DictReader(f))
    np.testing.assert_array_equal([float(x["noise_var"]) for x in rows], np.asarray(r.noise_var))
    np.testing.assert_array_equal([float(x["distortion_var"]) for x in rows], np.asarray(r.distortion_var))
    np.testing.assert_array_equal([float(x["H_re"]) for x in rows], np.asarray(r.H).real)


def test_robust_without_a_period_names_the_keyword(cli, tmp_path):
    paths = _logs(cli, tmp_path, False)[:1]
    with pytest.raises(zwidth.InputError) as e:
        zwidth.estimate_logs(paths, estimator="robust")
    assert "period_samples" in str(e.value) and "::" not in str(e.value)
    p = cli("estimate", *paths, "--estimator", "robust", "-o", tmp_path / "x.csv", check=False)
    assert p.returncode == 2 and "--period-samples" in p.stderr and "::" not in p.stderr
    assert not (tmp_path / "x.csv").exists()
