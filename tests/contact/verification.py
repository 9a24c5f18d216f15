"""The verification matrix of the contact solver (issue 42): its operators, cases and referees.

Every influence operator the library offers x every method that accepts it x approach
and load control x with and without a hardness cap is a *cell*. A cell is solved on
seeded cases (:func:`cases`) through the public API (``contact.solve``) and checked by
referees that share no code with the solver:

- the KKT residual recomputed here from the dense matrix, with this file's own formula
  (Eq 19-22; with a cap the natural residual of the box problem), and the load error
  ``|mean p - P| / P``: a result flagged converged must meet ``tol`` and ``load_tol``
  by this measure, and one flagged unconverged must miss one of them;
- ``scipy.optimize.nnls`` (uncapped) or ``scipy.optimize.lsq_linear`` (method
  ``"bvls"``, capped) on the least-squares form of Eq 27, ``min |L^T p - L^-1 b|``
  with ``C = L L^T`` (Cholesky, scipy) and ``b = d - f``, at the approach the solver
  returned: its load, its complementary energy and its gaps must agree. An operator
  with ``C 1 = 0`` (periodic and spectral half-spaces) is only semidefinite; its
  problem at ``d`` equals that of ``C + k 1 1^T / n`` at ``d + k mean(p)`` for the
  solution ``p`` (``C 1 = 0`` makes ``(C + k 1 1^T/n) p = C p + k mean(p) 1``), which
  is definite, so the referee solves that and must find ``p`` again.

Closed forms check the operators themselves (``test_verification_matrix.py``): a flat
punch on every finite block with nu = 0 (``p = E d / L``, Eq 44), the compliance of a
cosine mode on periodic cells of several aspects, Westergaard's wavy contact, Hertz.

The cases include the hard ones the issue names: ill-conditioned blocks (the paper's
mesh under a thick block: condition number 1e5-1e8), elongated periodic cells, contact
near 100 % (where Polonsky-Keer solvers are known to converge poorly, ContactMechanics
issue 3), and a load of 0.07 E* against a hardness of 0.1 E* (ContactMechanics issue
68: no convergence above p = 0.07 E* with H = 0.1 E*).

Units SI: lengths m, pressures Pa, compliances m/Pa. Operators built with a unit
modulus (the matrix-free half-space and hybrid blocks) are taken as E = 1 Pa bodies.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Callable

import numpy as np
import scipy.linalg
import scipy.optimize

from roughcontact import contact
from roughcontact.contact import SolverOptions, counterface
from roughcontact.elasticity.halfspace import (
    PeriodicHalfSpace,
    SpectralHalfSpace,
    halfspace_influence,
)
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.elasticity.operators import block_operator, halfspace_operator
from roughcontact.elasticity.protocol import DenseInfluence

TOL = 1e-10
LOAD_TOL = 1e-8
METHODS = ("steepest", "cg", "pcg", "pivot", "exact", "auto")
CONTROLS = ("approach", "load")
#: The referee's agreement: load, energy (relative), gaps (of the gap scale).
LOAD_RTOL = 1e-6
ENERGY_RTOL = 1e-8
GAP_RTOL = 1e-6


@dataclasses.dataclass(frozen=True)
class Body:
    """An operator of the matrix: the operator, its effective modulus ``E*`` [Pa], its
    grid ``(nx, ny)`` and plan size ``(Lx, Ly)`` [m]."""

    name: str
    operator: object
    modulus: float
    grid: tuple[int, int]
    size: tuple[float, float]

    @property
    def n(self) -> int:
        return self.grid[0] * self.grid[1]

    @functools.cached_property
    def matrix(self) -> np.ndarray:
        """The dense ``C`` [m/Pa]: the operator's own or its columns ``C e_j``."""
        held = getattr(self.operator, "matrix", None)
        if isinstance(self.operator, np.ndarray):
            held = self.operator
        if held is not None:
            return np.asarray(held, dtype=float)
        columns = np.asarray(self.operator.matvec(np.eye(self.n)), dtype=float)
        return 0.5 * (columns + columns.T)

    @property
    def zero_mean(self) -> bool:
        """``C 1 = 0``: the periodic and spectral half-spaces without a mean compliance."""
        return getattr(self.operator, "mean_compliance", None) == 0.0


