#!/usr/bin/env python3
"""Issue 30, must-have 4, the Python side: a hostile user's values for every public entry of
the module, judged against the CLI given the same value.

    python3 tests/python/hostile_py_probe.py BUILD_DIR ZWIDTH_EXE SOURCE_DIR [-k SUBSTR] [-v]

Each case runs in a worker process (a crash or a hang is that case's, the next one goes on
in a new worker; 30 s and 4 GiB each). A keyword case is judged against the CLI: where the
CLI (the flag of the same value, or the same value in a file) exits 2, the module must raise
ValueError/TypeError/OSError naming the keyword; where the CLI exits 0, the module must
accept. Values with no CLI form (a bool, a string, a list for a number) must be refused with
TypeError/ValueError. Other cases (saves, mutation, pickled state, locale, threads, signals)
check themselves and raise Wrong. Prints one line per mishandled case and the counts:
refused / accepted / crashed / hung / wrong (mishandled: crashed + hung + wrong).
Not a pytest file: tests/python/test_hostile_py.py holds the tests of each class found.
"""
import json
import math
import os
import re
import subprocess
import sys
import tempfile

INF, NAN = float("inf"), float("nan")


class Wrong(Exception):
    """The module did something mishandled (a wrong file, a wrong answer, a lost check)."""


# Values tried for every numeric keyword: (label, value, the CLI's text or None).
REALS = [("nan", NAN, "nan"), ("inf", INF, "inf"), ("-inf", -INF, "-inf"), ("neg", -1.0, "-1"),
         ("zero", 0.0, "0"), ("huge", 1e300, "1e300"), ("bool", True, None), ("str", "1", None),
         ("list", [], None)]
INTS = [("neg", -1, "-1"), ("zero", 0, "0"), ("big", 2**31, "2147483648"), ("huge", 10**12, "1000000000000"),
        ("float", 2.5, None), ("nan", NAN, None), ("bool", True, None), ("str", "1", None)]
OPTIONAL_NONE = [("none", None, "")]  # "" : the flag left out


