"""The adjoint PPE divergence (isph/projection.py) against a dense NumPy transpose of the gradient."""
import numpy as np

from granudep.isph import approximate, operators
from granudep.isph.bundles import WallSurface, pairs_of
from granudep.isph.projection import adjoint_divergence


def _cloud(n_side=9, dx=0.01, seed=0):
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(n_side) * dx, np.arange(n_side) * dx)
    x = gx.ravel() + rng.uniform(-0.2, 0.2, gx.size) * dx
    y = gy.ravel() + rng.uniform(-0.2, 0.2, gy.size) * dx + 0.05   # far from any wall: no wall particles
    return x, y, dx


def test_adjoint_divergence_is_minus_the_transpose_of_the_gradient():
    x, y, dx = _cloud()
    nf = x.size
    h = 1.3 * dx
    vol = dx * dx
    pairs = pairs_of(x, y, nf, 2.0 * h, 0.0, h)
    _, _, _, _, lmat, _ = operators.geometry_terms(pairs, nf, h, vol)
    zeros = np.zeros(nf)
    empty = np.zeros(0)
    detached = np.zeros(nf, np.bool_)
    # dense gradient matrices from unit pressure fields
    gxm = np.zeros((nf, nf))
    gym = np.zeros((nf, nf))
    for k in range(nf):
        e = np.zeros(nf)
        e[k] = 1.0
        a, b = approximate.pressure_gradient(pairs, nf, vol, e, (zeros, zeros), lmat, WallSurface(empty, empty, empty), 1e-3,
                                           1000.0, detached)
        gxm[:, k], gym[:, k] = a, b
    rng = np.random.default_rng(1)
    u, v = rng.normal(size=nf), rng.normal(size=nf)
    d = adjoint_divergence(pairs, nf, vol, u, v, lmat)
    assert np.allclose(d, -(gxm.T @ u + gym.T @ v), rtol=1e-10, atol=1e-10 * np.abs(d).max())


def _setup(jitter, n_side=13, seed=2):
    rng = np.random.default_rng(seed)
    dx = 0.01
    gx, gy = np.meshgrid(np.arange(n_side) * dx, np.arange(n_side) * dx)
    x = gx.ravel() + rng.uniform(-jitter, jitter, gx.size) * dx
    y = gy.ravel() + rng.uniform(-jitter, jitter, gy.size) * dx + 0.05
    nf = x.size
    h = 1.3 * dx
    pairs = pairs_of(x, y, nf, 2.0 * h, 0.0, h)
    _, _, _, _, lmat, _ = operators.geometry_terms(pairs, nf, h, dx * dx)
    cx, cy = x - x.mean(), y - y.mean()
    inner = (np.abs(cx) < 2.5 * dx) & (np.abs(cy) < 2.5 * dx)
    return x, y, dx, pairs, lmat, inner


def test_adjoint_divergence_is_exact_for_linear_fields_on_a_lattice():
    x, y, dx, pairs, lmat, inner = _setup(0.0)
    u = 0.3 + 2.0 * x - 1.0 * y
    v = -0.1 + 0.5 * x + 3.0 * y                          # div = 5
    d = adjoint_divergence(pairs, x.size, dx * dx, u, v, lmat)
    assert np.allclose(d[inner], 5.0, rtol=1e-9)


def test_adjoint_divergence_sees_a_uniform_translation_on_a_disordered_cloud():
    """Why it is not the default: on a disordered cloud Σ_j V ∇W_kj ≠ 0, and the adjoint of the
    renormalised gradient reads a uniform translation as divergence (the renormalised divergence
    reads exactly 0)."""
    x, y, dx, pairs, lmat, inner = _setup(0.2)
    nf = x.size
    u = np.full(nf, 1.0)
    v = np.zeros(nf)
    d_adj = adjoint_divergence(pairs, nf, dx * dx, u, v, lmat)
    d_ren = operators.divergence(pairs, nf, dx * dx, u, v, lmat)
    assert np.max(np.abs(d_ren[inner])) < 1e-9
    assert np.sqrt(np.mean(d_adj[inner] ** 2)) > 1.0        # 1/s for 1 m/s: O(disorder / h)


