"""zwidth as a Python user expects it (issue 27 items 1-6, issue 30's Python cases): a poor
fit warns, reprs give the verdict in %g, inputs are checked with messages naming the
keyword, every result pickles, compares and deep-copies (across processes too), stubs and
signatures match the module, long calls stop on Ctrl-C, the thread count is bounded, files
written are ones the CLI reads (under a German locale too), and read_log/fit/plot/FRD do
what the CLI's flags do. Checked against the CLI's output where it computes the same.
"""
import ast, copy, importlib.metadata, inspect, json, multiprocessing, os, pickle, re, signal
import subprocess, sys, textwrap, time, warnings

import numpy as np
import pytest

import zwidth


@pytest.fixture(scope="module")
def short_log():
    """4 s at 1 kHz: with window_length 2048 only 2 Welch segments -> a poor fit (few_averages)."""
    return zwidth.simulate(zwidth.Model.table1(), seconds=4, seed=3)


@pytest.fixture(scope="module")
def good(log_h5):
    frf = zwidth.estimate(zwidth.read_log(log_h5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", zwidth.FitQualityWarning)
        res = zwidth.fit(frf, modes=2)
    return frf, res


def _module_env():
    return dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(zwidth.__file__)),
                PYTHONDONTWRITEBYTECODE="1")


# ---------------------------------------------------------------- 1. results that speak

def test_poor_fit_warns_with_its_reasons_and_the_keywords(short_log):
    with pytest.warns(zwidth.FitQualityWarning) as w:
        res = zwidth.fit(short_log, window_length=2048, allow_short=True)
    assert issubclass(zwidth.FitQualityWarning, UserWarning)
    poor = [x.message for x in w if issubclass(x.category, zwidth.FitQualityWarning)]
    assert len(poor) == 1  # beside it: the fit's own warnings (few averages: its chi2 limit scaled)
    assert res.quality == "poor" and [r["code"] for r in poor[0].reasons] == \
        [r["code"] for r in res.quality_reasons]
    text = str(poor[0])
    assert "few_averages" in text and "window_length" in text and "::" not in text
    assert "--" not in text  # the keyword, not the CLI's flag
    assert repr(res).startswith("<zwidth.FitResult poor (") and "few_averages" in repr(res)


def test_good_fit_does_not_warn_and_says_good(good):
    _, res = good
    assert res.quality == "good" and repr(res).startswith("<zwidth.FitResult good: converged")


def test_reprs_use_g_and_say_the_verdict(good, short_log):
    m = zwidth.Model(1e-7, 2.5e-9, [(300.0, 1.0, 200.0, 2.0)])
    assert "m=1e-07" in repr(m) and "b=2.5e-09" in repr(m) and "(300, 1, 200, 2)" in repr(m)
    frf, res = good
    assert "fit=good" in repr(res.model) and "fit=good" in repr(zwidth.ZWidth(res.model))
    assert repr(frf).startswith(f"<zwidth.FrequencyResponse {len(frf)} bins")
    assert "5000" not in repr(short_log) and "4000 samples at 1000 Hz (4 s)" in repr(short_log)
    r = zwidth.relay(zwidth.Model.table1(), 2, 0.0)
    assert repr(r).startswith(f"<zwidth.RelayResult {r.status}: K_cr=")
    assert "B=0.01 K_cr=" in repr(zwidth.ZWidth(zwidth.Model.table1()).point(0.01))


def test_used_is_the_mask_the_cli_saves(good, cli, log_h5, tmp_path):
    """FitResult.used equals the used_by_fit column of `zwidth run`'s frf.csv."""
    frf, res = good
    cli("run", log_h5, "-o", tmp_path / "r", "--no-figures", "--modes", "2", "--delays", "2")
    cols = np.genfromtxt(tmp_path / "r" / "frf.csv", delimiter=",", names=True)
    assert res.used.dtype == bool and len(res.used) == len(frf)
    assert np.array_equal(res.used, cols["used_by_fit"] == 1)
    assert 0 < res.used.sum() < len(frf)  # the shipped log leaves the unexcited top out


# ---------------------------------------------------------------- 2. inputs checked

