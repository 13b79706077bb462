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


def cascade_zoh(model, T):
    """(Ad, Bd, Cd) of the exact ZOH of G(s): each factor (rigid body, then every section) its own
    small state space (scipy.signal.tf2ss), joined by the series rule, then cont2discrete. Its
    eigenvalues keep their digits where the roots of the expanded polynomials do not (a lightly
    damped zero, the double pole at z = 1), so a check built on it does not depend on how a
    LAPACK resolves an ill-conditioned root."""
    import scipy.signal as ss
    factors = [([1.0], [model["m"], model["b"], 0.0])]
    for md in model["modes"]:
        w, c, v, dd = md["omega"], md["c"], md["v"], md["d"]
        factors.append((np.array([1.0, dd, v * v]) * w * w / (v * v), [1.0, c, w * w]))
    A = Bs = C = Dd = None
    for num, den in factors:
        a2, b2, c2, d2 = ss.tf2ss(num, den)
        if A is None:
            A, Bs, C, Dd = a2, b2, c2, d2
            continue
        n1, n2 = A.shape[0], a2.shape[0]  # u -> (A, Bs, C, Dd) -> (a2, b2, c2, d2)
        A = np.block([[A, np.zeros((n1, n2))], [b2 @ C, a2]])
        Bs = np.vstack([Bs, b2 @ Dd])
        C = np.hstack([d2 @ C, c2])
        Dd = d2 @ Dd
    Ad, Bd, Cd, _, _ = ss.cont2discrete((A, Bs, C, Dd), T, method="zoh")
    return Ad, Bd, Cd


def loop_eigenvalues(Ad, Bd, Cd, K, B, dt, T):
    """Closed-loop poles of eq. (2) as the eigenvalues of one matrix over
    [x_k, v_{k-1} .. v_{k-dt}, y_{k-1}], v the controller output -(K y_k + (B/T)(y_k - y_{k-1}))
    delayed dt samples."""
    nx = Ad.shape[0]
    M = np.zeros((nx + dt + 1, nx + dt + 1))
    vrow = np.zeros(nx + dt + 1)  # v_k = -(K + B/T) C x_k + (B/T) y_{k-1}
    vrow[:nx] = -(K + B / T) * Cd[0]
    vrow[nx + dt] = B / T
    M[:nx, :nx] = Ad
    if dt == 0:
        M[:nx, :] += np.outer(Bd[:, 0], vrow)
    else:
        M[:nx, nx + dt - 1] += Bd[:, 0]
        M[nx, :] = vrow
        for i in range(1, dt):
            M[nx + i, nx + i - 1] = 1.0
    M[nx + dt, :nx] = Cd[0]
    return np.linalg.eigvals(M)


def first_unstable_k(max_root, B, d, k_min=1e-7, k_max=1e4, rel=1e-11):
    """(lo, hi): the K_cr bracket of the loop with max_root(K, B, d) (the largest closed-loop pole
    modulus), scanned on a geometric grid for the first unstable K and bisected to rel; None when
    unstable at k_min (K_cr = 0), (inf, inf) when no K up to k_max is unstable."""
    ks = np.geomspace(k_min, k_max, 400)
    if max_root(ks[0], B, d) > 1.0:
        return None
    prev = ks[0]
    for k in ks[1:]:
        if max_root(k, B, d) > 1.0:
            lo, hi = prev, k
            while hi / lo - 1.0 > rel:
                mid = 0.5 * (lo + hi)
                lo, hi = (lo, mid) if max_root(mid, B, d) > 1.0 else (mid, hi)
            return lo, hi
        prev = k
    return float("inf"), float("inf")
