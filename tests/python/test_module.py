"""zwidth (Python) against the CLI on the same files, against SciPy/NumPy where an
independent computation exists, model round trips, and exceptions.

Data: the shipped PHANToM log (datasets/phantom/phantom_30s.*, simulated from Table I)
and logs simulated here with fixed seeds.
"""
import json, os, pickle, subprocess, threading, time

import numpy as np
import pytest

import zwidth

T = 1e-3


def table1_dict(path):
    with open(path) as f:
        return json.load(f)


def factored_G(mj, s):
    """G(s) of eq. (1) from its factored formula, written out here."""
    g = 1 / (mj["m"] * s * s + mj["b"] * s)
    for md in mj["modes"]:
        g = g * md["omega"] ** 2 / md["v"] ** 2 * (s * s + md["d"] * s + md["v"] ** 2) / (
            s * s + md["c"] * s + md["omega"] ** 2)
    return g


# ---------------------------------------------------------------- logs and estimate

def test_read_log_equals_the_csv_columns(log_csv):
    log = zwidth.read_log(log_csv)
    raw = np.loadtxt(log_csv, delimiter=",", skiprows=1)
    assert log.num_samples == raw.shape[0]
    assert np.array_equal(log.u, raw[:, 1]) and np.array_equal(log.y, raw[:, 2])
    assert log.sample_rate_hz == pytest.approx(1000.0, rel=1e-9)
    assert np.allclose(log.t, raw[:, 0], rtol=0, atol=1e-9)


def test_read_log_csv_and_h5_agree(log_csv, log_h5):
    a, b = zwidth.read_log(log_csv), zwidth.read_log(log_h5)
    assert np.array_equal(a.u, b.u) and np.array_equal(a.y, b.y)


def test_read_log_selectors(tmp_path):
    p = tmp_path / "cols.csv"
    rng = np.random.default_rng(3)
    u, y = rng.standard_normal(100), rng.standard_normal(100)
    with open(p, "w") as f:
        f.write("tau,theta\n")
        for a, b in zip(u, y):
            f.write(f"{a!r},{b!r}\n")
    log = zwidth.read_log(str(p), input_column="tau", output_column="theta", time_column="", rate=500.0)
    assert np.array_equal(log.u, u) and np.array_equal(log.y, y) and log.sample_rate_hz == 500.0


@pytest.mark.parametrize("opts,flags", [
    ({}, []),
    ({"window": "hamming", "window_length": 2048, "overlap": 0.25, "detrend": "mean", "estimator": "h2",
      "fmin": 2.0, "fmax": 200.0},
     ["--window", "hamming", "--window-length", "2048", "--overlap", "0.25", "--detrend", "mean",
      "--estimator", "h2", "--fmin", "2", "--fmax", "200"]),
])
def test_estimate_equals_cli_bit_for_bit(cli, log_h5, tmp_path, opts, flags):
    out = tmp_path / "frf.h5"
    cli("estimate", log_h5, "-o", out, *flags)
    ref = zwidth.FrequencyResponse.load(str(out))
    for got in (zwidth.estimate(zwidth.read_log(log_h5), **opts), zwidth.estimate(log_h5, **opts)):
        for name in ("f_hz", "H", "coherence", "H_std", "S_uu", "S_yy"):
            assert np.array_equal(getattr(got, name), getattr(ref, name)), name
        assert got.num_averages == ref.num_averages


@pytest.mark.parametrize("opts,flags", [
    ({"estimator": "lpm"}, ["--estimator", "lpm"]),
    ({"estimator": "lrm"}, ["--estimator", "lrm"]),
    ({"estimator": "lrm", "local_half_width": 9, "local_order": 3, "local_denominator_order": 1, "fmin": 2.0},
     ["--estimator", "lrm", "--local-half-width", "9", "--local-order", "3", "--local-denominator-order", "1",
      "--fmin", "2"]),
])
def test_estimate_local_equals_cli_bit_for_bit(cli, log_h5, tmp_path, opts, flags):
    out = tmp_path / "frf.h5"
    cli("estimate", log_h5, "-o", out, *flags)
    ref = zwidth.FrequencyResponse.load(str(out))
    log = zwidth.read_log(log_h5)
    for got in (zwidth.estimate(log, **opts), zwidth.estimate(log_h5, **opts),
                zwidth.estimate(log.u, log.y, log.sample_rate_hz, **opts)):
        for name in ("f_hz", "H", "coherence", "H_std", "S_uu", "S_yy"):
            assert np.array_equal(getattr(got, name), getattr(ref, name)), name


