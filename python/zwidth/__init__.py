"""zwidth: from a haptic device's logs to a fitted model of eq. (1) and its Z-width.

Python binding of the zwidth C++ library (Gil, Puerto, Diaz and Sanchez, "On the
Z-Width Limitation due to the Vibration Modes of Haptic Interfaces"). NumPy arrays
in and out; SI units and rad/s throughout. See docs/python.md.

    log = zwidth.read_log("phantom_30s.h5")
    res = zwidth.fit(log, modes=2)           # warns FitQualityWarning when the fit is poor
    print(res)                                # the verdict first
    z = zwidth.ZWidth(res.model, period_s=1e-3, delay_samples=2)
    K_cr, f_cr = z.critical(numpy.linspace(0, 0.02, 1000))

Errors: zwidth.InputError (a ValueError) for bad input, zwidth.ComputationError
(a RuntimeError) for a computation that failed; the messages are the CLI's, with
the keywords of this module where the CLI names its flags. Ctrl-C stops a long call
with KeyboardInterrupt. Threads: set_num_threads(n), or ZWIDTH_NUM_THREADS.
"""
import os
import warnings

from . import _zwidth
from ._zwidth import (  # noqa: F401
    __version__, InputError, ComputationError,
    Model, Log, FrequencyResponse, FitResult, CriticalPoint, ZWidth, RelayResult,
)
from ._zwidth import _build_info
from . import _signatures

__all__ = ["__version__", "InputError", "ComputationError", "FitQualityWarning", "Model", "Log",
           "FrequencyResponse", "FitResult", "CriticalPoint", "ZWidth", "RelayResult", "read_log",
           "estimate", "estimate_logs", "simulate", "fit", "run", "relay", "check", "validate", "build_info", "set_num_threads",
           "num_threads", "from_frd", "to_frd"]


class FitQualityWarning(UserWarning):
    """A fit judged poor (or not converged): its numbers, and the Z-width from them, are not to be
    trusted. `.reasons` holds the fit's quality_reasons (dicts code, message, advice) and `.result`
    the FitResult. Turn it into an error with warnings.simplefilter("error", zwidth.FitQualityWarning)."""

    def __init__(self, result):
        self.result = result
        self.reasons = result.quality_reasons
        if not result.converged:
            text = f"the fit did not converge ({result.status}): {result.message}"
        else:
            text = "poor fit: " + "; ".join(f"{r['code']}: {r['message']} ({r['advice']})" for r in self.reasons)
        super().__init__(text)


for _cls in (Model, Log, FrequencyResponse, FitResult, CriticalPoint, ZWidth, RelayResult):
    _signatures.wrap_class(_cls)


_ORIGINAL_NEW = {}


def _restore(cls, state):
    """An object of cls from its pickled state: allocated, then built by __setstate__ (which
    checks the state as the constructor checks its arguments)."""
    obj = _ORIGINAL_NEW[cls](cls)
    obj.__setstate__(state)
    return obj


def _guard_new(cls, constructible):
    """cls.__new__(cls) without __init__ made an object whose C++ value was never constructed
    (pybind11): repr() or any attribute read uninitialised memory and crashed the interpreter.
    So __new__ constructs (the bound __init__ on the new object, which checks the arguments) and
    __init__ is left with nothing to do; pickle, copy and multiprocessing build through _restore.
    A class the module alone makes (FitResult, CriticalPoint, RelayResult) has no __new__."""
    original = cls.__new__
    _ORIGINAL_NEW[cls] = original
    init = cls.__init__

    def __new__(c, *args, **kwargs):
        if not constructible:
            raise TypeError(f"zwidth.{cls.__name__} is made by the module (zwidth.fit, ZWidth.point, "
                            "zwidth.relay), not by hand")
        _signatures.check_numbers(init._numbers, (None,) + args, kwargs)
        obj = original(c)
        try:
            init._builtin(obj, *args, **kwargs)  # C++: no Python frame holds obj if it raises
        except BaseException:
            del obj  # never constructed: not left in the traceback's locals (a verbose traceback reprs them)
            raise
        return obj

    def __init__(self, *args, **kwargs):
        pass  # built by __new__

    if constructible:  # inspect.signature(cls) reads __new__ first: the constructor's
        import inspect
        __new__.__signature__ = inspect.signature(init)
        __init__.__signature__ = inspect.signature(init)
        __init__.__doc__ = init.__doc__
        cls.__init__ = __init__
    cls.__new__ = staticmethod(__new__)
    cls.__reduce_ex__ = lambda self, protocol: (_restore, (type(self), self.__getstate__()))