@pytest.mark.parametrize("call, kind, words", [
    (lambda u, y: zwidth.estimate(np.c_[u, u], np.c_[y, y], 1000.0), zwidth.InputError, "u has shape (4000, 2)"),
    (lambda u, y: zwidth.Log(np.c_[u, u], y, 1000.0), zwidth.InputError, "u has shape"),
    (lambda u, y: zwidth.estimate(u, np.where(np.arange(len(y)) == 7, np.nan, y), 1000.0), zwidth.InputError,
     "y[7] = nan"),
    (lambda u, y: zwidth.Log(u, y[:-1], 1000.0), zwidth.InputError, "same length"),
    (lambda u, y: zwidth.Log(u.astype(str), y, 1000.0), TypeError, "u must be an array of real numbers"),
    (lambda u, y: zwidth.Log(u, y, float("nan")), zwidth.InputError, "sample_rate_hz = nan"),
    (lambda u, y: zwidth.Log(u, y, "1000"), TypeError, "sample_rate_hz must be a number, not str"),
    (lambda u, y: zwidth.fit(zwidth.estimate(u, y, 1000.0, window_length=512), delay_samples=2.5), TypeError,
     "delay_samples must be an integer, not float"),
    (lambda u, y: zwidth.ZWidth(zwidth.Model.table1(), delay_samples=2.0), TypeError, "delay_samples must be an integer"),
    (lambda u, y: zwidth.ZWidth(zwidth.Model.table1()).is_stable(float("nan"), 0.0), zwidth.InputError, "K = nan"),
    (lambda u, y: zwidth.ZWidth(zwidth.Model.table1()).critical([0.0, -1.0]), zwidth.InputError, "B[1] = -1"),
    (lambda u, y: zwidth.Model(1e-3, 1e-3, [(1.0, 2.0, 3.0)]), zwidth.InputError, "modes[0]: expected a tuple"),
    (lambda u, y: zwidth.Model(True, 1e-3), TypeError, "m must be a number, not bool"),
])
def test_bad_inputs_name_the_argument(short_log, call, kind, words):
    with pytest.raises(kind) as e:
        call(short_log.u, short_log.y)
    assert words in str(e.value)
    assert "Unable to cast" not in str(e.value) and "::" not in str(e.value)


def test_is_stable_nan_was_true():
    """is_stable(nan, 0) answered True; now refused like the CLI's scene check refuses NaN."""
    z = zwidth.ZWidth(zwidth.Model.table1())
    for K, B in ((np.nan, 0.0), (1.0, np.inf), (-1.0, 0.0)):
        with pytest.raises(zwidth.InputError):
            z.is_stable(K, B)


def test_response_above_nyquist_is_refused():
    f = np.linspace(1.0, 2000.0, 64)
    with pytest.raises(zwidth.InputError, match="above the Nyquist frequency of 500 Hz"):
        zwidth.FrequencyResponse(f, 1.0 / (1j * f) ** 2, 1000.0, num_averages=10)


def test_model_setters_validate_and_modes_drop_the_covariance(good, cli, tmp_path):
    _, res = good
    m = copy.deepcopy(res.model)
    with pytest.raises(zwidth.InputError, match="m = -1"):
        m.m = -1.0
    assert m.m == res.model.m  # unchanged
    assert m.covariance is not None
    m.modes = m.modes[:1]
    assert m.covariance is None and m.std is None
    m.save(tmp_path / "one.json")
    back = zwidth.Model.load(str(tmp_path / "one.json"))
    assert back == m
    cli("boundary", tmp_path / "one.json", "--delays", "2", "-o", tmp_path / "b.csv")  # the CLI reads it


def test_saved_files_are_ones_the_cli_reads(short_log, cli, tmp_path):
    short_log.save(str(tmp_path / "l.csv"))
    cli("estimate", tmp_path / "l.csv", "-o", tmp_path / "f.csv", "--window-length", "512")
    frf = zwidth.estimate(short_log, window_length=512)
    frf.save(str(tmp_path / "g.csv"))
    cli("fit", tmp_path / "g.csv", "-o", tmp_path / "m.json")  # the Nyquist bin included
    made = zwidth.FrequencyResponse(frf.f_hz, frf.H, 1000.0, num_averages=8)
    made.save(str(tmp_path / "h.csv"))
    assert zwidth.FrequencyResponse.load(str(tmp_path / "h.csv")) is not None


def test_option_table_keywords_are_the_modules(src):
    """Every keyword of io/option_names.cc is a parameter of a zwidth function or method."""
    body = open(os.path.join(src, "io", "option_names.cc")).read()
    rows = re.findall(r'\{"([A-Za-z0-9_]+::[a-z_0-9]+)",\s*"([^"]*)",\s*"([^"]*)"\}', body)
    assert len(rows) > 40
    names = set()
    for obj in [getattr(zwidth, n) for n in zwidth.__all__]:
        for f in ([obj] if callable(obj) and not isinstance(obj, type) else
                  [getattr(obj, a) for a in vars(obj) if callable(getattr(obj, a, None))] if isinstance(obj, type) else []):
            try:
                names.update(inspect.signature(f).parameters)
            except (TypeError, ValueError):
                pass
    for field, _, keyword in rows:
        if keyword:
            name = re.match(r"\w+", keyword).group(0)
            assert name in names, f"{field}: keyword {keyword!r} is not a parameter of the module"


