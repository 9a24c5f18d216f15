"""Force-deflection curves of a contact cell: one record in dimensionless form, one in SI units.

A cell (``m`` surfaces on one body) is swept once in dimensionless form
(:func:`roughcontact.contact.nondim.solve_cell`, a :class:`NondimSweep`) and
read in SI units for any sigma and E (:func:`roughcontact.contact.nondim.to_physical`,
a :class:`PhysicalSweep`). Both records hold the same per-step arrays, declared
once in :class:`CellSweep`, each under the name of its quantity: in SI units in
a PhysicalSweep, made dimensionless in a NondimSweep (by the scale of
:data:`roughcontact.contact.nondim.SI_SCALES`: lengths by sigma, pressures by
``E sigma / L``, ``k_P`` by E). Scalars that are passed on to other code keep
one name per unit: the cap of a capped sweep is ``hardness`` H [Pa] in a
PhysicalSweep and ``nondim_hardness`` ``H L / (E sigma)`` [-] in a NondimSweep.

Every array has shape (m, k): surface by approach step; the pressure and load
profiles of a NondimSweep have shape (m, k, R), the spot-area and gap quantiles
of the interface quantities (m, k, S) and (m, k, G).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from roughcontact.contact.checks import check_positive
from roughcontact.contact.result import (
    INTERFACE,
    INTERFACE_SCALARS,
    INTERFACE_UNITS,
    METHOD_NAME,
    InterfaceColumns,
    ProbedColumns,
    SweepResult,
    zero_plastic_area,
)

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "DIAGNOSTICS",
    "PROFILES",
    "SOLVER_FIELDS",
    "CellSweep",
    "NondimSweep",
    "PhysicalSweep",
    "interface_arrays",
    "solver_arrays",
]

#: Diagnostics of the solves: the same numbers in both records.
DIAGNOSTICS = ("iterations", "matvecs", "residual", "converged", "stiffness_converged")
#: Per-step solution profiles a NondimSweep may hold, (m, k, R).
PROFILES = ("pressure_profile", "load_profile")
#: Record field -> SweepResult field, for the arrays both records read from the
#: solver's :func:`roughcontact.contact.sweep` under the same name.
SOLVER_FIELDS = {name: name for name in ("approach", "mean_plane_deflection",
                                         "real_area_fraction", "max_pressure",
                                         "plastic_area_fraction", *DIAGNOSTICS)}
#: dtype of the per-step arrays that are not floats.
_DTYPES = {"iterations": int, "matvecs": int, "converged": bool, "stiffness_converged": bool}


@dataclass(frozen=True, kw_only=True)
class CellSweep(InterfaceColumns, ProbedColumns):
    """The per-step arrays of a swept cell, shared by :class:`NondimSweep` and
    :class:`PhysicalSweep` (units: SI, and in brackets the dimensionless form).

    Attributes
    ----------
    approach : ndarray
        Rigid approach ``d`` [m] (``d / sigma``).
    nominal_pressure : ndarray
        ``P = F / A_n`` [Pa] (``P L / (E sigma)``).
    mean_plane_deflection : ndarray
        ``d_b``, the mean of ``u`` [m] (Eq 35) (``d_b / sigma``).
    real_area_fraction : ndarray
        Fraction of elements in contact, ``p > 0`` [-] (saturated ones included).
    max_pressure : ndarray
        Largest element pressure [Pa] (``p_max L / (E sigma)``).
    normalized_stiffness : ndarray
        ``k_P = (L / A_n) dF/dd`` at fixed contact set [Pa] (Eq 33)
        (``k_P / E = dPhat / ddhat``).
    plastic_area_fraction : ndarray
        Fraction of elements at the hardness cap [-]; zeros for an elastic
        sweep (also when not given to the constructor).
    iterations, matvecs : ndarray of int
        Work of the contact solve at each step.
    residual : ndarray
        KKT residual of each solve [-] (:mod:`roughcontact.contact`; the same
        in both forms).
    converged : ndarray of bool
        The contact solve reached its ``tol`` and every value it reported is finite.
    stiffness_converged : ndarray of bool
        The active-set CG of the stiffness reached its ``stiffness_tol`` and
        the stiffness is finite.
    thickness : float
        Block thickness ``L`` [m] (for a half-space, the reference length of
        the scaling).
    spot_count, mean_spot_area, perimeter, corrected_real_area_fraction : ndarray or None
        The contact spots (count, mean area [m^2]), the Manhattan perimeter [m] and
        the perimeter-corrected real area fraction [-]
        (:mod:`roughcontact.contact.interface`): the same in both forms (lateral
        lengths do not scale); None when not recorded.
    mean_gap : ndarray or None
        Mean interfacial separation [m] (``/ sigma``); None when not recorded.
    spot_area_quantiles, gap_quantiles : ndarray or None
        (m, k, S) spot areas [m^2] and (m, k, G) gaps [m] (``/ sigma``) at the
        probabilities of :mod:`roughcontact.contact.interface`; None when not recorded.
    counter_deflection : ndarray or None
        Of a pair of elastic bodies: the counter body's mean-plane deflection [m]
        (``/ sigma``; :mod:`roughcontact.contact.counterface`); None with a rigid one.
    probe_columns : ProbeColumns
        The columns of the probes the sweep was given
        (:mod:`roughcontact.contact.probes`), by name: in SI units (in units of
        ``sigma**length_power`` of each :class:`~roughcontact.contact.probes.Column`);
        empty without probes.
    """

    approach: np.ndarray
    nominal_pressure: np.ndarray
    mean_plane_deflection: np.ndarray
    real_area_fraction: np.ndarray
    max_pressure: np.ndarray
    normalized_stiffness: np.ndarray
    iterations: np.ndarray
    matvecs: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    stiffness_converged: np.ndarray
    thickness: float
    plastic_area_fraction: np.ndarray | None = None
    counter_deflection: np.ndarray | None = None

    def __post_init__(self):
        zero_plastic_area(self)


@dataclass(frozen=True, kw_only=True)
class NondimSweep(CellSweep):
    """Dimensionless force-deflection sweep of one cell
    (:mod:`roughcontact.contact.nondim`): the arrays of :class:`CellSweep` in
    their dimensionless form, and the settings of the solve.

    Attributes
    ----------
    element_area : float
        Contact element area ``dA`` [m^2] of the influence matrix.
    n_elements : int
        Contact elements per surface ``n``.
    method, tol, stiffness_tol, precision, max_iter
        Settings of the contact and stiffness solves (``max_iter`` None: the
        solver's default).
    nondim_hardness : float or None
        Dimensionless pressure cap ``H L / (E sigma)`` of a capped sweep
        (``0 <= p L / (E sigma) <= H L / (E sigma)``); None for the elastic problem.
    profile_ranks, pressure_profile, load_profile : ndarray or None
        The solutions' pressure profiles (dimensionless, like ``max_pressure``)
        and load profiles at the ranks ``profile_ranks``
        (:mod:`roughcontact.contact.validity`); None when not recorded.
    solved_by : ndarray of str
        (m, k): the method whose solution each step holds, ``method`` or the
        fallback that answered where it fell short
        (:mod:`roughcontact.contact.retries`); ``method`` everywhere when not given.
    """

    element_area: float
    n_elements: int
    method: str
    tol: float
    stiffness_tol: float
    precision: str
    max_iter: int | None
    nondim_hardness: float | None = None
    profile_ranks: np.ndarray | None = None
    pressure_profile: np.ndarray | None = None
    load_profile: np.ndarray | None = None
    solved_by: np.ndarray | None = None

    def __post_init__(self):
        super().__post_init__()
        named = (np.full(np.shape(self.approach), self.method, dtype=METHOD_NAME)
                 if self.solved_by is None else np.asarray(self.solved_by).astype(METHOD_NAME))
        object.__setattr__(self, "solved_by", named)

    @property
    def nominal_area(self) -> float:
        """Nominal contact area ``A_n = n dA`` [m^2]."""
        return self.n_elements * self.element_area


@dataclass(frozen=True, kw_only=True)
class PhysicalSweep(CellSweep):
    """Force-deflection sweep of one cell in SI units, for one (sigma, E): the
    arrays of :class:`CellSweep` and those that need the nominal area.

    Attributes
    ----------
    load : ndarray
        Total force ``F = P A_n`` [N].
    contact_stiffness : ndarray
        ``dF/dd`` at fixed contact set [N/m].
    sigma : float
        Height scale [m] (NaN if the sweep was solved directly in SI units).
    E : float
        Young's modulus [Pa] (NaN if solved directly in SI units).
    nominal_area : float
        ``A_n`` [m^2].
    hardness : float or None
        Pressure cap ``H`` [Pa] of a capped sweep; None for the elastic problem.
    """

    load: np.ndarray
    contact_stiffness: np.ndarray
    sigma: float
    E: float
    nominal_area: float
    hardness: float | None = None

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
        thickness = check_positive(thickness, "thickness")
        nominal_area = check_positive(nominal_area, "nominal_area")
        arrays = solver_arrays(result, {**SOLVER_FIELDS, "load": "load",
                                        "nominal_pressure": "nominal_pressure",
                                        "contact_stiffness": "contact_stiffness"},
                               stiffness="contact_stiffness")
        return cls(**arrays, **interface_arrays(result), probe_columns=result.probe_columns,
                   normalized_stiffness=thickness / nominal_area * arrays["contact_stiffness"],
                   sigma=float(sigma), E=float(E), thickness=thickness,
                   nominal_area=nominal_area, hardness=result.hardness)

    def to_frame(self) -> pd.DataFrame:
        """One row per (surface, step), long format.

        Columns: ``surface``, ``step`` (0-based), ``approach`` [m], ``load``
        [N], ``nominal_pressure`` [Pa], ``mean_plane_deflection`` [m],
        ``asperity_deflection`` [m], ``real_area_fraction`` [-],
        ``max_pressure`` [Pa], ``contact_stiffness`` [N/m],
        ``normalized_stiffness`` [Pa], ``iterations``, ``matvecs``,
        ``residual`` [-], ``converged``, ``stiffness_converged``,
        ``plastic_area_fraction``, ``plastic_load_fraction`` [-] and, when
        recorded, the (m, k) interface quantities (``spot_count``,
        ``mean_spot_area`` [m^2], ``perimeter`` [m], ``corrected_real_area_fraction``
        [-], ``mean_gap`` [m]) and the probe columns (in their
        :class:`~roughcontact.contact.probes.Column` units; ``bool`` for a yes/no
        state). The units are also in ``frame.attrs["units"]``, the scales in
        ``frame.attrs``.
        """
        m, k = self.approach.shape
        columns = {
            "surface": np.repeat(np.arange(m), k),
            "step": np.tile(np.arange(k), m),
        }
        units = dict(_PHYSICAL_UNITS)
        if self.mean_gap is not None:
            units.update({name: INTERFACE_UNITS[name] for name in INTERFACE_SCALARS})
        units.update({column.name: "bool" if column.state else column.unit
                      for column in self.probe_columns.specs})
        for name in units:
            columns[name] = np.asarray(self.column(name)).ravel()
        import pandas as pd

        frame = pd.DataFrame(columns)
        frame.attrs.update(units=units, sigma=self.sigma, E=self.E,
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


def interface_arrays(result) -> dict:
    """The interface quantities (:data:`~roughcontact.contact.result.INTERFACE`) of a
    solver sweep or record, by name; empty when it did not record them."""
    if result.mean_gap is None:
        return {}
    arrays = {name: np.asarray(getattr(result, name)) for name in INTERFACE}
    if result.counter_deflection is not None:  # a pair of elastic bodies
        arrays["counter_deflection"] = np.asarray(result.counter_deflection)
    return arrays


def solver_arrays(result, names: Mapping[str, str], stiffness: str) -> dict:
    """The per-step arrays of a solver sweep under the names of a record.

    Parameters
    ----------
    result : SweepResult
        Result of :func:`roughcontact.contact.sweep`.
    names : mapping
        Record field -> the ``result`` field it is read from.
    stiffness : str
        The record field of the stiffness, vouched for by ``stiffness_converged``.

    Returns
    -------
    dict
        Record field -> (m, k) array (int for the counts, bool for the flags,
        float otherwise). A step with a non-finite stiffness is flagged
        ``stiffness_converged=False``, one with any other non-finite value
        ``converged=False``.
    """
    arrays = {name: np.asarray(getattr(result, source), dtype=_DTYPES.get(name, float))
              for name, source in names.items()}
    finite = np.logical_and.reduce([np.isfinite(values) for name, values in arrays.items()
                                    if name not in _DTYPES and name != stiffness])
    arrays["converged"] = arrays["converged"] & finite
    arrays["stiffness_converged"] = arrays["stiffness_converged"] & np.isfinite(arrays[stiffness])
    return arrays
