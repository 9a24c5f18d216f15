"""Flow through the contact gap: the Reynolds equation with the local cubic law.

The method
----------
*Equation.* Steady, incompressible, laminar flow of a Newtonian fluid of
viscosity ``eta`` [Pa s] through a thin gap ``g(x, y) >= 0`` [m] between two
surfaces at rest. Across the gap the velocity profile is parabolic, so the flow
per unit width [m^2/s] follows the local cubic law and conserves mass
(the Reynolds equation without sliding or squeeze terms)::

    q = -(g^3 / (12 eta)) grad p,        div q = 0   =>   div(g^3 grad p) = 0.

*Domain and boundary conditions.* The gap field of ``(ny, nx)`` elements of
sides ``(dx, dy)`` [m] (``dx`` along the last axis) is the channel: the flow
runs along x (or along y: the same problem on the transposed field). The
pressure is given on the inlet side ``x = 0`` (``p_in``) and on the outlet side
``x = Lx = nx dx`` (``p_out``); the two other sides are a value, :class:`Sides`:
:data:`PERIODIC` (``p(x, y + Ly) = p(x, y)``: the field repeats across the
flow) or :data:`SEALED` (no flow through them, ``q_y = 0``).

*Discretisation.* Finite volumes on the element grid (Patankar 1980, Ch 4):
one unknown, the pressure at the element's centre, per element. The flow
through the face shared by the x-neighbours P and E is
``F = k_f (p_P - p_E) dy / (12 eta dx)``, with ``k_f`` the face value of the
local conductance ``k = g^3`` given by a rule, a value (:class:`FaceRule`):

- :data:`HARMONIC` (default): ``k_f = 2 k_P k_E / (k_P + k_E)``, the series
  conductance of the two half elements, the interface rule of Patankar
  (1980, Sec 4.2-3) for a conductivity that jumps between control volumes.
  It is exact for a gap varying along the flow element by element: the
  resistance of a row is then ``sum_i dx / k_i``, whatever the contrast.
- :data:`ARITHMETIC`: ``k_f = (k_P + k_E) / 2``, the rule of a node-based
  finite-difference scheme that interpolates ``g^3`` to the face. It lets a
  narrow element pass more than it can: it overestimates the flow where the gap
  varies fast on the grid (at coarse resolution, and at every constriction).

y-faces alike (``dx / dy`` for ``dy / dx``). The inlet face lies half an
element before the first centre: ``F = k_P (p_in - p_P) dy / (12 eta dx / 2)``,
and so the outlet face. With ``k`` uniform the scheme is exact (a linear
pressure), and on a smooth gap it is second order in the element size.

*Contact and connectivity.* An element in contact, ``g == 0``, is closed:
every face it shares carries nothing, under either rule. The open elements are
thus connected through shared edges only (4-connectivity; across the sides when
they are periodic, never across the inlet or outlet), the convention of the
contact spots in :mod:`roughcontact.contact.interface`. The clusters of open
elements are of four kinds:

- *through*: touching the inlet and the outlet side; the flow's only path, and
  the only elements whose pressures are solved for;
- *dead ends*: touching one side only; at that side's pressure, no flow;
- *pockets*: touching neither (fluid trapped between contacts): pressure
  undefined (NaN), no flow;
- none through: the free space does not connect inlet to outlet (below the
  percolation threshold, reached near a relative contact area of 0.42 for
  isotropic roughness: Dapp et al. 2012; 0.415: Wang & Mueser 2021): zero
  flow, no solve, ``connected`` False.

Leaving the dead ends and pockets out of the linear system keeps it symmetric
positive definite (every cluster solved has a face of given pressure), so it is
never singular.

*Results* (:class:`FlowResult`). The effective conductance
``K = 12 eta Q Lx / (Ly (p_in - p_out))`` [m^3], with ``Q`` the total flow
through the field [m^3/s]: the cube of the gap of a flat channel that
carries the same flow (a flat gap ``h`` gives ``K = h^3``). It does not depend
on ``eta`` or the pressures (the equation is linear), so the solver works with
``eta = 1/12`` and ``p_in - p_out = 1``.

*Precision.* ``Q`` is read from the dissipation ``Q dp = sum t (p_i - p_j)^2``
over every face, the inlet's and outlet's half faces included: at the solution it
equals the flow (Green's identity of the discrete system), it is the minimum the
pressures reach at the given inlet and outlet pressures (the discrete Dirichlet
principle), so an error of the pressures changes it in the second order only,
and as a sum of non-negative terms it is never negative. The flow through the
inlet, ``sum t (1 - p)``, is not used: upstream of a narrow throat ``1 - p`` is
below the rounding of 1: on a 32 x 32 field crossed by a closed column with one
throat cell of 1e-5 of the open gap (``K`` about 1e-15 of the open field's), the
inlet's flow gave -59 to +58 times the exact ``K`` over 40 places of the throat
with each kind of sides, the dissipation within 8e-13 of it. The flow through the
outlet, ``sum t p``, reads pressures near 0 and keeps its precision there; its
relative disagreement with the dissipation is the field's ``balance`` (1e-16 to
1e-12 on the fields measured, 7e-13 at most on those throats). A batch with a
field off balance by more than ``balance_tol`` is solved again with iterative
refinement, the residual in extended precision (Higham 2002, Sec 12.1): a chain
of gaps of 1e-12 of the largest between two open pools then gives the series
conductance (2.5e-55 m^3) to rounding, against 2e-48 of the first solve's noise.
A field still off balance is flagged (:attr:`FlowResult.balanced`).

From ``K``:

- the flow factor ``phi = K / mean(g)^3``, the mean over the nominal area
  (closed elements included), against a flat gap of the same mean;
- the pressure flow factor of Patir & Cheng (1978) ``phi_x = K / h^3``, with
  ``h`` the nominal separation, the distance between the two surfaces' mean
  planes (not the mean gap: where the surfaces touch, the local film thickness
  is zero, and the mean gap exceeds ``h``). Patir & Cheng define it by the
  mean flow of a rough bearing, ``q_x = -phi_x (h^3 / (12 eta)) dp/dx``, and
  computed it on a bearing with the pressure given at inlet and outlet and no
  flow through the sides (:data:`SEALED`); their fits are in
  :func:`roughcontact.transport.references.patir_cheng_phi_x`;
- the leak rate of a seal of width ``W`` across the flow and length ``L``
  along it under a pressure drop ``dp`` [Pa], the field being a representative
  patch of its interface: ``Q = K W dp / (12 eta L)`` [m^3/s] (:class:`Seal`).

*Solver.* The linear system of the through elements (five-point, symmetric
positive definite) is solved by a value of :mod:`roughcontact.transport.flow_solvers`
(imported here too: :class:`DirectSolver`: SuperLU with a
minimum-degree ordering of ``A^T + A``, default; :class:`BandedCholesky`: LAPACK's
band Cholesky, faster on small grids with sealed sides; :class:`JacobiCG`: conjugate
gradients with a diagonal preconditioner). The direct solve is faster at every
size measured, 3.7 times at 64^2 to 15 times at 1024^2 on a Gaussian gap with
16 % contact, CG's iterations doubling with each doubling of the grid
(``benchmarks/bench_flow.py``); the direct solve's time does not depend on the
conductance contrast, while CG's iterations grow with it (near percolation:
not measured). The fields of a stack are solved together, as
one block-diagonal system per batch of at most ``batch_unknowns`` elements.

References
----------
N. Patir, H. S. Cheng, "An average flow model for determining effects of
three-dimensional roughness on partial hydrodynamic lubrication", ASME J.
Lubr. Technol. 100 (1978) 12-17.

W. B. Dapp, A. Luecke, B. N. J. Persson, M. H. Mueser, "Self-affine elastic
contacts: percolation and leakage", Phys. Rev. Lett. 108 (2012) 244301.

A. Wang, M. H. Mueser, "Percolation and Reynolds flow in elastic contacts of
isotropic and anisotropic, randomly rough surfaces", Tribol. Lett. 69 (2021) 1.

S. V. Patankar, Numerical Heat Transfer and Fluid Flow, Hemisphere (1980).

N. J. Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., SIAM (2002).

G. Strang, Introduction to Applied Mathematics, Wellesley-Cambridge (1986), Ch 2
(equilibrium equations: the minimum principle of a network).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph as csgraph

from roughcontact.transport.flow_solvers import (
    DIRECT,
    BandedCholesky,
    DirectSolver,
    JacobiCG,
    refined,
)

__all__ = [
    "ARITHMETIC",
    "BALANCE_TOL",
    "DIRECT",
    "FACE_RULES",
    "FLOW_DIRECTIONS",
    "HARMONIC",
    "PERIODIC",
    "SEALED",
    "BandedCholesky",
    "DirectSolver",
    "FaceRule",
    "FlowResult",
    "FlowSetup",
    "JacobiCG",
    "Seal",
    "Sides",
    "solve_flow",
]


logger = logging.getLogger("roughcontact.transport")

# --------------------------------------------------------------------------- face rules


def _harmonic(k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """``2 k1 k2 / (k1 + k2)``, zero where either is zero."""
    total = k1 + k2
    return np.divide(2.0 * k1 * k2, total, out=np.zeros_like(total), where=total > 0.0)


def _arithmetic(k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
    """``(k1 + k2) / 2``, zero where either is zero (a closed element passes nothing)."""
    return np.where((k1 > 0.0) & (k2 > 0.0), 0.5 * (k1 + k2), 0.0)


@dataclass(frozen=True)
class FaceRule:
    """How the conductances ``k = g^3`` [m^3] of two neighbours make their face's.

    Parameters
    ----------
    name : str
        Its name in :data:`FACE_RULES`.
    combine : callable
        ``combine(k1, k2)`` [m^3], elementwise, zero where either ``k`` is zero
        (an element in contact passes nothing, under every rule).
    """

    name: str
    combine: Callable[[np.ndarray, np.ndarray], np.ndarray] = field(repr=False)

    def __call__(self, k1: np.ndarray, k2: np.ndarray) -> np.ndarray:
        return self.combine(k1, k2)


#: The series conductance of two half elements (Patankar 1980, Sec 4.2-3; the default).
HARMONIC = FaceRule("harmonic", _harmonic)
#: The mean of the two elements' ``g^3`` (a node-based finite-difference scheme).
ARITHMETIC = FaceRule("arithmetic", _arithmetic)
#: The face rules by name.
FACE_RULES = MappingProxyType({rule.name: rule for rule in (HARMONIC, ARITHMETIC)})


# --------------------------------------------------------------------------- sides


def _periodic_pairs(count: int) -> tuple[np.ndarray, np.ndarray]:
    rows = np.arange(count)
    return rows, (rows + 1) % count


def _sealed_pairs(count: int) -> tuple[np.ndarray, np.ndarray]:
    rows = np.arange(count - 1)
    return rows, rows + 1


@dataclass(frozen=True)
class Sides:
    """The two sides parallel to the flow.

    Parameters
    ----------
    name : str
        ``"periodic"`` or ``"sealed"``.
    pairs : callable
        ``pairs(count)``: the rows ``(lo, hi)`` across the flow that share a face,
        of ``count`` rows (periodic: the last row neighbours the first).
    """

    name: str
    pairs: Callable[[int], tuple[np.ndarray, np.ndarray]] = field(repr=False)


#: The field repeats across the flow: the last row neighbours the first.
PERIODIC = Sides("periodic", _periodic_pairs)
#: No flow through the sides (Patir & Cheng's bearing).
SEALED = Sides("sealed", _sealed_pairs)


# --------------------------------------------------------------------------- setup and seal

#: The default balance tolerance (:attr:`FlowSetup.balance_tol`): above the 1e-16 to
#: 1e-12 of every field measured, ordinary or with a throat of 1e-5 of the gap, far
#: below the disagreement of a solve that lost its precision (order 1).
BALANCE_TOL = 1e-6

#: Flow directions: along x (the last axis of a field) or along y.
FLOW_DIRECTIONS = ("x", "y")


def _positive(value, name: str, unit: str) -> float:
    """``float(value)``, or ValueError naming ``name`` unless positive and finite."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a positive number [{unit}], got {value!r}") from None
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{name} must be positive and finite [{unit}], got {value!r}")
    return number


