"""Plain-NumPy references of the ISPH operators (tests only): brute-force pairs over all particles,
the formulas of the kernels' docstrings written out once more, no cell list, no numba.

Every function takes the particle positions (granular first, ``nf`` of them) and the smoothing
length; the pair convention is the kernels' one: r_ij = x_i − x_j, ∇_i W_ij = (dW/dr)/r · r_ij."""
import math

import numpy as np


def wendland(r, h):
    """W and (dW/dr)/r of the 2D Wendland C2 kernel, support 2h (0 at r = 0 for the second)."""
    q = np.asarray(r, float) / h
    t = np.clip(1.0 - 0.5 * q, 0.0, None)
    w = 7.0 / (4.0 * math.pi * h * h) * t ** 4 * (2.0 * q + 1.0)
    dwdr = 7.0 / (4.0 * math.pi * h ** 3) * (-5.0 * q) * t ** 3
    with np.errstate(invalid="ignore", divide="ignore"):
        gw = np.where(np.asarray(r) > 1e-12 * h, dwdr / np.asarray(r, float), 0.0)
    return w, gw


def pairs(x, y, nf, h):
    """Every (i, j), i granular, j ≠ i any particle, with |x_i − x_j| < 2h: i, j, rx, ry, r."""
    ii, jj = np.meshgrid(np.arange(nf), np.arange(x.size), indexing="ij")
    rx = x[ii] - x[jj]
    ry = y[ii] - y[jj]
    r = np.hypot(rx, ry)
    keep = (r < 2.0 * h) & (ii != jj)
    return ii[keep], jj[keep], rx[keep], ry[keep], r[keep]


def geometry(x, y, nf, h, vol):
    """∇·r = −Σ V (dW/dr)/r r², C = V W(0) + Σ V W, ∇C = Σ V ∇W, M = −Σ V (dW/dr)/r r ⊗ r and
    L = M⁻¹ where det M, M_xx, M_yy > 0.4 (else the identity)."""
    i, j, rx, ry, r = pairs(x, y, nf, h)
    w, gw = wendland(r, h)
    divr = np.zeros(nf)
    np.add.at(divr, i, -vol * gw * r * r)
    conc = np.full(nf, vol * wendland(0.0, h)[0])
    np.add.at(conc, i, vol * w)
    gcx = np.zeros(nf)
    gcy = np.zeros(nf)
    np.add.at(gcx, i, vol * gw * rx)
    np.add.at(gcy, i, vol * gw * ry)
    m = np.zeros((nf, 2, 2))
    for a, ra in enumerate((rx, ry)):
        for b, rb in enumerate((rx, ry)):
            np.add.at(m[:, a, b], i, -vol * gw * ra * rb)
    lmat = np.tile(np.eye(2), (nf, 1, 1))
    det = np.linalg.det(m)
    ok = (det > 0.4) & (m[:, 0, 0] > 0.4) & (m[:, 1, 1] > 0.4)
    lmat[ok] = np.linalg.inv(m[ok])
    return divr, conc, gcx, gcy, lmat.reshape(nf, 4), m


def granular_gradient(x, y, nf, h, vol, f, lmat):
    """L_i Σ_j V (f_j − f_i) ∇_i W_ij over granular neighbours j (the kernels' renormalised
    difference gradient without wall terms)."""
    i, j, rx, ry, r = pairs(x, y, nf, h)
    g = j < nf
    i, j, rx, ry, r = i[g], j[g], rx[g], ry[g], r[g]
    _, gw = wendland(r, h)
    a = np.zeros((nf, 2))
    np.add.at(a[:, 0], i, vol * (f[j] - f[i]) * gw * rx)
    np.add.at(a[:, 1], i, vol * (f[j] - f[i]) * gw * ry)
    lm = lmat.reshape(nf, 2, 2)
    return np.einsum("iab,ib->ia", lm, a)


def shepard(x, y, nf, h, f):
    """(W(0) f_i + Σ_j W_ij f_j)/(W(0) + Σ_j W_ij) over granular neighbours j."""
    i, j, rx, ry, r = pairs(x, y, nf, h)
    g = j < nf
    w, _ = wendland(r[g], h)
    w0 = wendland(0.0, h)[0]
    num = w0 * f[:nf].astype(float)
    den = np.full(nf, w0)
    np.add.at(num, i[g], w * f[j[g]])
    np.add.at(den, i[g], w)
    return num / den