def _block(mesh: str, grid, thickness: float, nu: float, E: float = 2.0e9,
           size=(1.5e-3, 1.5e-3)) -> tuple:
    geom = BlockGeometry(size=size, thickness=thickness, grid=grid, mesh=mesh, nu=nu, E=E)
    matrix = unit_modulus_influence(geom) / E
    return DenseInfluence(matrix, geom.element_area, grid), E / (1.0 - nu**2)


def _body(name: str, build: Callable[[], tuple], grid, size) -> Body:
    operator, modulus = build()
    return Body(name, operator, modulus, tuple(grid), tuple(size))


SQUARE = (1.5e-3, 1.5e-3)


def core_bodies() -> dict[str, Callable[[], Body]]:
    """The operators of the core matrix (``make test``), built on first use: every kind
    of influence operator, on grids of 64-144 elements."""
    nu = 0.3
    love = 1.0 / (1.0 - nu**2)  # E* of a unit-modulus body [Pa]
    grid = (10, 10)
    return {
        # the paper's mesh under a thick block: condition number 6e5 at 10 x 10
        "block paper": lambda: _body("block paper", lambda: _block("paper", grid, 10e-3, 0.0),
                                     grid, SQUARE),
        "block graded": lambda: _body("block graded",
                                      lambda: _block("graded", grid, 5e-3, nu), grid, SQUARE),
        "block refined": lambda: _body("block refined",
                                       lambda: _block("refined", (8, 8), 2e-3, nu), (8, 8),
                                       SQUARE),
        "block converged": lambda: _body("block converged",
                                         lambda: _block("converged", (8, 8), 2e-3, nu), (8, 8),
                                         SQUARE),
        "hybrid block": lambda: _body(
            "hybrid block", lambda: (block_operator(
                BlockGeometry(size=SQUARE, thickness=2e-3, grid=(12, 12), mesh="refined",
                              nu=nu), coarse_grid=(4, 4)), love), (12, 12), SQUARE),
        "free half-space": lambda: _body(
            "free half-space", lambda: (halfspace_operator((12, 12), SQUARE, nu), love),
            (12, 12), SQUARE),
        "dense half-space": lambda: _body(
            "dense half-space", lambda: (DenseInfluence(
                halfspace_influence((10, 10), SQUARE, 2.0e9, nu), (SQUARE[0] / 10) ** 2,
                (10, 10)), 2.0e9 / (1 - nu**2)), (10, 10), SQUARE),
        "periodic half-space": lambda: _body(
            "periodic half-space", lambda: (PeriodicHalfSpace((12, 12), SQUARE, 2.0e9, nu),
                                            2.0e9 / (1 - nu**2)), (12, 12), SQUARE),
        "periodic 8:1": lambda: _body(
            "periodic 8:1", lambda: (PeriodicHalfSpace((32, 4), (1.6e-3, 0.2e-3), 2.0e9, nu),
                                     2.0e9 / (1 - nu**2)), (32, 4), (1.6e-3, 0.2e-3)),
        "spectral half-space": lambda: _body(
            "spectral half-space", lambda: (SpectralHalfSpace((12, 12), SQUARE, 2.0e9, nu),
                                            2.0e9 / (1 - nu**2)), (12, 12), SQUARE),
        "spectral 1:8": lambda: _body(
            "spectral 1:8", lambda: (SpectralHalfSpace((4, 32), (0.2e-3, 1.6e-3), 2.0e9, nu),
                                     2.0e9 / (1 - nu**2)), (4, 32), (0.2e-3, 1.6e-3)),
        # two bodies (Eq 17-18): a dense pair, and a matrix-free one
        "pair dense": lambda: _body("pair dense", _dense_pair, (8, 8), SQUARE),
        "pair matrix-free": lambda: _body("pair matrix-free", _matrix_free_pair, (12, 12),
                                          SQUARE),
    }


def _dense_pair():
    block, modulus = _block("refined", (8, 8), 2e-3, 0.3)
    half = DenseInfluence(halfspace_influence((8, 8), SQUARE, 6.0e9, 0.3), block.element_area,
                          (8, 8))
    pair = counterface.equivalent_operator(block, half)
    # 1/E*_pair = 1/E*_1 + 1/E*_2 (nearly: the block is finite)
    return pair, 1.0 / (1.0 / modulus + (1 - 0.3**2) / 6.0e9)