@pytest.mark.parametrize("estimator", ["lpm", "lrm"])
def test_estimate_local_of_a_noise_free_log_is_the_zoh_response(estimator):
    """No noise: the local model removes the transient, so the estimate is the exact sampled
    response (Model.response with period_s, itself checked against SciPy's cont2discrete),
    where Welch's H1 leaks (30 s: at 10 s the LPM's quadratic over 13 bins of 0.1 Hz misses a
    mode by 7 %, as docs/estimators.md says)."""
    model = zwidth.Model.table1()
    log = zwidth.simulate(model, seconds=30, seed=3, encoder_step_rad=0.0, noise_std_rad=0.0)
    T = 1 / log.sample_rate_hz

    def worst(frf):
        band = (frf.f_hz >= 0.7) & (frf.f_hz <= 250)
        exact = model.response(frf.f_hz[band], period_s=T)
        return np.max(np.abs(frf.H[band] - exact) / np.abs(exact))

    local = worst(zwidth.estimate(log, estimator=estimator))
    assert local < 2e-3
    assert worst(zwidth.estimate(log)) > 20 * local


def test_estimate_local_refuses_welch_keywords_and_unknown_estimators():
    log = zwidth.simulate(zwidth.Model.table1(), seconds=3, seed=1)
    with pytest.raises(zwidth.InputError, match="window_length"):
        zwidth.estimate(log, estimator="lpm", window_length=2048)
    with pytest.raises(zwidth.InputError, match="lpm, lrm"):
        zwidth.estimate(log, estimator="lsm")
    with pytest.raises(zwidth.InputError, match="local_order = 9"):
        zwidth.estimate(log, estimator="lrm", local_order=9)


def test_estimate_equals_scipy_welch(log_h5):
    from scipy import signal
    log = zwidth.read_log(log_h5)
    frf = zwidth.estimate(log.u, log.y, log.sample_rate_hz)
    kw = dict(fs=log.sample_rate_hz, window="hann", nperseg=4096, noverlap=2048, detrend="linear")
    f, puu = signal.welch(log.u, **kw)
    _, puy = signal.csd(log.u, log.y, **kw)
    _, coh = signal.coherence(log.u, log.y, **kw)
    keep = (f >= 0.7) & (f < log.sample_rate_hz / 2)  # the default band: fmin 0.7 Hz up to Nyquist
    assert np.allclose(frf.f_hz, f[keep], rtol=1e-13, atol=0)
    H = puy[keep] / puu[keep]
    # Inside the torque's band (300 Hz) to 1e-9; above it S_uu is tiny and the ratio carries both roundings.
    band = f[keep] <= 300
    assert np.max(np.abs(frf.H - H)[band] / np.abs(H)[band]) < 1e-9
    assert np.max(np.abs(frf.H - H) / np.abs(H)) < 1e-7
    assert np.max(np.abs(frf.coherence - coh[keep])) < 1e-9


def test_frequency_response_round_trip(log_h5, tmp_path):
    frf = zwidth.estimate(zwidth.read_log(log_h5))
    for name in ("r.csv", "r.h5"):
        frf.save(str(tmp_path / name))
        back = zwidth.FrequencyResponse.load(str(tmp_path / name))
        assert np.array_equal(back.H, frf.H) and np.array_equal(back.f_hz, frf.f_hz)


def test_simulate_equals_cli(cli, table1_json, tmp_path):
    out = tmp_path / "sim.h5"
    cli("simulate", "--model", table1_json, "-o", out, "--seconds", "3", "--seed", "7", "--noise-std", "1e-6")
    a = zwidth.read_log(str(out))
    b = zwidth.simulate(zwidth.Model.load(table1_json), seconds=3, seed=7, noise_std_rad=1e-6)
    assert np.array_equal(a.u, b.u) and np.array_equal(a.y, b.y)


# ---------------------------------------------------------------- fit

@pytest.fixture(scope="module")
def fitted(log_h5):
    return zwidth.fit(zwidth.estimate(zwidth.read_log(log_h5)), modes=2)


def test_fit_equals_cli_bit_for_bit(cli, log_h5, tmp_path, fitted):
    out = tmp_path / "m.json"
    cli("fit", log_h5, "--modes", "2", "-o", out)  # else the defaults of both (delay_samples auto, fit::UserFitOptions)
    ref = zwidth.Model.load(str(out))
    got = fitted.model
    assert fitted.converged and fitted.status == "converged"
    assert (got.m, got.b, got.modes, got.delay_samples) == (ref.m, ref.b, ref.modes, ref.delay_samples)
    assert got.std == ref.std
    assert fitted.chi2_per_dof == ref.fit_info["chi2_per_dof"]
    assert fitted.brief_report() in cli("fit", log_h5, "--modes", "2", "-o", tmp_path / "m2.json").stdout


def test_fit_recovers_table1_within_its_std(fitted, table1_json):
    """The shipped log was simulated from Table I: the fit must land within 4 std of it."""
    ref = table1_dict(table1_json)
    m, s = fitted.model, fitted.model.std
    assert abs(m.m - ref["m"]) < 4 * s["m"]
    for got, sd, md in zip(m.modes, s["modes"], ref["modes"]):
        for g, e, key in zip(got, sd, ("omega", "c", "v", "d")):
            assert abs(g - md[key]) < 4 * e, key


