"""Kernel, gradient and physics building blocks of the DA model."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from granudep.config import ConfigError
from granudep.da.kernels import gauss_gradw, gauss_w, kernel_norm
from granudep.da.physics import coulomb_update, earth_pressure_coefficients
from granudep.da.verification import check_linear_gradient, linear_fields


def test_kernel_integrates_to_one_and_gradient_is_minus_dw_dxi():
    L, qc = 0.01, 3.0
    norm = kernel_norm(L, qc)
    r = np.linspace(-4 * L, 4 * L, 80001)
    w = np.array([gauss_w(v, L, norm, qc) for v in r])
    assert abs(np.trapezoid(w, r) - 1.0) < 1e-6
    # eq 24 with r = x_i - x_j is -dW/dx_i = +dW/dr
    eps = 1e-7
    for rv in (-0.02, -0.003, 0.004, 0.015):
        fd = (gauss_w(rv + eps, L, norm, qc) - gauss_w(rv - eps, L, norm, qc)) / (2 * eps)
        assert gauss_gradw(rv, L, norm, qc) == pytest.approx(-fd, rel=1e-6)


def test_linear_fields_have_exact_gradients():
    for row in check_linear_gradient():
        assert row["passed"], row


def test_gradient_sign_as_printed_would_flip():
    # eq 29 as printed (B2 with a minus sign) returns -du/dx: our corrected value has the right sign
    *_, du, interior, c1, b = linear_fields()
    assert np.all(np.sign(du) == np.sign(b))


def test_earth_pressure_coefficients():
    phi, th = math.radians(25.5), math.radians(22.0)
    ka, kp = earth_pressure_coefficients("paper", phi, phi, th)
    assert ka == pytest.approx(0.893264, abs=1e-6) and kp == pytest.approx(2.016758, abs=1e-6)
    # theta = 0: Rankine (1 - sin φ)/(1 + sin φ) and its inverse
    ka0, kp0 = earth_pressure_coefficients("paper", phi, phi, 0.0)
    assert ka0 == pytest.approx((1 - math.sin(phi)) / (1 + math.sin(phi)), rel=1e-12)
    assert kp0 == pytest.approx((1 + math.sin(phi)) / (1 - math.sin(phi)), rel=1e-12)
    ka, kp = earth_pressure_coefficients("savage_hutter", phi, phi, th)
    assert ka == pytest.approx(kp) == pytest.approx(2 / math.cos(phi) ** 2 - 1)
    assert earth_pressure_coefficients("one", phi, phi, th) == (1.0, 1.0)
    with pytest.raises(ConfigError, match="geometry.theta_deg"):
        earth_pressure_coefficients("paper", phi, phi, math.radians(30.0))
    with pytest.raises(ConfigError, match="material.phi_basal_deg"):
        earth_pressure_coefficients("savage_hutter", phi, math.radians(28.0), th)


def test_coulomb_update_stops_but_never_reverses():
    assert coulomb_update(1.0, 0.3) == pytest.approx(0.7)
    assert coulomb_update(-1.0, 0.3) == pytest.approx(-0.7)
    assert coulomb_update(0.2, 0.3) == 0.0
    assert coulomb_update(-0.2, 0.3) == 0.0


@pytest.mark.slow
def test_kernels_without_jit():
    """The same gradient checks with NUMBA_DISABLE_JIT=1 (kernels work as plain Python too)."""
    code = ("from granudep.da.verification import check_linear_gradient as c\n"
            "rows = c()\nassert all(r['passed'] for r in rows), rows\nprint('ok')")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "ok" in out.stdout
