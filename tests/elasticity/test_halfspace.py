"""Tests of the elastic half-space influence coefficients (Love 1929)."""

import time

import numpy as np
import pytest
from scipy import integrate, special

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.contact.references import westergaard_pressure
from roughcontact.elasticity.halfspace import (
    PeriodicHalfSpace,
    halfspace_influence,
    love_rectangle,
)

E = 2.0e9
NU = 0.3
LOVE = (1.0 - NU**2) / (np.pi * E)  # (1 - nu^2) / (pi E) [m/Pa per m]
E_STAR = E / (1.0 - NU**2)


def element_cosine_compliance(theta):
    """``R(theta) = lambda E* q / 2`` of element-constant pressure ``cos(q x_j)`` [-].

    The field on elements of width ``dx`` (``theta = q dx / 2``, ``0 < theta < pi``)
    has the aliases ``q + 2 pi m / dx`` with amplitudes ``sin(theta + pi m) /
    (theta + pi m)``; the half-space answers each with ``2 / (E* |q + 2 pi m / dx|)``
    and at the element centres every alias is ``cos(q x_j)`` again, so

        R = theta sin(theta) sum_m (-1)^m / ((theta + pi m) |theta + pi m|)
          = theta sin(theta) / (4 pi^2) [psi1(a/2) - psi1((1 + a)/2)
                                          + psi1((1 - a)/2) - psi1(1 - a/2)],

    ``a = theta / pi``, ``psi1`` the trigamma function (the alternating sums
    over m >= 0 and m < 0 as Hurwitz zeta differences).
    """
    a = theta / np.pi
    psi1 = special.polygamma(1, np.array([a / 2, (1 + a) / 2, (1 - a) / 2, 1 - a / 2]))
    alternating = psi1[0] - psi1[1] + psi1[2] - psi1[3]
    return theta * np.sin(theta) * alternating / (4.0 * np.pi**2)


def test_square_centre_closed_form():
    # Square of side 2a: u = 8 (1 - nu^2) p a ln(1 + sqrt 2) / (pi E).
    a = 0.7e-3
    expected = 8.0 * (1.0 - NU**2) * a * np.log(1.0 + np.sqrt(2.0)) / (np.pi * E)
    # abs=0: approx's default abs=1e-12 would pass any m/Pa value
    assert love_rectangle(0.0, 0.0, a, a, E, NU) == pytest.approx(expected, rel=1e-13, abs=0.0)


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
    assert love_rectangle(x, y, a, b, E, NU) == pytest.approx(LOVE * total, rel=1e-8, abs=0.0)


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
            assert C[k, m] == pytest.approx(expected, rel=1e-12, abs=0.0)
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
    assert op.element_area == pytest.approx(1.2e-3 * 0.8e-3 / n, rel=1e-6, abs=0.0)
    rng = np.random.default_rng(1)
    q, r = rng.random(n), rng.random(n)
    # Symmetric.
    assert q @ (op @ r) == pytest.approx(r @ (op @ q), rel=1e-12, abs=0.0)
    # Uniform pressure gives u = mean_compliance * P (the zero-mode convention).
    np.testing.assert_allclose(op @ np.full(n, 2.0e5), 3e-12 * 2.0e5, rtol=1e-10)
    # Columns of a batch are independent products.
    batch = rng.random((n, 3))
    stacked = np.column_stack([op.matvec(batch[:, j]) for j in range(3)])
    np.testing.assert_allclose(op @ batch, stacked, rtol=1e-12, atol=1e-25)
    # diagonal() is C[i, i] of the operator.
    unit = np.zeros(n)
    unit[37] = 1.0
    assert op.diagonal()[37] == pytest.approx((op @ unit)[37], rel=1e-12, abs=0.0)
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


@pytest.mark.parametrize("theta", [0.01, 0.3, np.pi / 4, 1.5])
def test_element_cosine_compliance_is_the_alias_sum(theta):
    # The trigamma form of the referee against its alias sum written out
    # (terms fall as m^-2 with alternating signs: 10^6 of them to 1e-12).
    m = np.arange(-10**6, 10**6 + 1)
    shifted = theta + np.pi * m
    alias_sum = theta * np.sin(theta) * np.sum((-1.0) ** m / (shifted * np.abs(shifted)))
    assert element_cosine_compliance(theta) == pytest.approx(alias_sum, rel=1e-10)
    assert element_cosine_compliance(theta) == pytest.approx(
        1.0 - theta**2 / 6.0, abs=0.3 * theta**3)