def test_fit_auto_delay_equals_cli(cli, tmp_path):
    model = zwidth.Model.table1()
    model.delay_samples = 1
    log = zwidth.simulate(model, seconds=20, seed=11)
    path = tmp_path / "d1.h5"
    log.save(str(path))
    cli("fit", path, "-o", tmp_path / "m.json", "--delay-samples", "auto")
    ref = zwidth.Model.load(str(tmp_path / "m.json"))
    got = zwidth.fit(zwidth.estimate(zwidth.read_log(str(path))), delay_samples="auto").model
    assert got.delay_samples == ref.delay_samples == 1
    assert got.modes == ref.modes


def test_fit_from_a_response_built_in_memory():
    """A response computed from Table I's exact ZOH model is fitted back to Table I."""
    ref = zwidth.Model.table1()
    f = np.linspace(1, 300, 600)
    frf = zwidth.FrequencyResponse(f, ref.response(f, period_s=T), 1 / T)
    # No Welch averages behind it: refused as the CLI refuses it, fitted with allow_short=True.
    with pytest.raises(zwidth.InputError, match="allow_short=True"):
        zwidth.fit(frf)
    with pytest.warns(zwidth.FitQualityWarning, match="few_averages"):
        res = zwidth.fit(frf, allow_short=True)
    assert res.quality == "poor" and "few_averages" in [r["code"] for r in res.quality_reasons]
    got = res.model
    assert got.m == pytest.approx(ref.m, rel=1e-6)
    for a, b in zip(got.modes, ref.modes):
        assert np.allclose(a, b, rtol=1e-5)


# ---------------------------------------------------------------- model

def test_model_response_continuous_equals_factored_formula(table1_json):
    mj = table1_dict(table1_json)
    f = np.array([0.5, 5, 50, 66, 76, 87, 184, 300, 450])
    got = zwidth.Model.load(table1_json).response(f)
    ref = factored_G(mj, 2j * np.pi * f)
    assert got.shape == f.shape and np.max(np.abs(got - ref) / np.abs(ref)) < 1e-12


def test_model_response_zoh_equals_scipy_cont2discrete(table1_json):
    from scipy import signal
    mj = table1_dict(table1_json)
    num, den = np.array([1.0]), np.array([mj["m"], mj["b"], 0.0])
    for md in mj["modes"]:
        k = md["omega"] ** 2 / md["v"] ** 2
        num = np.polymul(num, k * np.array([1, md["d"], md["v"] ** 2]))
        den = np.polymul(den, [1, md["c"], md["omega"] ** 2])
    A, B, C, D = signal.tf2ss(num, den)
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B, C, D), T, method="zoh")
    f = np.array([[0.5, 5, 50], [76, 184, 450]])
    z = np.exp(2j * np.pi * f * T)
    ref = np.vectorize(lambda zz: (Cd @ np.linalg.solve(zz * np.eye(len(Ad)) - Ad, Bd))[0, 0] + Dd[0, 0])(z)
    model = zwidth.Model.load(table1_json)
    model.delay_samples = 3
    got = model.response(f, period_s=T)
    assert got.shape == f.shape
    assert np.max(np.abs(got - ref * z ** -3) / np.abs(ref)) < 1e-7


def test_to_scipy_matches_response():
    from scipy import signal
    model = zwidth.Model.table1()
    model.delay_samples = 2
    w = 2 * np.pi * np.array([1.0, 30, 77, 200])

    def ss_resp(sys_, s):  # C (sI - A)^-1 B + D, without SciPy's transfer-function detour
        return np.array([(sys_.C @ np.linalg.solve(x * np.eye(sys_.A.shape[0]) - sys_.A, sys_.B))[0, 0]
                         + sys_.D[0, 0] for x in s])
    gc = model.to_scipy()
    assert isinstance(gc, signal.StateSpace) and gc.dt is None
    hc = ss_resp(gc, 1j * w)
    assert np.max(np.abs(hc - model.response(w / 2 / np.pi)) / np.abs(hc)) < 1e-12
    gz = model.to_scipy(T)
    assert gz.dt == T and gz.A.shape == (8, 8)
    hd = ss_resp(gz, np.exp(1j * w * T))
    assert np.max(np.abs(hd - model.response(w / 2 / np.pi, period_s=T)) / np.abs(hd)) < 1e-9


def test_model_round_trips(tmp_path, fitted, cli):
    for m in (zwidth.Model.table1(), fitted.model,
              zwidth.Model(2e-3, 0.01, [(300.0, 20.0, 250.0, 15.0)], delay_samples=1, name='a "quoted" name',
                           sample_period_s=5e-4)):
        p = tmp_path / "m.json"
        m.save(str(p))
        back = zwidth.Model.load(str(p))
        assert (back.m, back.b, back.modes, back.delay_samples, back.name, back.sample_period_s, back.std) == \
               (m.m, m.b, m.modes, m.delay_samples, m.name, m.sample_period_s, m.std)
        assert zwidth.Model.from_json(m.to_json()).modes == m.modes
        assert pickle.loads(pickle.dumps(m)).modes == m.modes
        # The CLI reads what Python wrote.
        cli("export", p, "--format", "json", "-o", tmp_path / "again.json")
        assert zwidth.Model.load(str(tmp_path / "again.json")).modes == m.modes


