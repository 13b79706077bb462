"""Figures on matplotlib (imported when this module is): the measured response with its
+-2 sigma band and the fitted model over the bins the fit used, the coherence, and the stable
(B, K) region per loop delay. Each function draws into the axes given (or new ones) and returns
them; nothing is shown or saved."""
import numpy as np
import matplotlib.pyplot as plt

from . import ZWidth


def _axes(ax, rows=1):
    if ax is not None:
        return ax
    _, ax = plt.subplots(rows, 1, sharex=True, squeeze=rows == 1)
    return ax if rows == 1 else list(ax[:, 0])


def bode(frf, result=None, axes=None, sigmas=2.0, all_bins=False):
    """|H| [log] and phase [deg] of a FrequencyResponse against f [Hz] with the band H +- sigmas H_std;
    with a FitResult, only the bins it used (all_bins=True: every bin, the unused ones grey) and its
    model's exact ZOH response. axes: (magnitude, phase) axes or None. Returns them."""
    mag, ph = axes if axes is not None else _axes(None, 2)
    f, H, s = frf.f_hz, frf.H, frf.H_std
    keep = np.ones(len(f), bool) if result is None else result.used
    if result is not None and all_bins:
        mag.loglog(f[~keep], np.abs(H[~keep]), ".", color="0.7", label="not used by the fit")
    fk, Hk, sk = f[keep], H[keep], s[keep]
    mag.loglog(fk, np.abs(Hk), label="measured")
    mag.fill_between(fk, np.maximum(np.abs(Hk) - sigmas * sk, np.abs(Hk) * 1e-3), np.abs(Hk) + sigmas * sk,
                     alpha=0.3, label=f"+-{sigmas:g} sigma")
    ph.semilogx(fk, np.degrees(np.unwrap(np.angle(Hk))))
    if result is not None:
        G = result.model.response(fk, period_s=frf.period_s)
        mag.loglog(fk, np.abs(G), "k", label=f"fitted model ({result.quality})")
        ph.semilogx(fk, np.degrees(np.unwrap(np.angle(G))), "k")
    mag.set(ylabel="|H|")
    ph.set(xlabel="frequency [Hz]", ylabel="phase [deg]")
    mag.legend()
    return mag, ph


def coherence(frf, result=None, ax=None):
    """The magnitude-squared coherence against f [Hz], the bins the FitResult used marked."""
    ax = _axes(ax)
    ax.semilogx(frf.f_hz, frf.coherence, label="coherence")
    if result is not None:
        ax.semilogx(frf.f_hz[result.used], frf.coherence[result.used], ".", label="used by the fit")
        ax.legend()
    ax.set(xlabel="frequency [Hz]", ylabel="coherence", ylim=(0, 1.05))
    return ax


def region(model, delays=(2, 4, 8), period_s=None, B=None, ax=None, **zwidth_options):
    """The stable (B, K) region per loop delay [samples]: filled below K_CR(B) (the interval from
    K = 0+), with the reopened bands' intervals past B_max_from_zero. B [N m s/rad]: an array, or
    None for 0 .. 1.05 x the largest B_max of the delays. Returns the axes."""
    ax = _axes(ax)
    zs = [ZWidth(model, period_s=period_s, delay_samples=d, **zwidth_options) for d in delays]
    if B is None:
        bmax = max((z.summary()["B_max"] or 0.0) for z in zs) or 1.0
        B = np.linspace(0.0, 1.05 * bmax, 400)
    B = np.asarray(B, float)
    for d, z in zip(delays, zs):
        K_cr, _ = z.critical(B)
        line, = ax.plot(B, K_cr, label=f"d = {d}")
        ax.fill_between(B, 0, K_cr, color=line.get_color(), alpha=0.2)
        for b in B[K_cr == 0]:
            for lo, hi in z.stable_intervals(float(b)):
                if np.isfinite(hi):
                    ax.plot([b, b], [lo, hi], color=line.get_color(), alpha=0.4, lw=0.8)
    ax.set(xlabel="B [N m s/rad]", ylabel="K [N m/rad]", title="stable below each curve")
    ax.legend()
    return ax