def keyword_table(d):
    """(name, python call taking the value, CLI argv or None, flag, kind, optional)."""
    md, lg, lh, fr, sc, out = d["model"], d["log_csv"], d["log_h5"], d["frf_csv"], d["scene"], d["out"]
    T = []

    def add(name, py, cli, flag, kind, optional=False):
        T.append((name, py, cli, flag, kind, optional))

    # simulate
    for kw, flag, kind in [("seconds", "--seconds", "r"), ("sample_rate_hz", "--rate", "r"),
                           ("torque_rms", "--torque-rms", "r"), ("bandwidth_hz", "--bandwidth-hz", "r"),
                           ("encoder_step_rad", "--encoder-step", "r"), ("noise_std_rad", "--noise-std", "r"),
                           ("delay_samples", "--delay-samples", "i"), ("seed", "--seed", "i")]:
        base = {"seconds": 2.0}
        add(f"simulate.{kw}", f"zw.simulate(M, **{{**{base!r}, {kw!r}: V}})",
            ["simulate", "--model", md, "--seconds", "2", "-o", out + "/sim_{id}.csv"], flag, kind)
    # estimate from a Log and from a path (the selectors)
    for kw, flag, kind in [("window_length", "--window-length", "i"), ("overlap", "--overlap", "r"),
                           ("fmin", "--fmin", "r"), ("fmax", "--fmax", "r")]:
        add(f"estimate(log).{kw}", f"zw.estimate(LOG, **{{{kw!r}: V}})",
            ["estimate", lh, "-o", out + "/frf_{id}.csv"], flag, kind)
    for kw, flag, kind in [("local_half_width", "--local-half-width", "i"), ("local_order", "--local-order", "i"),
                           ("local_differences", "--local-differences", "i")]:
        add(f"estimate(lpm).{kw}", f"zw.estimate(LOG, estimator='lpm', **{{{kw!r}: V}})",
            ["estimate", lh, "--estimator", "lpm", "-o", out + "/frf_{id}.csv"], flag, kind)
    for kw, flag, kind in [("rate", "--rate", "r"), ("input_scale", "--input-scale", "r"),
                           ("output_scale", "--output-scale", "r")]:
        add(f"estimate(path).{kw}", f"zw.estimate(LOGH5, **{{{kw!r}: V}})",
            ["estimate", lh, "-o", out + "/frf_{id}.csv"], flag, kind)
        add(f"read_log.{kw}", f"zw.read_log(LOGH5, **{{{kw!r}: V}})", None, None, kind)
    add("read_log.max_interval_deviation", "zw.read_log(LOGCSV, max_interval_deviation=V)", None, None, "r")
    add("estimate(u,y).sample_rate_hz", "zw.estimate(LOG.u, LOG.y, V)",
        ["estimate", lg, "--time-column", "none", "-o", out + "/frf_{id}.csv"], "--rate", "r")
    for kw, flag, kind in [("period_samples", "--period-samples", "i"),
                           ("transient_periods", "--transient-periods", "i")]:
        add(f"estimate_logs.{kw}", f"zw.estimate_logs(LOGH5, **{{**dict(estimator='robust', period_samples=1000), {kw!r}: V}})",
            ["estimate", lh, "--estimator", "robust", "--period-samples", "1000", "-o", out + "/frf_{id}.csv"], flag, kind)
    add("estimate_logs.overlap", "zw.estimate_logs(LOGH5, overlap=V)",
        ["estimate", lh, "-o", out + "/frf_{id}.csv"], "--overlap", "r")
    # fit
    fit_base = "modes=1, max_starts=1, delay_samples=0"
    fit_cli = ["fit", fr, "--modes", "1", "--starts", "1", "--delay-samples", "0", "-o", out + "/fit_{id}.json"]
    for kw, flag, kind in [("max_modes", "--max-modes", "i"), ("max_auto_delay", "--max-delay", "i"),
                           ("fmin", "--fmin", "r"), ("fmax", "--fmax", "r"),
                           ("min_input_power_ratio", "--min-input-power", "r"),
                           ("min_coherence", "--min-coherence", "r"), ("max_starts", "--starts", "i"),
                           ("max_iterations", "--max-iterations", "i")]:
        add(f"fit.{kw}", f"zw.fit(FRF, **{{**dict({fit_base}), {kw!r}: V}})", fit_cli, flag, kind)
    for kw in ["min_damping_ratio", "max_pole_damping_ratio", "max_zero_damping_ratio", "max_frequency_fraction",
               "relative_std_floor", "function_tolerance"]:
        add(f"fit.{kw}", f"zw.fit(FRF, **{{**dict({fit_base}), {kw!r}: V}})", None, None, "r")
    add("fit.modes", "zw.fit(FRF, modes=V, max_starts=1, delay_samples=0)",
        ["fit", fr, "--starts", "1", "--delay-samples", "0", "-o", out + "/fit_{id}.json"], "--modes", "i")
    add("fit.delay_samples", "zw.fit(FRF, modes=1, max_starts=1, delay_samples=V)",
        ["fit", fr, "--modes", "1", "--starts", "1", "-o", out + "/fit_{id}.json"], "--delay-samples", "i")
    # ZWidth
    bnd = ["boundary", md, "--b-points", "3", "-o", out + "/b_{id}.csv"]
    add("ZWidth.period_s", "zw.ZWidth(M, period_s=V).summary()", bnd + ["--delays", "2"], "--period", "r", True)
    add("ZWidth.delay_samples", "zw.ZWidth(M, delay_samples=V).summary()", bnd, "--delays", "i")
    add("ZWidth.velocity_filter_hz", "zw.ZWidth(M, velocity_filter_hz=V).summary()", bnd + ["--delays", "2"],
        "--velocity-filter-hz", "r", True)
    for kw, kind in [("min_grid_points", "i"), ("grid_points_per_delay", "i"), ("theta_tolerance", "r")]:
        add(f"ZWidth.{kw}", f"zw.ZWidth(M, {kw}=V).summary()", None, None, kind)
    add("ZWidth.summary.monte_carlo", "zw.ZWidth(MFIT).summary(monte_carlo=V)",
        ["boundary", d["model_fit"], "--b-points", "3", "--delays", "2", "-o", out + "/b_{id}.csv"],
        "--monte-carlo", "i")
    add("ZWidth.summary.seed", "zw.ZWidth(MFIT).summary(monte_carlo=3, seed=V)",
        ["boundary", d["model_fit"], "--b-points", "3", "--delays", "2", "--monte-carlo", "3",
         "-o", out + "/b_{id}.csv"], "--seed", "i")
    # The B and K of one point: the same values as a scene object's (zwidth check).
    for meth in ["critical(V)", "point(V)", "stable_intervals(V)", "crossings(V)", "boundary([V])",
                 "is_stable(1.0, V)", "characteristic_polynomial(1.0, V)"]:
        add(f"ZWidth.{meth.split('(')[0]}.B", f"zw.ZWidth(M).{meth}",
            ["check", "{scene_B}", "--model", md, "--delay", "2", "--json"], None, "r")
    for meth in ["is_stable(V, 0.01)", "characteristic_polynomial(V, 0.01)"]:
        add(f"ZWidth.{meth.split('(')[0]}.K", f"zw.ZWidth(M).{meth}",
            ["check", "{scene_K}", "--model", md, "--delay", "2", "--json"], None, "r")
    # relay
    rel = ["relay", md, "--delay", "2", "--damping", "0.001", "--seconds", "2"]
    for kw, flag, kind, opt in [("damping", "--damping", "r", False), ("period_s", "--period", "r", True),
                                ("amplitude", "--amplitude", "r", False), ("seconds", "--seconds", "r", False),
                                ("velocity_filter_hz", "--velocity-filter-hz", "r", True),
                                ("delay_samples", "--delay", "i", False)]:
        add(f"relay.{kw}", f"zw.relay(M, **{{**dict(delay_samples=2, damping=0.001, seconds=2.0), {kw!r}: V}})",
            rel, flag, kind, opt)
    add("relay.settle_fraction", "zw.relay(M, 2, 0.001, seconds=2.0, settle_fraction=V)", None, None, "r")
    # check
    chk = ["check", sc, "--model", md, "--delay", "2", "--json"]
    for kw, flag, kind, opt in [("period_s", "--period", "r", True),
                                ("velocity_filter_hz", "--velocity-filter-hz", "r", True),
                                ("marginal_sigmas", "--marginal-sigmas", "r", False),
                                ("delay_samples", "--delay", "i", False)]:
        add(f"check.{kw}", f"zw.check(SCENE, M, **{{**dict(delay_samples=2), {kw!r}: V}})", chk, flag, kind, opt)
    # validate
    add("validate.max_lag", "zw.validate(MFIT, LOG, max_lag=V)",
        ["validate", d["model_fit"], lh, "-o", out + "/v_{id}.json"], "--max-lag", "i")
    add("validate.relative_std_floor", "zw.validate(MFIT, LOG, relative_std_floor=V)", None, None, "r")
    # export
    add("Model.export.period_s", "M.export(OUT + '/e_{id}.json', 'json', period_s=V)",
        ["export", md, "--format", "json", "-o", out + "/e_{id}.json"], "--period", "r", True)
    add("Model.response.period_s", "M.response([1.0, 10.0], period_s=V)",
        ["export", md, "--format", "json", "-o", out + "/e_{id}.json"], "--period", "r", True)
    add("Model.state_space.period_s", "M.state_space(period_s=V)",
        ["export", md, "--format", "statespace", "-o", out + "/e_{id}.txt"], "--period", "r", True)
    # Model fields: the same value in a model JSON read by the CLI (boundary)
    for field, kind in [("m", "r"), ("b", "r"), ("delay_samples", "i"), ("sample_period_s", "r")]:
        add(f"Model().{field}", f"zw.ZWidth(zw.Model(**{{**MARGS, {field!r}: V}})).summary()",
            ["boundary", "{model_" + field + "}", "--b-points", "3", "--delays", "2", "-o", out + "/b_{id}.csv"],
            None, kind, field == "sample_period_s")
        add(f"Model.{field}=", f"MC = zw.Model.table1(); setattr(MC, {field!r}, V); zw.ZWidth(MC).summary(); MC.save(OUT + '/m_{id}.json')",
            ["boundary", "{model_" + field + "}", "--b-points", "3", "--delays", "2", "-o", out + "/b_{id}.csv"],
            None, kind, field == "sample_period_s")
    for k in range(4):
        add(f"Model().modes[0].{'wcvd'[k]}", f"zw.ZWidth(zw.Model(**{{**MARGS, 'modes': [MODE({k}, V)]}})).summary()",
            ["boundary", "{model_mode" + str(k) + "}", "--b-points", "3", "--delays", "2", "-o", out + "/b_{id}.csv"],
            None, "r")
    # FrequencyResponse: the same value in a response file read by `zwidth fit`
    add("FrequencyResponse.sample_rate_hz", "zw.fit(zw.FrequencyResponse(FRF.f_hz, FRF.H, V, num_averages=6), "
        f"{fit_base})", ["fit", "{frf_rate}", "--modes", "1", "--starts", "1", "--delay-samples", "0",
                         "-o", out + "/fit_{id}.json"], None, "r")
    add("FrequencyResponse.num_averages", "zw.fit(zw.FrequencyResponse(FRF.f_hz, FRF.H, 1000.0, num_averages=V), "
        f"{fit_base})", ["fit", "{frf_navg}", "--modes", "1", "--starts", "1", "--delay-samples", "0",
                         "-o", out + "/fit_{id}.json"], None, "i")
    add("FrequencyResponse.load.sample_rate_hz", "zw.FrequencyResponse.load(FRFCSV, sample_rate_hz=V)", None, None, "r")
    add("set_num_threads.n", "zw.set_num_threads(V); zw.ZWidth(M).summary(); zw.set_num_threads(None)",
        None, None, "i", True)
    add("Log.sample_rate_hz", "zw.Log(LOG.u, LOG.y, V).save(OUT + '/l_{id}.csv')",
        ["estimate", lg, "--time-column", "none", "-o", out + "/frf_{id}.csv"], "--rate", "r")
    return T


def keyword_cases(d):
    """Every (keyword, value) case of keyword_table: (id, code, cli argv or None, expectation)."""
    cases = []
    for name, py, cli, flag, kind, optional in keyword_table(d):
        values = list(REALS if kind == "r" else INTS) + (OPTIONAL_NONE if optional else [("none", None, None)])
        for label, value, text in values:
            cid = f"{name}={label}"
            literal = (f"float({str(value)!r})" if isinstance(value, float) and not math.isfinite(value)
                       else "(" + repr(value) + ")")
            code = re.sub(r"\bV\b", lambda _: literal, py.replace("{id}", _safe(cid)))
            argv = None
            if cli is not None and text is not None:
                argv = [a.replace("{id}", _safe(cid)) for a in cli]
                if flag is None:  # the value goes into a file
                    argv = [a if not (a.startswith("{") and a.endswith("}")) else "@" + a[1:-1] + "=" + text
                            for a in argv]
                elif text != "" and flag in argv:
                    argv = list(argv)
                    argv[argv.index(flag) + 1] = text
                elif text != "":
                    argv = argv + [flag, text]
            expectation = ("type" if text is None and not (label == "none" and optional) else
                           ("accept" if label == "none" else "cli"))
            if name.endswith(".fmax") and label == "inf":
                expectation = "accept"  # the documented default: up to Nyquist (the CLI: --fmax left out)
            if name.endswith(".seed") and label == "neg":
                expectation = "type"  # the CLI's UINT takes -1 as 2^64 - 1 (a CLI matter, reported)
            if label == "list" and name.split(".")[1] in ("critical", "boundary", "is_stable"):
                expectation = "accept"  # an empty array of B: an empty answer
            cases.append((cid, code, argv, expectation))
    return cases


