"""Issue 24, item 1: a model fitted at 1 ms with delay_samples 1 used at 0.5 ms. Python
converts its delay as the CLI's --period does (io::ResolveModelPeriod): the same K_CR(0) to
the last digit as `zwidth boundary --period 0.0005`, a UserWarning in Python's words, and a
fraction of a sample refused."""
import json, os, warnings

import pytest

import zwidth


@pytest.fixture
def fitted_1ms(table1_json, tmp_path):
    with open(table1_json) as f:
        m = json.load(f)
    m["delay_samples"], m["sample_period_s"] = 1, 0.001
    path = tmp_path / "fitted_1ms.json"
    path.write_text(json.dumps(m))
    return str(path)


def cli_kcr(cli, model, period, tmp_path):
    s = tmp_path / "s.json"
    p = cli("boundary", model, "--period", period, "--delays", 2, "--b-points", 20,
            "-o", tmp_path / "b.csv", "--summary", s)
    with open(s) as f:
        return json.load(f)["delays"][0]["K_cr_at_zero_B"], p.stderr


def test_zwidth_at_another_period_equals_the_cli_to_the_last_digit(cli, fitted_1ms, tmp_path):
    expected, note = cli_kcr(cli, fitted_1ms, 0.0005, tmp_path)
    assert "2 samples at the period 0.0005 s" in note
    m = zwidth.Model.load(fitted_1ms)
    with pytest.warns(UserWarning, match="2 samples at the period 0.0005 s"):
        z = zwidth.ZWidth(m, period_s=5e-4, delay_samples=2)
    assert z.summary()["K_cr_at_zero_B"] == expected
    assert m.delay_samples == 1  # the caller's model is left as it is


def test_same_period_gives_no_warning(fitted_1ms):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        zwidth.ZWidth(zwidth.Model.load(fitted_1ms), period_s=1e-3, delay_samples=2)


def test_fraction_of_a_sample_is_refused(fitted_1ms):
    with pytest.raises(zwidth.InputError, match="2.5 samples"):
        zwidth.ZWidth(zwidth.Model.load(fitted_1ms), period_s=4e-4, delay_samples=2)


@pytest.mark.parametrize("period", [1000.0, 1e-9])
def test_period_out_of_range_is_refused_in_python_words(fitted_1ms, period):
    with pytest.raises(zwidth.InputError) as e:
        zwidth.ZWidth(zwidth.Model.load(fitted_1ms), period_s=period, delay_samples=2)
    assert "period_s" in str(e.value) and "::" not in str(e.value) and "--period" not in str(e.value)


def test_period_s_of_log_and_response(log_h5):
    log = zwidth.read_log(log_h5)
    assert log.period_s == 1.0 / log.sample_rate_hz
    frf = zwidth.estimate(log)
    assert frf.period_s == 1.0 / frf.sample_rate_hz