for _cls in (Model, Log, FrequencyResponse, ZWidth):
    _guard_new(_cls, True)
for _cls in (FitResult, CriticalPoint, RelayResult):
    _guard_new(_cls, False)
for _e in (InputError, ComputationError):
    _e.__module__ = "zwidth"

read_log = _signatures.wrap(_zwidth.read_log)
simulate = _signatures.wrap(_zwidth.simulate)
relay = _signatures.wrap(_zwidth.relay)
check = _signatures.wrap(_zwidth.check)
validate = _signatures.wrap(_zwidth.validate)
set_num_threads = _signatures.wrap(_zwidth.set_num_threads)
num_threads = _signatures.wrap(_zwidth.num_threads)


def _path(data):
    return os.fspath(data) if isinstance(data, (str, os.PathLike)) else None


def _estimate_signature():
    """estimate(data, y=None, sample_rate_hz=None, *, <Welch keywords>, <log selectors>)."""
    import inspect
    sigs, _ = _signatures.overloads(_zwidth.estimate)
    by_first = {s[1][0][0]: _signatures.signature(s) for s in sigs}
    P = inspect.Parameter
    params = [P("data", P.POSITIONAL_OR_KEYWORD, annotation="Log | str | os.PathLike | ArrayLike"),
              P("y", P.POSITIONAL_OR_KEYWORD, default=None, annotation="ArrayLike | None"),
              P("sample_rate_hz", P.POSITIONAL_OR_KEYWORD, default=None, annotation="float | None")]
    seen = {"data", "y", "sample_rate_hz", "u", "path", "log"}
    for first in ("u", "path"):
        for p in by_first[first].parameters.values():
            if p.name not in seen:
                seen.add(p.name)
                params.append(p.replace(kind=P.KEYWORD_ONLY))
    return inspect.Signature(params, return_annotation="FrequencyResponse")


def estimate(data, y=None, sample_rate_hz=None, **options):
    _signatures.check_numbers(_ESTIMATE_NUMBERS, (), dict(options, sample_rate_hz=sample_rate_hz))
    path = _path(data)
    if isinstance(data, Log) or path is not None:
        if y is not None or sample_rate_hz is not None:
            raise TypeError("estimate(log or path, ...): y and sample_rate_hz are the log's own; "
                            "pass them only with arrays: estimate(u, y, sample_rate_hz)")
        return _zwidth.estimate(path if path is not None else data, **options)
    if y is None or sample_rate_hz is None:
        raise TypeError("estimate(u, y, sample_rate_hz): pass the output y and the sample rate [Hz] "
                        "with the input array u (or a Log, or a log file's path)")
    if any(k in options for k in ("input_column", "output_column", "time_column", "rate")):
        raise TypeError("estimate(u, y, sample_rate_hz): the log selectors are for a path")
    return _zwidth.estimate(data, y, sample_rate_hz, **options)


estimate.__signature__ = _estimate_signature()
_ESTIMATE_NUMBERS = (None, _signatures.number_names(_zwidth.estimate)[1])
estimate.__doc__ = """The Welch frequency response y/u, as `zwidth estimate` computes it.

estimate(u, y, sample_rate_hz, ...): from two 1-D arrays (u [N m], y [rad]) sampled at
sample_rate_hz [Hz]; estimate(log, ...) from a Log; estimate(path, ..., selectors) streamed
from a log file (read_log's keywords select its columns). """ + _signatures.overloads(_zwidth.estimate)[1]

_fit = _zwidth.fit