@pytest.mark.parametrize("fmt", ["json", "matlab", "python", "statespace"])
def test_export_equals_cli_byte_for_byte(cli, tmp_path, fmt):
    m = zwidth.Model(2e-3, 0.01, [(300.0, 20.0, 250.0, 15.0)], delay_samples=1, name="it's \"x\"\n%")
    m.save(str(tmp_path / "m.json"))
    cli("export", tmp_path / "m.json", "--format", fmt, "--period", "0.0005", "-o", tmp_path / "cli.out")
    m.export(str(tmp_path / "py.out"), fmt, period_s=5e-4)
    py_out, cli_out = (tmp_path / "py.out").read_bytes(), (tmp_path / "cli.out").read_bytes()
    if fmt in ("json", "statespace"):  # byte for byte but the provenance (date, command, inputs: issue 26)
        py_json, cli_json = json.loads(py_out), json.loads(cli_out)
        assert cli_json.pop("provenance")["command"].startswith("zwidth export")
        py_json.pop("provenance")
        py_out, cli_out = json.dumps(py_json, indent=2).encode(), json.dumps(cli_json, indent=2).encode()
    assert py_out == cli_out


def test_table1_is_the_papers():
    m = zwidth.Model.table1()
    assert 1 / m.m == pytest.approx(856, rel=1e-3) and m.b / m.m == pytest.approx(5, rel=1e-9)
    assert [round(w * w) for w, _, _, _ in m.modes] == [229600, 1344000]
    assert [round(v * v) for _, _, v, _ in m.modes] == [174400, 298800]


# ---------------------------------------------------------------- Z-width

def test_zwidth_equals_cli_boundary_and_summary(cli, table1_json, tmp_path):
    cli("boundary", table1_json, "--delays", "2,4", "--b-step", "0.0025", "--b-max", "0.1", "-o",
        tmp_path / "b.csv", "--summary", tmp_path / "s.json")
    rows = np.genfromtxt(tmp_path / "b.csv", delimiter=",", names=True)
    summ = json.load(open(tmp_path / "s.json"))
    model = zwidth.Model.load(table1_json)
    for i, d in enumerate((2, 4)):
        z = zwidth.ZWidth(model, delay_samples=d)
        r = rows[rows["delay_samples"] == d]
        Bs = 0.0 + np.arange(len(r)) * 0.0025  # as the CLI forms them: b_min + k b_step
        assert [f"{v:.12g}" for v in Bs] == [f"{v:.12g}" for v in r["B"]]
        b = z.boundary(Bs)
        K, f = z.critical(Bs)
        assert np.array_equal(K, b["K_cr"]) and np.array_equal(f, b["f_cr_hz"], equal_nan=True)
        for col in ("K_cr", "f_cr_hz", "K_margin", "f_margin_hz"):
            assert [f"{v:.15g}" for v in b[col]] == [f"{v:.15g}" for v in r[col]], col
        for col in ("unstable_at_zero_k", "margin_agrees", "verified"):
            assert np.array_equal(b[col], r[col].astype(bool)), col
        assert z.summary() == summ["delays"][i]


def test_critical_scalar_and_shapes():
    z = zwidth.ZWidth(zwidth.Model.table1(), T, 2)
    K, f = z.critical(0.01)
    assert isinstance(K, float) and (K, f) == tuple(z.point(0.01))
    B = np.linspace(0, 0.02, 12).reshape(3, 4)
    K2, f2 = z.critical(B)
    assert K2.shape == (3, 4) and K2[0, 0] == z.critical(0.0)[0]


def closed_loop_roots(mj, K, B, d):
    """Roots of the closed loop of eq. (2), built from SciPy's ZOH transfer function."""
    from scipy import signal
    num, den = np.array([1.0]), np.array([mj["m"], mj["b"], 0.0])
    for md in mj["modes"]:
        k = md["omega"] ** 2 / md["v"] ** 2
        num = np.polymul(num, k * np.array([1, md["d"], md["v"] ** 2]))
        den = np.polymul(den, [1, md["c"], md["omega"] ** 2])
    nz, dz, _ = signal.cont2discrete((num, den), T, method="zoh")
    nz = np.trim_zeros(np.atleast_1d(np.squeeze(nz)), "f")
    # z^(d+1) D(z) + ((K + B/T) z - B/T) N(z) = 0
    p = np.polyadd(np.polymul(np.r_[1.0, np.zeros(d + 1)], dz), np.polymul([K + B / T, -B / T], nz))
    return np.roots(p)