def _safe(cid):
    return "".join(c if c.isalnum() else "_" for c in cid)


# Cases that check themselves: (id, code). The code raises Wrong when mishandled.
def special_cases():
    C = []

    def add(cid, code):
        C.append((cid, code))

    # Arrays: shape, length, dtype, non-contiguous, NaN inside, empty
    arrays = {
        "nan_inside": "np.r_[LOG.u[:-1], np.nan]", "2d": "np.c_[LOG.u, LOG.u]", "empty": "np.array([])",
        "short": "LOG.u[:-1]", "complex": "LOG.u.astype(complex)", "object": "np.array(['a'] * len(LOG.u))",
        "ragged": "[[1.0], [1.0, 2.0]]", "scalar": "1.0", "inf_inside": "np.r_[np.inf, LOG.u[1:]]",
    }
    for which in ("u", "y"):
        for label, expr in arrays.items():
            args = {"u": "LOG.u", "y": "LOG.y"}
            args[which] = expr
            add(f"Log.{which}={label}", f"expect_refused(lambda: zw.Log({args['u']}, {args['y']}, 1000.0), {which!r})")
            add(f"estimate(u,y).{which}={label}",
                f"expect_refused(lambda: zw.estimate({args['u']}, {args['y']}, 1000.0), {which!r})")
    for label in ("int", "noncontig", "fortran_col", "float32", "list"):
        expr = {"int": "np.round(LOG.u * 1e4).astype(np.int64)", "noncontig": "np.repeat(LOG.u, 2)[::2]",
                "fortran_col": "np.asfortranarray(np.c_[LOG.u, LOG.y])[:, 0]", "float32": "LOG.u.astype(np.float32)",
                "list": "list(LOG.u)"}[label]
        add(f"Log.u={label} (accepted, equal)",
            f"u = {expr}; l = zw.Log(u, LOG.y, 1000.0); expect(np.array_equal(l.u, np.asarray(u, float)), 'u changed')")
        add(f"estimate(u,y).u={label} (accepted, equal)",
            f"u = {expr}; a = zw.estimate(u, LOG.y, 1000.0); b = zw.estimate(np.asarray(u, float), LOG.y, 1000.0); "
            "expect(np.array_equal(a.H, b.H), 'H differs')")
    fr_arrays = {
        "f_nan": ("np.r_[np.nan, FRF.f_hz[1:]]", "FRF.H", "None", "f_hz"),
        "f_decreasing": ("FRF.f_hz[::-1].copy()", "FRF.H", "None", "f_hz"),
        "f_above_nyquist": ("FRF.f_hz * 2", "FRF.H", "None", "f_hz"),
        "f_negative": ("FRF.f_hz - 10", "FRF.H", "None", "f_hz"),
        "f_2d": ("np.c_[FRF.f_hz, FRF.f_hz]", "FRF.H", "None", "f_hz"),
        "H_short": ("FRF.f_hz", "FRF.H[:-1]", "None", "H"),
        "H_nan": ("FRF.f_hz", "np.r_[FRF.H[:-1], np.nan]", "None", "H"),
        "H_str": ("FRF.f_hz", "np.array(['a'] * len(FRF.H))", "None", "H"),
        "H_zero": ("FRF.f_hz", "np.zeros(len(FRF.H))", "None", "H"),
        "H_std_zero": ("FRF.f_hz", "FRF.H", "np.zeros(len(FRF.H))", "H_std"),
        "H_std_neg": ("FRF.f_hz", "FRF.H", "-np.ones(len(FRF.H))", "H_std"),
        "H_std_nan": ("FRF.f_hz", "FRF.H", "np.r_[np.nan, FRF.H_std[1:]]", "H_std"),
        "H_std_short": ("FRF.f_hz", "FRF.H", "FRF.H_std[:-1]", "H_std"),
        "empty": ("np.array([])", "np.array([])", "None", "f_hz"),
    }
    for label, (f, H, Hs, kw) in fr_arrays.items():
        add(f"FrequencyResponse.{label}",
            f"expect_refused(lambda: zw.FrequencyResponse({f}, {H}, 1000.0, H_std={Hs}, num_averages=6), {kw!r})")
    for label, coh in {"coh_above_1": "np.full(len(FRF.f_hz), 1.5)", "coh_neg": "np.full(len(FRF.f_hz), -0.1)",
                       "coh_nan": "np.r_[np.nan, FRF.coherence[1:]]", "coh_short": "FRF.coherence[:-1]"}.items():
        add(f"FrequencyResponse.{label}",
            f"expect_refused(lambda: zw.FrequencyResponse(FRF.f_hz, FRF.H, 1000.0, coherence={coh}, "
            "num_averages=6), 'coherence')")
    # B and K arrays
    for label, expr in {"B_nan_inside": "[0.0, np.nan]", "B_str": "['a']",
                        "B_object": "np.array([None])", "B_3d_nan": "np.full((1, 1, 1), np.nan)"}.items():
        add(f"ZWidth.critical.{label}", f"expect_refused(lambda: zw.ZWidth(M).critical({expr}), 'B', shape_ok=True)")
    add("ZWidth.critical.B_empty (accepted)", "r = zw.ZWidth(M).critical([]); expect(len(r[0]) == 0, 'not empty')")
    add("ZWidth.critical.B_noncontig (equal)",
        "B = np.linspace(0, 0.02, 20)[::2]; z = zw.ZWidth(M); a = z.critical(B)[0]; "
        "b = z.critical(np.ascontiguousarray(B))[0]; expect(np.array_equal(a, b), 'differs')")
    add("ZWidth.is_stable.K_B_shapes", "expect_refused(lambda: zw.ZWidth(M).is_stable([1.0, 2.0], [0.0, 0.1, 0.2]), 'K')")
    # Model modes of the wrong form
    for label, modes in {"str": "'abc'", "short_tuple": "[(1.0, 2.0, 3.0)]", "nan": "[(np.nan, 1.0, 1.0, 1.0)]",
                         "nested_str": "[('a', 1.0, 1.0, 1.0)]", "dict": "[{'omega': 1.0}]", "int": "3",
                         "ndarray_2x3": "np.ones((2, 3))"}.items():
        add(f"Model.modes={label}", f"expect_refused(lambda: zw.Model(0.001, 0.005, modes={modes}), 'modes')")
        add(f"Model.modes= setter {label}", f"mc = zw.Model.table1(); "
            f"expect_refused(lambda: setattr(mc, 'modes', {modes}), 'modes'); "
            "expect(mc == zw.Model.table1(), 'changed by a refused set')")
    add("Model.modes=ndarray (accepted)", "m = zw.Model(0.001, 0.005, modes=np.array([[500.0, 80, 400, 80]])); "
        "expect(m.modes == [(500.0, 80.0, 400.0, 80.0)], 'modes')")
    add("Model.name=newline quote (export round trip)",
        "mc = zw.Model.table1(); mc.name = 'a\\n\\'\"; b\\\\'; p = OUT + '/name.json'; mc.save(p); "
        "expect(zw.Model.load(p).name == mc.name, 'name lost'); cli_ok(['export', p, '--format', 'json', '-o', OUT + '/name2.json'])")
    # covariance
    n = "len(MFIT.covariance_names)"
    for label, cov, kw in [("wrong_size", "np.eye(3)", "covariance"), ("nan", f"np.full(({n}, {n}), np.nan)", "covariance"),
                           ("negative_diag", f"-np.eye({n})", "covariance"),
                           ("asymmetric", f"np.triu(np.ones(({n}, {n})))", "covariance"),
                           ("str", "'abc'", "covariance"), ("1d", f"np.ones({n} * {n})", "covariance"),
                           ("huge", f"np.eye({n}) * 1e300", "covariance")]:
        add(f"Model.covariance={label}",
            f"mc = zw.Model.from_json(MFIT.to_json()); expect_refused_like_cli(lambda: (setattr(mc, 'covariance', {cov}), "
            "zw.ZWidth(mc).summary(monte_carlo=3)), "
            f"{kw!r}, 'covariance', {cov})")
    add("Model.covariance kept after modes set",
        "mc = zw.Model.from_json(MFIT.to_json()); mc.modes = mc.modes; "
        "expect(mc.covariance is None and mc.std is None, 'kept a covariance of the old sections')")
    # mutation after construction, then use and save
    add("Model.sample_period_s=1000 then ZWidth/save",
        "mc = zw.Model.table1(); refused_at_some_step([lambda: setattr(mc, 'sample_period_s', 1000.0), "
        "lambda: zw.ZWidth(mc).summary()], 'sample_period_s'); "
        "expect_save_refused_or_readable(lambda p: mc.save(p), 'model')")
    add("Model.sample_period_s=1e-9 then ZWidth/save",
        "mc = zw.Model.table1(); refused_at_some_step([lambda: setattr(mc, 'sample_period_s', 1e-9), "
        "lambda: zw.ZWidth(mc).summary()], 'sample_period_s'); "
        "expect_save_refused_or_readable(lambda p: mc.save(p), 'model')")
    add("Model.delay_samples=10**6 then ZWidth",
        "mc = zw.Model.table1(); refused_at_some_step([lambda: setattr(mc, 'delay_samples', 10**6), "
        "lambda: zw.ZWidth(mc).summary()], 'delay_samples')")
    for label, state in {"Log nan rate": "('', float('nan'), LOG.u.tobytes(), LOG.y.tobytes())",
                         "Log nan sample": "('', 1000.0, np.r_[np.nan, LOG.u[1:]].tobytes(), LOG.y.tobytes())",
                         "Log short y": "('', 1000.0, LOG.u.tobytes(), LOG.y[:-5].tobytes())",
                         "Log rate 5": "('', 5.0, LOG.u.tobytes(), LOG.y.tobytes())"}.items():
        add(f"pickled {label} then save/estimate",
            f"box = []; "
            f"refused_at_some_step([lambda: box.append(RESTORE(zw.Log, {state})), lambda: zw.estimate(box[0])], None) and "
            "expect_save_refused_or_readable(lambda p: box[0].save(p), 'log')")
    add("pickled FrequencyResponse nan rate then fit/save",
        "s = list(FRF.__getstate__()); s[0] = float('nan'); box = []; "
        "refused_at_some_step([lambda: box.append(RESTORE(zw.FrequencyResponse, tuple(s))), "
        "lambda: zw.fit(box[0], modes=1, max_starts=1, delay_samples=0)], None) and "
        "expect_save_refused_or_readable(lambda p: box[0].save(p), 'frf')")
    add("pickled FrequencyResponse bytes of other lengths then fit",
        "s = list(FRF.__getstate__()); s[6] = s[6][:16]; box = []; "
        "refused_at_some_step([lambda: box.append(RESTORE(zw.FrequencyResponse, tuple(s))), "
        "lambda: zw.fit(box[0], modes=1, max_starts=1, delay_samples=0)], None) and "
        "expect_save_refused_or_readable(lambda p: box[0].save(p), 'frf')")
    add("pickled ZWidth negative delay",
        "s = list(zw.ZWidth(M).__getstate__()); s[2] = -5; box = []; "
        "refused_at_some_step([lambda: box.append(RESTORE(zw.ZWidth, tuple(s))), lambda: box[0].summary()], 'delay_samples')")
    add("pickled ZWidth nan tolerance",
        "s = list(zw.ZWidth(M).__getstate__()); s[3] = (2048, 64, float('nan'), True); box = []; "
        "refused_at_some_step([lambda: box.append(RESTORE(zw.ZWidth, tuple(s))), lambda: box[0].summary()], 'theta_tolerance')")
    add("pickled ZWidth nan period",
        "s = list(zw.ZWidth(M).__getstate__()); s[1] = float('nan'); box = []; "
        "refused_at_some_step([lambda: box.append(RESTORE(zw.ZWidth, tuple(s))), lambda: box[0].summary()], 'period_s')")
    # Paths: folders, missing, empty, NUL, the input itself, PathLike, devices
    readers = {"read_log": "zw.read_log(P)", "estimate(path)": "zw.estimate(P)", "Model.load": "zw.Model.load(P)",
               "FrequencyResponse.load": "zw.FrequencyResponse.load(P)", "estimate_logs": "zw.estimate_logs(P)",
               "check(scene path)": "zw.check(P, M, 2)", "validate(path)": "zw.validate(MFIT, P)"}
    for rn, code in readers.items():
        for label, p in {"folder": "OUT", "missing": "OUT + '/missing.h5'", "empty": "''",
                         "nul": "LOGH5 + '\\0x'", "devnull": "'/dev/null'"}.items():
            add(f"{rn} path={label}", f"P = {p}; expect_refused(lambda: {code}, None, errors=(ValueError, OSError))")
    add("read_log path=PathLike (accepted)", "import pathlib; zw.read_log(pathlib.Path(LOGH5))")
    add("Model.load path=PathLike (accepted)", "import pathlib; zw.Model.load(pathlib.Path(MODEL))")
    add("FrequencyResponse.load path=PathLike (accepted)", "import pathlib; zw.FrequencyResponse.load(pathlib.Path(FRFCSV))")
    add("validate path=PathLike (accepted)", "import pathlib; zw.validate(MFIT, pathlib.Path(LOGH5))")
    writers = {"Log.save": ("LOG.save(P)", ".csv"), "Model.save": ("M.save(P)", ".json"),
               "Model.export": ("M.export(P, 'matlab')", ".m"), "FrequencyResponse.save": ("FRF.save(P)", ".csv"),
               "Log.save h5": ("LOG.save(P)", ".h5"), "Model.export mat": ("M.export(P, 'mat')", ".mat")}
    for wn, (code, ext) in writers.items():
        for label, p in {"folder": "OUT", "missing_parent": f"OUT + '/no/such{ext}'", "empty": "''",
                         "nul": f"OUT + '/nul{ext}\\0x'", "devnull": "'/dev/null'",
                         "trailing_slash": f"OUT + '/slash{ext}/'"}.items():
            add(f"{wn} path={label}",
                f"P = {p}; before = sorted(os.listdir(OUT)); expect_refused(lambda: {code}, None, errors=(ValueError, OSError)); "
                "expect(sorted(os.listdir(OUT)) == before, 'left a file: ' + str(set(os.listdir(OUT)) - set(before)))")
        add(f"{wn} path=PathLike (accepted)", f"import pathlib; P = pathlib.Path(OUT + '/pl{_safe(wn)}{ext}'); {code}; "
            "expect(P.exists(), 'not written')")
    add("run out_dir=the log itself", "expect_refused(lambda: zw.run(LOGH5, LOGH5, figures=False), 'out_dir', "
        "errors=(ValueError, OSError)); expect(zw.read_log(LOGH5).num_samples == LOG.num_samples, 'input changed')")
    add("run out_dir=folder of the log", "expect_refused(lambda: zw.run(LOGH5, os.path.dirname(LOGH5), figures=False), "
        "None, errors=(ValueError, OSError))")
    add("run logs=[]", "expect_refused(lambda: zw.run([], OUT + '/run_empty', figures=False), 'logs')")
    add("run logs=same log twice", "expect_refused(lambda: zw.run([LOGH5, LOGH5], OUT + '/run_twice', figures=False), None)")
    add("estimate_logs same log twice", "expect_refused(lambda: zw.estimate_logs([LOGH5, LOGH5]), None)")
    add("estimate_logs []", "expect_refused(lambda: zw.estimate_logs([]), 'paths')")
    add("run delays=[]", "expect_refused(lambda: zw.run(LOGH5, OUT + '/run_nodelay', figures=False, delays=[]), 'delays')")
    add("run delays=[-1]", "expect_refused(lambda: zw.run(LOGH5, OUT + '/run_negdelay', figures=False, delays=[-1]), 'delays')")
    add("run delays=[5000]", "expect_refused(lambda: zw.run(LOGH5, OUT + '/run_bigdelay', figures=False, delays=[5000]), 'delays')")
    for kw, v in [("b_step", "float('nan')"), ("b_step", "-1.0"), ("b_points", "-1"),
                  ("b_points", "10**9"), ("report_filter_hz", "float('nan')"), ("velocity_filter_hz", "float('nan')"),
                  ("hand", "(float('nan'), 0.0, 0.0)"), ("hand", "(1e300, 0.0, 0.0)"), ("units", "'furlong'"),
                  ("fmin", "float('nan')"), ("fmax", "float('nan')"), ("overlap", "float('nan')")]:
        add(f"run {kw}={v}", f"expect_refused(lambda: zw.run(LOGH5, OUT + '/run_{_safe(kw + v)}', figures=False, {kw}={v}), "
            f"{kw!r}); expect(not os.path.exists(OUT + '/run_{_safe(kw + v)}'), 'left a folder')")
    # hands
    for label, hand in {"nan": "(float('nan'), 0.0, 0.0)", "neg": "(-1.0, 0.0, 0.0)", "huge": "(1e300, 0.0, 0.0)",
                        "two": "(1.0, 0.0)", "str": "'1,0,0'"}.items():
        add(f"ZWidth.hand={label}", f"expect_refused(lambda: zw.ZWidth(M, hand={hand}).summary(), 'hand')")
        add(f"relay.hand={label}", f"expect_refused(lambda: zw.relay(M, 2, 0.001, seconds=2.0, hand={hand}), 'hand')")
    # scenes
    for label, obj in {"K_nan": "('a', float('nan'), 0.0)", "B_neg": "('a', 1.0, -1.0)", "K_huge": "('a', 1e300, 0.0)",
                       "name_newline": "('a\\nb', 1.0, 0.0)", "K_str": "('a', '1', 0.0)",
                       "two": "('a', 1.0)"}.items():
        add(f"check scene {label}", f"expect_refused_like_cli(lambda: zw.check([{obj}], M, 2), None, 'scene', {obj})")
    add("check scene=[] (as the CLI)", "expect_refused_like_cli(lambda: zw.check([], M, 2), 'scene', 'scene', None)")
    return C