def _paths(data):
    """[path, ...] of a log file's path or a list of them; None for anything else."""
    if _path(data) is not None:
        return [_path(data)]
    if isinstance(data, (list, tuple)) and data and all(_path(p) is not None for p in data):
        return [_path(p) for p in data]
    return None


def fit(data, *args, **kwargs):
    # kwargs: fit's own, then (for a Log or a path) estimate's.
    fit_names = set(_fit_signature.parameters) - {"estimate_options"}
    est = {k: kwargs.pop(k) for k in list(kwargs) if k not in fit_names}
    paths = _paths(data)
    if paths is None and not isinstance(data, Log):
        if est:
            raise TypeError(f"fit() got unexpected keyword arguments {sorted(est)} (estimate's keywords are "
                            "for a Log or a path)")
        if not isinstance(data, FrequencyResponse):
            raise TypeError(f"fit(data): data must be a FrequencyResponse, a Log or a log file's path, "
                            f"not {type(data).__name__}")
        _signatures.check_numbers(_FIT_NUMBERS, (data,) + args, kwargs)
        res = _fit(data, *args, **kwargs)
    else:
        _signatures.check_numbers(_FIT_NUMBERS, (data,) + args, kwargs)
        kw = dict(_fit_plain.__signature__.bind(data, *args, **kwargs).arguments)
        kw.pop("frf")
        own = {k: kw.pop(k) for k in ("friction", "units", "name") if k in kw}
        own = (own.get("friction", "auto"), own.get("units"), own.get("name", ""))
        if paths is not None:
            # `zwidth fit LOG...`: estimate_logs' keywords, and fmin/fmax bound the estimate
            # too (FitFlags::Resolve).
            unknown = sorted(set(est) - _names(_zwidth._estimate_logs_options))
            if unknown:
                raise TypeError(f"fit() got unexpected keyword arguments {unknown} (a log file's path takes "
                                "estimate_logs' keywords)")
            _signatures.check_numbers((None, _signatures.number_names(_zwidth._estimate_logs_options)[1]), (), est)
            for k in ("fmin", "fmax"):
                if k in kw:
                    est[k] = kw[k]
            res = _zwidth._fit_logs(paths, _zwidth._estimate_logs_options(**est), _zwidth._fit_options(**kw), *own)
        else:
            # `zwidth fit LOG`'s rule for a Log: fmin/fmax bound the estimate too, and the friction
            # refit reads the log with the Welch options the response was estimated with
            # (analysis::FrictionInputFor, as the command gives it its flags).
            for k in ("fmin", "fmax"):
                if k in kw:
                    est[k] = kw[k]
            frf = estimate(data, **est)  # its errors first, in estimate's words
            welch = _zwidth._estimate_logs_options(**{k: v for k, v in est.items()
                                                      if k in _names(_zwidth._estimate_logs_options)})
            res = _zwidth._fit_response(frf, _zwidth._fit_options(**kw), *own, data, welch)
    if res.quality != "good":
        warnings.warn(FitQualityWarning(res), stacklevel=2)
    return res


def _fit_with_estimate_signature():
    import inspect
    sig = inspect.signature(_fit_plain)
    first, *rest = sig.parameters.values()
    first = first.replace(name="data", annotation="FrequencyResponse | Log | str | os.PathLike")
    var = inspect.Parameter("estimate_options", inspect.Parameter.VAR_KEYWORD)
    return sig.replace(parameters=[first, *rest, var])


_fit_plain = _signatures.wrap(_fit)
_FIT_NUMBERS = _signatures.number_names(_fit)
_fit_signature = _fit_with_estimate_signature()
fit.__signature__ = _fit_signature
fit.__doc__ = _fit_plain.__doc__ + """

data may also be a Log (estimated first with estimate's keywords, window_length=...,
passed through estimate_options) or a log file's path or a list of them (as `zwidth fit
LOG...`: estimate_logs' keywords, input_column=..., whole_record=...; fmin/fmax bound the
estimate too). The friction fit reads the Log's or the file's samples again (with a Log:
Welch's default settings at the response's window).
A poor fit (quality != 'good') raises the warning FitQualityWarning with its reasons."""