@dataclass(frozen=True)
class FlowSetup:
    """The flow problem a gap field is solved in, and how.

    Parameters
    ----------
    spacing : (float, float)
        Element sides ``(dx, dy)`` [m], ``dx`` along the last axis of a field.
    direction : {"x", "y"}
        The flow runs along x (inlet at the first column) or along y (inlet at
        the first row).
    sides : Sides
        The two sides parallel to the flow: :data:`PERIODIC` (default) or
        :data:`SEALED`.
    face_rule : FaceRule
        :data:`HARMONIC` (default) or :data:`ARITHMETIC`.
    solver : DirectSolver, BandedCholesky or JacobiCG
        The linear solver, default :data:`DIRECT` (any value with their
        ``batch_unknowns``, ``solve(matrix, rhs) -> (x, iterations)`` and
        ``solve_by(matrix, rhs) -> (x, iterations, name of the solver that answered)``).
    balance_tol : float
        The largest balance (:attr:`FlowResult.balance`, the relative disagreement of
        the dissipation and the outlet's flow) a field's solve is accepted with; a
        batch with a field beyond it is solved again with iterative refinement
        (module docstring), and a field still beyond it is flagged
        (:attr:`FlowResult.balanced` False). Default :data:`BALANCE_TOL`.
    """

    spacing: tuple[float, float]
    direction: str = "x"
    sides: Sides = PERIODIC
    face_rule: FaceRule = HARMONIC
    solver: DirectSolver | BandedCholesky | JacobiCG = DIRECT
    balance_tol: float = BALANCE_TOL

    def __post_init__(self):
        try:
            dx, dy = self.spacing
        except (TypeError, ValueError):
            raise ValueError(f"spacing must be two element sides (dx, dy) [m], "
                             f"got {self.spacing!r}") from None
        object.__setattr__(self, "spacing", (_positive(dx, "spacing dx", "m"),
                                             _positive(dy, "spacing dy", "m")))
        if self.direction not in FLOW_DIRECTIONS:
            raise ValueError(f"direction must be one of {FLOW_DIRECTIONS}, "
                             f"got {self.direction!r}")
        for name, kind in (("sides", Sides), ("face_rule", FaceRule)):
            if not isinstance(getattr(self, name), kind):
                raise ValueError(f"{name} must be a {kind.__name__} "
                                 f"(e.g. {'PERIODIC' if kind is Sides else 'HARMONIC'}), "
                                 f"got {getattr(self, name)!r}")
        object.__setattr__(self, "balance_tol", _positive(self.balance_tol, "balance_tol", "-"))

    def along_flow(self) -> tuple[Callable[[np.ndarray], np.ndarray], tuple[float, float]]:
        """The map of a field (..., ny, nx) to the one whose flow runs along its last axis
        (its own inverse), and that field's spacing (along the flow, across it) [m]."""
        dx, dy = self.spacing
        return _ORIENTATIONS[self.direction], ((dx, dy) if self.direction == "x" else (dy, dx))