# Saves: written, read back by the module and by the CLI, the same under a German locale.
def save_cases():
    C = []
    logs = {"normal": "LOG", "one_sample": "zw.Log([1.0], [2.0], 1000.0)", "two_samples": "zw.Log([1.0, 2.0], [2.0, 3.0], 1000.0)",
            "odd_rate": "zw.Log(LOG.u, LOG.y, 1000.0000001)", "rate_1e6": "zw.Log(LOG.u[:50], LOG.y[:50], 1e6)",
            "rate_10.5": "zw.Log(LOG.u[:50], LOG.y[:50], 10.5)", "huge_values": "zw.Log(LOG.u * 1e300, LOG.y, 1000.0)",
            "tiny_values": "zw.Log(LOG.u * 1e-320, LOG.y, 1000.0)", "constant": "zw.Log(np.zeros(100), np.zeros(100), 1000.0)",
            "rate_third": "zw.Log(LOG.u[:3000], LOG.y[:3000], 1000.0 / 3.0)"}
    for label, expr in logs.items():
        for ext in (".csv", ".h5", ".txt", ".mat"):
            C.append((f"Log.save {label}{ext}", f"save_round_trip_log(lambda: {expr}, {ext!r})"))
    models = {"table1": "M", "fitted": "MFIT", "delay": "zw.Model(0.001, 0.005, [(500.0, 80, 400, 80)], delay_samples=3, "
              "sample_period_s=1e-3)", "tiny_m": "zw.Model(1e-300, 1e-300)", "named": "zw.Model(0.001, 0.005, name='x\\'\\n\"y;%')"}
    for label, expr in models.items():
        C.append((f"Model.save {label}", f"save_round_trip_model(lambda: {expr}, None)"))
        for fmt in ("json", "hdf5", "matlab", "python", "statespace", "mat", "mat73"):
            C.append((f"Model.export {label} {fmt}", f"save_round_trip_model(lambda: {expr}, {fmt!r})"))
    for label, expr in {"estimated": "FRF", "made": "zw.FrequencyResponse(FRF.f_hz, FRF.H, 1000.0, num_averages=6)",
                        "one_bin": "zw.FrequencyResponse([10.0], [1.0 + 1j], 1000.0, num_averages=6)"}.items():
        for ext in (".csv", ".h5"):
            C.append((f"FrequencyResponse.save {label}{ext}", f"save_round_trip_frf(lambda: {expr}, {ext!r})"))
    C.append(("run folder German = C", "run_german()"))
    C.append(("messages German = C", "messages_german()"))
    return C