def _keywords_signature(first, options, extra=(), ret=None):
    """first's parameters, then the keywords of the option makers `options` (keyword-only)."""
    import inspect
    P = inspect.Parameter
    params, seen = list(first), {p.name for p in first}
    for f in options:
        for p in _signatures.signature(_signatures.overloads(f)[0][0]).parameters.values():
            if p.name not in seen:
                seen.add(p.name)
                params.append(p.replace(kind=P.KEYWORD_ONLY))
    return inspect.Signature(params + list(extra), return_annotation=ret or inspect.Signature.empty)


def _names(f):
    return set(_signatures.signature(_signatures.overloads(f)[0][0]).parameters)


def estimate_logs(paths, **options):
    _signatures.check_numbers((None, _signatures.number_names(_zwidth._estimate_logs_options)[1]), (), options)
    return _zwidth._estimate_logs(paths, _zwidth._estimate_logs_options(**options))


def _estimate_logs_signature():
    import inspect
    P = inspect.Parameter
    return _keywords_signature([P("paths", P.POSITIONAL_OR_KEYWORD, annotation="str | os.PathLike | list")],
                               [_zwidth._estimate_logs_options], ret="FrequencyResponse")


estimate_logs.__signature__ = _estimate_logs_signature()
estimate_logs.__doc__ = _signatures.overloads(_zwidth._estimate_logs_options)[1]


def run(logs, out_dir, **options):
    # options: run's own (_run's keywords), estimate_logs' and fit's; fmin/fmax bound both the
    # estimate and the fit's band, as `zwidth run --fmin/--fmax`.
    own = _names(_zwidth._run) - {"logs", "out_dir", "estimate", "fit", "command_line"}
    est_names = _names(_zwidth._estimate_logs_options)
    fit_names = _names(_zwidth._fit_options)
    _signatures.check_numbers((None, set().union(*(_signatures.number_names(f)[1] for f in (
        _zwidth._run, _zwidth._estimate_logs_options, _zwidth._fit_options)))), (), options)
    unknown = sorted(set(options) - own - est_names - fit_names)
    if unknown:
        raise TypeError(f"run() got unexpected keyword arguments {unknown}")
    est = {k: v for k, v in options.items() if k in est_names}
    fit_kw = {k: v for k, v in options.items() if k in fit_names}
    est_defaults = _signatures.signature(_signatures.overloads(_zwidth._estimate_logs_options)[0][0]).parameters
    for k in ("fmin", "fmax"):  # the fit's band is the estimate's, as FitFlags::Resolve
        fit_kw[k] = est.get(k, est_defaults[k].default)
    run_kw = {k: v for k, v in options.items() if k in own}
    logs = [os.fspath(p) for p in logs] if not isinstance(logs, (str, os.PathLike)) else os.fspath(logs)
    call = "zwidth.run(" + ", ".join([repr(logs), repr(os.fspath(out_dir))] +
                                     [f"{k}={v!r}" for k, v in options.items()]) + ")"
    return _zwidth._run(logs, os.fspath(out_dir), _zwidth._estimate_logs_options(**est),
                        _zwidth._fit_options(**fit_kw), command_line=call, **run_kw)


def _run_signature():
    import inspect
    P = inspect.Parameter
    first = [P("logs", P.POSITIONAL_OR_KEYWORD, annotation="str | os.PathLike | list"),
             P("out_dir", P.POSITIONAL_OR_KEYWORD, annotation="str | os.PathLike")]
    own = [p.replace(kind=P.KEYWORD_ONLY)
           for p in _signatures.signature(_signatures.overloads(_zwidth._run)[0][0]).parameters.values()
           if p.name not in ("logs", "out_dir", "estimate", "fit", "command_line")]
    return _keywords_signature(first + own, [_zwidth._estimate_logs_options, _zwidth._fit_options], ret="dict")


