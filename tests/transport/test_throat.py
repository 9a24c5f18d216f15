"""The conductance keeps its precision near sealing (issue 49).

A field crossed by a closed column of contact but for one throat cell of 1e-5 of the
open gap passes about 1e-15 of the open field's flow: read from the inlet's flow,
``sum t (1 - p)``, it lost its sign. The referees share no code with the flow module:

- an exact solve in rational arithmetic (``fractions.Fraction``) of the five-point
  system assembled here (harmonic faces, square elements), on 12 x 12 and 16 x 16;
- on 32 x 32 (too slow in exact arithmetic: 26 s a field) Rayleigh's monotonicity
  law: shorting every element but the throat (its two faces in series) bounds ``K``
  from above, keeping only the straight path along the throat's row bounds it from
  below; the bounds, evaluated exactly, lie 3e-14 apart relatively.
"""

import logging
from fractions import Fraction

import numpy as np
import pytest
import scipy.sparse.linalg as spla

from roughcontact.contact.probes import SolvedFields
from roughcontact.transport import (
    PERIODIC,
    SEALED,
    BandedCholesky,
    DirectSolver,
    FlowProbe,
    FlowSetup,
    solve_flow,
)

THROAT = Fraction(1, 100_000)  # the throat's gap over the open gap


def _throat_field(n: int, column: int, row: int, throat=THROAT) -> list[list[Fraction]]:
    """An n x n field of gap 1 crossed by a closed ``column`` but for one cell at ``row``."""
    gap = [[Fraction(1)] * n for _ in range(n)]
    for i in range(n):
        gap[i][column] = Fraction(0)
    gap[row][column] = throat
    return gap


def _exact_conductance(gap, periodic: bool) -> Fraction:
    """K [gap^3] of a square-element field, flow along x, by Gaussian elimination in
    rational arithmetic of the five-point system (harmonic faces; half faces of 2 k at
    inlet and outlet), unknowns column by column; K from the inlet's flow, exact here."""
    ny, nx = len(gap), len(gap[0])
    k = [[g**3 for g in row] for row in gap]
    number = {}
    for j in range(nx):
        for i in range(ny):
            if k[i][j]:
                number[i, j] = len(number)
    rows = [{} for _ in number]
    rhs = [Fraction(0)] * len(number)

    def couple(first, second):
        ka, kb = k[first[0]][first[1]], k[second[0]][second[1]]
        if first not in number or second not in number or first == second:
            return
        t = 2 * ka * kb / (ka + kb)
        a, b = number[first], number[second]
        rows[a][a] = rows[a].get(a, 0) + t
        rows[b][b] = rows[b].get(b, 0) + t
        rows[a][b] = rows[a].get(b, 0) - t
        rows[b][a] = rows[b].get(a, 0) - t

    for (i, j), a in number.items():
        if j + 1 < nx:
            couple((i, j), (i, j + 1))
        if i + 1 < ny or periodic:
            couple((i, j), ((i + 1) % ny, j))
        for end, value in ((0, 1), (nx - 1, 0)):
            if j == end:
                rows[a][a] = rows[a].get(a, 0) + 2 * k[i][j]
                rhs[a] += 2 * k[i][j] * value
    for c in range(len(rows)):
        for r in [r for r in rows[c] if r > c]:
            factor = rows[r].pop(c) / rows[c][c]
            for col, value in rows[c].items():
                if col > c:
                    rows[r][col] = rows[r].get(col, 0) - factor * value
            rhs[r] -= factor * rhs[c]
    p = [Fraction(0)] * len(rows)
    for c in reversed(range(len(rows))):
        p[c] = (rhs[c] - sum(v * p[col] for col, v in rows[c].items() if col > c)) / rows[c][c]
    inflow = sum(2 * k[i][0] * (1 - p[number[i, 0]]) for i in range(ny) if (i, 0) in number)
    return inflow * Fraction(nx, ny)


def _computed(gap, sides, solver=None) -> float:
    array = np.array([[float(g) for g in row] for row in gap])
    setup = FlowSetup((1.0, 1.0), "x", sides) if solver is None else FlowSetup(
        (1.0, 1.0), "x", sides, solver=solver)
    result = solve_flow(array, setup)
    assert result.connected and result.balanced
    return float(result.conductance)


@pytest.mark.parametrize("sides", [SEALED, PERIODIC], ids=lambda s: s.name)
@pytest.mark.parametrize(("n", "column", "row"), [(16, 8, 8), (12, 3, 0), (12, 9, 11)])
def test_throat_against_an_exact_rational_solve(sides, n, column, row):
    gap = _throat_field(n, column, row)
    exact = _exact_conductance(gap, periodic=sides is PERIODIC)
    assert abs(float(exact) / float(THROAT) ** 3 - 1.0) < 1e-2  # about g_t^3
    for solver in (None, BandedCholesky()):
        assert abs(_computed(gap, sides, solver) / float(exact) - 1.0) < 1e-9


