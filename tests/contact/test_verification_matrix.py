"""The verification matrix (issue 42): every operator x method x control x cap, refereed.

Each cell of :func:`test_cell` is one influence operator of
:func:`verification.core_bodies` (dense blocks on the four mesh presets, the hybrid
block, the free, dense, periodic and spectral half-spaces on square and elongated cells,
two bodies dense and matrix-free) x one method x approach or load control x without
or with a hardness cap, solved on seeded cases (light and near-full contact; a cap at
0.6 of the peak pressure, and 0.07 E* against H = 0.1 E*) through ``contact.solve``
with its retries, and refereed by scipy (``nnls``, ``lsq_linear``) and an independent
KKT residual (:mod:`verification`). Every cell must converge to both tolerances or be
refused with its message (pcg takes no cap); a result is flagged converged exactly
when the referees find both tolerances met; load, energy and gaps agree with scipy's.

The closed forms below check the operators under every method and control: the flat
punch on every finite block with nu = 0 (``u = P L / E``, Eq 44), Westergaard's wavy
contact on elongated periodic cells, Hertz on the free half-space, and two bodies equal
to one of the composite modulus (Eq 17-18).

The larger seeded set (more seeds, larger and worse-conditioned blocks, more aspects,
the issue's own cases) runs with ``pytest -m verification``
(``test_verification_seeded.py``); ``benchmarks/verification_matrix.py`` writes the
table of docs/performance/verification.md from both.
"""

from __future__ import annotations

import numpy as np
import pytest
import verification as V

from roughcontact import contact
from roughcontact.contact import SolverOptions, counterface
from roughcontact.contact.references import hertz, sphere_gap, westergaard_pressure
from roughcontact.elasticity.halfspace import (
    PeriodicHalfSpace,
    SpectralHalfSpace,
    halfspace_influence,
)
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.elasticity.operators import halfspace_operator
from roughcontact.elasticity.protocol import DenseInfluence

BODIES = V.core_bodies()
_BUILT: dict = {}


def body(name: str) -> V.Body:
    """The core body ``name``, built once per test process."""
    if name not in _BUILT:
        _BUILT[name] = BODIES[name]()
    return _BUILT[name]


CELLS = [(b, m, c, capped) for b in BODIES for m in V.METHODS for c in V.CONTROLS
         for capped in (False, True)]


@pytest.mark.parametrize("name, method, control, capped", CELLS,
                         ids=[f"{b}-{m}-{c}-{'capped' if k else 'elastic'}"
                              for b, m, c, k in CELLS])
def test_cell(name, method, control, capped):
    chosen = body(name)
    for case in V.cases(chosen, capped=capped):
        if method == "steepest" and case.name == "near full":
            continue  # steepest descent near full contact: 20000 iterations; seeded set
        verdict = V.verify(chosen, method, control, case)
        expected = V.refusal_expected(chosen, method, case)
        if expected:
            assert verdict.refused is not None and expected in verdict.refused, verdict
            continue
        assert verdict.refused is None, verdict
        assert verdict.honest, verdict
        assert verdict.converged, verdict
        assert verdict.agrees, verdict


# ---------------------------------------------------------------------------
# Closed forms


PUNCH_E = 2.0e9
PUNCH_L = 3e-3


@pytest.fixture(scope="module")
def punch_blocks():
    """Blocks with nu = 0 on each mesh preset (4 x 4 elements). Under a uniform pressure
    P each deflects by ``P L / E`` (uniaxial strain, in every mesh's space): the rows of
    the centre-point matrix sum to ``L / E``. Those of its symmetric part (what the
    solver takes) do too on one finite element per contact element (paper, graded), and
    to 0.4 % here where 2 x 2 elements share one (refined, converged: the centre-point
    matrix is not symmetric near free sides, ``unit_modulus_influence``)."""
    out = {}
    for mesh in ("paper", "graded", "refined", "converged"):
        geom = BlockGeometry(size=(1e-3, 1e-3), thickness=PUNCH_L, grid=(4, 4), mesh=mesh,
                             nu=0.0, E=PUNCH_E)
        out[mesh] = DenseInfluence(unit_modulus_influence(geom) / PUNCH_E, geom.element_area,
                                   (4, 4))
    return out