@pytest.mark.parametrize("d", [1, 2, 4])
def test_k_cr_is_the_stability_edge_of_scipys_loop(table1_json, d):
    mj = table1_dict(table1_json)
    z = zwidth.ZWidth(zwidth.Model.load(table1_json), T, d)
    for B in (0.0, 0.005, 0.02):
        K, _ = z.critical(B)
        assert np.max(np.abs(closed_loop_roots(mj, 0.999 * K, B, d))) < 1
        assert np.max(np.abs(closed_loop_roots(mj, 1.001 * K, B, d))) > 1
        assert z.is_stable(0.999 * K, B) and not z.is_stable(1.001 * K, B)


def test_is_stable_broadcasts_and_agrees_with_roots(table1_json):
    mj = table1_dict(table1_json)
    z = zwidth.ZWidth(zwidth.Model.load(table1_json), T, 2)
    K = np.array([[0.5], [3.0], [20.0]])
    B = np.array([0.0, 0.01, 0.05, 0.09])
    got = z.is_stable(K, B)
    assert got.shape == (3, 4) and got.dtype == bool
    ref = np.array([[np.max(np.abs(closed_loop_roots(mj, k, b, 2))) < 1 for b in B] for k in K[:, 0]])
    assert np.array_equal(got, ref)


def test_check_equals_cli(cli, table1_json, tmp_path):
    scene = {"objects": [{"name": "wall", "K": 2.0, "B": 0.0}, {"name": "damped", "K": 20, "B": 0.05},
                         {"name": "too soft?", "K": 0.0, "B": 0.2}, {"K": 1.0, "B": 0.001}]}
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(scene))
    run = cli("check", p, "--model", table1_json, "--delay", "2", "--json", check=False)
    ref = json.loads(run.stdout)
    assert ref.pop("provenance")["command"].startswith("zwidth check")  # the CLI's JSON carries it (issue 26)
    # The CLI exits 3 when an object is unstable (0 when all are stable).
    assert run.returncode == (3 if not all(o["stable"] for o in ref["objects"]) else 0)
    model = zwidth.Model.load(table1_json)
    assert zwidth.check(str(p), model, 2) == ref
    assert zwidth.check(scene["objects"], model, 2) == ref
    tuples = [(o.get("name", f"object{i}"), np.float64(o["K"]), np.float32(o["B"]) if i == 0 else o["B"])
              for i, o in enumerate(scene["objects"])]
    assert zwidth.check(tuples, model, 2) == ref


def test_relay_equals_cli(cli, table1_json):
    ref = json.loads(cli("relay", table1_json, "--delay", "2", "--damping", "0.01", "--seconds", "8",
                         "--json").stdout)
    r = zwidth.relay(zwidth.Model.load(table1_json), 2, 0.01, seconds=8)
    for key in ("K_cr", "f_cr_hz", "K_cr_peak", "f_cr_peak_hz", "refined", "relay_runs", "diverged"):
        assert getattr(r, key) == ref[key], key
    assert r.position.shape == (8000,)
    K_exact, _ = zwidth.ZWidth(zwidth.Model.load(table1_json), T, 2).critical(0.01)
    assert ref["K_cr_exact"] == K_exact


def test_relay_with_filter_and_hand_equals_cli(cli, table1_json):
    ref = json.loads(cli("relay", table1_json, "--delay", "4", "--damping", "0.005", "--seconds", "10",
                         "--velocity-filter-hz", "50", "--hand", "1e-3,2e-3,0.5", "--json").stdout)
    r = zwidth.relay(zwidth.Model.load(table1_json), 4, 0.005, seconds=10, velocity_filter_hz=50,
                     hand=(1e-3, 2e-3, 0.5))
    for key in ("K_cr", "f_cr_hz", "K_cr_peak", "status", "relay_runs", "below_band"):
        assert getattr(r, key) == ref[key], key
    assert r.status == "refined"
    assert abs(r.K_cr / ref["K_cr_exact"] - 1) < 1e-3


def test_long_calls_release_the_gil():
    z = zwidth.ZWidth(zwidth.Model.table1(), T, 2)
    B = np.linspace(0, 0.1, 40000)
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(1)
            time.sleep(0.001)

    th = threading.Thread(target=count)
    th.start()
    t0 = time.perf_counter()
    z.critical(B)
    elapsed = time.perf_counter() - t0
    done.set()
    th.join()
    # With the GIL held the counter could not run at all during the sweep.
    assert elapsed > 0.05 and len(ticks) > 5, (elapsed, len(ticks))


def test_threads_give_the_serial_results(log_h5):
    """Calls run without the GIL: several threads at once must give what one thread gives."""
    from concurrent.futures import ThreadPoolExecutor
    z = zwidth.ZWidth(zwidth.Model.table1(), T, 2)
    log = zwidth.read_log(log_h5)
    B = np.linspace(0, 0.1, 500)
    K_ref, _ = z.critical(B)
    H_ref = zwidth.estimate(log).H
    with ThreadPoolExecutor(4) as pool:
        Ks = list(pool.map(lambda _: z.critical(B)[0], range(4)))
        Hs = list(pool.map(lambda _: zwidth.estimate(log).H, range(4)))
    assert all(np.array_equal(k, K_ref) for k in Ks) and all(np.array_equal(h, H_ref) for h in Hs)