def other_cases():
    return [(f"{c}.__new__({c}{extra}) without __init__, then repr",
             f"expect_refused(lambda: repr(zw.{c}.__new__(zw.{c}{extra})), None, errors=(ValueError, TypeError))")
            for c in ("Log", "Model", "FrequencyResponse", "FitResult", "CriticalPoint", "ZWidth", "RelayResult")
            for extra in ("", ", 1")] + [("threads: estimate, fit, ZWidth, h5 reads and saves at once", "threads()"),
            ("threads: mat reads and exports at once", "threads_mat()"),
            ("signals: handlers untouched by saves, Ctrl-C raises KeyboardInterrupt", "signals()")]


# ---------------------------------------------------------------------------------------------
# Worker side
# ---------------------------------------------------------------------------------------------
WORKER_PRELUDE = r'''
import os, sys, json, math, locale, threading, warnings, subprocess
import numpy as np
warnings.simplefilter("ignore")
import zwidth as zw
D = json.loads(os.environ["PROBE_FILES"])
EXE = os.environ["ZWIDTH_EXE"]
OUT = D["out"]; MODEL = D["model"]; LOGH5 = D["log_h5"]; LOGCSV = D["log_csv"]; FRFCSV = D["frf_csv"]
RESTORE = zw.Model.table1().__reduce_ex__(2)[0]  # what pickle.loads calls
M = zw.Model.table1(); MC = zw.Model.table1(); MFIT = zw.Model.load(D["model_fit"])
LOG = zw.read_log(LOGH5); FRF = zw.FrequencyResponse.load(FRFCSV); SCENE = D["scene"]
MARGS = dict(m=0.001168, b=0.00584, modes=[(479.166, 83.0, 417.612, 80.0)])
def MODE(k, v):
    t = [479.166, 83.0, 417.612, 80.0]; t[k] = v; return tuple(t)

class Wrong(Exception):
    pass

def expect(cond, what):
    if not cond:
        raise Wrong(what)

def names(e, kw):
    return kw is None or kw in str(e) or (kw == "out_dir" and "output folder" in str(e))

def expect_refused(f, kw, errors=(ValueError, TypeError), shape_ok=False):
    try:
        f()
    except errors as e:
        if not names(e, kw):
            raise Wrong(f"refused ({type(e).__name__}) without naming {kw!r}: {str(e)[:200]}")
        return
    except Exception as e:
        raise Wrong(f"{type(e).__name__} instead of {errors}: {str(e)[:200]}")
    raise Wrong("accepted")

def cli(argv):
    return subprocess.run([EXE, *argv], capture_output=True, text=True, timeout=60)

def cli_ok(argv):
    p = cli(argv)
    expect(p.returncode == 0, f"zwidth {' '.join(argv[:2])} refused what the module wrote: {p.stderr.strip()[:200]}")

def expect_refused_like_cli(f, kw, what, value):
    """Setting `what` to value: refused exactly where the CLI refuses the same value in a file."""
    refused = None
    try:
        f()
        refused = False
    except (ValueError, TypeError) as e:
        refused = str(e)
    cli_refuses = cli_refuses_value(what, value)
    if cli_refuses and refused is False:
        raise Wrong(f"accepted; the CLI refuses it")
    if refused and not cli_refuses:
        raise Wrong(f"refused; the CLI accepts it: {refused[:150]}")
    if refused and kw and kw not in refused:
        raise Wrong(f"refused without naming {kw!r}: {refused[:150]}")

def cli_refuses_value(what, value):
    if what == "covariance":
        j = json.loads(MFIT.to_json())
        try:
            c = np.asarray(value, dtype=float)
        except (ValueError, TypeError):
            return True
        if not np.all(np.isfinite(c)):
            return True
        j["covariance"] = c.tolist()
        p = OUT + "/cov_probe.json"
        open(p, "w").write(json.dumps(j))
        return cli(["boundary", p, "--delays", "2", "--b-points", "3", "--monte-carlo", "3",
                    "-o", OUT + "/cov_probe.csv"]).returncode == 2
    if what == "scene":
        objs = [] if value is None else [dict(zip(["name", "K", "B"], value))]
        p = OUT + "/scene_probe.json"
        try:
            open(p, "w").write(json.dumps({"objects": objs}, allow_nan=True))
        except (TypeError, ValueError):
            return True
        return cli(["check", p, "--model", MODEL, "--delay", "2", "--json"]).returncode == 2
    raise AssertionError(what)

def refused_at_some_step(steps, kw):
    """Each step in turn; one must refuse (ValueError/TypeError naming kw): a bad value never used."""
    for i, s in enumerate(steps):
        try:
            s()
        except (ValueError, TypeError, OSError) as e:
            if kw is not None and kw not in str(e):
                raise Wrong(f"refused without naming {kw!r}: {str(e)[:200]}")
            return i > 0  # refused at the first step: there is no object to save
    raise Wrong("every step accepted the bad value")

def expect_save_refused_or_readable(save, kind):
    p = OUT + "/probe_save_" + kind + (".json" if kind == "model" else ".csv")
    if os.path.exists(p):
        os.remove(p)
    try:
        save(p)
    except (ValueError, TypeError, OSError):
        expect(not os.path.exists(p), "left a file after refusing")
        return
    reader = {"model": ["export", p, "--format", "json", "-o", OUT + "/probe_save_check.json"],
              "log": ["estimate", p, "-o", OUT + "/probe_save_check.csv"],
              "frf": ["fit", p, "--modes", "1", "--starts", "1", "--delay-samples", "0", "--allow-short",
                      "-o", OUT + "/probe_save_check.json"]}[kind]
    cli_ok(reader)

def german(f):
    """f(tag) under de_DE.UTF-8 and under C: both results; a written path's bytes are kept in
    the result (the same path both times, so that the provenance's command is the same)."""
    old = locale.setlocale(locale.LC_ALL)
    def once(loc):
        locale.setlocale(locale.LC_ALL, loc)
        try:
            r = f("x")
        finally:
            locale.setlocale(locale.LC_ALL, old)
        if isinstance(r, tuple) and r[0] == "written":
            r = (r[0], r[1], read_bytes(r[1]))
        elif isinstance(r, str) and os.path.isdir(r):
            r = read_bytes(r)
            import shutil; shutil.rmtree(OUT + "/run_x")
        return r
    de = once("de_DE.UTF-8")
    c = once("C")
    return de, c

def read_bytes(p):
    if os.path.isdir(p):
        return {n: read_bytes(os.path.join(p, n)) for n in sorted(os.listdir(p))}
    return open(p, "rb").read()

def textual(ext_or_fmt):
    return ext_or_fmt in (".csv", ".txt", "json", "matlab", "python", "statespace")

def saved_twice(save, path, text):
    """save(path) under de_DE.UTF-8 and under C: ('refused', message) or ('written', path, bytes)
    for each; both must agree, a refusal leaves no file, and a text file's lines (but for the
    date) must be the same bytes."""
    def w(tag):
        if os.path.exists(path):
            os.remove(path)
        try:
            save(path)
        except (ValueError, TypeError, OSError) as e:
            expect(not os.path.exists(path), "left a file after refusing")
            return ("refused", str(e))
        return ("written", path)
    de, c = german(w)
    expect(de[0] == c[0], f"German {de[0]}, C {c[0]}")
    if c[0] == "written" and text:
        a = [l for l in de[2].split(b"\n") if b"created" not in l and b"date" not in l]
        b = [l for l in c[2].split(b"\n") if b"created" not in l and b"date" not in l]
        expect(a == b, "German text differs from C's: " + str([x for x in zip(a, b) if x[0] != x[1]][:2]))
    return c

def save_round_trip_log(make, ext):
    try:
        log = make()
    except ValueError:
        return  # refused when made: never saved
    c = saved_twice(log.save, OUT + f"/rt{ext}", textual(ext))
    if c[0] == "refused":
        return
    p = c[1]
    try:
        back = zw.read_log(p)
    except (ValueError, OSError) as e:
        raise Wrong(f"the module refuses its own file: {str(e)[:200]}")
    expect(back.num_samples == log.num_samples, f"{back.num_samples} samples read of {log.num_samples}")
    expect(np.array_equal(back.u, log.u) and np.array_equal(back.y, log.y), "samples changed")
    expect(abs(back.sample_rate_hz / log.sample_rate_hz - 1) < 1e-9, f"rate {back.sample_rate_hz} for {log.sample_rate_hz}")
    pc = cli(["estimate", p, "-o", OUT + "/rt_check.csv"])
    try:
        zw.estimate(back); module = 0
    except ValueError:
        module = 2
    expect(pc.returncode == module, f"zwidth estimate: exit {pc.returncode}, the module's estimate {module}: "
           f"{pc.stderr.strip()[:200]}")

def save_round_trip_model(make, fmt):
    try:
        model = make()
    except ValueError:
        return  # refused when made: never saved
    ext = {None: ".json", "json": ".json", "hdf5": ".h5", "matlab": ".m", "python": ".py", "statespace": ".txt",
           "mat": ".mat", "mat73": ".mat"}[fmt]
    c = saved_twice((lambda p: model.save(p)) if fmt is None else (lambda p: model.export(p, fmt, period_s=1e-3)),
                    OUT + f"/rtm_{fmt}{ext}", textual(fmt or "json"))
    if c[0] == "refused":
        return
    p = c[1]
    if fmt in (None, "json"):
        back = zw.Model.load(p)
        expect(back.m == model.m and back.b == model.b and back.modes == model.modes and back.name == model.name,
               "model changed by the round trip")
        cli_ok(["export", p, "--format", "json", "-o", OUT + f"/rtm_check_{os.getpid()}.json"])
    if fmt == "python":
        import ast
        tree = ast.parse(open(p).read())
        calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)]
        names_ = {getattr(n.func, "id", getattr(n.func, "attr", "?")) for n in calls}
        expect(names_ <= {"array", "StateSpace", "ss", "decode"}, f"calls {names_}")
        if model.name:
            consts = [n.value if isinstance(n.value, str) else n.value.decode("utf-8", "surrogateescape")
                      for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, (str, bytes))]
            expect(model.name in consts, "the name is not kept as one string literal")

def save_round_trip_frf(make, ext):
    try:
        frf = make()
    except ValueError:
        return  # refused when made: never saved
    c = saved_twice(frf.save, OUT + f"/rtf{ext}", textual(ext))
    if c[0] == "refused":
        return
    try:
        back = zw.FrequencyResponse.load(c[1])
    except (ValueError, OSError) as e:
        raise Wrong(f"the module refuses its own file: {str(e)[:200]}")
    expect(np.array_equal(back.f_hz, frf.f_hz) and np.array_equal(back.H, frf.H), "response changed")
    pc = cli(["fit", c[1], "--modes", "0", "--starts", "1", "--delay-samples", "0", "--allow-short",
              "-o", OUT + "/rtf_check.json"])
    expect(pc.returncode in (0, 1) or "bins" in pc.stderr, f"zwidth fit: exit {pc.returncode}: {pc.stderr.strip()[:200]}")

def run_german():
    def w(tag):
        p = OUT + f"/run_{tag}"
        zw.run(LOGH5, p, figures=False, delays=[2], modes=1, max_starts=1, delay_samples=0, b_points=20)
        return p
    de, c = german(w)
    a, b = de, c
    expect(sorted(a) == sorted(b), "other files")
    for n in a:
        keep = lambda l: not any(w in l for w in (b"created", b"date", b"seconds", b"zwidth.run(", b"_s\""))
        la = [l for l in a[n].split(b"\n") if keep(l)]
        lb = [l for l in b[n].split(b"\n") if keep(l)]
        diff = [x for x in zip(la, lb) if x[0] != x[1]]
        expect(not diff, f"{n}: German differs: {diff[:1]}")

def messages_german():
    bad = [lambda: zw.estimate(LOG.u, LOG.y, -5.0), lambda: zw.Log(LOG.u, LOG.y, 5.5),
           lambda: zw.ZWidth(M, period_s=0.5), lambda: zw.relay(M, 2, 0.001, amplitude=-0.5),
           lambda: zw.simulate(M, seconds=-2.5), lambda: zw.fit(FRF, modes=1, fmin=0.5, fmax=0.25),
           lambda: zw.estimate(LOG, overlap=1.5), lambda: zw.check([("a", 1.5, -0.5)], M, 2),
           lambda: zw.ZWidth(M, velocity_filter_hz=900.5), lambda: zw.FrequencyResponse([1.5, 0.5], [1, 1], 1000.0),
           lambda: zw.Model(0.001, -0.5), lambda: zw.ZWidth(M, theta_tolerance=0.5)]
    def w(tag):
        out = []
        for f in bad:
            try:
                f()
                out.append("accepted")
            except Exception as e:
                out.append(f"{type(e).__name__}: {e}")
        return out
    de, c = german(w)
    diff = [(x, y) for x, y in zip(de, c) if x != y]
    expect(not diff, f"{len(diff)} messages differ, e.g. {diff[:1]}")

def _in_threads(jobs, seconds=60):
    errors = []
    def run(f):
        try:
            f()
        except Exception as e:
            errors.append(f"{type(e).__name__}: {e}")
    ts = [threading.Thread(target=run, args=(f,), daemon=True) for f in jobs]
    for t in ts: t.start()
    for t in ts: t.join(seconds)
    expect(not any(t.is_alive() for t in ts), "deadlock: threads still running after 60 s")
    expect(not errors, f"errors: {errors[:2]}")

def threads():
    def reader():
        for _ in range(15): zw.read_log(LOGH5)
    def saver(k):
        def f():
            for i in range(15):
                LOG.save(OUT + f"/th_{k}_{i}.h5"); zw.FrequencyResponse.save(FRF, OUT + f"/thf_{k}_{i}.h5")
        return f
    def est():
        for _ in range(5): zw.estimate(LOGH5)
    def fit():
        for _ in range(2): zw.fit(FRF, modes=1, max_starts=2, delay_samples=0)
    def zwd():
        for _ in range(5): zw.ZWidth(M, delay_samples=3).summary()
    def runf():
        zw.run(LOGH5, OUT + "/th_run", figures=False, delays=[2], modes=1, max_starts=1, delay_samples=0, b_points=20)
    _in_threads([reader, reader, saver(0), saver(1), est, fit, zwd, runf])

def threads_mat():
    M.export(OUT + "/thm.mat", "mat")
    def reader():
        for _ in range(10):
            try: zw.read_log(OUT + "/thm.mat")
            except ValueError: pass  # a model file is not a log: refused, which is fine
    def exporter(k):
        def f():
            for i in range(10):
                M.export(OUT + f"/thm_{k}_{i}.mat", "mat73"); M.export(OUT + f"/thm_{k}_{i}.h5", "hdf5")
        return f
    _in_threads([reader, reader, exporter(0), exporter(1)])

def signals():
    import ctypes, signal as sg
    libc = ctypes.CDLL(None, use_errno=True)
    class SA(ctypes.Structure):
        _fields_ = [("handler", ctypes.c_void_p), ("mask", ctypes.c_ulong * 16), ("flags", ctypes.c_int),
                    ("restorer", ctypes.c_void_p)]
    def c_handlers():
        out = {}
        for s in (sg.SIGINT, sg.SIGTERM, sg.SIGPIPE, sg.SIGXFSZ, sg.SIGHUP, sg.SIGCHLD, sg.SIGSEGV):
            sa = SA()
            libc.sigaction(int(s), None, ctypes.byref(sa))
            out[int(s)] = sa.handler
        return out
    py_before = {s: sg.getsignal(s) for s in (sg.SIGINT, sg.SIGTERM, sg.SIGPIPE)}
    c_before = c_handlers()
    LOG.save(OUT + "/sig.h5"); LOG.save(OUT + "/sig.csv"); M.save(OUT + "/sig.json"); M.export(OUT + "/sig.mat", "mat")
    FRF.save(OUT + "/sigf.csv")
    zw.run(LOGH5, OUT + "/sig_run", figures=False, delays=[2], modes=1, max_starts=1, delay_samples=0, b_points=20)
    zw.fit(FRF, modes=1, max_starts=1)
    expect({s: sg.getsignal(s) for s in py_before} == py_before, "Python's handlers changed")
    after = c_handlers()
    expect(after == c_before, f"C handlers changed: {[s for s in after if after[s] != c_before[s]]}")
    try:
        os.kill(os.getpid(), sg.SIGINT)
        import time; time.sleep(0.1)
    except KeyboardInterrupt:
        return
    raise Wrong("Ctrl-C did not raise KeyboardInterrupt")

def run_keyword(code, want_name, german_check=True):
    try:
        exec(code, globals())
    except (ValueError, TypeError, OSError) as e:
        msg = str(e)
        de = None
        if german_check:
            old = locale.setlocale(locale.LC_ALL)
            try:
                locale.setlocale(locale.LC_ALL, "de_DE.UTF-8")
                try:
                    exec(code, globals())
                    de = "accepted under de_DE.UTF-8"
                except Exception as e2:
                    de = str(e2)
            finally:
                locale.setlocale(locale.LC_ALL, old)
        return {"py": "refused", "type": type(e).__name__, "msg": msg[:300], "named": want_name in msg,
                "german_same": de is None or de == msg, "de": (de or "")[:300]}
    except Exception as e:
        return {"py": "error", "type": type(e).__name__, "msg": str(e)[:300]}
    return {"py": "accepted"}

def run_special(code):
    try:
        exec(code, globals())
    except Wrong as e:
        return {"py": "wrong", "msg": str(e)[:400]}
    except Exception as e:
        return {"py": "error", "type": type(e).__name__, "msg": str(e)[:300]}
    return {"py": "ok"}
'''