# ------------------------------------------------------------------------------------------------
# adjoint-pair projection with pressure-carrying walls, against plain NumPy
# ------------------------------------------------------------------------------------------------
from granudep.isph import ppe_operator as po  # noqa: E402
from granudep.isph import projection as pj  # noqa: E402


def _walled_cloud(jitter=0.15, n_side=10, seed=3):
    """Granular particles over a three-layer bed (surface y = 0, normal +y), as the solver lays it."""
    rng = np.random.default_rng(seed)
    dx = 0.01
    gx, gy = np.meshgrid((np.arange(n_side) + 0.5) * dx, (np.arange(n_side) + 0.5) * dx)
    xf = gx.ravel() + rng.uniform(-jitter, jitter, gx.size) * dx
    yf = np.maximum(gy.ravel() + rng.uniform(-jitter, jitter, gy.size) * dx, 0.3 * dx)
    wxg, wyg = np.meshgrid((np.arange(-3, n_side + 3) + 0.5) * dx, -(np.arange(3) + 0.5) * dx)
    nf = xf.size
    x = np.concatenate((xf, wxg.ravel()))
    y = np.concatenate((yf, wyg.ravel()))
    nw = wxg.size
    h = 1.3 * dx
    pairs = pairs_of(x, y, nf, 2.0 * h, 0.0, h)
    _, _, _, _, lmat, _ = operators.geometry_terms(pairs, nf, h, dx * dx)
    wnx, wny = np.zeros(nw), np.ones(nw)
    return dict(x=x, y=y, nf=nf, nw=nw, dx=dx, h=h, start=pairs.start, nbr=pairs.nbr, rx=pairs.rx, ry=pairs.ry,
                rr=pairs.rr, gw=pairs.gw, lmat=lmat, wnx=wnx, wny=wny, pairs=pairs,
                walls=WallSurface(wnx, wny, np.zeros(nw)))


def _naive_d(c):
    """Dense D (nodes × particles, x and y) from the formulas of isph/projection.py, pair by pair."""
    nf, nw, vol = c["nf"], c["nw"], c["dx"] ** 2
    dxm = np.zeros((nf + nw, nf))
    dym = np.zeros((nf + nw, nf))
    for k in range(nf):
        lk = c["lmat"][k].reshape(2, 2)
        for q in range(c["start"][k], c["start"][k + 1]):
            j = c["nbr"][q]
            r = np.array([c["rx"][q], c["ry"][q]])
            g = vol * c["gw"][q]
            lr = g * (lk @ r)
            if j < nf:                               # (u_j − u_k)·(L_k r) V g
                dxm[k, j] += lr[0]
                dym[k, j] += lr[1]
                dxm[k, k] -= lr[0]
                dym[k, k] -= lr[1]
            else:
                n = np.array([c["wnx"][j - nf], c["wny"][j - nf]])
                a = -(n @ lr) * n                     # −(u_k·n)(n·L_k r) V g
                dxm[k, k] += a[0]
                dym[k, k] += a[1]
                b = -g * (n @ r) * n                  # wall row: (u_k·n)(n·r_wk) V g
                dxm[j, k] += b[0]
                dym[j, k] += b[1]
    return dxm, dym


def _coo(c):
    return pj.divergence_entries(c["pairs"], c["nf"], c["dx"] ** 2, c["lmat"], c["walls"])


def test_adjoint_pair_divergence_matches_the_pairwise_formula_and_its_gradient_is_minus_the_transpose():
    c = _walled_cloud()
    nf, n = c["nf"], c["nf"] + c["nw"]
    rows, cols, cx, cy = _coo(c)
    dxm, dym = _naive_d(c)
    rng = np.random.default_rng(4)
    u, v, p = rng.normal(size=nf), rng.normal(size=nf), rng.normal(size=n)
    d = po.apply_divergence(n, rows, cols, cx, cy, u, v)
    assert np.allclose(d, dxm @ u + dym @ v, rtol=1e-12, atol=1e-12 * np.abs(d).max())
    gx, gy = po.apply_gradient(nf, rows, cols, cx, cy, p)
    assert np.allclose(gx, -dxm.T @ p, atol=1e-12 * np.abs(gx).max())
    assert np.allclose(gy, -dym.T @ p, atol=1e-12 * np.abs(gy).max())
    # discrete integration by parts: Σ u·G p = −Σ p D u
    assert np.isclose(np.dot(u, gx) + np.dot(v, gy), -np.dot(p, d), rtol=1e-12)


