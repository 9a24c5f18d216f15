"""What a contact sweep records of the conductance across each of its solutions' spots.

A :class:`ConductanceProbe` is a probe (:class:`~roughcontact.contact.probes.Probe`)
a sweep is given through its interface grid
(:class:`~roughcontact.contact.interface.InterfaceGrid`, ``probes``). At every step it
takes each surface's contact set, the elements with ``p > 0`` (the same in a
dimensionless sweep and in SI: the pressure's scale does not move its support), and
solves the spot conductance through the thermal body's influence
(:func:`~roughcontact.transport.conduction.spot.spot_conductance`'s equation, ``R_AA q
= 1``, ``C = dA 1^T q``, by the tangent stiffness's CG). The body is a value:

:class:`HalfSpaceBody`
    a half-space, periodic (FFT; the face's mean temperature the reference, so the
    conductance is the constriction's alone) or free (the zero-padded FFT, or the
    dense element integral);
:class:`BlockBody`
    the finite block of the elastic model
    (:class:`~roughcontact.elasticity.influence.BlockGeometry`), isothermal base,
    insulated sides (:func:`~roughcontact.transport.conduction.block.unit_conductivity_influence`).

The counter body is a perfect conductor (isothermal face). Two bodies of the same
kind in series have the influence ``R_unit (1/k1 + 1/k2)`` on half-spaces: give the
series conductivity ``k1 k2 / (k1 + k2)``.

The influence is built once per grid for unit conductivity, ``k R`` [m] (it depends
on the geometry only), kept on the value (not in its settings), and one CG per
surface and step serves both quantities: the thermal conductance is ``k C_1`` and the
electrical resistance ``rho_e / C_1`` (``C_1`` [m] the unit-conductivity
conductance). The grid spacing the sweep passes is in metres in both forms of a sweep,
so every column is in SI units as recorded (``length_power`` 0).

Columns (those of the thermal quantity with a conductivity, the electrical one with a
resistivity):

:data:`CONDUCTANCE`
    ``C`` [W/K]: 0 without contact; inf at full contact of a periodic half-space (no
    constriction left, and a half-space has no bulk);
:data:`CONDUCTANCE_PER_AREA`
    ``h_c = C / A_n`` [W/(m^2 K)], likewise;
:data:`BULK_SHARE`
    ``R_bulk C`` [-], the bulk's share of the resistance (0 on half-spaces and
    without contact; 1 at full contact of a block);
:data:`CONSTRICTION_PER_AREA`
    ``h_s = 1 / (A_n (1/C - R_bulk))`` [W/(m^2 K)], the spots' constriction alone per
    nominal area (what the half-space correlations give; ``h_c`` on a half-space; 0
    without contact, inf at full contact);
:data:`ELECTRICAL_RESISTANCE`
    ``1 / C_e`` [Ohm]: inf without contact (recorded only at zero load, which the
    aggregation never reads), 0 at full contact of a periodic half-space;
:data:`CONVERGED`
    the CG met its tolerance; where it did not, the step's conductances and
    resistance are recorded as NaN (the aggregation leaves them out) and a warning
    on the ``roughcontact.transport`` logger names the surfaces.

These names are the conductance's only spelling.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from roughcontact.contact.cg import default_max_iter
from roughcontact.contact.checks import as_operator, given_matrix
from roughcontact.contact.probes import Column, SolvedFields
from roughcontact.contact.products import Products
from roughcontact.contact.stiffness import DIAGONAL_SAFETY, free_set_cg
from roughcontact.transport.conduction.bodies import (
    BlockBody,
    HalfSpaceBody,
    SeriesBody,
    body_from_params,
)

__all__ = ["BODY_KINDS", "BULK_SHARE", "CONDUCTANCE", "CONDUCTANCE_PER_AREA",
           "CONSTRICTION_PER_AREA", "CONVERGED", "ELECTRICAL_RESISTANCE", "NO_CONDUCTION",
           "BlockBody", "ConductanceProbe", "ConductionMaterials", "HalfSpaceBody",
           "SeriesBody", "body_from_params", "conductance_probe_from_params",
           "direct_totals", "materials_from_params"]

logger = logging.getLogger("roughcontact.transport")

#: The columns' names (module docstring).
CONDUCTANCE, CONDUCTANCE_PER_AREA, BULK_SHARE, ELECTRICAL_RESISTANCE, CONVERGED = (
    "thermal_conductance", "thermal_conductance_per_area", "conduction_bulk_share",
    "electrical_resistance", "conduction_converged")
CONSTRICTION_PER_AREA = "constriction_conductance_per_area"
def _check_material(key: str, value, unit: str):
    """``value`` as a finite positive float, or None when not given."""
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{key} must be a finite positive number [{unit}] or absent, "
                         f"got {value!r}")
    return number


@dataclass(frozen=True)
class ConductanceProbe:
    """The conductance a sweep records at every step (module docstring).

    Parameters
    ----------
    body : HalfSpaceBody or BlockBody
        The body the heat or current enters through the spots.
    conductivity : float, optional
        Thermal conductivity ``k`` [W/(m K)]: records the thermal columns.
    resistivity : float, optional
        Electrical resistivity ``rho_e`` [Ohm m]: records the electrical resistance.
        At least one of the two.
    tol : float
        Estimated relative error of ``C`` at which the CG stops.
    counter_conductivity, counter_resistivity : float, optional
        The counter body's [W/(m K)], [Ohm m]: it is then a free half-space of that
        material in series (:class:`SeriesBody`; dense where the body is), else a perfect
        conductor (its isothermal face). Each needs the body's own.
    """

    #: The name its settings are stored under (:class:`~roughcontact.contact.probes.Probe`).
    kind: ClassVar[str] = "conductance"

    body: HalfSpaceBody | BlockBody
    conductivity: float | None = None
    resistivity: float | None = None
    tol: float = 1e-10
    counter_conductivity: float | None = None
    counter_resistivity: float | None = None
    _influences: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    _given: object = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.body, HalfSpaceBody | BlockBody):
            raise ValueError(f"body must be a HalfSpaceBody or a BlockBody, got "
                             f"{type(self.body).__name__}")
        conductivity = _check_material("conductivity", self.conductivity, "W/(m K)")
        resistivity = _check_material("resistivity", self.resistivity, "Ohm m")
        for key, own, unit in (("counter_conductivity", conductivity, "W/(m K)"),
                               ("counter_resistivity", resistivity, "Ohm m")):
            value = _check_material(key, getattr(self, key), unit)
            if value is not None and own is None:
                raise ValueError(f"{key} needs the body's own "
                                 f"{key.removeprefix('counter_')}: give both, or neither "
                                 "(the counter body a perfect conductor)")
            object.__setattr__(self, key, value)
        if conductivity is None and resistivity is None:
            raise ValueError("conductivity or resistivity must be given (a thermal "
                             "conductivity [W/(m K)], an electrical resistivity [Ohm m], "
                             "or both): the probe has nothing to record without one")
        tol = _check_material("tol", self.tol, "-")
        if tol is None or tol >= 1.0:
            raise ValueError(f"tol must be in (0, 1), got {self.tol!r}")
        object.__setattr__(self, "conductivity", conductivity)
        object.__setattr__(self, "resistivity", resistivity)
        object.__setattr__(self, "tol", tol)

    @property
    def columns(self) -> tuple[Column, ...]:
        """Its columns (module docstring): the thermal ones with a conductivity, the
        electrical resistance with a resistivity, then the CG's convergence."""
        thermal = (
            Column(CONDUCTANCE, "W/K",
                   "C, thermal conductance of the contact spots (isothermal spots, no flux "
                   "elsewhere, perfectly conducting counter body; 0 without contact, inf at "
                   "full contact of a periodic half-space, NaN where the CG did not "
                   "converge)"),
            Column(CONDUCTANCE_PER_AREA, "W/(m^2 K)",
                   "h_c = C / A_n, thermal contact conductance per nominal area (0 without "
                   "contact)"),
            Column(BULK_SHARE, "1",
                   "R_bulk C, the bulk's share of the resistance (0 on half-spaces and "
                   "without contact, 1 at full contact of a block)"),
            Column(CONSTRICTION_PER_AREA, "W/(m^2 K)",
                   "h_s = 1 / (A_n (1/C - R_bulk)), the spots' constriction conductance "
                   "alone per nominal area (h_c on a half-space; 0 without contact)"),
        ) if self.conductivity is not None else ()
        electrical = (
            Column(ELECTRICAL_RESISTANCE, "Ohm",
                   "electrical contact resistance 1 / C_e (inf without contact, at zero "
                   "load only; 0 at full contact of a periodic half-space; NaN where the "
                   "CG did not converge)"),
        ) if self.resistivity is not None else ()
        return (*thermal, *electrical,
                Column(CONVERGED, "1", "share of surfaces whose conductance CG met its "
                       "tolerance", dtype=bool))

    def params(self) -> dict:
        """Its settings as plain values (a stored file's record of what was solved; the
        counter's materials only where given)."""
        counter = {key: getattr(self, key) for key in ("counter_conductivity",
                                                       "counter_resistivity")
                   if getattr(self, key) is not None}
        return {"body": self.body.params(), "conductivity": self.conductivity,
                "resistivity": self.resistivity, "tol": self.tol, **counter}

    def _counter_body(self) -> HalfSpaceBody:
        """The counter body where its material is given: a free half-space, dense where
        the body's influence is (the series one matrix)."""
        dense = isinstance(self.body, BlockBody) or self.body.dense
        return HalfSpaceBody(periodic=not dense and self.body.periodic, dense=dense)

    @property
    def thermal_body(self) -> HalfSpaceBody | BlockBody | SeriesBody:
        """The body the heat crosses: ``body``, and the counter body in series where its
        conductivity is given (``ratio = k1 / k2``)."""
        if self.counter_conductivity is None:
            return self.body
        return SeriesBody(self.body, self._counter_body(),
                          self.conductivity / self.counter_conductivity)

    @property
    def electrical_body(self) -> HalfSpaceBody | BlockBody | SeriesBody:
        """The body the current crosses (``ratio = rho2 / rho1``)."""
        if self.counter_resistivity is None:
            return self.body
        return SeriesBody(self.body, self._counter_body(),
                          self.counter_resistivity / self.resistivity)

    def with_unit_influence(self, unit) -> ConductanceProbe:
        """The same probe given its body's ``k R`` [m] built elsewhere (a stored file,
        :meth:`BlockBody.unit_influence`'s result): used on the grid it fits, checked
        there as the body would check its own."""
        probe = dataclasses.replace(self)
        object.__setattr__(probe, "_given", unit)
        return probe

    def influence(self, grid, spacing, body=None):
        """``k R`` [m] of ``body`` (default the probe's own) on ``grid`` ``(nx, ny)`` of
        sides ``spacing`` [m] and its bulk resistance times ``k`` [1/m], built once (the
        probe's body's given, :meth:`with_unit_influence`) and kept."""
        body = self.body if body is None else body
        key = (body, tuple(int(g) for g in grid), tuple(float(s) for s in spacing))
        if key not in self._influences:
            # the given k R is the probe's own body's (a series' first); no other's
            own = body == self.body or getattr(body, "first", None) == self.body
            unit = body.unit_influence(*key[1:], built=self._given if own else None)
            operator = as_operator(unit, key[2][0] * key[2][1])
            parts = body.parts()
            bulk = (body.unit_bulk_resistance(operator, self.tol) if len(parts) == 1 else
                    sum(ratio * self.influence(grid, spacing, part)[1]
                        for part, ratio in parts))
            self._influences[key] = (operator, bulk)
        return self._influences[key]

    def _unit_conductance(self, operator, contact, body):
        """``(C_1, converged)`` (m,) of the contact sets ``contact`` (m, n): ``dA 1^T
        (k R_AA)^-1 1`` [m] (0 for an empty set, inf for a full one where the body has no
        resistance there). On a dense influence each set's ``k R_AA`` is factored
        (Cholesky, float64; :func:`direct_totals`), the sets it does not settle to
        ``tol`` go to CG; otherwise CG on every set together."""
        m, n = contact.shape
        unit = np.zeros(m)
        converged = np.ones(m, dtype=bool)
        full = contact.all(axis=1) & body.unbounded_at_full_contact
        unit[full] = np.inf
        rows = np.flatnonzero(contact.any(axis=1) & ~full)
        matrix = given_matrix(operator)
        if rows.size and matrix is not None:
            totals, settled = direct_totals(matrix, contact[rows], self.tol)
            unit[rows[settled]] = operator.element_area * totals[settled]
            rows = rows[~settled]
        if rows.size:
            solution = free_set_cg(Products(operator), contact[rows], np.zeros((rows.size, n)),
                                   self.tol, default_max_iter(n))
            unit[rows] = operator.element_area * solution.total
            converged[rows] = solution.converged
        return unit, converged

    def measure(self, fields: SolvedFields) -> dict:
        """The columns (module docstring) of the solutions of ``fields``: the contact set
        ``pressure > 0`` of every field (..., ny, nx), on elements of sides ``spacing``
        [m]; name -> array of the leading shape."""
        pressure = np.asarray(fields.pressure)
        lead, (ny, nx) = pressure.shape[:-2], pressure.shape[-2:]
        contact = (pressure > 0.0).reshape(-1, nx * ny)
        solved = {}  # body -> (C_1 [m] (NaN where not converged), converged, bulk)

        def solve(body):
            if body not in solved:
                operator, unit_bulk = self.influence((nx, ny), fields.spacing, body)
                unit, ok = self._unit_conductance(operator, contact, body)
                solved[body] = (np.where(ok, unit, np.nan), ok, unit_bulk)
            return solved[body]

        area = fields.spacing[0] * fields.spacing[1] * nx * ny
        out = {}
        if self.conductivity is not None:
            unit, _, unit_bulk = solve(self.thermal_body)
            conductance = self.conductivity * unit
            out[CONDUCTANCE] = conductance.reshape(lead)
            out[CONDUCTANCE_PER_AREA] = (conductance / area).reshape(lead)
            out[BULK_SHARE] = (unit_bulk * unit if unit_bulk > 0.0 else np.where(
                np.isnan(unit), np.nan, 0.0)).reshape(lead)
            with np.errstate(divide="ignore"):
                constriction = np.where(unit > 0.0, 1.0 / (1.0 / unit - unit_bulk), unit)
            out[CONSTRICTION_PER_AREA] = (self.conductivity * constriction / area
                                          ).reshape(lead)
        if self.resistivity is not None:
            unit = solve(self.electrical_body)[0]
            with np.errstate(divide="ignore"):
                out[ELECTRICAL_RESISTANCE] = (self.resistivity / unit).reshape(lead)
        converged = np.logical_and.reduce([ok for _, ok, _ in solved.values()])
        out[CONVERGED] = converged.reshape(lead)
        if not converged.all():
            where = np.flatnonzero(~converged)
            logger.warning(
                "conductance CG did not reach tol %.3g for %d of %d fields (indices %s); "
                "their conductance recorded as NaN, flagged in %s", self.tol, where.size,
                converged.size, where[:10].tolist(), CONVERGED)
        return out