@pytest.mark.parametrize("capped", [False, True], ids=["elastic", "capped"])
@pytest.mark.parametrize("control", V.CONTROLS)
@pytest.mark.parametrize("method", V.METHODS)
def test_flat_punch_on_every_mesh(punch_blocks, method, control, capped):
    # A rigid flat punch on a smooth block: full contact, C p = d 1, so p = E d / L
    # (Eq 44) where the rows sum to L / E; with a cap H below every element's share,
    # p = H everywhere; under load control P, d = P / mean(C^-1 1) (= P L / E).
    flat = np.zeros((4, 4))
    d = 1e-6
    full = PUNCH_E * d / PUNCH_L
    hardness = 0.5 * full if capped else None
    for mesh, op in punch_blocks.items():
        if method == "pcg" and capped:
            with pytest.raises(ValueError, match="does not solve the capped problem"):
                contact.solve(op, flat, d, hardness=hardness, options=SolverOptions(method=method))
            continue
        unit = np.linalg.solve(op.matrix, np.ones(16))  # C^-1 1 [Pa/m], numpy
        exact_rows = mesh in ("paper", "graded")
        assert unit.mean() * PUNCH_L / PUNCH_E == pytest.approx(
            1.0, rel=1e-9 if exact_rows else 1e-2), mesh
        if control == "approach":
            result = contact.solve(op, flat, d, hardness=hardness,
                                   options=SolverOptions(method=method, tol=1e-12))
            expected_p, expected_d = (hardness if capped else d * unit), d
        else:
            load = 0.25 * full
            result = contact.solve(op, flat, mean_pressure=load, hardness=hardness,
                                   options=SolverOptions(method=method, tol=1e-12))
            expected_p, expected_d = load * unit / unit.mean(), load / unit.mean()
        assert result.converged, (mesh, result.residual)
        assert result.real_area_fraction == 1.0
        np.testing.assert_allclose(result.pressure.ravel(), np.broadcast_to(expected_p, 16),
                                   rtol=1e-7, err_msg=mesh)
        assert result.approach / expected_d == pytest.approx(1.0, rel=1e-7), mesh
        if exact_rows:
            np.testing.assert_allclose(result.pressure, hardness if capped and
                                       control == "approach" else result.nominal_pressure,
                                       rtol=1e-7, err_msg=mesh)


WAVE_E, WAVE_NU = 2.0e9, 0.3