def worker():
    import resource
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
    g = {}
    exec(WORKER_PRELUDE, g)
    print("ready", flush=True)
    for line in sys.stdin:
        job = json.loads(line)
        if job["kind"] == "kw":
            r = g["run_keyword"](job["code"], job["name"])
        else:
            r = g["run_special"](job["code"])
        print(json.dumps(r), flush=True)


def setup(build, exe, src, tmp):
    """The files every case reads: the CLI's inputs and the module's."""
    sys.path.insert(0, os.path.join(build, "python"))
    import numpy as np
    import zwidth as zw
    import warnings
    warnings.simplefilter("ignore")
    out = os.path.join(tmp, "out")
    os.makedirs(out)
    m = zw.Model.table1()
    d = {"out": out, "model": os.path.join(tmp, "table1.json"), "log_h5": os.path.join(tmp, "log.h5"),
         "log_csv": os.path.join(tmp, "log.csv"), "frf_csv": os.path.join(tmp, "frf.csv"),
         "scene": os.path.join(tmp, "scene.json"), "model_fit": os.path.join(tmp, "fit.json")}
    m.save(d["model"])
    log = zw.simulate(m, seconds=20.0, noise_std_rad=1e-5)
    log.save(d["log_h5"]); log.save(d["log_csv"])
    frf = zw.estimate(log)
    frf.save(d["frf_csv"])
    zw.fit(frf, modes=2, max_starts=2).model.save(d["model_fit"])
    json.dump({"objects": [{"name": "wall", "K": 1.0, "B": 0.001}]}, open(d["scene"], "w"))
    return d


