"""Issue 30, must-have 4, the Python side: what tests/python/hostile_py_probe.py found mishandled,
one test per class. Each value is judged against an independent reader: the CLI given the same
value in a file (its exit status), or the module's own reader of what it wrote."""
import json
import locale
import os
import pathlib
import pickle
import re

import numpy as np
import pytest

import zwidth


@pytest.fixture(scope="module")
def log():
    return zwidth.simulate(zwidth.Model.table1(), seconds=8.0, noise_std_rad=1e-5)


@pytest.fixture(scope="module")
def frf(log):
    return zwidth.estimate(log)


# --- Paths: a NUL byte ends a C file name, so it named another file --------------------------

WRITERS = {
    "Log.save csv": lambda log, frf, p: log.save(p + ".csv"),
    "Log.save h5": lambda log, frf, p: log.save(p + ".h5"),
    "Model.save": lambda log, frf, p: zwidth.Model.table1().save(p + ".json"),
    "Model.export mat": lambda log, frf, p: zwidth.Model.table1().export(p + ".mat", "mat"),
    "Model.export matlab": lambda log, frf, p: zwidth.Model.table1().export(p + ".m", "matlab"),
    "FrequencyResponse.save": lambda log, frf, p: frf.save(p + ".csv"),
}


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_a_path_with_a_nul_byte_is_refused_and_nothing_is_written(writer, log, frf, tmp_path):
    with pytest.raises(ValueError, match="path: the path contains a NUL byte"):
        WRITERS[writer](log, frf, str(tmp_path / "out") + "\0tail")
    assert os.listdir(tmp_path) == []  # not 'out' (where the C library stopped), nor a temporary


@pytest.mark.parametrize("reader", ["read_log", "estimate", "estimate_logs", "validate", "Model.load",
                                    "FrequencyResponse.load", "check"])
def test_a_path_with_a_nul_byte_is_refused_by_every_reader(reader, log_h5, table1_json, tmp_path):
    m = zwidth.Model.table1()
    call = {"read_log": lambda p: zwidth.read_log(p), "estimate": lambda p: zwidth.estimate(p),
            "estimate_logs": lambda p: zwidth.estimate_logs([p]), "validate": lambda p: zwidth.validate(m, p),
            "Model.load": lambda p: zwidth.Model.load(p), "FrequencyResponse.load": zwidth.FrequencyResponse.load,
            "check": lambda p: zwidth.check(p, m, 2)}[reader]
    # The part before the NUL is a real file of the right kind: read, it would have been accepted.
    real = {"Model.load": table1_json, "check": table1_json}.get(reader, log_h5)
    with pytest.raises(ValueError, match="NUL byte"):
        call(real + "\0.bak")


def test_paths_may_be_path_objects_and_bytes(log, frf, tmp_path):
    m = zwidth.Model.table1()
    m.save(tmp_path / "m.json")
    assert zwidth.Model.load(tmp_path / "m.json") == m
    assert zwidth.Model.load(os.fsencode(tmp_path / "m.json")) == m
    log.save(tmp_path / "l.h5")
    assert np.array_equal(zwidth.read_log(tmp_path / "l.h5").u, log.u)
    frf.save(tmp_path / "f.csv")
    assert np.array_equal(zwidth.FrequencyResponse.load(tmp_path / "f.csv").H, frf.H)
    with pytest.raises(TypeError, match="path must be a path"):
        m.save(42)


# --- Messages under a German locale are the C locale's (printf and std::to_string) -------------

def _messages(log, frf):
    bad = [lambda: zwidth.estimate(log, overlap=1.5), lambda: zwidth.estimate(log.u, log.y, 5.5),
           lambda: zwidth.estimate(log, fmin=1e4), lambda: zwidth.ZWidth(zwidth.Model.table1(), period_s=0.5),
           lambda: zwidth.simulate(zwidth.Model.table1(), bandwidth_hz=600.5),
           lambda: zwidth.FrequencyResponse(frf.f_hz * 2.5, frf.H, 1000.0),
           lambda: zwidth.Model(0.001, 0.005, sample_period_s=0.5)]
    out = []
    for f in bad:
        with pytest.raises(ValueError) as e:
            f()
        out.append(str(e.value))
    return out