@pytest.mark.parametrize("control", V.CONTROLS)
@pytest.mark.parametrize("method", V.METHODS)
@pytest.mark.parametrize("kind", ["periodic 64:4", "spectral 4:64"])
def test_westergaard_on_elongated_cells(kind, method, control):
    # A wave along the long period of an 16:1 cell, uniform along the short one, pressed
    # to a contact 33 elements wide (a = 16.5 dx falls between element centres).
    n, dx, amplitude = 64, 1e-6, 1e-8
    wavelength = n * dx
    s = (np.arange(n) - n // 2) * dx
    wave = amplitude * (1.0 - np.cos(2.0 * np.pi * s / wavelength))
    if kind.startswith("periodic"):
        op = PeriodicHalfSpace((n, 4), (n * dx, 4 * dx), WAVE_E, WAVE_NU)
        gap = np.tile(wave, (4, 1))
    else:
        op = SpectralHalfSpace((4, n), (4 * dx, n * dx), WAVE_E, WAVE_NU)
        gap = np.tile(wave[:, None], (1, 4))
    e_star = WAVE_E / (1.0 - WAVE_NU**2)
    half_width = 16.5 * dx
    load = np.pi * e_star * amplitude / wavelength * np.sin(np.pi * half_width / wavelength) ** 2
    if control == "load":
        result = contact.solve(op, gap, mean_pressure=load, options=SolverOptions(method=method))
    else:
        at_load = contact.solve(op, gap, mean_pressure=load, options=SolverOptions(method="exact"))
        result = contact.solve(op, gap, at_load.approach, options=SolverOptions(method=method))
    assert result.converged
    profile = result.pressure[0] if kind.startswith("periodic") else result.pressure[:, 0]
    expected = westergaard_pressure(s, wavelength, half_width, load)
    assert abs(np.count_nonzero(profile) - 33) <= 2
    rms = np.sqrt(np.mean((profile - expected) ** 2) / np.mean(expected**2))
    assert rms < 0.02  # measured: below 1e-2 for every method (element size)
    assert result.nominal_pressure / load == pytest.approx(1.0, rel=1e-6)


HERTZ_N, HERTZ_DX, HERTZ_RADIUS = 24, 1e-6, 1e-2


@pytest.mark.parametrize("control", V.CONTROLS)
@pytest.mark.parametrize("method", V.METHODS)
@pytest.mark.parametrize("kind", ["free", "dense"])
def test_hertz_on_the_half_space(kind, method, control):
    # A sphere on the free half-space (matrix-free FFT of Love's kernel, E = 1) and on
    # its dense matrix: contact radius and peak pressure of Hertz at the computed load,
    # within 5 % (a contact 16 elements across).
    nu = 0.3
    e_star = 1.0 / (1.0 - nu**2)
    grid = (HERTZ_N, HERTZ_N)
    size = (HERTZ_N * HERTZ_DX, HERTZ_N * HERTZ_DX)
    op = halfspace_operator(grid, size, nu) if kind == "free" else DenseInfluence(
        halfspace_influence(grid, size, 1.0, nu), HERTZ_DX**2, grid)
    gap = sphere_gap(HERTZ_N, HERTZ_DX, HERTZ_RADIUS)
    approach = (8 * HERTZ_DX) ** 2 / HERTZ_RADIUS
    if control == "approach":
        result = contact.solve(op, gap, approach, element_area=HERTZ_DX**2,
                               options=SolverOptions(method=method))
    else:
        load = 4.0 / 3.0 * e_star * HERTZ_RADIUS**0.5 * approach**1.5 / size[0] / size[1]
        result = contact.solve(op, gap, mean_pressure=load, element_area=HERTZ_DX**2,
                               options=SolverOptions(method=method))
    assert result.converged
    expected = hertz(result.load, HERTZ_RADIUS, e_star)
    a = np.sqrt(np.count_nonzero(result.pressure) * HERTZ_DX**2 / np.pi)
    assert a / expected.a == pytest.approx(1.0, rel=0.05)
    assert result.max_pressure / expected.p0 == pytest.approx(1.0, rel=0.05)
    assert expected.d / result.approach == pytest.approx(1.0, rel=0.05)


@pytest.mark.parametrize("control", V.CONTROLS)
@pytest.mark.parametrize("method", V.METHODS)
def test_two_half_spaces_are_one_of_the_composite_modulus(method, control):
    # Eq 17-18: bodies of E1 = 2 GPa, nu 0.3 and E2 = 6 GPa, nu 0.2 pressed together
    # are one half-space of 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2; Love's matrix is
    # (1 - nu^2)/E times a shape, so the sum is that of the composite body exactly.
    grid, size = (10, 10), (1.5e-3, 1.5e-3)
    area = (size[0] / 10) ** 2
    first = halfspace_influence(grid, size, 2.0e9, 0.3)
    second = halfspace_influence(grid, size, 6.0e9, 0.2)
    composite = (1 - 0.3**2) / 2.0e9 + (1 - 0.2**2) / 6.0e9
    single = DenseInfluence(halfspace_influence(grid, size, 1.0 / composite, 0.0), area, grid)
    pair = counterface.equivalent_operator(DenseInfluence(first, area, grid),
                                                   DenseInfluence(second, area, grid))
    chosen = V.Body("pair", pair, 1.0 / composite, grid, size)
    case = V.cases(chosen, capped=False)[0]
    keys = ({"approach": case.approach} if control == "approach"
            else {"mean_pressure": case.mean_pressure})
    both = contact.solve(pair, case.gap, **keys, options=SolverOptions(method=method))
    one = contact.solve(single, case.gap, **keys, options=SolverOptions(method=method))
    assert both.converged and one.converged
    np.testing.assert_array_equal(both.contact_set, one.contact_set)
    assert np.abs(both.pressure - one.pressure).max() <= 1e-6 * one.max_pressure
    assert both.approach / one.approach == pytest.approx(1.0, rel=1e-8)