#: Each direction's map to a flow along the last axis (each its own inverse).
_ORIENTATIONS = MappingProxyType({"x": lambda a: a, "y": lambda a: np.swapaxes(a, -1, -2)})


@dataclass(frozen=True)
class Seal:
    """A seal whose interface a gap field represents.

    Parameters
    ----------
    pressure_drop : float
        Inlet minus outlet pressure, ``dp >= 0`` [Pa].
    viscosity : float
        Dynamic viscosity ``eta`` of the fluid [Pa s].
    width : float
        Width ``W`` of the seal across the flow [m] (e.g. its circumference).
    length : float
        Length ``L`` of the seal along the flow [m].
    """

    pressure_drop: float
    viscosity: float
    width: float
    length: float

    def __post_init__(self):
        try:
            drop = float(self.pressure_drop)
        except (TypeError, ValueError):
            drop = math.nan
        if not (math.isfinite(drop) and drop >= 0.0):
            raise ValueError(f"pressure_drop must be finite and >= 0 [Pa] (inlet minus "
                             f"outlet), got {self.pressure_drop!r}")
        object.__setattr__(self, "pressure_drop", drop)
        object.__setattr__(self, "viscosity", _positive(self.viscosity, "viscosity", "Pa s"))
        object.__setattr__(self, "width", _positive(self.width, "width", "m"))
        object.__setattr__(self, "length", _positive(self.length, "length", "m"))

    def leak_rate(self, conductance) -> np.ndarray:
        """``Q = K W dp / (12 eta L)`` [m^3/s] of the effective conductance ``K`` [m^3]."""
        return (np.asarray(conductance, dtype=float) * self.width * self.pressure_drop
                / (12.0 * self.viscosity * self.length))