def _rayleigh_bounds(n: int) -> tuple[Fraction, Fraction]:
    """Bounds on K of an n x n throat field (square elements, K = Q): the throat's two
    harmonic faces in series, alone (every other conductance infinite: an upper bound)
    or with the n - 2 unit faces and two half faces of the straight path along its row
    (every other conductance zero: a lower bound)."""
    k = THROAT**3
    throat = 2 * (1 + k) / (2 * k)  # two faces of 2 k / (1 + k) in series
    return 1 / (throat + (n - 2)), 1 / throat


@pytest.mark.parametrize("sides", [SEALED, PERIODIC], ids=lambda s: s.name)
def test_throat_on_32_by_32_within_rayleighs_bounds(sides):
    low, high = _rayleigh_bounds(32)
    assert float((high - low) / low) < 1e-13
    middle = float((low + high) / 2)
    for column, row in [(16, 16), (28, 16), (22, 31), (4, 16), (7, 31), (1, 0), (30, 5)]:
        computed = _computed(_throat_field(32, column, row), sides)
        assert abs(computed / middle - 1.0) < 1e-9, (column, row)


def test_a_chain_of_rounding_size_gaps_gets_its_series_conductance_after_refinement():
    """Two open pools joined by a chain of eight cells of 1e-12 of the open gap: the first
    solve's noise in the pools (rounding of p near 1 and 0) outweighs the chain's
    dissipation; refined, the conductance is the chain's series conductance."""
    gap = np.zeros((6, 12))
    gap[:, :2] = gap[:, -2:] = 1.0
    gap[3, 2:-2] = 1e-12
    k = Fraction(1, 10**12) ** 3
    # two faces pool-chain of 2 k / (1 + k), seven chain faces of k, in series; pools
    # and half faces add at most 10 units of resistance (1e-35 relative)
    series = 1 / (2 * (1 + k) / (2 * k) + 7 / k)
    for sides in (SEALED, PERIODIC):
        result = solve_flow(gap, FlowSetup((1.0, 1.0), "x", sides))
        assert result.refined and result.balanced and result.connected
        expected = float(series * Fraction(12, 6))  # K = Q Lx / Ly
        assert abs(float(result.conductance) / expected - 1.0) < 1e-9


class _Sloppy(DirectSolver):
    """A linear solver that returns half the solution (a solve that lost its way)."""

    def solve(self, matrix, rhs):
        return 0.5 * spla.spsolve(matrix.tocsc(), rhs), 0


def test_a_solve_off_balance_is_retried_then_flagged(caplog):
    rng = np.random.default_rng(5)
    gap = np.maximum(rng.normal(size=(2, 10, 12)) + 1.0, 0.0)
    result = solve_flow(gap, FlowSetup((1.0, 1.0), solver=_Sloppy()))
    assert result.connected.all() and result.refined.all()
    assert not result.balanced.any() and (result.balance > 1e-3).all()
    # the probe records the balance, the conductance as NaN, and says so
    probe = FlowProbe(directions=("x",), sides="periodic", solver=_Sloppy())
    fields = SolvedFields(np.zeros_like(gap), gap, np.ones(2), (1.0, 1.0), True)
    with caplog.at_level(logging.WARNING, logger="roughcontact.transport"):
        columns = probe.measure(fields)
    assert np.isnan(columns["flow_conductance_x"]).all()
    assert np.isnan(columns["flow_factor_x"]).all()
    np.testing.assert_array_equal(columns["flow_balance_x"], result.balance)
    assert columns["flow_connected_x"].all()
    assert "flow along x off balance for 2 of 2 fields" in caplog.text
    assert "flow_balance_x" in caplog.text
    # a good solve of the same fields: balanced, nothing flagged, no warning
    caplog.clear()
    good = FlowProbe(directions=("x",), sides="periodic").measure(fields)
    assert (good["flow_conductance_x"] > 0).all() and (good["flow_balance_x"] < 1e-10).all()
    assert "off balance" not in caplog.text


def test_the_band_solvers_fallback_is_named_and_logged(caplog):
    """Periodic sides couple the first row and the last (11 rows of 12 apart: bandwidth
    132): too wide for the band Cholesky solver, whose fallback answers; sealed sides
    keep the band at the 12 elements along the flow."""
    gap = np.ones((2, 12, 12))
    with caplog.at_level(logging.DEBUG, logger="roughcontact.transport"):
        wide = solve_flow(gap, FlowSetup((1.0, 1.0), "x", PERIODIC,
                                         solver=BandedCholesky(max_bandwidth=8)))
    assert (wide.solved_by == "DirectSolver").all()
    assert "bandwidth 132 over BandedCholesky's 8; solved by DirectSolver" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.DEBUG, logger="roughcontact.transport"):
        narrow = solve_flow(gap, FlowSetup((1.0, 1.0), "x", SEALED,
                                           solver=BandedCholesky(max_bandwidth=12)))
    assert (narrow.solved_by == "BandedCholesky").all() and "solved by" not in caplog.text
    np.testing.assert_allclose(wide.conductance, 1.0, rtol=1e-12)  # a flat channel
    np.testing.assert_allclose(narrow.conductance, 1.0, rtol=1e-12)
