"""Issue 30, round four, in Python: each keyword bounded as the CLI bounds the same value
(tests/hostile4_test.sh): the theta grid's size, the encoder step, a torque RMS, a relay's
damping, a scene's K and B, a fixed fit delay a model file can hold."""
import numpy as np
import pytest

import zwidth


@pytest.fixture(scope="module")
def model():
    return zwidth.Model.table1()


@pytest.mark.parametrize("kw", [{"min_grid_points": 10**9}, {"grid_points_per_delay": 10**6}])
def test_a_theta_grid_past_its_bound_is_refused_not_allocated(model, kw):
    # 10**9 points: std::bad_alloc under a memory limit, the OOM killer without one.
    with pytest.raises(zwidth.InputError, match=next(iter(kw))):
        zwidth.ZWidth(model, **kw)


def test_the_largest_theta_grid_is_still_accepted(model):
    z = zwidth.ZWidth(model, min_grid_points=2**20)
    assert z.stable_intervals(0.0)


@pytest.mark.parametrize("q", [5.0, 1e300, 1e-300])
def test_simulate_refuses_an_encoder_step_a_model_file_refuses(model, q):
    with pytest.raises(zwidth.InputError, match="an encoder step is 0"):
        zwidth.simulate(model, 1.0, encoder_step_rad=q)


def test_simulate_refuses_a_torque_rms_whose_log_every_reader_refuses(model):
    with pytest.raises(zwidth.InputError, match=r"torque_rms = 1e\+300 is above 1e12"):
        zwidth.simulate(model, 1.0, torque_rms=1e300)


def test_relay_refuses_a_damping_past_the_walls_bound(model):
    with pytest.raises(zwidth.InputError, match=r"damping must lie in \[0, 1e12\]"):
        zwidth.relay(model, 2, 1e300, seconds=1.0)


@pytest.mark.parametrize("obj", [("a", 1e300, 0.0), ("a", 1.0, 1e13)])
def test_check_refuses_scene_values_past_the_walls_bound(model, obj):
    with pytest.raises(zwidth.InputError, match=r"must be finite and in \[0, 1e12\]"):
        zwidth.check([obj], model, 2)


def test_fit_refuses_a_fixed_delay_no_model_file_holds(model):
    frf = zwidth.estimate(zwidth.simulate(model, 20.0))
    with pytest.raises(zwidth.InputError, match=r"delay_samples must be in \[0, 1000\]"):
        zwidth.fit(frf, modes=2, delay_samples=100000)