# ---------------------------------------------------------------- 3. pickle, ==, deepcopy

@pytest.fixture(scope="module")
def every_type(good, short_log):
    frf, res = good
    z = zwidth.ZWidth(res.model, delay_samples=4, velocity_filter_hz=100.0, hand=(1e-4, 1e-3, 0.1))
    return [short_log, frf, res, res.model, z, z.point(0.01), zwidth.relay(zwidth.Model.table1(), 2, 0.0, seconds=5)]


def test_every_type_pickles_compares_and_deep_copies(every_type):
    for obj in every_type:
        for back in (pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj), copy.copy(obj)):
            assert type(back) is type(obj) and back == obj and not (back != obj), type(obj).__name__
            assert repr(back) == repr(obj)
    log, frf, res, model, z, point, relay = every_type
    assert pickle.loads(pickle.dumps(res)).brief_report() == res.brief_report()
    assert np.array_equal(pickle.loads(pickle.dumps(res)).used, res.used)
    assert pickle.loads(pickle.dumps(z)).summary() == z.summary()
    other = zwidth.Model.table1()
    other.b *= 2
    assert other != zwidth.Model.table1() and log != zwidth.simulate(zwidth.Model.table1(), seconds=4, seed=4)


def test_every_type_crosses_a_two_process_pool(every_type):
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        back = pool.map_async(copy.copy, every_type).get(timeout=120)
    assert back == every_type


# ---------------------------------------------------------------- 4. stubs, signatures, metadata

def test_every_function_and_method_has_a_signature_and_a_docstring():
    for name in zwidth.__all__:
        obj = getattr(zwidth, name)
        if isinstance(obj, type) and not issubclass(obj, Exception):
            for a, member in vars(obj).items():
                if a.startswith("__") and a != "__init__" or not callable(member) and not isinstance(member, staticmethod):
                    continue
                f = getattr(obj, a)
                inspect.signature(f)  # raises when it cannot be read
                assert (f.__doc__ or "").strip() or a in ("__init__",), f"{name}.{a} has no docstring"
        elif callable(obj) and not isinstance(obj, type):
            inspect.signature(obj)
            assert (obj.__doc__ or "").strip(), name
    assert list(inspect.signature(zwidth.fit).parameters)[:3] == ["data", "modes", "max_modes"]
    assert list(inspect.signature(zwidth.Model.save).parameters) == ["self", "path"]
    assert list(inspect.signature(zwidth.Model).parameters)[:2] == ["m", "b"]
    assert inspect.signature(zwidth.estimate).parameters["window_length"].default == 0  # the CLI's rule of the rate and length


def test_stubs_match_the_module():
    stub = os.path.join(os.path.dirname(zwidth.__file__), "__init__.pyi")
    tree = ast.parse(open(stub).read())
    top = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    for name in zwidth.__all__:
        if name == "__version__":
            continue
        assert name in top, f"{name} missing from the stubs"
        obj = getattr(zwidth, name)
        if isinstance(top[name], ast.FunctionDef):
            stub_args = [a.arg for a in top[name].args.args + top[name].args.kwonlyargs]
            assert stub_args == [p.name for p in inspect.signature(obj).parameters.values()
                                 if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)], name
        elif not issubclass(obj, Exception):
            methods = {n.name: n for n in top[name].body if isinstance(n, ast.FunctionDef)}
            for a, member in vars(obj).items():
                if isinstance(member, property) or (not a.startswith("__") and callable(member)):
                    assert a in methods, f"{name}.{a} missing from the stubs"
            for a, node in methods.items():
                if a == "__eq__" or isinstance(vars(obj).get(a), property):
                    continue
                sig = inspect.signature(vars(obj)[a] if a != "__init__" else obj.__init__)
                want = [p.name for p in sig.parameters.values() if p.kind not in (p.VAR_KEYWORD, p.VAR_POSITIONAL)]
                got = [x.arg for x in node.args.args + node.args.kwonlyargs]
                if isinstance(vars(obj)[a], staticmethod):
                    assert got == want, f"{name}.{a}"
                else:
                    assert got == (want if want[:1] == ["self"] else ["self"] + want), f"{name}.{a}"


def test_version_metadata(cli):
    assert importlib.metadata.version("zwidth") == zwidth.__version__
    assert zwidth.__version__ in cli("--version").stdout