# ---------------------------------------------------------------- errors

def cli_message(cli, *args):
    p = cli(*args, check=False)
    assert p.returncode == 2
    # The error is the last line (the log readers print what they found before it).
    return p.stderr.strip().splitlines()[-1].removeprefix("zwidth: error: ")


def test_bad_input_raises_input_error_with_the_cli_message(cli, tmp_path, table1_json):
    missing = str(tmp_path / "nope.csv")
    with pytest.raises(zwidth.InputError) as e:
        zwidth.read_log(missing)
    assert isinstance(e.value, ValueError)
    assert str(e.value) == cli_message(cli, "estimate", missing, "-o", tmp_path / "x.csv")
    bad = tmp_path / "bad.json"
    bad.write_text('{"m": 1, "b": 1, "mdoes": []}')
    with pytest.raises(zwidth.InputError) as e:
        zwidth.Model.load(str(bad))
    assert str(e.value) == cli_message(cli, "export", bad, "-o", tmp_path / "y.json")
    short = tmp_path / "short.csv"
    zwidth.simulate(zwidth.Model.table1(), seconds=1).save(str(short))
    # The library names the option field; the CLI prints its flag in its place, Python its keyword.
    # Both defaults now follow the log (a 1 s log fits its window); a 4096 window is given to both here.
    # So the message of a window too long for the log is the same one.
    short_cli = cli_message(cli, "estimate", short, "-o", tmp_path / "z.csv", "--window-length", "4096")
    assert "--window-length 512 or less" in short_cli
    with pytest.raises(ValueError) as e:
        zwidth.estimate(zwidth.read_log(str(short)), window_length=4096)
    assert str(e.value) == short_cli.replace("--window-length", "window_length")
    with pytest.raises(ValueError) as e:
        zwidth.estimate(str(short), window_length=4096)
    assert str(e.value) == short_cli.replace("--window-length", "window_length")


@pytest.mark.parametrize("call", [
    lambda: zwidth.Model(-1.0, 0.1),
    lambda: zwidth.Model(1.0, 0.1, [(100.0, -1.0, 90.0, 1.0)]),
    lambda: zwidth.estimate(np.zeros(10000), np.zeros(10000), 1000.0, window="blackman"),
    lambda: zwidth.estimate(np.zeros(10000), np.zeros(9999), 1000.0),
    lambda: zwidth.estimate(np.zeros(10000), np.zeros(10000), 1000.0, overlap=1.0),
    lambda: zwidth.fit(zwidth.FrequencyResponse([1.0], [1.0], 1000.0), modes=-1),
    lambda: zwidth.fit(zwidth.FrequencyResponse([1.0], [1.0], 1000.0), delay_samples="sometimes"),
    lambda: zwidth.ZWidth(zwidth.Model.table1(), -1e-3, 2),
    lambda: zwidth.ZWidth(zwidth.Model.table1(), T, -1),
    lambda: zwidth.check([("x", -1.0, 0.0)], zwidth.Model.table1(), 2),
    lambda: zwidth.check([{"name": "x", "K": 1.0, "B": 0.0, "C": 2}], zwidth.Model.table1(), 2),
    lambda: zwidth.check([("x", True, 0.0)], zwidth.Model.table1(), 2),
    lambda: zwidth.check([("x", "1", 0.0)], zwidth.Model.table1(), 2),
    lambda: zwidth.check([("x", float("nan"), 0.0)], zwidth.Model.table1(), 2),
    lambda: zwidth.relay(zwidth.Model.table1(), 2, 0.0, amplitude=-1),
    lambda: zwidth.Model.table1().response([1.0], period_s=0.0),
    lambda: zwidth.Model.table1().export("/tmp/never-written.x", "excel"),
])
def test_bad_requests_raise_input_error(call):
    with pytest.raises(zwidth.InputError):
        call()


def test_exception_classes():
    assert issubclass(zwidth.InputError, ValueError)
    assert issubclass(zwidth.ComputationError, RuntimeError)
    assert not issubclass(zwidth.ComputationError, ValueError)


def test_version_matches_cli(cli):
    out = cli("--version").stdout
    info = zwidth.build_info()
    assert out.splitlines()[0] == "zwidth " + zwidth.__version__
    debian = {"ceres": "libceres-dev", "eigen": "libeigen3-dev", "fftw": "libfftw3-dev", "hdf5": "libhdf5-dev",
              "cli11": "libcli11-dev", "nlohmann_json": "nlohmann-json3-dev"}
    for key, pkg in debian.items():
        assert info[key] and info[key] in out, key
        # Independently: the version of the Debian package it was built against.
        q = subprocess.run(["dpkg-query", "-W", "-f=${Version}", pkg], capture_output=True, text=True)
        if q.returncode == 0:
            assert q.stdout.split(":")[-1].startswith(info[key]), (key, info[key], q.stdout)


