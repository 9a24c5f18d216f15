"""Spot conductance of a contact set: uniform temperature on the spots, no flux elsewhere.

Two bodies touch on a set ``A`` of contact elements. Heat (or current) crosses
only there: the flux density ``q`` [W/m^2] is zero off ``A``, and on ``A`` the
two faces have one temperature. With ``R`` [K m^2/W] the thermal influence of
the pair, the sum of the two bodies' influences (they are in series: the same
flux leaves one face and enters the other, their temperature rises add, ``R =
R1 + R2``, :func:`in_series`), a unit temperature drop across the interface
gives

    R_AA q_A = 1,     C = dA 1^T q_A = dA 1^T (R_AA)^-1 1     [W/K],

the interface's conductance (Holm 1967, Sec 4: the constriction resistance of
isothermal spots; the same equation Greenwood 1966 solves for clusters of
spots). ``R_AA`` is symmetric positive definite, so the solve is the tangent
stiffness's (:func:`roughcontact.contact.stiffness.free_set_cg`: conjugate
gradients on ``A``, the error of ``C`` bounded by ``tol`` through its
variational estimate), and on half-spaces the two coincide up to ``2 k / E*``
(Barber 2003: ``C = 2 K / (E* (rho1 + rho2))``, ``K`` the tangent stiffness of
the same contact set, ``rho = 1 / k``).

The resistance ``1 / C`` [K/W] splits into the **bulk** resistance, that of
full contact (``L / (k A_n)`` for a block of thickness ``L`` with an isothermal
base: :func:`full_contact_resistance`; 0 on a half-space, whose bulk is
infinite and whose temperatures are taken from the mean plane) and the
**constriction** resistance, the rest: what the spots add by funnelling the
heat (:class:`SpotConductance`). The electrical contact resistance is the same
problem with electrical conductivities ``1 / rho_e`` [S/m] in the influences:
``C`` in S, ``1 / C`` in Ohm (``quantity="electrical"``).

References
----------
R. Holm, Electric Contacts: Theory and Application, 4th ed., Springer (1967), Sec 4.
J. A. Greenwood, "Constriction resistance and the real area of contact",
Br. J. Appl. Phys. 17 (1966) 1621-1632.
J. R. Barber, "Bounds on the electrical resistance between contacting elastic
rough bodies", Proc. R. Soc. Lond. A 459 (2003) 53-66.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from roughcontact.contact.checks import as_operator, check_positive
from roughcontact.contact.counterface import equivalent_operator
from roughcontact.contact.products import Products
from roughcontact.contact.stiffness import free_set_cg

__all__ = ["QUANTITIES", "SpotConductance", "full_contact_resistance", "in_series",
           "spot_conductance"]

#: What crosses the interface -> the units of the record's conductance, conductance
#: per nominal area and resistances.
QUANTITIES = MappingProxyType({
    "thermal": MappingProxyType({"conductance": "W/K", "conductance_per_area": "W/(m^2 K)",
                                 "resistance": "K/W"}),
    "electrical": MappingProxyType({"conductance": "S", "conductance_per_area": "S/m^2",
                                    "resistance": "Ohm"}),
})


@dataclass(frozen=True)
class SpotConductance:
    """The conductance of one contact set and its split into bulk and constriction.

    Attributes
    ----------
    conductance : float
        ``C = dA 1^T (R_AA)^-1 1`` [W/K, or S for the electrical quantity].
    nominal_area : float
        ``A_n`` [m^2], the area of the contact grid.
    bulk_resistance : float
        Resistance of full contact [K/W or Ohm] (0 on half-spaces).
    contact_elements : int
        Elements in ``A``.
    converged : bool
        Whether CG met its tolerance on ``C``.
    products : int
        Operator products the CG took.
    quantity : {"thermal", "electrical"}
        What crosses the interface; the units follow (:data:`QUANTITIES`).
    """

    conductance: float
    nominal_area: float
    bulk_resistance: float
    contact_elements: int
    converged: bool
    products: int
    quantity: str = "thermal"

    def __post_init__(self):
        if self.quantity not in QUANTITIES:
            raise ValueError(f"quantity must be one of {tuple(QUANTITIES)}, "
                             f"got {self.quantity!r}")

    @property
    def units(self):
        """Units of ``conductance``, ``conductance_per_area`` and the resistances."""
        return QUANTITIES[self.quantity]

    @property
    def conductance_per_area(self) -> float:
        """``h_c = C / A_n`` [W/(m^2 K), or S/m^2]."""
        return self.conductance / self.nominal_area

    @property
    def resistance(self) -> float:
        """``1 / C`` [K/W or Ohm]; inf without contact."""
        return 1.0 / self.conductance if self.conductance > 0.0 else np.inf

    @property
    def constriction_resistance(self) -> float:
        """``1 / C - R_bulk`` [K/W or Ohm]: what the spots add to full contact."""
        return self.resistance - self.bulk_resistance

    @property
    def bulk_share(self) -> float:
        """``R_bulk C`` [-]: the bulk's share of the resistance (0 on half-spaces)."""
        return self.bulk_resistance * self.conductance