# ---------------------------------------------------------------- 5. interruptible and bounded

def test_monte_carlo_stops_within_a_second_of_sigint(good, tmp_path):
    _, res = good
    res.model.save(str(tmp_path / "m.json"))
    script = textwrap.dedent(f"""
        import os, signal, threading, time, zwidth
        z = zwidth.ZWidth(zwidth.Model.load({str(tmp_path / "m.json")!r}), delay_samples=2)
        sent = []
        def kill():
            sent.append(time.monotonic())
            os.kill(os.getpid(), signal.SIGINT)
        threading.Timer(1.0, kill).start()
        try:
            z.summary(monte_carlo=100000)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted after", time.monotonic() - sent[0])
        print("alive", zwidth.ZWidth(zwidth.Model.table1()).summary()["K_cr_at_zero_B"] > 0)
    """)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=_module_env(), timeout=120)
    assert p.returncode == 0, p.stderr
    m = re.search(r"interrupted after ([0-9.e-]+)", p.stdout)
    assert m, p.stdout
    assert float(m.group(1)) < 1.0 and "alive True" in p.stdout


@pytest.mark.parametrize("threads", ["1", "2"])
def test_zwidth_num_threads_bounds_the_threads(log_h5, threads):
    """With ZWIDTH_NUM_THREADS=n the fit's ParallelFor runs on n threads (the caller's among
    them): counted in /proc/self/task while a fit of modes='auto' runs."""
    script = textwrap.dedent(f"""
        import os, threading, zwidth
        frf = zwidth.estimate(zwidth.read_log({log_h5!r}))
        zwidth.fit(frf, modes=1)  # warm-up: libraries' own threads start here
        seen, stop = [], threading.Event()
        def watch():
            while not stop.is_set():
                seen.append(len(os.listdir("/proc/self/task")))
        base = len(os.listdir("/proc/self/task")) + 1  # + the watcher
        t = threading.Thread(target=watch); t.start()
        zwidth.fit(frf, modes="auto")
        stop.set(); t.join()
        print(zwidth.num_threads(), max(seen) - base + 1)
    """)
    env = dict(_module_env(), ZWIDTH_NUM_THREADS=threads)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0, p.stderr
    n, used = map(int, p.stdout.split())
    assert n == int(threads) and used == int(threads)


def test_bad_thread_settings_are_refused():
    with pytest.raises(zwidth.InputError, match="num_threads = -1"):
        zwidth.set_num_threads(-1)
    zwidth.set_num_threads(1)
    assert zwidth.num_threads() == 1
    zwidth.set_num_threads(None)
    p = subprocess.run([sys.executable, "-c", "import zwidth; zwidth.ZWidth(zwidth.Model.table1()); "
                        "import numpy; zwidth.fit(zwidth.simulate(zwidth.Model.table1(), seconds=10), modes=1)"],
                       capture_output=True, text=True, env=dict(_module_env(), ZWIDTH_NUM_THREADS="two"))
    assert p.returncode != 0 and "ZWIDTH_NUM_THREADS = 'two'" in p.stderr


# ---------------------------------------------------------------- locale

def test_files_are_written_with_dots_under_a_german_locale(tmp_path, short_log, cli):
    loc = tmp_path / "locale"
    loc.mkdir()
    p = subprocess.run(["localedef", "-i", "de_DE", "-f", "UTF-8", str(loc / "de_DE.UTF-8")], capture_output=True)
    if p.returncode not in (0, 1) or not (loc / "de_DE.UTF-8").exists():
        pytest.skip("cannot build a de_DE locale here (localedef)")
    short_log.save(str(tmp_path / "ref.csv"))
    script = textwrap.dedent(f"""
        import locale, zwidth
        locale.setlocale(locale.LC_ALL, "de_DE.UTF-8")
        assert locale.localeconv()["decimal_point"] == ","
        log = zwidth.read_log({str(tmp_path / "ref.csv")!r})
        log.save({str(tmp_path / "de.csv")!r})
        zwidth.Model.table1().export({str(tmp_path / "m.m")!r}, "matlab")
        zwidth.estimate(log, window_length=512).save({str(tmp_path / "f.csv")!r})
    """)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                       env=dict(_module_env(), LOCPATH=str(loc)))
    assert p.returncode == 0, p.stderr
    assert open(tmp_path / "de.csv").read() == open(tmp_path / "ref.csv").read()
    assert "m = 0.001168" in open(tmp_path / "m.m").read()
    cli("fit", tmp_path / "f.csv", "-o", tmp_path / "m.json")