def test_adjoint_pair_divergence_is_exact_for_linear_fields_away_from_walls_and_blind_to_wall_sliding():
    c = _walled_cloud(jitter=0.0, n_side=14)
    nf, n = c["nf"], c["nf"] + c["nw"]
    rows, cols, cx, cy = _coo(c)
    x, y = c["x"][:nf], c["y"][:nf]
    inner = (np.abs(x - x.mean()) < 2.5 * c["dx"]) & (np.abs(y - y.mean()) < 2.5 * c["dx"])
    u = 0.3 + 2.0 * x - 1.0 * y
    v = -0.1 + 0.5 * x + 3.0 * y                          # div = 5
    d = po.apply_divergence(n, rows, cols, cx, cy, u, v)
    assert np.allclose(d[:nf][inner], 5.0, rtol=1e-9)
    # a uniform slide along the bed: no divergence anywhere, walls included (walls see u·n only)
    d = po.apply_divergence(n, rows, cols, cx, cy, np.ones(nf), np.zeros(nf))
    assert np.max(np.abs(d)) < 1e-9 * np.max(np.abs(cx))


def _project(c, stab, us, vs, fs=None, dt=1e-3, rho=1000.0, passes=8):
    nf, nw = c["nf"], c["nw"]
    fs = np.zeros(nf, np.bool_) if fs is None else fs
    conc = np.ones(nf)

    def solve(indptr, indices, data, rhs, guess):
        # dense least squares: with ε = 0 the operator D Dᵀ may be (near) singular
        m = np.zeros((rhs.size, rhs.size))
        for r in range(rhs.size):
            m[r, indices[indptr[r]:indptr[r + 1]]] += data[indptr[r]:indptr[r + 1]]
        return np.linalg.lstsq(m, rhs, rcond=1e-13)[0]

    return pj.adjoint_pair_projection(c["pairs"], nf, nw, c["dx"] ** 2, c["lmat"], c["walls"], fs, 0.0, us, vs, conc, 1.0, 0.0, dt, rho,
                                      0.01 * c["h"] ** 2, 1.0, stab, np.zeros(nf + nw), solve,
                                      np.zeros(nw, np.bool_), max_passes=passes)


def test_adjoint_pair_matrix_equals_the_dense_product_plus_the_compact_laplacian():
    c = _walled_cloud()
    nf, nw, n = c["nf"], c["nw"], c["nf"] + c["nw"]
    rows, cols, cx, cy = _coo(c)
    ei, ej, ea = pj.compact_laplacian_edges(c["pairs"], nf, c["dx"] ** 2,
                                            0.01 * c["h"] ** 2, 1.0)
    dxm, dym = _naive_d(c)
    lc = np.zeros((n, n))
    for i, j, a in zip(ei, ej, ea):
        lc[i, i] += a
        lc[j, j] += a
        lc[i, j] -= a
        lc[j, i] -= a
    stab = 0.3
    full = (1.0 - stab) * (dxm @ dxm.T + dym @ dym.T) + stab * lc
    known = np.zeros(n, bool)
    known[:5] = True                                  # a few Dirichlet particles
    known[nf:] = ~(np.abs(dxm[nf:]).sum(1) > 0)       # dry walls
    unknown = np.full(n, -1, np.int64)
    unk = np.flatnonzero(~known)
    unknown[unk] = np.arange(unk.size)
    p = np.where(known, np.random.default_rng(5).normal(size=n), 0.0)
    b = np.random.default_rng(6).normal(size=n)
    system = po.PPESystem(n, rows, cols, cx, cy, nf, ei, ej, ea, stab, unknown, unk.size)
    indptr, indices, data, rhs = po.assemble_adjoint_ppe(system, p, b)
    dense = np.zeros((unk.size, unk.size))
    for r in range(unk.size):
        assert indices[indptr[r]] == r                # diagonal first
        for q in range(indptr[r], indptr[r + 1]):
            dense[r, indices[q]] += data[q]
    assert np.allclose(dense, full[np.ix_(unk, unk)], atol=1e-12 * np.abs(full).max())
    assert np.allclose(rhs, b[unk] - full[np.ix_(unk, np.flatnonzero(known))] @ p[known],
                       atol=1e-10 * np.abs(rhs).max())
    # the node blocks of the threads (one per numba thread) do not change a bit of it
    for nblock in (2, 3, 7):
        got = po._assemble_blocks.serial(system, p, b, nblock)
        for a, e in zip(got, (indptr, indices, data, rhs)):
            assert a.dtype == e.dtype and np.array_equal(a, e), nblock


