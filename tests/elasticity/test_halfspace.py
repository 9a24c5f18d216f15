"""Tests of the elastic half-space influence coefficients (Love 1929)."""

import time

import numpy as np
import pytest
from scipy import integrate

from roughcontact.elasticity.halfspace import (
    PeriodicHalfSpace,
    halfspace_influence,
    love_rectangle,
)

E = 2.0e9
NU = 0.3
LOVE = (1.0 - NU**2) / (np.pi * E)  # (1 - nu^2) / (pi E) [m/Pa per m]


def test_square_centre_closed_form():
    # Square of side 2a: u = 8 (1 - nu^2) p a ln(1 + sqrt 2) / (pi E).
    a = 0.7e-3
    expected = 8.0 * (1.0 - NU**2) * a * np.log(1.0 + np.sqrt(2.0)) / (np.pi * E)
    assert love_rectangle(0.0, 0.0, a, a, E, NU) == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("x, y", [(0.3, -0.2), (1.7, 0.4), (-2.5, -1.5), (1.0, 0.0)])
def test_rectangle_matches_quadrature(x, y):
    # Direct numerical integration of (1 - nu^2)/(pi E) * 1/r over the rectangle.
    a, b = 1.0, 0.6
    x, y = x * a, y * b

    def integrand(eta, xi):
        return 1.0 / np.hypot(x - xi, y - eta)

    # Split at the field point so the 1/r singularity sits on a corner.
    xs = sorted({-a, a, *([x] if -a < x < a else [])})
    ys = sorted({-b, b, *([y] if -b < y < b else [])})
    total = 0.0
    for x0, x1 in zip(xs[:-1], xs[1:], strict=True):
        for y0, y1 in zip(ys[:-1], ys[1:], strict=True):
            total += integrate.dblquad(integrand, x0, x1, y0, y1, epsabs=1e-12, epsrel=1e-11)[0]
    assert love_rectangle(x, y, a, b, E, NU) == pytest.approx(LOVE * total, rel=1e-8)


def test_far_field_is_boussinesq():
    # Point load F = 4ab: u = (1 - nu^2) F / (pi E r), error O((a/r)^2).
    a, b = 1e-4, 2e-4
    r = np.array([50.0, 200.0]) * b
    angle = 0.3
    u = love_rectangle(r * np.cos(angle), r * np.sin(angle), a, b, E, NU)
    point = (1.0 - NU**2) * 4.0 * a * b / (np.pi * E * r)
    error = np.abs(u / point - 1.0)
    assert (error < 2.0 * (b / r) ** 2).all()
    assert error[1] < error[0] / 8.0  # quadratic decay: 4x farther, ~16x smaller


def test_rectangle_vectorized_and_even():
    x = np.linspace(-3e-3, 3e-3, 7)[:, None]
    y = np.linspace(-2e-3, 2e-3, 5)[None, :]
    u = love_rectangle(x, y, 1e-3, 0.5e-3, E, NU)
    assert u.shape == (7, 5)
    np.testing.assert_allclose(u, love_rectangle(-x, y, 1e-3, 0.5e-3, E, NU), rtol=1e-13)
    np.testing.assert_allclose(u, love_rectangle(x, -y, 1e-3, 0.5e-3, E, NU), rtol=1e-13)
    assert (u > 0).all()


def test_influence_matrix_entries_and_ordering():
    # Non-square grid and elements: compare every entry with Love's formula at
    # the offset between centres, flat index k = iy * nx + ix.
    nx, ny, lx, ly = 5, 3, 2e-3, 0.9e-3
    dx, dy = lx / nx, ly / ny
    C = halfspace_influence((nx, ny), (lx, ly), E, NU)
    assert C.shape == (15, 15)
    for k in range(nx * ny):
        iy, ix = divmod(k, nx)
        for m in range(nx * ny):
            jy, jx = divmod(m, nx)
            expected = love_rectangle((ix - jx) * dx, (iy - jy) * dy, dx / 2, dy / 2, E, NU)
            assert C[k, m] == pytest.approx(expected, rel=1e-12)
    np.testing.assert_array_equal(C, C.T)