# ---------------------------------------------------------------- 6. the whole job

def test_read_log_scales_units_and_delimiter_equal_the_cli(tmp_path, short_log, cli):
    t = np.arange(short_log.num_samples)  # milliseconds
    with open(tmp_path / "l.txt", "w") as f:
        f.write("time;tau_counts;theta_counts\n")
        for k, u, y in zip(t, short_log.u, short_log.y):
            f.write(f"{k};{u * 100:.17g};{y * 1e4:.17g}\n")
    kw = dict(time_column="time", input_column="tau_counts", output_column="theta_counts", time_unit="ms",
              input_scale=0.01, output_scale=1e-4, delimiter=";")
    log = zwidth.read_log(str(tmp_path / "l.txt"), **kw)
    assert log.sample_rate_hz == pytest.approx(1000.0) and np.allclose(log.u, short_log.u, rtol=1e-12)
    cli("estimate", tmp_path / "l.txt", "-o", tmp_path / "f.csv", "--window-length", "512", "--time-column", "time",
        "--input-column", "tau_counts", "--output-column", "theta_counts", "--time-unit", "ms",
        "--input-scale", "0.01", "--output-scale", "1e-4", "--delimiter", ";")
    mine = zwidth.estimate(str(tmp_path / "l.txt"), window_length=512, **kw)
    theirs = zwidth.FrequencyResponse.load(str(tmp_path / "f.csv"))
    assert np.array_equal(mine.H, theirs.H)
    with pytest.raises(zwidth.InputError) as e:
        zwidth.read_log(str(tmp_path / "l.txt"), **dict(kw, time_unit="min"))
    assert "time_unit" in str(e.value) and "::" not in str(e.value) and "--" not in str(e.value)


def test_fit_of_a_log_and_of_a_path_equal_the_two_steps(log_h5):
    log = zwidth.read_log(log_h5)
    # A log or a path also goes to the friction fit (as `zwidth fit`), whose record the model's "fit"
    # holds ("friction": not run with friction="none", none detected here with "auto"), and gives the
    # encoder step read from its samples (the shipped log's 2 pi / 40960 rad); a response alone
    # cannot: everything else is the two steps' to the last bit.
    two = zwidth.fit(zwidth.estimate(log, window_length=2048), modes=2, friction="none")
    assert two.model.encoder_step is None

    def without_friction_record(r):
        j = json.loads(r.model.to_json())
        j["fit"].pop("friction", None)
        j.pop("encoder_step", None)
        return j, np.asarray(r.covariance).tobytes(), np.asarray(r.used).tobytes()

    for friction in ("none", "auto"):
        for data in (log, log_h5):
            got = zwidth.fit(data, modes=2, window_length=2048, friction=friction)
            assert without_friction_record(got) == without_friction_record(two), (friction, data)
            assert abs(got.model.encoder_step / (2 * np.pi / 40960) - 1) < 1e-9, got.model.encoder_step
    with pytest.raises(TypeError, match="window_length"):
        zwidth.fit(zwidth.estimate(log), window_length=2048)
    with pytest.raises(TypeError, match="not ndarray"):
        zwidth.fit(log.u)


def test_plot_helpers_draw_the_used_bins(good):
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    import zwidth.plot as zp
    frf, res = good
    mag, ph = zp.bode(frf, res)
    assert np.array_equal(mag.get_lines()[0].get_xdata(), frf.f_hz[res.used])
    assert np.allclose(mag.get_lines()[1].get_ydata(), np.abs(res.model.response(frf.f_hz[res.used], 1e-3)))
    ax = zp.coherence(frf, res)
    assert len(ax.get_lines()) == 2
    ax = zp.region(res.model, delays=(2, 4))
    K, _ = zwidth.ZWidth(res.model, delay_samples=2).critical(ax.get_lines()[0].get_xdata())
    assert np.array_equal(ax.get_lines()[0].get_ydata(), K)


def test_frd_in_and_out(good):
    control = pytest.importorskip("control")
    frf, _ = good
    frd = zwidth.to_frd(frf)
    back = zwidth.from_frd(frd, num_averages=frf.num_averages)
    assert np.allclose(back.f_hz, frf.f_hz) and np.array_equal(back.H, frf.H)
    assert isinstance(frd, control.FrequencyResponseData)


def test_frd_without_python_control_says_so():
    try:
        import control  # noqa: F401
        pytest.skip("python-control is installed")
    except ImportError:
        pass
    with pytest.raises(ImportError, match="python-control is not installed"):
        zwidth.to_frd(zwidth.FrequencyResponse([1.0, 2.0], [1.0, 0.5], 100.0))