def in_series(first, second=None, *, element_area: float | None = None):
    """The influence of two bodies in series, ``R1 + R2`` [K m^2/W] (module docstring).

    The sum of compliances of :func:`roughcontact.contact.counterface.equivalent_operator`:
    a dense pair summed into one matrix, matrix-free operators added product by
    product; ``second`` None (a perfect conductor) returns ``first``.
    """
    return equivalent_operator(first, second, element_area=element_area)


def _conductance_solve(op, contact: np.ndarray, tol: float, max_iter: int | None):
    """``(dA 1^T (R_AA)^-1 1, converged, products)`` of one contact set by CG."""
    n = op.shape[0]
    limit = max(1000, 2 * n) if max_iter is None else int(max_iter)
    solution = free_set_cg(Products(op), contact.reshape(1, n), np.zeros((1, n)), tol, limit)
    return (float(op.element_area * solution.total[0]), bool(solution.converged[0]),
            int(solution.products[0]))


def full_contact_resistance(resistance, *, element_area: float | None = None,
                            tol: float = 1e-12, max_iter: int | None = None) -> float:
    """Resistance of full contact [K/W]: ``1 / (dA 1^T R^-1 1)``, the bulk of the body.

    ``L / (k A_n)`` for a block of thickness ``L`` with an isothermal base (its
    rows sum to ``L / k``; the sum of the two for blocks in series). Not for a
    half-space: its bulk is unbounded (a periodic one's ``R`` is singular with
    ``mean_compliance = 0``); take 0 there.
    """
    op = as_operator(resistance, element_area)
    conductance, _, _ = _conductance_solve(op, np.ones(op.shape[0], dtype=bool), tol, max_iter)
    return 1.0 / conductance


def spot_conductance(resistance, contact, *, bulk_resistance: float = 0.0,
                     element_area: float | None = None, tol: float = 1e-10,
                     max_iter: int | None = None, quantity: str = "thermal") -> SpotConductance:
    """The conductance of the contact set ``contact`` through ``resistance`` (module docstring).

    Parameters
    ----------
    resistance : ndarray (n, n) or influence operator
        Thermal influence ``R`` [K m^2/W] of the pair (:func:`in_series`), or the
        electrical one [Ohm m^2]; symmetric positive definite on ``A``.
    contact : array_like of bool, n elements (any shape)
        The contact set ``A``, e.g. ``pressure > 0`` of a solved step.
    bulk_resistance : float, optional
        Full-contact resistance [K/W or Ohm] (:func:`full_contact_resistance`;
        0, the default, for half-spaces).
    element_area : float, optional
        ``dA`` [m^2] of a plain ndarray ``resistance``.
    tol : float, optional
        Estimated relative error of ``C`` at which the CG stops.
    max_iter : int, optional
        CG iteration limit, default ``max(1000, 2 n)``.
    quantity : {"thermal", "electrical"}
        Names the units of the record.

    Returns
    -------
    SpotConductance
        ``C`` (0 without contact), ``h_c``, the bulk and constriction resistances.
    """
    op = as_operator(resistance, element_area)
    n = op.shape[0]
    mask = np.asarray(contact, dtype=bool).reshape(-1)
    if mask.size != n:
        raise ValueError(f"contact must have {n} elements (the operator's), got {mask.size}")
    tol = check_positive(tol)
    bulk = float(bulk_resistance)
    if not (np.isfinite(bulk) and bulk >= 0.0):
        raise ValueError(f"bulk_resistance must be a finite non-negative K/W, got {bulk!r}")
    conductance, converged, products = _conductance_solve(op, mask, tol, max_iter) \
        if mask.any() else (0.0, True, 0)
    return SpotConductance(conductance, float(op.element_area * n), bulk,
                           int(np.count_nonzero(mask)), converged, products, quantity)