run.__signature__ = _run_signature()
run.__doc__ = """`zwidth run LOG... -o OUT_DIR` from Python: the same library function writes the same
folder (summary.json, model.json, frf.csv, boundary.csv, report.html, figures/), byte for byte
but for the provenance's command and date; nothing on stdout. Keywords: run's own (force,
figures (False: --no-figures), png, reference ('table1' or a model JSON's path), delays, units,
velocity_filter_hz, hand (M, B, K), b_step, b_points, report_filter_hz, friction ('auto': the
Coulomb friction fitted when one log shows it, 'coulomb', 'none': as `zwidth run --friction`),
table2 (True: Table II's relay points beside the model, as `zwidth run --table2`)),
estimate_logs' (the
window, the selectors, whole_record, ...; fmin/fmax also bound the fit) and fit's (modes, default
'auto' as `zwidth fit` and `run`, delay_samples, allow_short, ...). OUT_DIR must be new or empty (or
force=True); its parent must exist; nothing is left behind on an error or Ctrl-C. Warnings
(a poor fit's, the estimate's) are raised as UserWarning; a poor fit also as
FitQualityWarning. Returns a dict: out_dir, quality ('good'/'poor'), figures, fit_report."""


def build_info():
    """The versions of zwidth and of the libraries it was built with (as `zwidth --version`)."""
    return dict(_build_info)


def _to_scipy(self, period_s=None):
    """scipy.signal.StateSpace of the model: continuous (period_s=None) or its exact
    zero-order-hold discretisation at period_s [s] with the input delay as states (dt = period_s)."""
    from scipy import signal
    A, B, C, D = self.state_space(period_s)
    if period_s is None:
        return signal.StateSpace(A, B, C, D)
    return signal.StateSpace(A, B, C, D, dt=period_s)


def _to_control(self, period_s=None):
    """python-control StateSpace of the model (needs the `control` package), as to_scipy."""
    control = _control()
    A, B, C, D = self.state_space(period_s)
    if period_s is None:
        return control.ss(A, B, C, D)
    return control.ss(A, B, C, D, period_s)


def _control():
    try:
        import control
    except ImportError as e:
        raise ImportError("python-control is not installed (pip install control; Debian 12 has no package): "
                          f"{e}") from e
    return control


def to_frd(frf):
    """python-control FrequencyResponseData of a FrequencyResponse (omega = 2 pi f_hz [rad/s],
    dt = the response's sample period T [s], its period_s)."""
    import numpy as np
    control = _control()
    return control.frd(frf.H, 2 * np.pi * frf.f_hz, dt=frf.period_s)


def from_frd(frd, sample_rate_hz=None, num_averages=1):
    """A FrequencyResponse from python-control's FrequencyResponseData (SISO): f_hz = omega / 2 pi;
    sample_rate_hz from frd.dt when it is a number, else given [Hz]. No coherence (1) nor H_std
    (|H| 1e-3), as for a response file without those columns; fitting it needs num_averages >= 3
    or allow_short=True."""
    import numpy as np
    if sample_rate_hz is None:
        dt = getattr(frd, "dt", None)
        if not isinstance(dt, (int, float)) or isinstance(dt, bool) or not dt > 0:
            raise InputError("from_frd: the FRD has no sample period (dt); pass sample_rate_hz [Hz]")
        sample_rate_hz = 1.0 / dt
    H = np.asarray(frd.fresp)
    if H.ndim == 3:
        if H.shape[:2] != (1, 1):
            raise InputError(f"from_frd: the FRD has {H.shape[0]} outputs and {H.shape[1]} inputs: pass a SISO one")
        H = H[0, 0]
    return FrequencyResponse(np.asarray(frd.omega) / (2 * np.pi), H, sample_rate_hz, num_averages=num_averages)


Model.to_scipy = _to_scipy
Model.to_control = _to_control
FrequencyResponse.to_frd = to_frd
FrequencyResponse.from_frd = staticmethod(from_frd)


def __getattr__(name):
    if name == "batch":  # zwidth.batch: `zwidth batch` on threads or a dask.distributed Client
        from ._batch import batch
        return batch
    if name == "plot":  # zwidth.plot imports matplotlib only when used
        import importlib
        return importlib.import_module(".plot", __name__)
    raise AttributeError(f"module 'zwidth' has no attribute {name!r}")