def _matrix_free_pair():
    first = halfspace_operator((12, 12), SQUARE, 0.3)
    second = counterface.scaled(halfspace_operator((12, 12), SQUARE, 0.0), 0.5)
    pair = counterface.equivalent_operator(first, second)
    return pair, 1.0 / ((1 - 0.3**2) + 0.5)


# ---------------------------------------------------------------------------
# Cases


@dataclasses.dataclass(frozen=True)
class Case:
    """One problem of a cell: the gaps ``f`` (ny, nx) [m], the approach [m] and the load
    [Pa] of its solution, and the cap [Pa] (None: uncapped)."""

    name: str
    gap: np.ndarray
    approach: float
    mean_pressure: float
    hardness: float | None


def rough_gap(body: Body, seed: int, slope: float) -> np.ndarray:
    """A seeded Gaussian surface's initial separation ``max z - z`` [m] on ``body``'s grid,
    rms slope ``slope`` [-], correlation length about 3 elements."""
    nx, ny = body.grid
    rng = np.random.default_rng(seed)
    qx = np.fft.rfftfreq(nx) * nx / body.size[0]
    qy = np.fft.fftfreq(ny) * ny / body.size[1]
    dx = body.size[0] / nx
    q = np.hypot(qx[None, :], qy[:, None]) * 3.0 * dx
    z = np.fft.irfft2(np.fft.rfft2(rng.standard_normal((ny, nx))) / (1.0 + q**2) ** 1.5,
                      s=(ny, nx))
    gx = np.diff(z, axis=1) / dx
    z *= slope / np.sqrt(np.mean(gx**2) * 2.0)
    return z.max() - z


def _exact(body: Body, gap, *, approach=None, mean_pressure=None, hardness=None):
    """Block principal pivoting's solution (a case's target, not a referee)."""
    result = contact.solve(body.operator, gap, approach, mean_pressure=mean_pressure,
                           hardness=hardness, element_area=body.size[0] * body.size[1] / body.n,
                           options=SolverOptions(method="exact", tol=1e-12))
    if not result.converged:
        raise RuntimeError(f"{body.name}: the case's exact solution did not converge "
                           f"(KKT residual {result.residual:.3g})")
    return result


def _approach_for_area(body: Body, gap, area: float) -> float:
    """The approach [m] at which the exact solution's real area fraction first reaches
    ``area`` (bisection on the rigid interference)."""
    lo, hi = float(gap.min()), float(np.quantile(gap, 0.999))
    if body.zero_mean:
        hi = min(hi, float(gap.mean()) * (1 - 1e-9))
    while not body.zero_mean and _exact(body, gap, approach=hi).real_area_fraction < area:
        lo, hi = hi, hi + 2.0 * (hi - float(gap.min()))  # a block deflects: further
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if _exact(body, gap, approach=mid).real_area_fraction < area:
            lo = mid
        else:
            hi = mid
    return hi


_CASES: dict[tuple[str, int], tuple] = {}


def _cases_of(body: Body, seed: int) -> tuple[Case, ...]:
    gap = rough_gap(body, seed, slope=0.02)
    out = []
    for label, area in (("light", 0.1), ("near full", 0.95)):
        d = _approach_for_area(body, gap, area)
        out.append(Case(label, gap, d, _exact(body, gap, approach=d).nominal_pressure, None))
    light = out[0]
    uncapped = _exact(body, gap, approach=light.approach)
    hardness = 0.6 * float(uncapped.max_pressure)
    capped = _exact(body, gap, approach=light.approach, hardness=hardness)
    out.append(Case("light, capped", gap, light.approach, capped.nominal_pressure, hardness))
    # ContactMechanics issue 68: P = 0.07 E* against H = 0.1 E*, on a steep surface
    steep = rough_gap(body, seed, slope=0.3)
    hardness, load = 0.1 * body.modulus, 0.07 * body.modulus
    hard = _exact(body, steep, mean_pressure=load, hardness=hardness)
    out.append(Case("P 0.07 E*, H 0.1 E*", steep, hard.approach, load, hardness))
    return tuple(out)