def direct_totals(matrix: np.ndarray, sets: np.ndarray, tol: float) -> tuple:
    """``1^T x`` of ``R_AA x = 1`` on each set ``A`` of ``sets`` (m, n) of a dense
    symmetric positive definite ``matrix`` (n, n), by Cholesky in float64, and whether
    each met ``tol``: by the CG's own test
    (:func:`~roughcontact.contact.stiffness.free_set_cg`: the estimated relative error of
    the total, ``32 (r / diag) . r <= tol (1^T x + x^T r)``, ``r`` the float64 residual).
    A set whose factorization fails, or that misses the test, is not settled (its total
    0): the caller solves it by CG."""
    from scipy.linalg import LinAlgError, cho_factor, cho_solve

    totals = np.zeros(sets.shape[0])
    settled = np.zeros(sets.shape[0], dtype=bool)
    for j, row in enumerate(sets):
        flat = np.flatnonzero(row)
        block = matrix[np.ix_(flat, flat)]
        try:
            x = cho_solve(cho_factor(block, check_finite=False), np.ones(flat.size),
                          check_finite=False)
        except LinAlgError:
            continue
        residual = 1.0 - block @ x
        total = float(x.sum() + x @ residual)
        estimate = DIAGONAL_SAFETY * float((residual / np.diagonal(block)) @ residual)
        if np.isfinite(total) and total > 0.0 and estimate <= tol * total:
            totals[j], settled[j] = total, True
    return totals, settled


