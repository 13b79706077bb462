"""G(s) of eq. (1) as polynomials, for the Python cross-checks (NumPy only).

G(s) = 1/(m s^2 + b s) times, per mode, (omega^2/v^2) (s^2 + d s + v^2)/(s^2 + c s + omega^2):
poles omega, c; zeros v, d; unit gain at DC, as in the appendix's G1 and G2.
"""
import numpy as np


def plant_tf(model):
    """(num, den) of G(s), highest power first, from a model JSON dict."""
    num, den = np.array([1.0]), np.array([model["m"], model["b"], 0.0])
    for md in model["modes"]:
        w, c, v, d = md["omega"], md["c"], md["v"], md["d"]
        num = np.polymul(num, np.array([1.0, d, v * v]) * (w * w) / (v * v))
        den = np.polymul(den, [1.0, c, w * w])
    return num, den