def test_adjoint_pair_projection_never_raises_the_kinetic_energy_and_removes_the_divergence():
    c = _walled_cloud()
    nf, n = c["nf"], c["nf"] + c["nw"]
    rows, cols, cx, cy = _coo(c)
    rng = np.random.default_rng(7)
    dt, rho = 1e-3, 1000.0
    x, y = c["x"][:nf], c["y"][:nf]
    fs = y > 0.085                                    # top rows: free surface, p = 0
    for stab, passes in ((0.0, 8), (0.0, 1), (0.1, 1), (0.5, 2)):
        us, vs = rng.normal(size=nf), rng.normal(size=nf) - 1.0   # pressed into the bed
        p, gx, gy, dry, released = _project(c, stab, us, vs, fs=fs, dt=dt, rho=rho, passes=passes)
        u, v = us - dt / rho * gx, vs - dt / rho * gy
        ke0 = 0.5 * np.sum(us ** 2 + vs ** 2)
        ke1 = 0.5 * np.sum(u ** 2 + v ** 2)
        assert ke1 < ke0
        if stab == 0.0:
            # the exact projection: D u = 0 on every node solved for, and ΔE = −½ (Δt/ρ)² |G p|²
            d = po.apply_divergence(n, rows, cols, cx, cy, u, v)
            d0 = po.apply_divergence(n, rows, cols, cx, cy, us, vs)
            solved = np.concatenate((~fs, p[nf:] != 0))
            assert np.max(np.abs(d[solved])) < 1e-6 * np.max(np.abs(d0[solved]))
            assert np.isclose(ke1 - ke0, -0.5 * (dt / rho) ** 2 * np.sum(gx ** 2 + gy ** 2), rtol=1e-6)


def test_adjoint_pair_stabilisation_leaves_a_divergence_that_vanishes_with_epsilon():
    """D u = −(Δt/ρ) ε (L_c − D Dᵀ) p after the projection: the weight ε of the compact Laplacian
    trades the checkerboard control against the divergence left for the next step."""
    c = _walled_cloud(n_side=14)
    nf, n = c["nf"], c["nf"] + c["nw"]
    rows, cols, cx, cy = _coo(c)
    x, y = c["x"][:nf], c["y"][:nf]
    fs = y > 0.125
    us, vs = np.sin(40.0 * y) + 3.0 * x, -1.0 - 2.0 * y + np.cos(30.0 * x)
    d0 = po.apply_divergence(n, rows, cols, cx, cy, us, vs)
    left = []
    for stab in (0.01, 0.1, 0.5):
        p, gx, gy, dry, released = _project(c, stab, us, vs, fs=fs, passes=1)
        d = po.apply_divergence(n, rows, cols, cx, cy, us - 1e-6 * gx, vs - 1e-6 * gy)
        solved = np.concatenate((~fs, p[nf:] != 0))
        left.append(np.sqrt(np.mean(d[solved] ** 2) / np.mean(d0[solved] ** 2)))
    # the default ε = 0.01 removes ~90 % of a smooth field's divergence in one projection; at
    # ε = 1/2 (the energy-stability limit) the compact half leaves about as much as there was
    assert left[0] < 0.15
    assert left[0] < left[1] < left[2]