def cases(body: Body, seed: int = 0, capped: bool | None = None) -> tuple[Case, ...]:
    """The seeded cases of ``body``: light (10 % contact) and near-full (95 %) contact
    uncapped; capped at 0.6 of the light case's peak pressure, and the high load against
    a hardness (above). ``capped`` selects the uncapped or capped ones."""
    key = (body.name, seed)
    if key not in _CASES:
        _CASES[key] = _cases_of(body, seed)
    found = _CASES[key]
    if capped is None:
        return found
    return tuple(case for case in found if (case.hardness is not None) == capped)


# ---------------------------------------------------------------------------
# Referees


def kkt(matrix, gap, approach, pressure, hardness=None) -> float:
    """The KKT residual of Eq 27 [-], computed here: ``max |C_ii p - clip(C_ii p - g, 0,
    C_ii H)| / max |d - f|`` with ``g = C p + f - d`` (``H`` infinite without a cap)."""
    f = gap.reshape(-1)
    p = pressure.reshape(-1)
    g = matrix @ p + f - approach
    c = np.diag(matrix)
    cap = np.inf if hardness is None else hardness
    natural = c * p - np.clip(c * p - g, 0.0, c * cap)
    return float(np.abs(natural).max() / max(np.abs(approach - f).max(), 1e-300))


def energy(matrix, gap, approach, pressure) -> float:
    """The complementary energy ``1/2 p.C p - p.(d - f)`` of Eq 27 [m Pa]."""
    p = pressure.reshape(-1)
    return float(0.5 * p @ matrix @ p - p @ (approach - gap.reshape(-1)))


def reference(body: Body, gap, approach: float, hardness, mean_pressure: float) -> np.ndarray:
    """scipy's solution [Pa] of Eq 27 at ``approach`` [m] (module docstring); for an
    operator with ``C 1 = 0`` the definite problem with ``k 1 1^T / n`` added, at
    ``approach + k mean_pressure`` (``mean_pressure`` [Pa] the solution's)."""
    matrix, b = body.matrix, approach - gap.reshape(-1)
    if body.zero_mean:
        k = float(np.diag(matrix).mean())
        matrix = matrix + k / body.n
        b = b + k * mean_pressure
    factor = scipy.linalg.cholesky(matrix, lower=True)
    design = factor.T
    target = scipy.linalg.solve_triangular(factor, b, lower=True)
    if hardness is None:
        pressure, _ = scipy.optimize.nnls(design, target, maxiter=50 * body.n)
        return pressure
    return scipy.optimize.lsq_linear(design, target, bounds=(0.0, hardness), method="bvls",
                                     tol=1e-15, lsmr_tol=None).x


@dataclasses.dataclass(frozen=True)
class Verdict:
    """One cell on one case: what the solver said and what the referees found."""

    body: str
    method: str
    control: str
    case: str
    refused: str | None = None
    converged: bool = False
    kkt: float = np.nan
    load_error: float = np.nan
    reference_load_error: float = np.nan
    energy_error: float = np.nan
    gap_error: float = np.nan
    iterations: int = 0
    seconds: float = 0.0

    @property
    def honest(self) -> bool:
        """The flag means what it says: converged iff both tolerances are met (by the
        referees' measure, with a margin of 1 % for the residual's rounding)."""
        if self.refused:
            return True
        met = self.kkt <= 1.01 * TOL and self.load_error <= LOAD_TOL
        return self.converged == met

    @property
    def agrees(self) -> bool:
        """The solution agrees with scipy's (load, energy, gaps) where it converged."""
        return self.refused is not None or not self.converged or (
            self.reference_load_error <= LOAD_RTOL and self.energy_error <= ENERGY_RTOL
            and self.gap_error <= GAP_RTOL)