def materialise(argv, d, tmp, cid):
    """An argv whose '@kind=VALUE' items become files holding that value."""
    out = []
    for a in argv:
        if not a.startswith("@"):
            out.append(a)
            continue
        kind, text = a[1:].split("=", 1)
        p = os.path.join(tmp, "in_" + _safe(cid) + (".csv" if kind.startswith("frf") else ".json"))
        num = {"nan": "NaN", "inf": "Infinity", "-inf": "-Infinity"}.get(text, text)
        if kind.startswith("scene_"):
            obj = {"name": "o", "K": 1.0, "B": 0.01}
            obj[kind[-1]] = "@@"
            open(p, "w").write(json.dumps({"objects": [obj]}).replace('"@@"', num))
        elif kind.startswith("model_"):
            j = {"m": 0.001168, "b": 0.00584, "modes": [{"omega": 479.166, "c": 83, "v": 417.612, "d": 80}],
                 "delay_samples": 0}
            field = kind[len("model_"):]
            if field.startswith("mode"):
                j["modes"][0]["wcvd"[int(field[4:])].replace("w", "omega")] = "@@"
            else:
                j[field] = "@@"
            open(p, "w").write(json.dumps(j).replace('"@@"', num))
        elif kind == "frf_rate" or kind == "frf_navg":
            lines = open(d["frf_csv"]).read().strip("\n").split("\n")
            col = lines[0].split(",").index("sample_rate_hz" if kind == "frf_rate" else "num_averages")
            rows = [lines[0]]
            for l in lines[1:]:
                cells = l.split(",")
                cells[col] = text
                rows.append(",".join(cells))
            open(p, "w").write("\n".join(rows) + "\n")
        else:
            raise AssertionError(kind)
        out.append(p)
    return out