def test_messages_with_numbers_are_the_same_under_a_german_locale(log, frf, german):
    de = _messages(log, frf)
    assert any(re.search(r"\d\.\d", m) for m in de)  # numbers with decimals are in them, with '.'
    assert not any(re.search(r"\d,\d", m) for m in de)
    locale.setlocale(locale.LC_ALL, "C")
    assert de == _messages(log, frf)


def test_the_locale_guard_leaves_pythons_locale_alone(log, german):
    zwidth.estimate(log)
    assert locale.localeconv()["decimal_point"] == ","  # Python's own formatting keeps its locale
    assert locale.format_string("%.1f", 0.5) == "0,5"


# --- A Model holds only what zwidth's reader takes (the same values in a model file) ------------

MODEL_VALUES = [("m", 1e300), ("m", 1e-300), ("b", 1e300), ("sample_period_s", 1000.0),
                ("sample_period_s", 1e-9), ("sample_period_s", 1e-3), ("delay_samples", 10**6),
                ("delay_samples", 1000), ("m", 2e-3)]


def _cli_takes_model(cli, tmp_path, field, value):
    j = json.loads(zwidth.Model.table1().to_json())
    j[field] = value
    p = tmp_path / "m.json"
    p.write_text(json.dumps(j))
    return cli("export", p, "--format", "json", "-o", tmp_path / "e.json", check=False).returncode == 0


@pytest.mark.parametrize("field,value", MODEL_VALUES)
def test_model_values_are_refused_exactly_where_the_cli_refuses_them(field, value, cli, tmp_path):
    takes = _cli_takes_model(cli, tmp_path, field, value)
    args = dict(m=1.168e-3, b=0.00584, modes=zwidth.Model.table1().modes)
    args[field] = value
    if takes:
        zwidth.Model(**args)
    else:
        with pytest.raises(ValueError, match=field):
            zwidth.Model(**args)
    m = zwidth.Model.table1()
    if takes:
        setattr(m, field, value)
        m.save(tmp_path / "saved.json")
        assert cli("export", tmp_path / "saved.json", "--format", "json", "-o", tmp_path / "e2.json",
                   check=False).returncode == 0
    else:
        with pytest.raises(ValueError, match=field):
            setattr(m, field, value)
        assert m == zwidth.Model.table1()  # unchanged by the refused set


def test_mode_values_are_refused_as_the_reader_refuses_them(cli, tmp_path):
    for k, key in enumerate(["omega", "c", "v", "d"]):
        mode = [479.166, 83.0, 417.612, 80.0]
        mode[k] = 1e300
        j = json.loads(zwidth.Model.table1().to_json())
        j["modes"][0][key] = 1e300
        (tmp_path / "m.json").write_text(json.dumps(j))
        assert cli("export", tmp_path / "m.json", "--format", "json", "-o", tmp_path / "e.json",
                   check=False).returncode == 2
        with pytest.raises(ValueError, match=rf"modes\[0\]\.{key}"):
            zwidth.Model(0.001168, 0.00584, modes=[tuple(mode)])


def test_covariance_must_be_the_square_matrix_the_json_holds(frf):
    res = zwidth.fit(frf, modes=2, max_starts=2)
    m = res.model
    n = len(m.covariance_names)
    cov = m.covariance
    with pytest.raises(ValueError, match=r"covariance has shape \(%d,\)" % (n * n)):
        m.covariance = cov.ravel()
    with pytest.raises(ValueError, match="covariance"):
        m.covariance = np.eye(3)
    m2 = zwidth.Model.from_json(m.to_json())
    m2.covariance = cov  # the same matrix: taken
    assert np.array_equal(m2.covariance, cov)


# --- A Log is what the readers take: save() never writes a log zwidth refuses ---------------------

@pytest.mark.parametrize("u,y,what", [([1.0], [2.0], "input"), (np.zeros(100), np.arange(100.0), "input"),
                                      (np.arange(100.0), np.ones(100), "output")])
def test_a_constant_log_is_refused_as_the_readers_refuse_it(u, y, what, tmp_path, cli):
    # The readers' verdict on the same samples, written by hand (not by the module).
    p = tmp_path / "hand.csv"
    p.write_text("t,torque,position\n" + "".join(f"{k / 1000!r},{a!r},{b!r}\n"
                                                for k, (a, b) in enumerate(zip(np.atleast_1d(u), np.atleast_1d(y)))))
    r = cli("estimate", p, "-o", tmp_path / "f.csv", check=False)
    assert r.returncode == 2 and "constant" in r.stderr
    with pytest.raises(ValueError, match=f"{what}.*constant"):
        zwidth.Log(u, y, 1000.0)


