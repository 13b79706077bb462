"""zwidth: from a haptic device's logs to a fitted model of eq. (1) and its Z-width.

Python binding of the zwidth C++ library (Gil, Puerto, Diaz and Sanchez, "On the
Z-Width Limitation due to the Vibration Modes of Haptic Interfaces"). NumPy arrays
in and out; SI units and rad/s throughout. See docs/python.md.

    log = zwidth.read_log("phantom_30s.h5")
    frf = zwidth.estimate(log)
    res = zwidth.fit(frf, modes=2)
    z = zwidth.ZWidth(res.model, period_s=1e-3, delay_samples=2)
    K_cr, f_cr = z.critical(numpy.linspace(0, 0.02, 1000))

Errors: zwidth.InputError (a ValueError) for bad input, zwidth.ComputationError
(a RuntimeError) for a computation that failed; the messages are the CLI's.
"""
from ._zwidth import (  # noqa: F401
    __version__, InputError, ComputationError,
    Model, Log, FrequencyResponse, FitResult, CriticalPoint, ZWidth, RelayResult,
    read_log, estimate, simulate, fit, relay, check,
)
from ._zwidth import _build_info

__all__ = ["__version__", "InputError", "ComputationError", "Model", "Log", "FrequencyResponse",
           "FitResult", "CriticalPoint", "ZWidth", "RelayResult", "read_log", "estimate", "simulate",
           "fit", "relay", "check", "build_info"]


def build_info():
    """The versions of zwidth and of the libraries it was built with (as `zwidth --version`)."""
    return dict(_build_info)


def _to_scipy(self, period_s=None):
    """scipy.signal.StateSpace of the model: continuous (period_s=None) or its exact
    zero-order-hold discretisation at period_s with the input delay as states (dt = period_s)."""
    from scipy import signal
    A, B, C, D = self.state_space(period_s)
    if period_s is None:
        return signal.StateSpace(A, B, C, D)
    return signal.StateSpace(A, B, C, D, dt=period_s)


def _to_control(self, period_s=None):
    """python-control StateSpace of the model (needs the `control` package), as to_scipy."""
    import control
    A, B, C, D = self.state_space(period_s)
    if period_s is None:
        return control.ss(A, B, C, D)
    return control.ss(A, B, C, D, period_s)


Model.to_scipy = _to_scipy
Model.to_control = _to_control