# ---------------------------------------------------------------- docs

def test_docs_python_example(src, tmp_path, cli):
    """Runs the worked example of docs/python.md (its python code block) in an empty folder."""
    pytest.importorskip("matplotlib")
    text = open(os.path.join(src, "docs/python.md")).read()
    code = "\n".join(b.split("```", 1)[0] for b in text.split("```python\n")[1:])  # every block, in order
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(zwidth.__file__)), MPLBACKEND="Agg")
    p = subprocess.run(["/usr/bin/python3", "-c", code], cwd=tmp_path, capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert open(tmp_path / "zwidth.png", "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    assert "<zwidth.FitResult good: converged" in p.stdout and "quality: good []" in p.stdout
    assert "wall stable: True" in p.stdout
    # The printed Z-width figures are the CLI's on the model the example saved.
    cli("boundary", tmp_path / "model.json", "--delays", "2,4,8", "--b-step", "0.01", "-o", tmp_path / "b.csv",
        "--summary", tmp_path / "s.json")
    for e in json.load(open(tmp_path / "s.json"))["delays"]:
        assert f"d = {e['delay_samples']}: K_cr(B=0) = {e['K_cr_at_zero_B']:.4g} N m/rad" in p.stdout


# ---------------------------------------------------------------- issue 17: quality, covariance, intervals, loop

@pytest.fixture(scope="module")
def auto_fit(cli, log_h5, tmp_path_factory):
    """`zwidth fit --modes auto` and zwidth.fit(modes="auto") on the shipped log."""
    out = tmp_path_factory.mktemp("auto") / "m.json"
    stdout = cli("fit", log_h5, "-o", out, "--modes", "auto").stdout  # both default to --delay-samples auto
    res = zwidth.fit(zwidth.estimate(zwidth.read_log(log_h5)), modes="auto")
    assert res.brief_report() in stdout
    return res, str(out)


def test_fit_modes_auto_quality_and_covariance_equal_cli(auto_fit):
    res, path = auto_fit
    ref = zwidth.Model.load(path)
    raw = json.load(open(path))
    got = res.model
    assert (got.m, got.b, got.modes, got.delay_samples) == (ref.m, ref.b, ref.modes, ref.delay_samples)
    assert len(got.modes) == 2  # Table I has two sections
    assert res.quality == ref.fit_info["quality"] in ("good", "poor")
    assert res.quality_reasons == ref.fit_info["quality_reasons"]
    assert all(set(r) == {"code", "message", "advice"} for r in res.quality_reasons)
    assert res.order_table == ref.fit_info["order_table"] and len(res.order_table) >= 3
    # The covariance: the JSON's "covariance" matrix, symmetric, ordered as its names.
    n = 2 + 4 * len(got.modes)
    assert res.covariance.shape == (n, n) and np.array_equal(res.covariance, np.array(raw["covariance"]["matrix"]))
    c = res.covariance  # symmetric positive semi-definite (to rounding)
    assert np.allclose(c, c.T, rtol=1e-9, atol=1e-9 * np.max(np.abs(c)))
    assert np.min(np.linalg.eigvalsh(0.5 * (c + c.T))) > -1e-9 * np.max(np.abs(c))
    assert res.covariance_names == raw["covariance"]["parameters"] == got.covariance_names
    assert res.covariance_names[:3] == ["m", "b", "modes[0].omega"] and len(res.covariance_names) == n
    # Its diagonal is the log-space variance: std of m = m * sqrt(var log m) to first order.
    assert np.sqrt(res.covariance[0, 0]) * got.m == pytest.approx(got.std["m"], rel=1e-6)
    assert np.array_equal(ref.covariance, res.covariance) and np.array_equal(got.covariance, res.covariance)


def test_fit_modes_keyword_errors():
    frf = zwidth.FrequencyResponse(np.linspace(1, 300, 50), np.ones(50), 1000.0, num_averages=10)
    with pytest.raises(zwidth.InputError, match="modes 'three'"):
        zwidth.fit(frf, modes="three")
    with pytest.raises(zwidth.InputError, match="max_modes"):
        zwidth.fit(frf, modes="auto", max_modes=99)


def test_model_covariance_round_trips(auto_fit, tmp_path):
    res, _ = auto_fit
    m = res.model
    m.save(str(tmp_path / "c.json"))
    back = zwidth.Model.load(str(tmp_path / "c.json"))
    assert np.array_equal(back.covariance, m.covariance)
    assert zwidth.Model.table1().covariance is None
    t = zwidth.Model.table1()
    with pytest.raises(zwidth.InputError):
        t.covariance = np.eye(3)  # Table I has 2 + 4 * 2 parameters


def test_summary_with_covariance_equals_cli(cli, auto_fit, tmp_path):
    """boundary --summary on a fitted model: the entry has "std" (delta method), equal to ZWidth.summary()."""
    _, path = auto_fit
    cli("boundary", path, "--delays", "2,4", "-o", tmp_path / "b.csv", "--summary", tmp_path / "s.json")
    summ = json.load(open(tmp_path / "s.json"))
    model = zwidth.Model.load(path)
    for i, d in enumerate((2, 4)):
        s = zwidth.ZWidth(model, delay_samples=d).summary()
        assert "std" in s and "B_max" in s and "B_max_from_zero" in s and "reopened_bands" in s
        assert s == summ["delays"][i]
    assert "std" not in zwidth.ZWidth(zwidth.Model.table1(), delay_samples=2).summary()


def test_stable_intervals_equal_cli_check_and_is_stable(cli, table1_json, tmp_path):
    model = zwidth.Model.load(table1_json)
    Bs = [0.0, 0.01, 0.05, 0.09, 0.2]
    objs = [{"name": f"o{i}", "K": 1.0, "B": b} for i, b in enumerate(Bs)]
    p = tmp_path / "scene.json"
    p.write_text(json.dumps({"objects": objs}))
    run = cli("check", p, "--model", table1_json, "--delay", "4", "--json", check=False)
    ref = json.loads(run.stdout)
    z = zwidth.ZWidth(model, delay_samples=4)
    for o, b in zip(ref["objects"], Bs):
        iv = z.stable_intervals(b)
        assert all(isinstance(t, tuple) and len(t) == 2 for t in iv)
        want = [(r["K_lo"], np.inf if r["K_hi"] is None else r["K_hi"]) for r in o["intervals"]]
        assert iv == want
        # is_stable agrees: inside each interval stable, between/after them not.
        for lo, hi in iv:
            top = hi if np.isfinite(hi) else 10 * max(lo, 1.0)
            assert z.is_stable(lo + 0.01 * (top - lo), b) and z.is_stable(lo + 0.99 * (top - lo), b)
            if np.isfinite(hi):
                assert not z.is_stable(hi * 1.001, b) or any(l2 < hi * 1.001 < h2 for l2, h2 in iv)
        if not iv:
            assert not any(z.is_stable(K, b) for K in np.geomspace(1e-3, 1e3, 50))
    assert run.returncode == (0 if all(o["stable"] for o in ref["objects"]) else 3)


def test_loop_options_equal_cli(cli, table1_json, tmp_path):
    """--velocity-filter-hz and --hand against velocity_filter_hz= and hand= (boundary summary and check)."""
    hand = (1e-4, 1e-3, 0.0)
    flags = ["--velocity-filter-hz", "50", "--hand", ",".join(map(repr, hand))]
    cli("boundary", table1_json, "--delays", "2", "-o", tmp_path / "b.csv", "--summary", tmp_path / "s.json", *flags)
    summ = json.load(open(tmp_path / "s.json"))
    model = zwidth.Model.load(table1_json)
    z = zwidth.ZWidth(model, delay_samples=2, velocity_filter_hz=50.0, hand=hand)
    assert z.hand == hand and len(z.filter_b) >= 1
    assert z.summary() == summ["delays"][0]
    plain = zwidth.ZWidth(model, delay_samples=2)
    assert z.summary()["K_cr_max"] != plain.summary()["K_cr_max"]  # the loop options change the region
    scene = [{"name": "a", "K": 2.0, "B": 0.0}, {"name": "b", "K": 30.0, "B": 0.05}]
    p = tmp_path / "scene.json"
    p.write_text(json.dumps({"objects": scene}))
    run = cli("check", p, "--model", table1_json, "--delay", "2", "--json", *flags, check=False)
    cli_json = json.loads(run.stdout)
    cli_json.pop("provenance")
    assert zwidth.check(scene, model, 2, velocity_filter_hz=50.0, hand=hand) == cli_json
    assert run.returncode == 3
    with pytest.raises(zwidth.InputError):
        zwidth.ZWidth(model, delay_samples=2, velocity_filter_hz=600.0)  # above Nyquist
    with pytest.raises(zwidth.InputError):
        zwidth.ZWidth(model, delay_samples=2, hand=(-1.0, 0.0, 0.0))


def test_summary_carries_the_pole_conditioning():
    """stability_test.conditioning (issue 31): the relative separation of the poles against an
    independent numpy computation from the modes (e^{pT}: 1, e^{-bT/m}, each mode's pair)."""
    m = zwidth.Model.table1()
    st = zwidth.ZWidth(m, T, 2).summary()["stability_test"]
    poles = [1.0, np.exp(-m.b / m.m * T)]
    for w, c, _, _ in m.modes:
        p = complex(-c / 2, np.sqrt(w * w - c * c / 4))
        poles += [np.exp(p * T), np.exp(p.conjugate() * T)]
    gaps = [abs(a - b) for i, a in enumerate(poles) for b in poles[i + 1:]]
    c = st["conditioning"]
    assert c["relative_separation"] == pytest.approx(min(gaps) / max(gaps), rel=1e-6)
    assert c["eigenvalue_condition"] >= 1.0 and 0 < c["eigenvalue_shift"] < 1e-6
    assert st["warning"] is None