def conductance_probe_from_params(params: dict) -> ConductanceProbe:
    """The probe of stored settings (:meth:`ConductanceProbe.params`)."""
    return ConductanceProbe(body_from_params(params["body"]),
                            conductivity=params.get("conductivity"),
                            resistivity=params.get("resistivity"), tol=float(params["tol"]),
                            counter_conductivity=params.get("counter_conductivity"),
                            counter_resistivity=params.get("counter_resistivity"))


#: The bodies a study's conductance may cross (:attr:`ConductionMaterials.body`).
BODY_KINDS = ("block", "halfspace")


@dataclass(frozen=True)
class ConductionMaterials:
    """What a conductance probe needs besides its body's geometry: the body's
    ``conductivity`` [W/(m K)] and/or ``resistivity`` [Ohm m], the CG's ``tol``
    (:class:`ConductanceProbe`), which ``body`` the heat crosses (one of
    :data:`BODY_KINDS`: the job's block, or a half-space) and the counter body's
    ``counter_conductivity`` and ``counter_resistivity`` (None: a perfect conductor);
    with neither of the body's materials, no conductance is recorded
    (:data:`NO_CONDUCTION`). A study's contact jobs share it and each gives it its own
    body (:meth:`probe`)."""

    conductivity: float | None = None
    resistivity: float | None = None
    tol: float = 1e-10
    body: str = "block"
    counter_conductivity: float | None = None
    counter_resistivity: float | None = None

    def __post_init__(self):
        if self.body not in BODY_KINDS:
            raise ValueError(f"body must be one of {BODY_KINDS}, got {self.body!r}")
        if self.enabled:  # refused with the probe's messages, numbers as the probe's
            checked = self.probe(HalfSpaceBody())
            for key in ("conductivity", "resistivity", "tol", "counter_conductivity",
                        "counter_resistivity"):
                object.__setattr__(self, key, getattr(checked, key))

    @property
    def enabled(self) -> bool:
        """A conductivity or a resistivity is given: the probe records something."""
        return self.conductivity is not None or self.resistivity is not None

    def probe(self, body: HalfSpaceBody | BlockBody) -> ConductanceProbe:
        """The probe of these materials through ``body``."""
        return ConductanceProbe(body, self.conductivity, self.resistivity, self.tol,
                                self.counter_conductivity, self.counter_resistivity)

    def params(self) -> dict:
        """Its settings as plain values (empty: none; the counter's only where given)."""
        if not self.enabled:
            return {}
        counter = {key: getattr(self, key) for key in ("counter_conductivity",
                                                       "counter_resistivity")
                   if getattr(self, key) is not None}
        return {"conductivity": self.conductivity, "resistivity": self.resistivity,
                "tol": self.tol, "body": self.body, **counter}


#: No conductance recorded.
NO_CONDUCTION = ConductionMaterials()


def materials_from_params(params: dict) -> ConductionMaterials:
    """The materials of stored settings (:meth:`ConductionMaterials.params`; empty:
    :data:`NO_CONDUCTION`)."""
    if not params:
        return NO_CONDUCTION
    return ConductionMaterials(params.get("conductivity"), params.get("resistivity"),
                               float(params["tol"]), str(params["body"]),
                               params.get("counter_conductivity"),
                               params.get("counter_resistivity"))
