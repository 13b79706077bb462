"""zwidth.fit is `zwidth fit` (issue #24): on a log with Coulomb friction both go through
analysis::FitToModelFile, so the Python model equals the CLI's model JSON number for number, with
the same verdict and reason codes and the friction fitted; and Ceres/glog print nothing."""
import json, warnings

import pytest

import zwidth

COULOMB = 0.004  # N m, the friction simulated


@pytest.fixture(scope="module")
def friction_log(cli, table1_json, tmp_path_factory):
    path = tmp_path_factory.mktemp("friction") / "f.h5"
    cli("simulate", "--model", table1_json, "-o", path, "--coulomb", COULOMB, "--seed", 7)
    return str(path)


def _numbers(j, at=""):
    """Every number and bool of a model JSON by its path (texts name flags or keywords, the
    provenance names the call: left out)."""
    if isinstance(j, dict):
        out = {}
        for k, v in j.items():
            if k != "provenance":
                out.update(_numbers(v, f"{at}.{k}"))
        return out
    if isinstance(j, list):
        out = {}
        for i, v in enumerate(j):
            out.update(_numbers(v, f"{at}[{i}]"))
        return out
    return {} if isinstance(j, str) or j is None else {at: j}


def test_fit_of_a_friction_log_equals_the_cli(cli, friction_log, table1_json, tmp_path):
    out = tmp_path / "cli.json"
    cli("fit", friction_log, "-o", out)
    want = json.loads(out.read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = zwidth.fit(friction_log)
    got = json.loads(res.model.to_json())
    assert got["fit"]["quality"] == want["fit"]["quality"]
    assert [r["code"] for r in got["fit"]["quality_reasons"]] == [r["code"] for r in want["fit"]["quality_reasons"]]
    assert [r["code"] for r in res.quality_reasons] == [r["code"] for r in want["fit"]["quality_reasons"]]
    gn, wn = _numbers(got), _numbers(want)
    assert gn.keys() == wn.keys()
    assert {k: v for k, v in gn.items() if v != wn[k]} == {}
    # The friction was fitted (the CLI's side, the truth beside): F_c near the simulated one and b
    # near Table I's, not the friction-inflated linear-only b.
    assert want["fit"]["friction"]["status"] == "fitted"
    assert res.model.friction is not None
    fc = 0.5 * (res.model.friction["coulomb_pos"] + res.model.friction["coulomb_neg"])
    assert abs(fc - COULOMB) < 0.25 * COULOMB, fc
    b_true = json.loads(open(table1_json).read())["b"]
    assert abs(res.model.b - b_true) < 0.5 * b_true, (res.model.b, b_true)
    assert want["fit"]["friction"]["linear_only_b"] > 2 * b_true  # what a linear fit would have said


def test_friction_and_units_keywords_as_the_cli_flags(cli, friction_log, tmp_path):
    out = tmp_path / "cli.json"
    cli("fit", friction_log, "-o", out, "--friction", "none", "--units", "linear")
    want = json.loads(out.read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = zwidth.fit(friction_log, friction="none", units="linear")
    assert res.model.units == "linear" and want["units"] == "linear"
    assert res.model.friction is None and "friction" not in want
    assert res.model.b == want["b"]
    with pytest.raises(zwidth.InputError, match="friction"):
        zwidth.fit(friction_log, friction="sticky")
    with pytest.raises(zwidth.InputError, match="units"):
        zwidth.fit(friction_log, units="metric")


def test_a_response_alone_cannot_fit_friction(friction_log):
    frf = zwidth.estimate(friction_log)
    with pytest.raises(zwidth.InputError, match="one time-domain log"):
        zwidth.fit(frf, friction="coulomb")
    with pytest.warns(UserWarning, match="friction not checked"):
        zwidth.fit(frf)


def test_a_log_in_memory_fits_friction_as_its_file(friction_log):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        from_file = zwidth.fit(friction_log)
        from_log = zwidth.fit(zwidth.read_log(friction_log))
    assert from_log.model.friction is not None
    assert from_log.model.b == from_file.model.b
    assert from_log.model.friction == from_file.model.friction


def test_fit_prints_nothing(friction_log, capfd):
    capfd.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        zwidth.fit(friction_log)
        zwidth.fit(zwidth.estimate(friction_log), friction="none")
    out, err = capfd.readouterr()
    assert out == "" and err == "", (out, err)


@pytest.fixture(scope="module")
def short_friction_log(cli, table1_json, tmp_path_factory):
    """8 s of Table I with Coulomb friction: a rigid-body fit (--modes 0) refits its friction in < 1 s."""
    path = tmp_path_factory.mktemp("friction8") / "f.h5"
    cli("simulate", "--model", table1_json, "-o", path, "--coulomb", COULOMB, "--seed", 7, "--seconds", 8)
    return str(path)


def test_friction_refit_of_a_log_uses_the_welch_options_given_as_the_cli(cli, short_friction_log, tmp_path):
    """zwidth.fit(Log, window=..., overlap=..., window_length=...): the friction refit reads the log with
    those Welch options, as `zwidth fit LOG --friction coulomb` with the same flags (FrictionInputFor),
    not with the defaults: the model equals the command's number for number, and the command's
    friction with default flags differs (so the comparison can fail)."""
    log_path = short_friction_log
    welch = dict(window="hamming", overlap=0.25, window_length=2048)
    flags = ["--window", "hamming", "--overlap", "0.25", "--window-length", "2048"]
    fit_flags = ["--friction", "coulomb", "--modes", "0", "--delay-samples", "1"]
    out, plain = tmp_path / "cli.json", tmp_path / "plain.json"
    cli("fit", log_path, "-o", out, *fit_flags, *flags)
    cli("fit", log_path, "-o", plain, *fit_flags)
    want, default = json.loads(out.read_text()), json.loads(plain.read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = zwidth.fit(zwidth.read_log(log_path), friction="coulomb", modes=0, delay_samples=1, **welch)
    got = json.loads(res.model.to_json())
    assert want["fit"]["friction"]["status"] == "fitted" and got["fit"]["friction"]["status"] == "fitted"
    gn, wn = _numbers(got), _numbers(want)
    assert gn.keys() == wn.keys()
    assert {k: v for k, v in gn.items() if v != wn[k]} == {}
    assert want["friction"] != default["friction"]  # the flags change the refit