class Pool:
    """One worker at a time; a crash or a hang ends it and the next case starts a new one."""

    def __init__(self, build, exe, src, files):
        self.env = dict(os.environ, PYTHONPATH=os.path.join(build, "python"), ZWIDTH_EXE=exe,
                        PROBE_FILES=json.dumps(files), PYTHONDONTWRITEBYTECODE="1")
        self.p = None

    def start(self):
        self.p = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--worker"], stdin=subprocess.PIPE,
                                  stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=self.env)
        assert self.p.stdout.readline().strip() == "ready"

    def run(self, job, timeout=30):
        import selectors
        if self.p is None:
            self.start()
        self.p.stdin.write(json.dumps(job) + "\n")
        self.p.stdin.flush()
        sel = selectors.DefaultSelector()
        sel.register(self.p.stdout, selectors.EVENT_READ)
        if not sel.select(timeout):
            self.p.kill(); self.p.wait(); self.p = None
            return {"py": "hung"}
        line = self.p.stdout.readline()
        if not line:
            rc = self.p.wait(); self.p = None
            return {"py": "crashed", "msg": f"worker died: exit {rc}"}
        return json.loads(line)


def judge_keyword(r, expectation, cli_rc):
    """'refused'/'accepted'/'crashed'/'hung' and, when mishandled, why."""
    py = r["py"]
    if py in ("crashed", "hung"):
        return py, r.get("msg", "")
    if py == "error":
        return "wrong", f"{r['type']} (not ValueError/TypeError/OSError): {r['msg']}"
    if py == "refused" and not r["german_same"]:
        return "wrong", f"message differs under de_DE: {r['msg'][:120]!r} vs {r['de'][:120]!r}"
    if expectation == "type":
        if py == "accepted":
            return "wrong", "a value of the wrong type accepted"
        return "refused", None
    if expectation == "accept":
        return ("accepted", None) if py == "accepted" else ("wrong", f"refused: {r['msg']}")
    if cli_rc is None:  # no CLI form: non-finite values must be refused, others not crash
        return ("refused", None) if py == "refused" else ("accepted", None)
    if cli_rc == 2 and py == "accepted":
        return "wrong", "accepted; the CLI refuses it (exit 2)"
    if cli_rc in (0, 3, 4) and py == "refused":
        return "wrong", f"refused; the CLI accepts it (exit {cli_rc}): {r['msg'][:200]}"
    if py == "refused" and not r["named"]:
        return "wrong", f"refused without naming the keyword: {r['msg'][:200]}"
    return py, None


def main():
    args = sys.argv[1:]
    if args and args[0] == "--worker":
        return worker()
    verbose = "-v" in args
    sel = args[args.index("-k") + 1] if "-k" in args else None
    build, exe, src = [os.path.abspath(a) for a in args[:3]]
    tmp = tempfile.mkdtemp(prefix="zwidth_probe_")
    d = setup(build, exe, src, tmp)
    pool = Pool(build, exe, src, d)
    counts = {}
    bad = []
    jobs = []
    for cid, code, argv, expectation in keyword_cases(d):
        jobs.append(("kw", cid, code, argv, expectation))
    for cid, code in special_cases() + save_cases() + other_cases():
        jobs.append(("sp", cid, code, None, None))
    for kind, cid, code, argv, expectation in jobs:
        if sel and sel not in cid:
            continue
        if kind == "kw":
            name = cid.split("=")[0].split(".")[-1]
            if "modes[" in cid:
                name = "modes"
            r = pool.run({"kind": "kw", "code": code, "name": name})
            cli_rc = None
            if argv is not None and expectation == "cli":
                try:
                    cli_rc = subprocess.run([exe, *materialise(argv, d, tmp, cid)], capture_output=True,
                                            timeout=60).returncode
                except subprocess.TimeoutExpired:
                    cli_rc = "hung"
                if cli_rc not in (0, 1, 2, 3, 4):
                    print(f"note: the CLI for {cid} gave {cli_rc}")
                    cli_rc = 2
            verdict, why = judge_keyword(r, expectation, cli_rc)
        else:
            r = pool.run({"kind": "sp", "code": code}, timeout=90)
            verdict = {"ok": "refused/accepted as it should", "wrong": "wrong", "error": "wrong"}.get(r["py"], r["py"])
            why = r.get("msg", "") if verdict != "refused/accepted as it should" else None
            if r["py"] == "error":
                why = f"{r['type']}: {r['msg']}"
            if verdict not in ("wrong", "crashed", "hung"):
                verdict = "ok"
        counts[verdict] = counts.get(verdict, 0) + 1
        if verdict in ("wrong", "crashed", "hung"):
            bad.append((cid, verdict, why))
            print(f"MISHANDLED {cid}: {verdict}: {why}", flush=True)
        elif verbose:
            print(f"{verdict:9} {cid}", flush=True)
    total = sum(counts.values())
    mishandled = sum(counts.get(k, 0) for k in ("wrong", "crashed", "hung"))
    print(f"\n{total} cases: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) +
          f"; mishandled {mishandled}")
    if pool.p:
        pool.p.stdin.close(); pool.p.wait()
    import shutil
    shutil.rmtree(tmp, ignore_errors=True)
    return 1 if mishandled else 0


if __name__ == "__main__":
    sys.exit(main())