def verify(body: Body, method: str, control: str, case: Case, retries: bool = True) -> Verdict:
    """Solve ``case`` on ``body`` with ``method`` under ``control`` through
    ``contact.solve`` and check it (module docstring); ``retries=False``: the method's
    own result."""
    area = body.size[0] * body.size[1] / body.n
    keys = dict(body=body.name, method=method, control=control, case=case.name)
    control_keys = ({"approach": case.approach} if control == "approach"
                    else {"mean_pressure": case.mean_pressure})
    start = time.perf_counter()
    try:
        result = contact.solve(body.operator, case.gap, hardness=case.hardness,
                               element_area=area, **control_keys,
                               options=SolverOptions(method=method, tol=TOL, load_tol=LOAD_TOL,
                                                     retries=retries))
    except ValueError as error:
        return Verdict(**keys, refused=str(error))
    seconds = time.perf_counter() - start
    d, p = result.approach, result.pressure
    load = float(p.mean())
    load_error = 0.0 if control == "approach" else abs(load - case.mean_pressure) / \
        case.mean_pressure
    referee = reference(body, case.gap, d, case.hardness, load)
    matrix = body.matrix
    scale = np.abs(d - case.gap).max()
    v, v_ref = energy(matrix, case.gap, d, p), energy(matrix, case.gap, d, referee)
    gap = matrix @ p.reshape(-1) + case.gap.reshape(-1) - d
    gap_ref = matrix @ referee + case.gap.reshape(-1) - d
    return Verdict(
        **keys, converged=bool(result.converged),
        kkt=kkt(matrix, case.gap, d, p, case.hardness), load_error=load_error,
        reference_load_error=abs(load - referee.mean()) / max(referee.mean(), 1e-300),
        energy_error=(v - v_ref) / max(abs(v_ref), 1e-300),
        gap_error=float(np.abs(gap - gap_ref).max() / scale),
        iterations=int(result.iterations), seconds=seconds)


def refusal_expected(body: Body, method: str, case: Case) -> str | None:
    """The message a cell must be refused with, or None: pcg solves no capped problem."""
    if method == "pcg" and case.hardness is not None:
        return "does not solve the capped problem"
    return None


# ---------------------------------------------------------------------------
# The seeded set (pytest -m verification; benchmarks/verification_matrix.py)


def random_block(seed: int) -> Body:
    """A dense block drawn from ``seed``: mesh preset, grid 10-20 per side (square or
    not), plan size 1-9 mm, thickness 0.3-5 times the plan size, nu (0 on the paper
    mesh, else 0-0.45): condition numbers from 1e1 (refined) to 1e7 (paper, thick)."""
    rng = np.random.default_rng(4200 + seed)
    mesh = ("paper", "graded", "refined", "converged")[seed % 4]
    side = int(rng.integers(10, 21)) if mesh != "converged" else int(rng.integers(6, 11))
    grid = (side, int(rng.choice([side, max(4, side // 2)])))
    width = float(rng.uniform(1e-3, 9e-3))
    size = (width, width * grid[1] / grid[0])
    thickness = width * float(rng.uniform(0.3, 5.0))
    nu = 0.0 if mesh == "paper" else float(rng.uniform(0.0, 0.45))
    name = f"random block {seed} ({mesh} {grid[0]}x{grid[1]}, L/w {thickness / width:.1f})"
    return _body(name, lambda: _block(mesh, grid, thickness, nu, size=size), grid, size)


def seeded_bodies() -> dict[str, Callable[[], Body]]:
    """The operators of the seeded set: the core ones, the issue's 32 x 32 paper-mesh
    block (condition number 6e7), eight random blocks, and periodic and spectral cells
    of aspect 64 (the hybrid block and the pairs as in the core)."""
    nu = 0.3
    out = dict(core_bodies())
    out["block paper 32 (issue 42)"] = lambda: _body(
        "block paper 32 (issue 42)",
        lambda: _block("paper", (32, 32), 10e-3, 0.0, E=5.11e8, size=(4.8e-3, 4.8e-3)),
        (32, 32), (4.8e-3, 4.8e-3))
    for seed in range(8):
        out[f"random block {seed}"] = functools.partial(random_block, seed)
    out["periodic 64:1"] = lambda: _body(
        "periodic 64:1", lambda: (PeriodicHalfSpace((256, 4), (2.56e-3, 0.04e-3), 2.0e9, nu),
                                  2.0e9 / (1 - nu**2)), (256, 4), (2.56e-3, 0.04e-3))
    out["spectral 1:64"] = lambda: _body(
        "spectral 1:64", lambda: (SpectralHalfSpace((4, 256), (0.04e-3, 2.56e-3), 2.0e9, nu),
                                  2.0e9 / (1 - nu**2)), (4, 256), (0.04e-3, 2.56e-3))
    return out
