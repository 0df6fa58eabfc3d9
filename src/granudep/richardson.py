"""Observed order of convergence and Richardson extrapolation from three resolutions.

For spacings h1 < h2 < h3 (finest first) and results f1, f2, f3, with e21 = f2 − f1 and
e32 = f3 − f2, the observed order p of f = f* + C h^p solves (h3^p − h2^p)/(h2^p − h1^p) = e32/e21
(the generalised Richardson form for unequal ratios, cf. Celik et al. 2008, J. Fluids Eng. 130,
078001), found by bisection, and the extrapolated value is f* = (r21^p f1 − f2)/(r21^p − 1). Only a
monotone sequence with shrinking differences (0 < e21/e32 < 1 for the ratios used) is convergent;
an oscillating sequence or one with no positive order is reported as not converging, with the
reason, and no extrapolation; an order below 0.5 is flagged as unreliable.
"""
from __future__ import annotations

import math


def observed_order(h, f, max_iter: int = 200) -> dict:
    """{"order", "extrapolated", "converging", "reason"} from the three finest (h, f) pairs."""
    pairs = sorted((float(a), float(b)) for a, b in zip(h, f) if math.isfinite(a) and math.isfinite(b))
    if len(pairs) < 3:
        return {"order": math.nan, "extrapolated": math.nan, "converging": False,
                "reason": f"{len(pairs)} resolution(s): three are needed"}
    (h1, f1), (h2, f2), (h3, f3) = pairs[:3]
    e21, e32 = f2 - f1, f3 - f2
    if e21 == 0.0 or e32 == 0.0:
        return {"order": math.nan, "extrapolated": math.nan, "converging": False,
                "reason": "two resolutions give the same value"}
    if e21 * e32 < 0.0:
        return {"order": math.nan, "extrapolated": math.nan, "converging": False,
                "reason": "not monotone in the spacing (oscillating)"}
    r21 = h2 / h1
    ratio = e32 / e21                                  # > 0 here

    def model(q: float) -> float:                      # (h3^q − h2^q)/(h2^q − h1^q), increasing in q
        return (h3 ** q - h2 ** q) / (h2 ** q - h1 ** q)

    floor = math.log(h3 / h2) / math.log(h2 / h1)      # its limit for q → 0
    if ratio <= floor:
        return {"order": math.nan, "extrapolated": math.nan, "converging": False,
                "reason": f"no positive observed order: the differences ({e32:+.4g} then {e21:+.4g}) shrink too "
                          "slowly for any power law (diverging or logarithmic)"}
    lo, hi = 1e-9, 1.0
    while model(hi) < ratio and hi < 64.0:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if model(mid) < ratio else (lo, mid)
    p = 0.5 * (lo + hi)
    ext = (r21 ** p * f1 - f2) / (r21 ** p - 1.0)
    reason = "" if p >= 0.5 else f"observed order {p:.2f} < 0.5: formally convergent, extrapolation unreliable"
    return {"order": p, "extrapolated": ext, "converging": True, "reason": reason}