def test_influence_matrix_positive_definite():
    C = halfspace_influence((12, 9), (1e-3, 1e-3), E, NU)
    assert np.linalg.eigvalsh(C).min() > 0.0


def test_influence_matrix_3600_is_fast():
    start = time.perf_counter()
    C = halfspace_influence((60, 60), (9e-3, 9e-3), 5.11e8, 0.0)
    elapsed = time.perf_counter() - start
    assert C.shape == (3600, 3600)
    assert elapsed < 2.0  # typically about 0.1 s


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(grid=(0, 4), size=(1e-3, 1e-3), E=E, nu=NU), "grid"),
        (dict(grid=(4, 4), size=(1e-3, -1e-3), E=E, nu=NU), "size"),
        (dict(grid=(4, 4), size=(1e-3, 1e-3), E=-1.0, nu=NU), "E"),
        (dict(grid=(4, 4), size=(1e-3, 1e-3), E=E, nu=0.7), "nu"),
    ],
)
def test_influence_matrix_rejects_bad_input(kwargs, name):
    with pytest.raises(ValueError, match=name):
        halfspace_influence(**kwargs)
    with pytest.raises(ValueError, match=name):
        PeriodicHalfSpace(**kwargs)


def test_periodic_matches_dense_for_local_load():
    # A load patch small against the period: the periodic operator equals the
    # half-space one up to an (almost) constant shift from the images and the
    # zero-mean convention.
    n, size = 64, 1e-3
    op = PeriodicHalfSpace((n, n), (size, size), E, NU)
    C = halfspace_influence((n, n), (size, size), E, NU)
    p = np.zeros((n, n))
    p[30:34, 29:35] = 1.0
    diff = (op @ p.ravel() - C @ p.ravel()).reshape(n, n)[26:38, 25:39]
    u_max = (C @ p.ravel()).max()
    assert np.ptp(diff) < 2e-3 * u_max


def test_periodic_operator_properties():
    nx, ny = 24, 18
    op = PeriodicHalfSpace((nx, ny), (1.2e-3, 0.8e-3), E, NU, mean_compliance=3e-12)
    n = nx * ny
    assert op.shape == (n, n)
    assert op.element_area == pytest.approx(1.2e-3 * 0.8e-3 / n)
    rng = np.random.default_rng(1)
    q, r = rng.random(n), rng.random(n)
    # Symmetric.
    assert q @ (op @ r) == pytest.approx(r @ (op @ q), rel=1e-12)
    # Uniform pressure gives u = mean_compliance * P (the zero-mode convention).
    np.testing.assert_allclose(op @ np.full(n, 2.0e5), 3e-12 * 2.0e5, rtol=1e-10)
    # Columns of a batch are independent products.
    batch = rng.random((n, 3))
    stacked = np.column_stack([op.matvec(batch[:, j]) for j in range(3)])
    np.testing.assert_allclose(op @ batch, stacked, rtol=1e-12, atol=1e-25)
    # diagonal() is C[i, i] of the operator.
    unit = np.zeros(n)
    unit[37] = 1.0
    assert op.diagonal()[37] == pytest.approx((op @ unit)[37], rel=1e-12)
    assert op.diagonal().shape == (n,)


def test_periodic_zero_mean_default_and_image_convergence():
    op = PeriodicHalfSpace((16, 16), (1e-3, 1e-3), E, NU)
    p = np.random.default_rng(2).random(256)
    assert abs((op @ p).mean()) < 1e-12 * np.abs(op @ p).max()
    many = PeriodicHalfSpace((16, 16), (1e-3, 1e-3), E, NU, images=8)
    np.testing.assert_allclose(op @ p, many @ p, atol=1e-4 * np.abs(many @ p).max())


def test_periodic_rejects_bad_pressure_shape():
    op = PeriodicHalfSpace((8, 8), (1e-3, 1e-3), E, NU)
    with pytest.raises(ValueError, match="pressure"):
        op.matvec(np.zeros(63))
    with pytest.raises(ValueError, match="mean_compliance"):
        PeriodicHalfSpace((8, 8), (1e-3, 1e-3), E, NU, mean_compliance=-1.0)