# --------------------------------------------------------------------------- results


@dataclass(frozen=True)
class FlowResult:
    """The flow through a stack of gap fields (leading axes of the fields).

    Attributes
    ----------
    conductance : ndarray
        Effective conductance ``K = 12 eta Q Lx / (Ly dp)`` [m^3] along the flow
        (module docstring): the cube of the flat gap that carries the same flow.
    mean_gap : ndarray
        Mean of the gap over the nominal area [m].
    connected : ndarray of bool
        The free space connects inlet to outlet (4-connectivity); False: ``K = 0``.
    open_fraction : ndarray
        Elements with ``g > 0`` over all elements [-].
    balance : ndarray
        ``|D - Q_out| / D`` [-], the relative disagreement of the two measures of the
        flow (module docstring, *Results*): the dissipation ``D`` the conductance is
        read from and the flow ``Q_out`` through the outlet side; 1e-16 to 1e-12 on
        the fields measured, 0 when not connected.
    iterations : ndarray of int
        Iterations of the linear solver (0: direct) of the system that held the field.
    direction : str
        ``"x"`` or ``"y"``.
    pressure : ndarray, (..., ny, nx), or None
        When asked for: ``(p - p_out) / (p_in - p_out)`` [-] at the element centres
        (1 at the inlet pressure, 0 at the outlet's); NaN in contact and in pockets.
    refined : ndarray of bool or None
        The system that held the field was solved again with iterative refinement (a
        field of its batch was off balance); None: not recorded.
    balance_tol : float
        The tolerance of :attr:`balanced` (:attr:`FlowSetup.balance_tol`).
    solved_by : ndarray of str or None
        The linear solver that gave the answer of the system that held the field (the
        setup's, or :class:`BandedCholesky`'s fallback); None: not recorded.
    """

    conductance: np.ndarray
    mean_gap: np.ndarray
    connected: np.ndarray
    open_fraction: np.ndarray
    balance: np.ndarray
    iterations: np.ndarray
    direction: str
    pressure: np.ndarray | None = None
    refined: np.ndarray | None = None
    balance_tol: float = BALANCE_TOL
    solved_by: np.ndarray | None = None

    @property
    def balanced(self) -> np.ndarray:
        """The field's two measures of the flow agree to ``balance_tol`` (a field not
        connected: True); False flags a conductance not to be trusted."""
        return np.asarray(self.balance <= self.balance_tol)

    @property
    def flow_factor(self) -> np.ndarray:
        """``phi = K / mean(g)^3`` [-]; NaN where the mean gap is zero."""
        cube = np.asarray(self.mean_gap, dtype=float) ** 3
        return np.divide(self.conductance, cube, out=np.full_like(cube, np.nan),
                         where=cube > 0.0)

    @property
    def hydraulic_gap(self) -> np.ndarray:
        """``K^(1/3)`` [m]: the flat gap that carries the same flow."""
        return np.cbrt(self.conductance)

    def patir_cheng_factor(self, separation) -> np.ndarray:
        """Patir & Cheng's pressure flow factor ``K / h^3`` [-] (module docstring) at
        the nominal separation ``h`` [m] (> 0) of the surfaces' mean planes, one per
        field or one for all."""
        h = np.asarray(separation, dtype=float)
        if not (np.all(np.isfinite(h)) and np.all(h > 0.0)):
            raise ValueError(f"separation must be positive and finite [m], got {separation!r}")
        return self.conductance / h**3

    def leak_rate(self, seal: Seal) -> np.ndarray:
        """The leak rate ``Q`` [m^3/s] of ``seal`` (:meth:`Seal.leak_rate`)."""
        return seal.leak_rate(self.conductance)


