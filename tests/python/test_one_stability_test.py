"""Issue 31, must-have 2: one stability test for every caller, from Python.

On hard models (8 lightly damped sections crowded together, where Schur-Cohn
once called stable loops unstable) ZWidth.is_stable, membership in
stable_intervals, critical, zwidth.check's verdict and summary()'s K_cr(0),
B_max and B_max_from_zero agree at every (K, B) of a grid that holds every
interval end at (1 +- 1e-3) and (1 +- 1e-4), and B_max and B_max_from_zero at
(1 +- 1e-3). tests/scene_check_test.cc's OneStabilityTest does the same in C++.
"""
import math

import numpy as np
import pytest
import zwidth

T = 1e-3


def crowded(ratio, zeta):
    modes = []
    for i in range(8):
        w = 300.0 * ratio ** i
        v = 0.93 * w
        modes.append((w, 2 * zeta * w, v, 2 * zeta * v))
    return zwidth.Model(1.168e-3, 0.00584, modes)


def inside_one(iv, K):
    return any((K > lo or (K == 0.0 and lo == 0.0)) and K < hi for lo, hi in iv)


@pytest.mark.parametrize("ratio,zeta,d", [(1.08, 0.025, 2), (1.01, 1e-3, 4)])
def test_every_caller_agrees_at_every_point_of_a_grid(ratio, zeta, d):
    model = crowded(ratio, zeta)
    z = zwidth.ZWidth(model, period_s=T, delay_samples=d)
    s = z.summary()
    assert s["stability_test"]["method"] == "eigenvalues"  # a hard model: the eigenvalue test decides
    b_max, b_zero, k0 = s["B_max"], s["B_max_from_zero"], s["K_cr_at_zero_B"]
    assert b_max is not None and b_max > 0
    Bs = [1.1 * b_max * i / 10 for i in range(11)]
    for b in (b_max, b_zero):
        if b is not None and b > 0:
            Bs += [b * (1 - 1e-3), b * (1 + 1e-3)]
    points, ivs, near = [], [], 0
    for B in Bs:
        iv = z.stable_intervals(B)
        K_cr, _ = z.critical(B)
        assert K_cr == (iv[0][1] if iv and iv[0][0] == 0.0 else 0.0), B
        k_top = k0
        Ks = [0.0]
        for lo, hi in iv:
            for e in (lo, hi):
                if e > 0 and math.isfinite(e):
                    k_top = max(k_top, e)
                    Ks += [e * (1 - r) for r in (1e-3, 1e-4)] + [e * (1 + r) for r in (1e-3, 1e-4)]
                    near += 4
        Ks += list(2 * k_top * np.geomspace(1e-4, 1.0, 25))
        points += [(K, B) for K in Ks]
        ivs += [iv] * len(Ks)
    K = np.array([p[0] for p in points])
    B = np.array([p[1] for p in points])
    got = z.is_stable(K, B)
    verdicts = zwidth.check([(f"o{i}", k, b) for i, (k, b) in enumerate(points)], model, d, period_s=T)["objects"]
    assert len(verdicts) == len(points)
    for i, (k, b) in enumerate(points):
        assert bool(got[i]) == inside_one(ivs[i], k), (k, b)
        assert bool(got[i]) == verdicts[i]["stable"], (k, b)
        if b > b_max:
            assert not got[i], (k, b)
        if k == 0.0:
            assert bool(got[i]) == (b_zero is None or b < b_zero), b
        if b == 0.0 and k > 0.0 and len(ivs[i]) == 1 and not s["reopened_bands"]:
            assert bool(got[i]) == (k < k0), k
    assert near > 0 and 0 < got.sum() < len(points)