def test_a_pickled_log_is_checked_as_the_constructor_checks(log, tmp_path):
    for rate, u in [(5.0, log.u), (float("nan"), log.u), (1000.0, np.r_[np.nan, log.u[1:]])]:
        state = ("", rate, u.tobytes(), log.y.tobytes())
        restore, _ = log.__reduce_ex__(2)  # what pickle.loads calls
        with pytest.raises(ValueError):
            restore(zwidth.Log, state)
    assert pickle.loads(pickle.dumps(log)) == log  # a real one still round-trips


def test_simulate_refuses_what_zwidth_simulate_refuses(cli, table1_json, tmp_path):
    for kw, flag, value in [("bandwidth_hz", "--bandwidth-hz", 600.0), ("sample_rate_hz", "--rate", 2e6),
                            ("delay_samples", "--delay-samples", 5000)]:
        r = cli("simulate", "--model", table1_json, flag, value, "-o", tmp_path / "s.csv", check=False)
        assert r.returncode == 2 and flag in r.stderr
        with pytest.raises(ValueError, match=kw):
            zwidth.simulate(zwidth.Model.table1(), **{kw: value})
    assert not (tmp_path / "s.csv").exists()


def test_a_simulated_position_that_never_moves_is_refused_naming_the_encoder_step(cli, table1_json, tmp_path):
    r = cli("simulate", "--model", table1_json, "--encoder-step", "1e300", "-o", tmp_path / "s.csv", check=False)
    assert r.returncode == 2 and "--encoder-step" in r.stderr and not (tmp_path / "s.csv").exists()
    with pytest.raises(ValueError, match="encoder_step_rad = 1e[+]300"):
        zwidth.simulate(zwidth.Model.table1(), seconds=2.0, encoder_step_rad=1e300)
    assert len(set(zwidth.simulate(zwidth.Model.table1(), seconds=2.0).y)) > 100  # the default moves


def test_a_rate_given_to_the_reader_has_the_files_range(log_h5, cli, tmp_path):
    with pytest.raises(ValueError, match="rate = 1e[+]300"):
        zwidth.read_log(log_h5, rate=1e300)
    with pytest.raises(ValueError, match="sample_rate_hz"):
        zwidth.estimate(np.sin(np.arange(100.0)), np.cos(np.arange(100.0)), 1e300)
    r = cli("estimate", log_h5, "--rate", "1e300", "-o", tmp_path / "f.csv", check=False)
    assert r.returncode == 2 and "--rate = 1e+300" in r.stderr


def test_estimate_of_lists_equals_estimate_of_arrays(log):
    a = zwidth.estimate(list(log.u), list(log.y), 1000.0)
    b = zwidth.estimate(log.u, log.y, 1000.0)
    assert np.array_equal(a.H, b.H)


def test_an_estimate_whose_spectra_overflow_is_refused_as_the_cli_refuses_it(log, tmp_path, cli):
    big = zwidth.Log(log.u * 1e300, log.y, 1000.0)
    big.save(tmp_path / "big.h5")
    r = cli("estimate", tmp_path / "big.h5", "-o", tmp_path / "f.csv", check=False)
    assert r.returncode == 2 and "overflow" in r.stderr
    for data in (big, (big.u, big.y, 1000.0)):
        with pytest.raises(ValueError, match="overflow"):
            zwidth.estimate(*data) if isinstance(data, tuple) else zwidth.estimate(data)


# --- Pickled responses and Z-widths are checked as when made -------------------------------------

def test_a_pickled_response_of_inconsistent_arrays_is_refused(frf):
    s = list(frf.__getstate__())
    s[6] = s[6][:16]  # H of one bin
    with pytest.raises(ValueError, match="f_hz has"):
        frf.__reduce_ex__(2)[0](zwidth.FrequencyResponse, tuple(s))
    assert pickle.loads(pickle.dumps(frf)) == frf