# --------------------------------------------------------------------------- the solve


def _checked_gap(gap, along_flow) -> np.ndarray:
    """The gap as a float stack (fields, ny, nx) with the flow along the last axis."""
    g = np.asarray(gap, dtype=float)
    if g.ndim < 2:
        raise ValueError(f"gap must hold fields of shape (..., ny, nx) [m], got shape {g.shape}")
    if g.shape[-1] < 2 or g.shape[-2] < 2:
        raise ValueError(f"gap must have at least 2 elements along and across the flow, "
                         f"got fields of shape {g.shape[-2:]} (ny, nx)")
    if not np.all(np.isfinite(g)):
        raise ValueError(f"gap must be finite [m]; it has {np.count_nonzero(~np.isfinite(g))} "
                         "NaN or infinite elements")
    if np.any(g < 0.0):
        raise ValueError(f"gap must be >= 0 [m] (0: in contact), got a minimum of {g.min():.6g}"
                         " (clip a solver's gap at 0 first)")
    flowing = along_flow(g)
    return np.ascontiguousarray(flowing.reshape(-1, *flowing.shape[-2:]))


def solve_flow(gap, setup: FlowSetup, *, keep_pressure: bool = False) -> FlowResult:
    """The flow through gap fields by the Reynolds equation (module docstring).

    Parameters
    ----------
    gap : array_like, (..., ny, nx)
        Gaps ``g >= 0`` [m] at the element centres (0: in contact), any leading
        axes (surfaces, steps).
    setup : FlowSetup
        Spacing, direction, sides, face rule and solver.
    keep_pressure : bool
        Return the pressure fields too (memory: one field per gap field).

    Returns
    -------
    FlowResult
        Conductance [m^3], mean gap [m], percolation, per field; see
        :meth:`FlowResult.patir_cheng_factor` and :meth:`FlowResult.leak_rate`.
    """
    along_flow, spacing = setup.along_flow()
    fields = _checked_gap(gap, along_flow)
    stack = np.shape(gap)[:-2]
    count, ny, nx = fields.shape
    per_batch = max(1, setup.solver.batch_unknowns // (ny * nx))
    parts = [_solve_batch(fields[start:start + per_batch], spacing, setup, keep_pressure)
             for start in range(0, count, per_batch)]
    joined = {name: np.concatenate([part[name] for part in parts]) for name in parts[0]}
    pressure = None
    if keep_pressure:
        pressure = along_flow(joined.pop("pressure").reshape(*stack, ny, nx))
    return FlowResult(
        conductance=joined["conductance"].reshape(stack),
        mean_gap=fields.mean(axis=(-2, -1)).reshape(stack),
        connected=joined["connected"].reshape(stack),
        open_fraction=np.mean(fields > 0.0, axis=(-2, -1)).reshape(stack),
        balance=joined["balance"].reshape(stack),
        iterations=joined["iterations"].reshape(stack),
        direction=setup.direction,
        pressure=pressure,
        refined=joined["refined"].reshape(stack),
        solved_by=joined["solved_by"].reshape(stack),
        balance_tol=setup.balance_tol,
    )


def _open_faces(k: np.ndarray, spacing, setup: FlowSetup):
    """The faces between open elements of a stack ``k`` (fields, ny, nx) flowing along
    its last axis: global element indices ``(a, b)`` and transmissibilities ``t``
    (face conductance times face length over centre distance) [m^3]."""
    dx, dy = spacing
    index = np.arange(k.size).reshape(k.shape)
    lo, hi = setup.sides.pairs(k.shape[1])
    a = np.concatenate([index[:, :, :-1].ravel(), index[:, lo, :].ravel()])
    b = np.concatenate([index[:, :, 1:].ravel(), index[:, hi, :].ravel()])
    t = np.concatenate([(setup.face_rule(k[:, :, :-1], k[:, :, 1:]) * (dy / dx)).ravel(),
                        (setup.face_rule(k[:, lo, :], k[:, hi, :]) * (dx / dy)).ravel()])
    keep = t > 0.0
    return a[keep], b[keep], t[keep]


def _clusters(k: np.ndarray, a: np.ndarray, b: np.ndarray):
    """Open elements by cluster kind: ``through`` (touching inlet and outlet),
    ``inlet_only`` and ``outlet_only`` (dead ends), flat over the stack ``k``."""
    size = k.size
    graph = sp.coo_matrix((np.ones(a.size, dtype=np.int8), (a, b)), shape=(size, size))
    _, labels = csgraph.connected_components(graph, directed=False)
    open_ = k.ravel() > 0.0
    index = np.arange(size).reshape(k.shape)
    touches = []
    for column in (index[:, :, 0].ravel(), index[:, :, -1].ravel()):
        mark = np.zeros(labels.max() + 1, dtype=bool)
        mark[labels[column[open_[column]]]] = True
        touches.append(mark[labels] & open_)
    inlet, outlet = touches
    return inlet & outlet, inlet & ~outlet, outlet & ~inlet


def _solve_batch(g: np.ndarray, spacing, setup: FlowSetup, keep_pressure: bool) -> dict:
    """The conductance [m^3], percolation, balance and (normalised) pressure of a batch
    of fields (fields, ny, nx) flowing along the last axis, in one sparse solve; solved
    again with iterative refinement
    (:func:`~roughcontact.transport.flow_solvers.refined`) where a connected field's
    balance exceeds ``setup.balance_tol``."""
    count, ny, nx = g.shape
    dx, dy = spacing
    scale = g.max(axis=(-2, -1))  # k in units of the field's largest gap cubed
    unit = np.where(scale > 0.0, scale, 1.0)
    k = (g / unit[:, None, None]) ** 3
    a, b, t = _open_faces(k, spacing, setup)
    through, inlet_only, outlet_only = _clusters(k, a, b)
    pressure = np.full(k.size, np.nan)  # pockets and contact
    pressure[inlet_only] = 1.0
    pressure[outlet_only] = 0.0
    inlet = np.arange(k.size).reshape(k.shape)[:, :, 0].ravel()
    outlet = inlet + (nx - 1)
    boundary = 2.0 * k.ravel() * (dy / dx)  # half an element to the inlet or outlet face
    matrix, rhs = _system(through, (a, b, t), boundary, inlet, outlet)
    field_of = np.arange(k.size) // (ny * nx)
    connected = np.bincount(field_of[through], minlength=count) > 0
    solved, iterations, used = (setup.solver.solve_by(matrix, rhs) if rhs.size
                                else (rhs, 0, type(setup.solver).__name__))
    for refining in (False, True):  # the first solve, then its refinement if off balance
        if refining:
            solved = refined(matrix, rhs, solved, setup.solver)
        pressure[through] = solved
        dissipation, q_out = _measures(pressure, through, (a, b, t), boundary,
                                       (inlet, outlet), field_of, count)
        balance = _balance(dissipation, q_out, connected)
        if np.all(balance <= setup.balance_tol):
            break
    out = {
        "conductance": dissipation * unit**3 * (nx * dx) / (ny * dy),
        "connected": connected,
        "balance": balance,
        "iterations": np.full(count, iterations),
        "refined": np.full(count, refining),
        "solved_by": np.full(count, used),
    }
    if keep_pressure:
        out["pressure"] = pressure.reshape(count, ny, nx)
    return out


def _measures(pressure, through, faces, boundary, ends, field_of, count: int):
    """Two measures of each field's flow (inlet pressure 1, outlet 0, transmissibilities
    in units of the field's largest ``k``): the dissipation ``D = sum t (p_i - p_j)^2``
    over the faces of the ``through`` elements, the inlet's and outlet's half faces
    included, and the flow ``Q_out = sum b p`` through the outlet side.

    Both equal the flow ``Q`` at the exact solution (multiply the row of each unknown by
    its pressure and sum: Green's identity of the discrete Laplacian). ``D`` is the
    quantity the solution minimises (the discrete Dirichlet principle: the pressures
    minimise the dissipation at the given inlet and outlet pressures, the minimum
    principle of a network in equilibrium; Strang 1986, Ch 2), so an error
    ``e`` of the pressures changes it by ``e^T A e`` only, second order, and a sum of
    non-negative terms it is never negative. ``Q_out`` reads the pressures next to the
    outlet, near 0, where a double keeps its relative precision; the inlet's flow
    ``sum b (1 - p)`` does not: upstream of a narrow throat ``1 - p`` is below the
    rounding of 1 (on a 32 x 32 field with one throat cell of 1e-5 of the open gap it
    gave -59 to +58 times the exact conductance, module docstring)."""
    a, b, t = faces
    inside = through[a]
    a, b, t = a[inside], b[inside], t[inside]
    dissipation = np.bincount(field_of[a], t * (pressure[a] - pressure[b]) ** 2,
                              minlength=count)
    inlet, outlet = ends
    for cells, drop in ((inlet, 1.0 - pressure[inlet]), (outlet, pressure[outlet])):
        live = through[cells]
        dissipation += np.bincount(field_of[cells[live]],
                                   boundary[cells[live]] * drop[live] ** 2, minlength=count)
    live = outlet[through[outlet]]
    q_out = np.bincount(field_of[live], boundary[live] * pressure[live], minlength=count)
    return dissipation, q_out


def _balance(dissipation, q_out, connected) -> np.ndarray:
    """``|D - Q_out| / D`` [-] of the connected fields (:func:`_measures`), 0 where not
    connected; NaN where a connected field's dissipation is not positive."""
    out = np.zeros(connected.shape)
    ok = connected & (dissipation > 0.0)
    out[ok] = np.abs(dissipation[ok] - q_out[ok]) / dissipation[ok]
    out[connected & ~ok] = np.nan
    return out


def _system(through, faces, boundary, inlet, outlet) -> tuple[sp.csr_matrix, np.ndarray]:
    """The five-point system of the pressures [-] of the ``through`` elements (inlet 1,
    outlet 0): the faces ``(a, b, t)`` among them, with the inlet and outlet faces'
    transmissibilities ``boundary`` on the diagonal; the matrix and right-hand side."""
    a, b, t = faces
    n = int(np.count_nonzero(through))
    number = np.cumsum(through) - 1  # an element's unknown, where it is through
    inside = through[a]  # a face of a through element joins two through elements
    ra, rb, rt = number[a[inside]], number[b[inside]], t[inside]
    diagonal = np.bincount(ra, rt, n) + np.bincount(rb, rt, n)
    rhs = np.zeros(n)
    for cells, value in ((inlet, 1.0), (outlet, 0.0)):
        live = cells[through[cells]]
        diagonal += np.bincount(number[live], boundary[live], n)
        rhs += np.bincount(number[live], boundary[live] * value, n)
    rows = np.concatenate([np.arange(n), ra, rb])
    columns = np.concatenate([np.arange(n), rb, ra])
    matrix = sp.csr_matrix((np.concatenate([diagonal, -rt, -rt]), (rows, columns)), shape=(n, n))
    return matrix, rhs
