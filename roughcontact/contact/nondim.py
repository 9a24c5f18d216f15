"""Non-dimensional contact sweeps: one solve per surface cell and geometry.

The contact problem of Section 3 of Kumar, Sadeghi & Krousgrill (2006) is
linear and homogeneous, so sigma (the height scale) and E (Young's modulus)
only rescale its solution (Eq 28-32). This module solves it once, in
dimensionless form, and maps the result to SI units for any (sigma, E).

Scaling
-------
With surface heights ``h = z / sigma``, the unit-modulus compliance
``Chat = E C`` [m] (``influence.unit_modulus_influence``; it depends on the
geometry and nu only) and the block thickness ``L`` [m], define

- influence operator: ``K = Chat / L`` [-]; back: ``C = L K / E`` [m/Pa]
- initial separation: ``fhat = max(h) - h``; back: ``f = sigma fhat`` [m]
- rigid approach: ``dhat = d / sigma``; back: ``d = sigma dhat`` [m]
- element pressure: ``phat = p L / (E sigma)``; back: ``p = E sigma phat / L`` [Pa]
- nominal pressure: ``Phat = mean(phat)``; back: ``P = E sigma Phat / L`` [Pa],
  load ``F = P A_n`` [N]
- mean-plane deflection (Eq 35): ``dhat_b = mean(K phat)``; back:
  ``d_b = sigma dhat_b`` [m]
- real area fraction: unchanged [-]
- stiffness: ``dPhat / ddhat``; back: ``k_P = E dPhat/ddhat`` [Pa] (Eq 33)

Substituting, ``u / sigma = K phat`` and the contact conditions (Eq 19-22)
``u + f - d = 0`` where ``p > 0``, ``>= 0`` elsewhere, become
``K phat + fhat - dhat = 0`` where ``phat > 0``, ``>= 0`` elsewhere: neither
sigma nor E appears. The normalized stiffness of Eq 33 is
``k_P = (L / A_n) dF/dd = (L / A_n) A_n dP/dd = E dPhat/ddhat``.

Relation to the paper's form (Eq 23-26): the paper writes ``p~ = p / E``,
``u~ = u / sigma``, ``d~ = d / sigma`` and ``C~ = C E / sigma = Chat /
sigma``, so ``u~ = C~ p~``. That form is equivalent but keeps sigma inside
``C~`` (and the pressure ``p~`` grows with sigma). The two are related by
``phat = (L / sigma) p~`` and ``K = (sigma / L) C~``; the form used here
absorbs sigma into the pressure, so one solve serves every sigma and E. For a
half-space operator (no thickness) any reference length may play the role
of ``L``, provided the same one is used in :func:`solve_cell` and
:func:`to_physical`.

The KKT residual of :mod:`roughcontact.contact` is invariant under this
scaling (it compares ``C_ii p_i`` with the gap, both lengths, and divides by
the largest rigid interference), so the dimensionless and the SI solves stop
on the same criterion.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from roughcontact.contact import validity
from roughcontact.contact.checks import approach_steps
from roughcontact.contact.methods import resolve_method, solve_many
from roughcontact.contact.result import SweepResult, zero_plastic_area
from roughcontact.contact.sweeps import sweep

__all__ = [
    "NondimSweep",
    "PhysicalSweep",
    "SweepProgress",
    "approach_grid",
    "dimensionless_operator",
    "initial_separation",
    "solve_cell",
    "to_physical",
]

logger = logging.getLogger("roughcontact.nondim")

#: Accepted range of the standard deviation of ``heights`` (in units of sigma);
#: outside it the heights were almost certainly passed in metres.
HEIGHT_STD_RANGE = (0.1, 10.0)
#: Relative tolerance when checking that to_physical gets the geometry of the solve.
GEOMETRY_RTOL = 1e-9
#: Relative tolerance of the dimensionless cap H L / (E sigma) in :func:`to_physical`.
HARDNESS_RTOL = 1e-5


# ---------------------------------------------------------------------------
# Results


@dataclass(frozen=True)
class SweepProgress:
    """Progress of :func:`solve_cell`, passed to its ``progress`` callback.

    Attributes
    ----------
    surfaces_done : int
        Surfaces whose sweep has finished, this batch included.
    surfaces_total : int
        Surfaces in the cell.
    step : int
        Approach step reported, 1-based.
    steps_total : int
        Approach steps per surface.
    iterations : int
        Contact-solver iterations of this batch at this step, summed over its
        surfaces.
    unconverged : int
        Surfaces of this batch whose contact solve did not converge at this step.
    elapsed : float
        Wall time since :func:`solve_cell` started [s], when the report is made.
    """

    surfaces_done: int
    surfaces_total: int
    step: int
    steps_total: int
    iterations: int
    unconverged: int
    elapsed: float


@dataclass(frozen=True)
class NondimSweep:
    """Dimensionless force-deflection sweep of one surface cell (module docstring).

    Every array has shape (m, k): surface by approach step.

    Attributes
    ----------
    approach : ndarray
        Rigid approach ``dhat = d / sigma`` [-].
    nominal_pressure : ndarray
        ``Phat = P L / (E sigma)`` [-].
    mean_plane_deflection : ndarray
        ``dhat_b = d_b / sigma`` [-] (Eq 35).
    real_area_fraction : ndarray
        Fraction of elements in contact [-].
    max_pressure : ndarray
        Largest element pressure ``phat_max = p_max L / (E sigma)`` [-].
    stiffness : ndarray
        ``dPhat / ddhat`` at fixed contact set [-]; ``k_P = E dPhat/ddhat`` (Eq 33).
    iterations, matvecs : ndarray of int
        Work of the contact solve at each step.
    residual : ndarray
        Dimensionless KKT residual of each solve (:mod:`roughcontact.contact`).
    converged : ndarray of bool
        Contact solve reached ``tol`` and every reported value is finite.
    stiffness_converged : ndarray of bool
        The active-set CG of the stiffness reached ``stiffness_tol`` and the
        stiffness is finite.
    thickness : float
        Reference length ``L`` [m] used in ``K = Chat / L``.
    element_area : float
        Contact element area ``dA`` [m^2] of the influence matrix.
    n_elements : int
        Contact elements per surface ``n``.
    method, tol, stiffness_tol, precision, max_iter
        Settings of the contact and stiffness solves (``max_iter`` None: the
        solver's default).
    hardness : float or None
        Dimensionless pressure cap ``H L / (E sigma)`` of a capped sweep
        (0 <= phat <= H L / (E sigma)); None for the elastic problem.
    plastic_area_fraction : ndarray or None
        Fraction of elements at the cap [-] (zeros for an elastic sweep).
    profile_ranks, pressure_profile, load_profile : ndarray or None
        The solutions' pressure profiles (dimensionless, like ``max_pressure``)
        and load profiles at the ranks ``profile_ranks``
        (:mod:`roughcontact.contact.validity`); None when not recorded.
    """

    approach: np.ndarray
    nominal_pressure: np.ndarray
    mean_plane_deflection: np.ndarray
    real_area_fraction: np.ndarray
    max_pressure: np.ndarray
    stiffness: np.ndarray
    iterations: np.ndarray
    matvecs: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    stiffness_converged: np.ndarray
    thickness: float
    element_area: float
    n_elements: int
    method: str
    tol: float
    stiffness_tol: float
    precision: str
    max_iter: int | None
    hardness: float | None = None
    plastic_area_fraction: np.ndarray | None = None
    profile_ranks: np.ndarray | None = None
    pressure_profile: np.ndarray | None = None
    load_profile: np.ndarray | None = None

    def __post_init__(self):
        zero_plastic_area(self)

    @property
    def nominal_area(self) -> float:
        """Nominal contact area ``A_n = n dA`` [m^2]."""
        return self.n_elements * self.element_area


@dataclass(frozen=True)
class PhysicalSweep:
    """Force-deflection sweep of one cell in SI units, for one (sigma, E).

    Every array has shape (m, k): surface by approach step.

    Attributes
    ----------
    approach : ndarray
        Rigid approach ``d`` [m].
    load : ndarray
        Total force ``F = P A_n`` [N].
    nominal_pressure : ndarray
        ``P = F / A_n`` [Pa].
    mean_plane_deflection : ndarray
        ``d_b`` [m], the mean of ``u`` (Eq 35).
    real_area_fraction : ndarray
        Fraction of elements in contact [-].
    max_pressure : ndarray
        Largest element pressure [Pa].
    contact_stiffness : ndarray
        ``dF/dd`` at fixed contact set [N/m].
    normalized_stiffness : ndarray
        ``k_P = (L / A_n) dF/dd`` [Pa] (Eq 33).
    iterations, matvecs, residual, converged, stiffness_converged : ndarray
        Diagnostics of the solves, as in :class:`NondimSweep`.
    sigma : float
        Height scale [m] (NaN if the sweep was solved directly in SI units).
    E : float
        Young's modulus [Pa] (NaN if solved directly in SI units).
    thickness : float
        Block thickness ``L`` [m] used in ``k_P``.
    nominal_area : float
        ``A_n`` [m^2].
    plastic_area_fraction : ndarray
        Fraction of elements at the cap [-] (zeros without one).
    hardness : float or None
        Pressure cap ``H`` [Pa] of a capped sweep; None for the elastic problem.
    """

    approach: np.ndarray
    load: np.ndarray
    nominal_pressure: np.ndarray
    mean_plane_deflection: np.ndarray
    real_area_fraction: np.ndarray
    max_pressure: np.ndarray
    contact_stiffness: np.ndarray
    normalized_stiffness: np.ndarray
    iterations: np.ndarray
    matvecs: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    stiffness_converged: np.ndarray
    sigma: float
    E: float
    thickness: float
    nominal_area: float
    plastic_area_fraction: np.ndarray | None = None
    hardness: float | None = None

    def __post_init__(self):
        zero_plastic_area(self)

    @property
    def asperity_deflection(self) -> np.ndarray:
        """``d_a = d - d_b`` [m] (Eq 45)."""
        return self.approach - self.mean_plane_deflection

    @property
    def plastic_load_fraction(self) -> np.ndarray:
        """Share of the load carried by elements at the cap, ``H A_p / (P A_n)`` [-]
        (zeros for an elastic sweep)."""
        if self.hardness is None:
            return np.zeros(np.shape(self.approach))
        with np.errstate(invalid="ignore", divide="ignore"):
            share = self.plastic_area_fraction * self.hardness / self.nominal_pressure
        return np.where(self.plastic_area_fraction > 0.0, share, 0.0)

    @classmethod
    def from_contact_sweep(cls, result: SweepResult, *, thickness: float,
                           nominal_area: float, sigma: float = float("nan"),
                           E: float = float("nan")) -> PhysicalSweep:
        """Wrap a :func:`roughcontact.contact.sweep` solved directly in SI units.

        ``thickness`` [m] gives ``k_P = (L / A_n) dF/dd``; ``nominal_area``
        [m^2] is ``n dA`` of that sweep. Unconverged flags are kept and steps
        with non-finite values are flagged unconverged.
        """
        thickness = _positive(thickness, "thickness")
        nominal_area = _positive(nominal_area, "nominal_area")
        values = (result.load, result.mean_plane_deflection, result.real_area_fraction,
                  result.max_pressure, result.residual)
        finite = np.logical_and.reduce([np.isfinite(v) for v in values])
        stiff = np.asarray(result.tangent_stiffness, dtype=float)
        return cls(
            approach=np.asarray(result.approach, dtype=float),
            load=np.asarray(result.load, dtype=float),
            nominal_pressure=np.asarray(result.nominal_pressure, dtype=float),
            mean_plane_deflection=np.asarray(result.mean_plane_deflection, dtype=float),
            real_area_fraction=np.asarray(result.real_area_fraction, dtype=float),
            max_pressure=np.asarray(result.max_pressure, dtype=float),
            contact_stiffness=stiff,
            normalized_stiffness=thickness / nominal_area * stiff,
            iterations=np.asarray(result.iterations),
            matvecs=np.asarray(result.matvecs),
            residual=np.asarray(result.residual, dtype=float),
            converged=np.asarray(result.converged, dtype=bool) & finite,
            stiffness_converged=np.asarray(result.stiffness_converged, dtype=bool)
            & np.isfinite(stiff),
            sigma=float(sigma),
            E=float(E),
            thickness=thickness,
            nominal_area=nominal_area,
            plastic_area_fraction=np.asarray(result.plastic_area_fraction, dtype=float),
            hardness=result.hardness,
        )

    def to_frame(self) -> pd.DataFrame:
        """One row per (surface, step), long format.

        Columns: ``surface``, ``step`` (0-based), ``approach`` [m], ``load``
        [N], ``nominal_pressure`` [Pa], ``mean_plane_deflection`` [m],
        ``asperity_deflection`` [m], ``real_area_fraction`` [-],
        ``max_pressure`` [Pa], ``contact_stiffness`` [N/m],
        ``normalized_stiffness`` [Pa], ``iterations``, ``matvecs``,
        ``residual`` [-], ``converged``, ``stiffness_converged``,
        ``plastic_area_fraction``, ``plastic_load_fraction`` [-]. The units
        are also in ``frame.attrs["units"]``, the scales in ``frame.attrs``.
        """
        m, k = self.approach.shape
        columns = {
            "surface": np.repeat(np.arange(m), k),
            "step": np.tile(np.arange(k), m),
        }
        for name in _PHYSICAL_UNITS:
            columns[name] = np.asarray(getattr(self, name)).ravel()
        frame = pd.DataFrame(columns)
        frame.attrs.update(units=dict(_PHYSICAL_UNITS), sigma=self.sigma, E=self.E,
                           thickness=self.thickness, nominal_area=self.nominal_area)
        return frame


_PHYSICAL_UNITS = {
    "approach": "m",
    "load": "N",
    "nominal_pressure": "Pa",
    "mean_plane_deflection": "m",
    "asperity_deflection": "m",
    "real_area_fraction": "1",
    "max_pressure": "Pa",
    "contact_stiffness": "N/m",
    "normalized_stiffness": "Pa",
    "iterations": "1",
    "matvecs": "1",
    "residual": "1",
    "converged": "bool",
    "stiffness_converged": "bool",
    "plastic_area_fraction": "1",
    "plastic_load_fraction": "1",
}


# ---------------------------------------------------------------------------
# Inputs


def _positive(value, name: str) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite positive number, got {value!r}") from None
    if not np.isfinite(out) or out <= 0.0:
        raise ValueError(f"{name} must be a finite positive number, got {value!r}")
    return out


def initial_separation(heights) -> np.ndarray:
    """Dimensionless initial separation ``fhat = max(h) - h`` per surface (Eq 21).

    Parameters
    ----------
    heights : array_like, (m, ny, nx) or (m, n)
        Heights in units of sigma (``z / sigma``), as stored in
        ``results/surfaces/<cell>.h5`` (:func:`roughcontact.study.storage.read_surfaces`).

    Returns
    -------
    ndarray, (m, n)
        ``fhat >= 0``, zero at each surface's highest point (first touch at
        ``dhat = 0``).

    Raises
    ------
    ValueError
        If the heights are not a finite batch, a surface is flat (all heights
        equal), or their standard deviation is outside ``HEIGHT_STD_RANGE``
        (heights passed in metres, not in sigma).
    """
    h = np.asarray(heights, dtype=float)
    if h.ndim not in (2, 3) or h.shape[0] < 1 or h[0].size < 2:
        raise ValueError(f"heights must have shape (m, ny, nx) or (m, n), got {h.shape}")
    if not np.isfinite(h).all():
        raise ValueError("heights must be finite (NaN or inf found)")
    flat = h.reshape(h.shape[0], -1)
    level = np.ptp(flat, axis=1) == 0.0
    if level.any():
        # std of equal heights is rounding noise (1e-16), not a scale: name the real problem
        j = int(np.argmax(level))
        raise ValueError(
            f"heights of surface {j} are all equal (a flat surface, standard deviation 0): "
            f"it has no roughness scale sigma to make the problem dimensionless. A flat "
            f"punch (full contact, C p = d) is solved in SI units with contact.solve."
        )
    std = flat.std(axis=1)
    low, high = HEIGHT_STD_RANGE
    if ((std < low) | (std > high)).any():
        j = int(np.argmax((std < low) | (std > high)))
        raise ValueError(
            f"heights must be in units of sigma (z / sigma, standard deviation near 1); "
            f"surface {j} has standard deviation {std[j]:.3g}, outside {HEIGHT_STD_RANGE}. "
            f"Divide heights in metres by sigma."
        )
    return flat.max(axis=1, keepdims=True) - flat


class _ScaledOperator:
    """A matrix-free unit-modulus operator divided by ``L``: ``K p = Chat p / L``."""

    def __init__(self, operator, thickness: float):
        self._operator = operator
        self._scale = 1.0 / thickness
        self.shape = tuple(operator.shape)
        grid = getattr(operator, "grid", None)
        if grid is not None:
            self.grid = grid
        mean_compliance = getattr(operator, "mean_compliance", None)
        if mean_compliance is not None:
            self.mean_compliance = mean_compliance * self._scale

    def diagonal(self) -> np.ndarray:
        return np.asarray(self._operator.diagonal(), dtype=float) * self._scale

    def matvec(self, pressure) -> np.ndarray:
        return np.asarray(self._operator.matvec(pressure), dtype=float) * self._scale


def dimensionless_operator(unit_influence, thickness: float):
    """``K = Chat / L``, the influence operator of the dimensionless problem.

    Parameters
    ----------
    unit_influence : ndarray (n, n) or operator object
        Unit-modulus compliance ``Chat = E C`` [m]: a dense symmetric matrix
        (``influence.unit_modulus_influence``, or ``halfspace_influence`` with
        ``E = 1``) or a matrix-free operator with ``shape``, ``diagonal()``
        and ``matvec`` built with ``E = 1`` (e.g. ``PeriodicHalfSpace``).
    thickness : float
        Block thickness ``L`` [m] (for a half-space, any reference length).

    Returns
    -------
    ndarray or operator object
        ``K`` [-], of the same kind as ``unit_influence``.
    """
    thickness = _positive(thickness, "thickness")
    if isinstance(unit_influence, np.ndarray) or not hasattr(unit_influence, "matvec"):
        return np.asarray(unit_influence, dtype=float) / thickness
    return _ScaledOperator(unit_influence, thickness)


def _check_steps(approaches, m: int) -> np.ndarray:
    steps = approach_steps(approaches, m, "units of sigma")
    if (np.diff(steps, axis=1) <= 0.0).any():
        raise ValueError("approaches must increase strictly along the steps (units of sigma)")
    return np.ascontiguousarray(steps)


# ---------------------------------------------------------------------------
# Sweep


def solve_cell(unit_influence, heights, *, thickness: float, element_area: float, approaches,
               method: str = "cg", tol: float = 1e-8, max_iter: int | None = None,
               stiffness_tol: float = 1e-6, precision: str = "double",
               batch_size: int | None = None,
               progress: Callable[[SweepProgress], None] | None = None,
               hardness: float | None = None, profile: bool = False) -> NondimSweep:
    """Dimensionless force-deflection sweep of all surfaces of one cell (Eq 27, 33, 35).

    Solves ``min 1/2 phat.K phat - phat.(dhat - fhat)`` over ``phat >= 0``
    (Eq 27 in the variables of the module docstring) for every surface at
    every approach with :func:`roughcontact.contact.sweep`: all surfaces of a
    batch at once, each step warm-started from the previous one, and the
    stiffness ``dPhat/ddhat = (1/n) 1^T (K_AA)^-1 1`` on the contact set ``A``
    at every step. The dimensionless element area is ``1/n`` (nominal area
    1), so the sweep's load is ``Phat`` and its tangent stiffness
    ``dPhat/ddhat``. The result holds for every sigma and E
    (:func:`to_physical`).

    Parameters
    ----------
    unit_influence : ndarray (n, n) or operator object
        ``Chat = E C`` [m], see :func:`dimensionless_operator`.
    heights : ndarray, (m, ny, nx) or (m, n)
        Surface heights in units of sigma (``z / sigma``).
    thickness : float
        Block thickness ``L`` [m] of the geometry ``Chat`` was built for.
    element_area : float
        Contact element area ``dA`` [m^2] of that geometry; recorded so that
        :func:`to_physical` can give loads in N.
    approaches : ndarray, (k,) or (m, k)
        Rigid approaches ``dhat = d / sigma`` [-], shared or per surface,
        non-negative and strictly increasing; see :func:`approach_grid`.
    method, tol, max_iter, stiffness_tol, precision
        Passed to :func:`roughcontact.contact.sweep`; ``tol`` bounds the
        dimensionless KKT residual, which is the same in SI units.
    batch_size : int, optional
        Surfaces per :func:`~roughcontact.contact.sweep` call (default: all
        in one call, the fastest). Smaller batches bound memory and give
        progress reports sooner.
    progress : callable, optional
        Called with a :class:`SweepProgress` for every step of every batch.
        ``contact.sweep`` offers no per-step hook, so the reports of a batch
        are made, in step order, when that batch is finished.
    hardness : float, optional
        Dimensionless pressure cap ``H L / (E sigma)`` (``0 <= phat <= H L /
        (E sigma)``): the result then holds only for the (sigma, E, H) with that
        value (:func:`to_physical` checks it). None: the elastic problem.
    profile : bool
        Record every solution's pressure and load profiles
        (:mod:`roughcontact.contact.validity`), from which the share of area
        and load above any hardness is read without another solve.

    Returns
    -------
    NondimSweep
        (m, k) arrays. Steps whose contact solve did not reach ``tol`` (or
        gave non-finite values) have ``converged=False``; their values are the
        solver's last iterate and must not be used as results. A warning is
        logged with their count.
    """
    thickness = _positive(thickness, "thickness")
    element_area = _positive(element_area, "element_area")
    gaps = initial_separation(heights)
    m, n = gaps.shape
    steps = _check_steps(approaches, m)
    k = steps.shape[1]
    if batch_size is None:
        batch_size = m
    if isinstance(batch_size, bool) or int(batch_size) != batch_size or batch_size < 1:
        raise ValueError(f"batch_size must be a positive integer or None, got {batch_size!r}")
    batch_size = int(batch_size)
    operator = dimensionless_operator(unit_influence, thickness)
    method = resolve_method(method, operator)  # recorded as solved
    if hardness is not None:
        hardness = _positive(hardness, "hardness (H L / (E sigma))")
    names = ("approach", "nominal_pressure", "mean_plane_deflection", "real_area_fraction",
             "max_pressure", "stiffness", "residual", "plastic_area_fraction")
    table = {name: np.empty((m, k)) for name in names}
    counts = {name: np.zeros((m, k), dtype=int) for name in ("iterations", "matvecs")}
    flags = {name: np.zeros((m, k), dtype=bool) for name in ("converged", "stiffness_converged")}
    ranks = validity.rank_grid(n) if profile else None
    profiles = ({name: np.zeros((m, k, ranks.size)) for name in ("pressure_profile",
                                                                  "load_profile")}
                if profile else {})
    start = time.perf_counter()
    for first in range(0, m, batch_size):
        rows = slice(first, min(m, first + batch_size))
        result = sweep(operator, gaps[rows], steps[rows], method=method, tol=tol,
                       max_iter=max_iter, element_area=1.0 / n, stiffness=True,
                       stiffness_tol=stiffness_tol, precision=precision,
                       hardness=hardness, profile=profile)
        table["approach"][rows] = steps[rows]
        table["nominal_pressure"][rows] = result.load
        table["mean_plane_deflection"][rows] = result.mean_plane_deflection
        table["real_area_fraction"][rows] = result.real_area_fraction
        table["max_pressure"][rows] = result.max_pressure
        table["stiffness"][rows] = result.tangent_stiffness
        table["residual"][rows] = result.residual
        table["plastic_area_fraction"][rows] = result.plastic_area_fraction
        for name, values in profiles.items():
            values[rows] = getattr(result, name)
        counts["iterations"][rows] = result.iterations
        counts["matvecs"][rows] = result.matvecs
        finite = np.logical_and.reduce(
            [np.isfinite(table[name][rows]) for name in names if name != "stiffness"])
        flags["converged"][rows] = result.converged & finite
        flags["stiffness_converged"][rows] = (
            result.stiffness_converged & np.isfinite(table["stiffness"][rows]))
        elapsed = time.perf_counter() - start
        logger.info("surfaces %d-%d of %d swept over %d steps (%.1f s, %d unconverged steps)",
                    rows.start + 1, rows.stop, m, k, elapsed,
                    int((~flags["converged"][rows]).sum()))
        if progress is not None:
            for step in range(k):
                progress(SweepProgress(
                    surfaces_done=rows.stop, surfaces_total=m, step=step + 1, steps_total=k,
                    iterations=int(counts["iterations"][rows, step].sum()),
                    unconverged=int((~flags["converged"][rows, step]).sum()),
                    elapsed=elapsed))
    bad = int((~flags["converged"]).sum())
    if bad:
        logger.warning("%d of %d contact solves did not reach tol %.3g; flagged converged=False",
                       bad, m * k, tol)
    bad_stiffness = int((~flags["stiffness_converged"]).sum())
    if bad_stiffness:
        logger.warning("%d of %d stiffness solves did not reach %.3g; flagged "
                       "stiffness_converged=False", bad_stiffness, m * k, stiffness_tol)
    return NondimSweep(**table, **counts, **flags, thickness=thickness,
                       element_area=element_area, n_elements=n, method=method, tol=float(tol),
                       stiffness_tol=float(stiffness_tol), precision=precision,
                       max_iter=None if max_iter is None else int(max_iter), hardness=hardness,
                       profile_ranks=ranks, **profiles)


# ---------------------------------------------------------------------------
# Approach grid


def approach_grid(heights, unit_influence=None, *, thickness: float | None = None,
                  target_area: float | None = None, target_pressure: float | None = None,
                  end: float | None = None, steps: int = 32, spacing: str = "log",
                  start: float = 1e-3, per_surface: bool = False, rtol: float = 1e-2,
                  method: str = "cg", tol: float = 1e-6,
                  precision: str = "double") -> np.ndarray:
    """Approaches ``dhat = d / sigma`` from first touch to a stated end.

    First touch is ``dhat = 0`` for every surface (``fhat = max(h) - h``).
    The end is, exactly one of:

    ``end``
        a given ``dhat``;
    ``target_area``
        the smallest approach at which the real area fraction reaches
        ``target_area`` (0 < target_area <= 1);
    ``target_pressure``
        the smallest approach at which the nominal pressure reaches
        ``Phat = target_pressure`` (for a physical target P [Pa]:
        ``Phat = P L / (E sigma)``; take the largest over the (sigma, E) to be
        served).

    The targets are found by bisection per surface on dimensionless solves
    (:func:`roughcontact.contact.solve_many`, tolerance ``tol``, each
    warm-started from the previous one),
    started from the rigid bearing-area approach (the ``target_area``
    quantile of ``fhat``) or from ``dhat = 1``, until the bracket is within
    ``rtol``; the upper end of the bracket is used, so each surface does
    reach the target (area and load grow with the approach). Without
    ``per_surface`` the grid is shared and ends at the largest of the
    surfaces' ends, so every surface covers the target.

    Parameters
    ----------
    heights : ndarray, (m, ny, nx) or (m, n)
        Heights in units of sigma.
    unit_influence : ndarray or operator, optional
        ``Chat = E C`` [m]; required for the targets.
    thickness : float, optional
        ``L`` [m]; required for the targets.
    steps : int
        Number of approaches ``k``; first touch itself (no load) is left out.
    spacing : {"log", "linear"}
        ``"log"``: ``geomspace(start * end, end, k)``, dense at low load
        where the stiffness changes fastest; ``"linear"``:
        ``end * (1..k) / k``.
    start : float
        First approach as a fraction of the end, for ``"log"``.
    per_surface : bool
        Return an (m, k) grid ending at each surface's own end.
    rtol, method, tol, precision
        Bracket width of the bisection, and the settings of its solves.

    Returns
    -------
    ndarray, (k,) or (m, k)
        Strictly increasing approaches [-] (units of sigma).
    """
    gaps = initial_separation(heights)
    m, n = gaps.shape
    chosen = [name for name, value in (("end", end), ("target_area", target_area),
                                       ("target_pressure", target_pressure))
              if value is not None]
    if len(chosen) != 1:
        raise ValueError(f"give exactly one of end, target_area, target_pressure; got {chosen}")
    if isinstance(steps, bool) or int(steps) != steps or steps < 1:
        raise ValueError(f"steps must be a positive integer, got {steps!r}")
    if spacing not in ("log", "linear"):
        raise ValueError(f"spacing must be 'log' or 'linear', got {spacing!r}")
    start = _positive(start, "start")
    if start >= 1.0:
        raise ValueError(f"start must be a fraction of the end in (0, 1), got {start!r}")
    rtol = _positive(rtol, "rtol")
    if end is not None:
        ends = np.full(m, _positive(end, "end"))
    else:
        if unit_influence is None or thickness is None:
            raise ValueError("unit_influence and thickness are needed to find a target's approach")
        operator = dimensionless_operator(unit_influence, thickness)
        if target_area is not None:
            target = float(target_area)
            if not 0.0 < target <= 1.0:
                raise ValueError(f"target_area must be in (0, 1], got {target_area!r}")
            guess = np.quantile(gaps, target, axis=1)
        else:
            target = _positive(target_pressure, "target_pressure")
            guess = np.ones(m)
        guess = np.where(guess > 0.0, guess, 1.0)

        last = {"pressure": None}

        def reached(d):
            # warm start from the previous evaluation (any p >= 0 is a valid start)
            results = solve_many(operator, gaps, d, method=method, tol=tol,
                                 element_area=1.0 / n, precision=precision,
                                 p0=last["pressure"])
            last["pressure"] = np.stack([r.pressure for r in results])
            unconverged = sum(not r.converged for r in results)
            if unconverged:
                logger.warning("approach_grid: %d of %d solves did not reach tol %.3g; the "
                               "end approach may be off", unconverged, m, tol)
            if target_area is not None:
                value = np.array([r.real_area_fraction for r in results])
            else:
                value = np.array([r.nominal_pressure for r in results])
            return value >= target

        ends = _bisect_ends(reached, guess, rtol)
    grid_end = ends if per_surface else np.array([ends.max()])
    if spacing == "log":
        grid = np.geomspace(grid_end * start, grid_end, int(steps), axis=1)
    else:
        grid = grid_end[:, None] * (np.arange(1, int(steps) + 1) / int(steps))[None, :]
    return grid if per_surface else grid[0]


def _bisect_ends(reached: Callable[[np.ndarray], np.ndarray], guess: np.ndarray,
                 rtol: float, max_doublings: int = 60) -> np.ndarray:
    """Smallest ``d`` per surface with ``reached(d)``, to relative width ``rtol``.

    ``reached`` maps approaches (m,) to booleans (m,) and must be monotone in
    ``d``. Returns the upper end of each final bracket.
    """
    low = np.zeros_like(guess)
    high = np.full_like(guess, np.inf)
    d = guess.copy()
    for _ in range(max_doublings):
        ok = reached(d)
        high = np.where(ok, d, high)
        low = np.where(ok, low, d)
        if np.isfinite(high).all():
            break
        d = np.where(np.isfinite(high), high, 2.0 * d)
    else:
        raise RuntimeError("approach_grid: target not reached after doubling the approach "
                           f"{max_doublings} times")
    while ((high - low) > rtol * high).any():
        d = 0.5 * (low + high)
        ok = reached(d)
        high = np.where(ok, d, high)
        low = np.where(ok, low, d)
    return high


# ---------------------------------------------------------------------------
# Back to SI units


def to_physical(nd: NondimSweep, sigma: float, E: float, thickness: float | None = None,
                area: float | None = None, hardness: float | None = None) -> PhysicalSweep:
    """SI force-deflection curves of a dimensionless sweep for one (sigma, E).

    ``d = sigma dhat``, ``d_b = sigma dhat_b``, ``P = E sigma Phat / L``,
    ``p_max = E sigma phat_max / L``, ``F = P A_n``, real area unchanged,
    ``k_P = E dPhat/ddhat`` (Eq 33) and ``dF/dd = k_P A_n / L`` (module
    docstring; Eq 28-32 of Kumar et al. 2006).

    Parameters
    ----------
    nd : NondimSweep
        Result of :func:`solve_cell`.
    sigma : float
        Standard deviation of the heights [m] (the unit of ``heights``).
    E : float
        Young's modulus [Pa].
    thickness : float, optional
        Block thickness ``L`` [m]; must equal the one of the solve, since
        ``K = Chat / L`` fixed it (default: that one).
    area : float, optional
        Nominal area ``A_n`` [m^2]; must equal ``nd.nominal_area`` (default).
    hardness : float, optional
        Pressure cap ``H`` [Pa] of a capped sweep (required for one, refused
        for an elastic one). A capped sweep holds only where ``H L / (E
        sigma)`` equals the value it was solved for: another (sigma, E, H)
        that changes it is refused, and must be solved anew.

    Returns
    -------
    PhysicalSweep
        Converged flags carried over unchanged.
    """
    sigma = _positive(sigma, "sigma")
    E = _positive(E, "E")
    for name, given, recorded in (("thickness", thickness, nd.thickness),
                                  ("area", area, nd.nominal_area)):
        if given is not None and abs(_positive(given, name) - recorded) > GEOMETRY_RTOL * recorded:
            raise ValueError(
                f"{name} = {given!r} differs from the {recorded!r} of the dimensionless solve; "
                f"the influence matrix fixes the geometry, solve the other geometry separately"
            )
    length = nd.thickness
    pressure_scale = E * sigma / length
    cap = _check_cap(nd, hardness, pressure_scale)
    nominal_pressure = pressure_scale * nd.nominal_pressure
    normalized_stiffness = E * nd.stiffness
    return PhysicalSweep(
        approach=sigma * nd.approach,
        load=nominal_pressure * nd.nominal_area,
        nominal_pressure=nominal_pressure,
        mean_plane_deflection=sigma * nd.mean_plane_deflection,
        real_area_fraction=nd.real_area_fraction.copy(),
        max_pressure=pressure_scale * nd.max_pressure,
        contact_stiffness=normalized_stiffness * nd.nominal_area / length,
        normalized_stiffness=normalized_stiffness,
        iterations=nd.iterations.copy(),
        matvecs=nd.matvecs.copy(),
        residual=nd.residual.copy(),
        converged=nd.converged.copy(),
        stiffness_converged=nd.stiffness_converged.copy(),
        sigma=sigma,
        E=E,
        thickness=length,
        nominal_area=nd.nominal_area,
        plastic_area_fraction=np.asarray(nd.plastic_area_fraction, dtype=float).copy(),
        hardness=cap,
    )


def _check_cap(nd: NondimSweep, hardness, pressure_scale: float) -> float | None:
    """``hardness`` [Pa] checked against the dimensionless cap of ``nd`` (:func:`to_physical`)."""
    if nd.hardness is None:
        if hardness is not None:
            raise ValueError(
                f"hardness = {hardness!r} Pa given, but the sweep is elastic (solved without a "
                f"cap): solve it with hardness H L / (E sigma), or check the elastic result "
                f"against H with roughcontact.contact.validity")
        return None
    if hardness is None:
        raise ValueError(
            f"the sweep was solved with the cap H L / (E sigma) = {nd.hardness:.6g}; give the "
            f"hardness H [Pa] so that the scaling can be checked")
    H = _positive(hardness, "hardness")
    wanted = H / pressure_scale
    if abs(wanted - nd.hardness) > HARDNESS_RTOL * nd.hardness:
        raise ValueError(
            f"H L / (E sigma) = {wanted:.6g} for this (sigma, E, H), but the sweep was solved "
            f"for {nd.hardness:.6g}: with a cap, pressure no longer scales with sigma E alone, "
            f"so this rescaling would change the problem; solve it anew with that cap")
    return H
