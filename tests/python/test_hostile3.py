"""Issue 30 after round two, in Python: values checked as the readers check them (a log or
response saved at a rate zwidth refuses), and the texts the module returns are the C
locale's under a German one."""
import locale

import numpy as np
import pytest

import zwidth


@pytest.mark.parametrize("rate", [5.0, 10.0, 0.001, 2e6])
def test_log_at_a_rate_the_readers_refuse_is_refused(rate):
    u = np.sin(np.arange(100.0)); y = np.cos(np.arange(100.0))
    with pytest.raises(zwidth.InputError, match="sample_rate_hz"):
        zwidth.Log(u, y, rate)


def test_log_at_a_rate_the_readers_take_round_trips(tmp_path):
    u = np.sin(np.arange(100.0)); y = np.cos(np.arange(100.0))
    path = tmp_path / "log.csv"
    zwidth.Log(u, y, 12.5).save(str(path))
    assert zwidth.read_log(str(path)).sample_rate_hz == pytest.approx(12.5)


@pytest.mark.parametrize("rate", [0.001, 1e9])
def test_response_at_a_rate_zwidth_refuses_is_refused(rate):
    f = np.linspace(1e-4, 4e-4, 4)
    with pytest.raises(zwidth.InputError, match=r"\[10, 1e6\]"):
        zwidth.FrequencyResponse(f, np.ones(4), rate, num_averages=10)


def test_texts_are_the_c_locales_under_german(log_h5, german):
    frf = zwidth.estimate(zwidth.read_log(log_h5))
    res = zwidth.fit(frf, modes=2)
    z = zwidth.ZWidth(res.model, delay_samples=2)
    de = [res.brief_report(), repr(res), repr(frf), repr(z), repr(res.model)]
    locale.setlocale(locale.LC_ALL, "C")
    c = [res.brief_report(), repr(res), repr(frf), repr(z), repr(res.model)]
    assert de == c