def test_a_pickled_zwidth_is_checked_as_the_constructor_checks():
    z = zwidth.ZWidth(zwidth.Model.table1())
    s = list(z.__getstate__())
    for i, v, kw in [(2, -5, "delay_samples"), (2, 5000, "delay_samples"), (1, float("nan"), "period_s")]:
        t = list(s)
        t[i] = v
        with pytest.raises(ValueError, match=kw):
            z.__reduce_ex__(2)[0](zwidth.ZWidth, tuple(t))


def test_a_loop_delay_has_the_clis_bound(cli, table1_json, tmp_path):
    r = cli("boundary", table1_json, "--delays", "5000", "-o", tmp_path / "b.csv", check=False)
    assert r.returncode == 2
    m = zwidth.Model.table1()
    for f in (lambda: zwidth.ZWidth(m, delay_samples=5000), lambda: zwidth.check([("a", 1.0, 0.0)], m, 5000),
              lambda: zwidth.relay(m, 5000, 0.001, seconds=1.0)):
        with pytest.raises(ValueError, match="delay_samples = 5000"):
            f()


# --- Scenes given as lists are read by the reader's rules ----------------------------------------

SCENES = [[], [("a", 1.0, 0.0), ("a", 2.0, 0.0)], [("", 1.0, 0.0)], [{"name": "a", "K": 1.0}],
          [{"name": "a", "K": "1", "B": 0.0}], [("a", 1.0, 0.01)], [{"K": 1.0, "B": 0.0}]]


@pytest.mark.parametrize("objects", SCENES, ids=range(len(SCENES)))
def test_a_scene_list_is_refused_exactly_where_the_same_scene_file_is(objects, cli, table1_json, tmp_path):
    as_json = [o if isinstance(o, dict) else dict(zip(["name", "K", "B"], o)) for o in objects]
    p = tmp_path / "scene.json"
    p.write_text(json.dumps({"objects": as_json}))
    r = cli("check", p, "--model", table1_json, "--delay", "2", "--json", check=False)
    m = zwidth.Model.table1()
    if r.returncode == 2:
        with pytest.raises(ValueError):
            zwidth.check(objects, m, 2)
    else:
        assert zwidth.check(objects, m, 2)["objects"] == zwidth.check(str(p), m, 2)["objects"]


def test_broadcasting_k_and_b_of_other_shapes_names_them():
    with pytest.raises(ValueError, match=r"K has shape \(2,\) and B \(3,\)"):
        zwidth.ZWidth(zwidth.Model.table1()).is_stable([1.0, 2.0], [0.0, 0.1, 0.2])


def test_response_messages_name_f_hz(frf):
    with pytest.raises(ValueError, match="f_hz reach"):
        zwidth.FrequencyResponse(frf.f_hz * 2, frf.H, 1000.0)
    with pytest.raises(ValueError, match=r"f_hz = -"):
        zwidth.FrequencyResponse(frf.f_hz - 10, frf.H, 1000.0)
    with pytest.raises(ValueError, match="paths: no log given"):
        zwidth.estimate_logs([])


# --- A bool is not a number (pybind11 took True as 1 where Number() refuses it) ------------------

BOOL_CALLS = {
    "seconds": lambda m, log, frf: zwidth.simulate(m, seconds=True),
    "damping": lambda m, log, frf: zwidth.relay(m, 2, True, seconds=1.0),
    "theta_tolerance": lambda m, log, frf: zwidth.ZWidth(m, theta_tolerance=True),
    "min_grid_points": lambda m, log, frf: zwidth.ZWidth(m, min_grid_points=True),
    "marginal_sigmas": lambda m, log, frf: zwidth.check([("a", 1.0, 0.0)], m, 2, marginal_sigmas=True),
    "overlap": lambda m, log, frf: zwidth.estimate(log, overlap=False),
    "sample_rate_hz": lambda m, log, frf: zwidth.estimate(log.u, log.y, True),
    "max_starts": lambda m, log, frf: zwidth.fit(frf, modes=1, max_starts=np.True_),
    "max_lag": lambda m, log, frf: zwidth.validate(m, log, max_lag=True),
    "input_scale": lambda m, log, frf: zwidth.read_log("x.h5", input_scale=True),
    "period_s": lambda m, log, frf: m.response([1.0], period_s=True),
    "b_points": lambda m, log, frf: zwidth.run("x.h5", "out", b_points=True),
}


