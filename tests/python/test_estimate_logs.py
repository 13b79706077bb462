"""zwidth.estimate_logs: the library's estimate of several logs (analysis::EstimateFromLogs), the
one that `zwidth estimate LOG...` uses. Checked against the CLI's output file to the last digit
(two callers of one function), against the single-log Welch estimate where they must agree, and
for its errors and warnings in Python's words."""
import csv
import warnings

import numpy as np
import pytest

import zwidth


def _read_frf_csv(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    f_hz = np.array([float(r["f_hz"]) for r in rows])
    H = np.array([complex(float(r["H_re"]), float(r["H_im"])) for r in rows])
    std = np.array([float(r["H_std"]) for r in rows])
    return f_hz, H, std


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory, table1_json):
    """Two 8 s runs of Table I's model (zwidth.simulate, seeds 11 and 12), saved as HDF5 logs."""
    d = tmp_path_factory.mktemp("runs")
    model = zwidth.Model.load(table1_json)
    paths = []
    for seed in (11, 12):
        p = d / f"run{seed}.h5"
        zwidth.simulate(model, seconds=8.0, seed=seed).save(str(p))
        paths.append(str(p))
    return paths


def test_two_runs_equal_the_cli_to_the_last_digit(two_runs, cli, tmp_path):
    out = tmp_path / "frf.csv"
    cli("estimate", *two_runs, "-o", out)
    f_cli, H_cli, std_cli = _read_frf_csv(out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = zwidth.estimate_logs(two_runs)
    np.testing.assert_array_equal(np.asarray(r.f_hz), f_cli)
    np.testing.assert_array_equal(np.asarray(r.H), H_cli)  # the CSV holds 17 digits: exact
    np.testing.assert_array_equal(np.asarray(r.H_std), std_cli)


def test_one_run_is_the_welch_estimate_of_that_log(two_runs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = zwidth.estimate_logs(two_runs[0], window_length=4096)
        b = zwidth.estimate(two_runs[0], window_length=4096)
    np.testing.assert_allclose(np.asarray(a.H), np.asarray(b.H), rtol=1e-12, atol=0)
    # Two runs average twice the segments of one.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        both = zwidth.estimate_logs(two_runs, window_length=4096)
    assert both.num_averages == 2 * a.num_averages


def test_dropped_samples_warn_with_the_keyword(two_runs):
    # 8 s at 1 kHz = 8000 samples; 4096-sample Hann segments at 50 %: 2 segments cover 6144,
    # the last 1856 samples are left out (worked out here, not read from the library).
    with pytest.warns(UserWarning) as record:
        zwidth.estimate_logs(two_runs[0], window_length=4096)
    texts = [str(w.message) for w in record]
    assert any("the last 1856 samples" in t and "window_length" in t and "--" not in t for t in texts), texts


def test_the_same_log_twice_is_refused(two_runs):
    with pytest.raises(zwidth.InputError, match="same samples"):
        zwidth.estimate_logs([two_runs[0], two_runs[0]])


def test_whole_record_of_one_log_names_the_keywords(two_runs):
    with pytest.raises(zwidth.InputError) as e:
        zwidth.estimate_logs(two_runs[0], whole_record=True)
    text = str(e.value)
    assert "whole_record" in text and "period_samples" in text and "--" not in text and "::" not in text


def test_default_window_follows_the_log_as_the_cli(two_runs):
    # 8000 samples at 1 kHz: 4096 is the power of two nearest 4.096 s, halved to 2048 so that the
    # log holds 3 segments (8000 < 2 * 4096); 2048-sample segments give 1000/2048 Hz bins.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = zwidth.estimate_logs(two_runs[0])
    np.testing.assert_allclose(np.diff(np.asarray(r.f_hz)), 1000.0 / 2048, rtol=1e-12)


def test_whole_record_of_two_runs_uses_every_sample(two_runs):
    r = zwidth.estimate_logs(two_runs, whole_record=True)
    # One rectangular segment of 8000 samples per run: bins at multiples of 1000/8000 Hz.
    f = np.asarray(r.f_hz)
    np.testing.assert_allclose(np.diff(f), 0.125, rtol=1e-12)


def test_paths_of_another_type_raise_a_type_error():
    with pytest.raises(TypeError):
        zwidth.estimate_logs([1, 2])


def test_a_log_too_short_is_refused_by_the_one_rule(two_runs, tmp_path):
    """39 ms at 1 kHz: estimate, fit and run refuse it as the CLI does (analysis::CheckLogLength):
    3 segments of the shortest default window, 256 samples at 1 kHz, need 512 samples."""
    log = zwidth.read_log(two_runs[0])
    short = zwidth.Log(log.u[:39], log.y[:39], 1000.0)
    want = r"too short: 39 samples \(0.039 s at 1000 Hz\).*at least 512 samples \(0.512 s\)"
    with pytest.raises(zwidth.InputError, match=want):
        zwidth.estimate(short)
    with pytest.raises(zwidth.InputError, match=want):
        zwidth.fit(short)
    path = tmp_path / "short.csv"
    short.save(str(path))
    with pytest.raises(zwidth.InputError, match=want):
        zwidth.run(str(path), str(tmp_path / "out"))
    assert not (tmp_path / "out" / "report.html").exists()
    zwidth.estimate(zwidth.Log(log.u[:512], log.y[:512], 1000.0))  # the shortest accepted