# Cells of aspect 1 to 512 in both orientations, square elements of 1 um except
# the last two (dx = dy / 4 and dx = 2 dy): (grid, element size (dx, dy) [m]).
COSINE_CELLS = [
    ((64, 64), (1e-6, 1e-6)),
    ((256, 32), (1e-6, 1e-6)),
    ((32, 256), (1e-6, 1e-6)),
    ((512, 8), (1e-6, 1e-6)),
    ((8, 512), (1e-6, 1e-6)),
    ((1024, 4), (1e-6, 1e-6)),
    ((4, 1024), (1e-6, 1e-6)),
    ((2048, 4), (1e-6, 1e-6)),
    ((4, 2048), (1e-6, 1e-6)),
    ((1024, 16), (0.25e-6, 1e-6)),
    ((16, 256), (2e-6, 1e-6)),
]


@pytest.mark.parametrize("grid, spacing", COSINE_CELLS,
                         ids=[f"{g[0]}x{g[1]}-dx/dy={d[0] / d[1]:g}" for g, d in COSINE_CELLS])
def test_periodic_cosine_modes_match_discrete_closed_form(grid, spacing):
    # The lowest cosine mode along each period, uniform along the other, is an
    # eigenvector of the circulant C with eigenvalue R(q d / 2) 2 / (E* q)
    # (element_cosine_compliance). Measured: 1.7e-4 below it on the square
    # cell, at most 2.3e-4 on the elongated ones (continuum replacement of the
    # images beyond the block, images = 3), 5e-4 leaves twice that; a block
    # of (2 images + 1)^2 images on the elongated cells missed by 2.6e-2
    # (aspect 8) to 0.88 (aspect 512).
    nx, ny = grid
    dx, dy = spacing
    op = PeriodicHalfSpace(grid, (nx * dx, ny * dy), E, NU)
    x = np.arange(nx) * dx
    y = np.arange(ny) * dy
    for coordinate, period, width in ((x[None, :], nx * dx, dx), (y[:, None], ny * dy, dy)):
        q = 2.0 * np.pi / period
        pressure = np.broadcast_to(np.cos(q * coordinate), (ny, nx)).ravel()
        compliance = pressure @ (op @ pressure) / (pressure @ pressure)
        expected = element_cosine_compliance(q * width / 2.0) * 2.0 / (E_STAR * q)
        # as a ratio: approx's default abs=1e-12 would pass any m/Pa value
        assert compliance / expected == pytest.approx(1.0, rel=5e-4)


@pytest.mark.parametrize("n_long, n_short", [(512, 64), (512, 8)])
@pytest.mark.parametrize("long_axis", [1, 0], ids=["x-long", "y-long"])
def test_periodic_wavy_contact_is_westergaard(n_long, n_short, long_axis):
    # A wave along the long period of an elongated cell (aspect 8 and 64),
    # uniform along the short one, pressed to a contact 129 elements wide:
    # half-width a = 64.5 dx falls between element centres, so the elements
    # in contact are |s| <= 64 dx unless an edge moves by a whole element.
    # Measured: pressures 0.16 % rms from Westergaard (the element size),
    # peak 2e-5 high; a block of (2 images + 1)^2 images gave 0.9 % and 24 %
    # rms, peak 0.4 % and 19 % high (aspect 8, 64).
    dx = 1e-6
    wavelength = n_long * dx
    s = (np.arange(n_long) - n_long // 2) * dx
    amplitude = 1e-8
    wave = amplitude * (1.0 - np.cos(2.0 * np.pi * s / wavelength))
    if long_axis == 1:
        grid, gap = (n_long, n_short), np.tile(wave, (n_short, 1))
    else:
        grid, gap = (n_short, n_long), np.tile(wave[:, None], (1, n_short))
    op = PeriodicHalfSpace(grid, (grid[0] * dx, grid[1] * dx), E, NU)
    half_width = 64.5 * dx
    p_star = np.pi * E_STAR * amplitude / wavelength
    mean_pressure = p_star * np.sin(np.pi * half_width / wavelength) ** 2
    result = contact.solve(op, gap, mean_pressure=mean_pressure,
                           options=SolverOptions(method="pcg"))
    assert result.converged
    pressure = result.pressure.reshape(gap.shape)
    profile = pressure[0] if long_axis == 1 else pressure[:, 0]
    expected = westergaard_pressure(s, wavelength, half_width, mean_pressure)
    in_contact = np.count_nonzero(profile)
    assert abs(in_contact - 129) <= 2
    rms = np.sqrt(np.mean((profile - expected) ** 2) / np.mean(expected**2))
    assert rms < 5e-3
    assert profile.max() == pytest.approx(expected.max(), rel=1e-3)