@pytest.mark.parametrize("kw", sorted(BOOL_CALLS))
def test_a_bool_for_a_number_is_a_type_error_naming_the_keyword(kw, log, frf):
    with pytest.raises(TypeError, match=f"{kw} must be a number, not bool"):
        BOOL_CALLS[kw](zwidth.Model.table1(), log, frf)


def test_numbers_of_every_numeric_type_are_still_taken(log):
    m = zwidth.Model.table1()
    a = zwidth.simulate(m, seconds=np.float32(2.0), sample_rate_hz=1000, seed=np.int64(3))
    b = zwidth.simulate(m, seconds=2.0, sample_rate_hz=1000.0, seed=3)
    assert a == b


# --- An object never constructed: Class.__new__(Class) read uninitialised memory -----------------

def test_new_without_init_is_refused_and_pickling_still_round_trips(log, frf):
    m = zwidth.Model.table1()
    z = zwidth.ZWidth(m)
    objects = [m, log, frf, zwidth.fit(frf, modes=1, max_starts=1, delay_samples=0), z, z.point(0.01),
               zwidth.relay(m, 2, 0.001, seconds=1.0)]
    import copy
    for o in objects:
        cls = type(o)
        for args in ((), (1,)):  # before: repr() of either crashed the interpreter (SIGSEGV)
            with pytest.raises((TypeError, ValueError)):
                cls.__new__(cls, *args)
        assert pickle.loads(pickle.dumps(o)) == o
        assert copy.copy(o) == o and copy.deepcopy(o) == o
    made = zwidth.Model.__new__(zwidth.Model, 0.001, 0.005)  # with its arguments: a whole model
    assert made == zwidth.Model(0.001, 0.005)

    class Mine(zwidth.Model):  # a subclass is still made with its arguments
        pass
    assert Mine(0.001, 0.005).m == 0.001


# --- Threads: the per-call C locale is per thread; HDF5 reads and saves at once do not deadlock ---

def test_threads_estimate_fit_zwidth_and_hdf5_at_once_under_a_german_locale(log, frf, tmp_path, german):
    import threading
    log.save(tmp_path / "in.h5")
    errors, texts = [], {}

    def job(k):
        try:
            for i in range(4):
                zwidth.read_log(tmp_path / "in.h5")
                log.save(tmp_path / f"o{k}_{i}.h5")
                log.save(tmp_path / f"o{k}_{i}.csv")
                zwidth.ZWidth(zwidth.Model.table1(), delay_samples=2 + k).summary()
            zwidth.fit(zwidth.estimate(tmp_path / "in.h5"), modes=1, max_starts=1, delay_samples=0)
            try:
                zwidth.estimate(log, overlap=1.5)
            except ValueError as e:
                texts[k] = str(e)
        except Exception as e:  # noqa: BLE001 (reported below)
            errors.append(f"{type(e).__name__}: {e}")

    threads = [threading.Thread(target=job, args=(k,), daemon=True) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not any(t.is_alive() for t in threads), "deadlock"
    assert not errors
    assert texts == {k: "overlap = 1.500000: must be in [0, 1)" for k in range(4)}  # the C locale's in every thread
    csv = [(tmp_path / f"o{k}_0.csv").read_bytes() for k in range(4)]
    assert len(set(csv)) == 1 and csv[0].split(b"\n")[2].startswith(b"0.001,")  # '.' decimals, 3 columns
    assert np.array_equal(zwidth.read_log(tmp_path / "o0_0.csv").u, log.u)
    assert locale.localeconv()["decimal_point"] == ","  # the main thread's locale untouched


def test_a_refused_constructor_leaves_no_unconstructed_object_in_the_traceback():
    # A verbose traceback (IPython %xmode Verbose, pytest's) reprs every frame's locals: the half-made
    # object of a refused ZWidth(...) used to be one of them, and its repr crashed the interpreter.
    for make in (lambda: zwidth.ZWidth(zwidth.Model.table1(), period_s=0.5), lambda: zwidth.Log([1.0], [2.0], 1e3),
                 lambda: zwidth.Model(1e300, 1.0), lambda: zwidth.FrequencyResponse([1.0], [1.0], 1e3, num_averages=0)):
        with pytest.raises(ValueError) as e:
            make()
        tb, seen = e.value.__traceback__, 0
        while tb is not None:
            for v in list(tb.tb_frame.f_locals.values()):
                repr(v)
                seen += 1
            tb = tb.tb_next
        assert seen > 0
