"""What the contact solver solves (:class:`Problem`) and how (:class:`SolverOptions`).

Every entry point of the solver (:func:`roughcontact.contact.solve`,
:func:`~roughcontact.contact.solve_many`, :func:`~roughcontact.contact.sweep`) takes
these two records: the problem, made and checked once from the operator, the gaps,
the cap and the interface grid (:meth:`Problem.of`), and the options, checked when
made. The short keyword forms of the entry points build the problem from their
arguments; :func:`~roughcontact.contact.sweeps.sweep_problem` and
:func:`~roughcontact.contact.methods.solve_problem` take a problem made beforehand.
The method is looked up by name in one registry
(:data:`roughcontact.contact.methods.REGISTRY`) when the two meet
(:class:`roughcontact.contact.methods.Solver`).

All quantities are SI: the operator ``C`` in m/Pa, the gaps in m, the cap in Pa.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from roughcontact.contact import checks
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.loads import LOAD_TOL
from roughcontact.elasticity.protocol import InfluenceOperator

__all__ = ["DEFAULT_OPTIONS", "LOAD_TOL", "Problem", "SolverOptions"]


@dataclass(frozen=True)
class Problem:
    """A checked contact problem: Eq 27 for ``m`` surfaces on one operator.

    Made by :meth:`of`, which checks every part once; the solver then asks nothing
    more of it.

    Attributes
    ----------
    operator : InfluenceOperator
        The influence coefficients ``C`` [m/Pa] with their element area ``dA``
        [m^2], certified symmetric positive definite
        (:func:`roughcontact.contact.checks.check_definite`).
    gaps : ndarray (m, n)
        Initial separations ``f`` [m] (Eq 21), one row per surface.
    shape : tuple
        The shape of one surface as given: ``(ny, nx)`` or ``(n,)``.
    hardness : float or None
        Pressure cap ``H`` [Pa]: Eq 27 over ``0 <= p <= H``; None: no cap.
    interface : InterfaceGrid or None
        The grid a sweep measures the interface quantities and the probes on
        (:mod:`roughcontact.contact.interface`, :mod:`roughcontact.contact.probes`);
        None: none recorded.
    """

    operator: InfluenceOperator
    gaps: np.ndarray
    shape: tuple
    hardness: float | None = None
    interface: InterfaceGrid | None = None

    @classmethod
    def of(cls, operator, gaps0, *, hardness=None, interface: InterfaceGrid | None = None,
           element_area=None, batched: bool = True) -> Problem:
        """The checked problem of ``operator`` and the initial separations ``gaps0``.

        Parameters
        ----------
        operator : ndarray (n, n) or operator object
            Influence coefficients ``C`` [m/Pa]: a dense symmetric matrix (then
            ``element_area`` is required) or an operator object
            (:func:`roughcontact.contact.checks.as_operator`).
        gaps0 : ndarray
            Initial separations ``f`` [m] (Eq 21): ``(m, ny, nx)`` or ``(m, n)``, or with
            ``batched=False`` one surface ``(ny, nx)`` or ``(n,)`` (named ``gap0`` in the
            messages).
        hardness : float, optional
            Pressure cap ``H`` [Pa]; None or ``+inf``: no cap.
        interface : InterfaceGrid, optional
            Record the interface quantities and the grid's probes on it (surfaces of
            shape ``(m, ny, nx)``, or an operator that knows its grid).
        element_area : float, optional
            Element area ``dA`` [m^2]; default ``operator.element_area``.
        batched : bool
            ``gaps0`` holds a batch of surfaces (default) or one.

        Raises
        ------
        ValueError
            Naming the argument at fault, in the order of the parameters;
            :class:`roughcontact.errors.IndefiniteOperator` for an operator that is
            not positive definite.
        """
        hardness = checks.check_hardness(hardness)
        op = checks.as_operator(operator, element_area)
        gaps, shape = checks.check_surfaces(gaps0, op, "gaps0" if batched else "gap0",
                                            batched=batched)
        if interface is not None and len(shape) != 2:
            raise ValueError(f"interface quantities need surfaces of shape (m, ny, nx) "
                             f"or an operator that knows its grid, got {shape}")
        checks.check_definite(op)
        return cls(op, gaps, shape, hardness, interface)


@dataclass(frozen=True)
class SolverOptions:
    """How a contact problem is solved: one record from the job to the solver.

    Checked when made (each message names the field at fault). The method is looked
    up by name when the options meet a problem
    (:class:`roughcontact.contact.methods.Solver`). ``stiffness``, ``stiffness_tol``,
    ``extrapolate``, ``profile`` and ``return_fields`` concern sweeps only
    (:func:`roughcontact.contact.sweep`); a single solve ignores them. Change a
    field with :meth:`with_` (``dataclasses.replace``).

    Attributes
    ----------
    method : str
        One of :data:`roughcontact.contact.methods.METHODS`; ``"auto"`` (default):
        chosen from the operator and the cap
        (:func:`~roughcontact.contact.methods.resolve_method`).
    tol : float
        Tolerance on the dimensionless KKT residual (:mod:`roughcontact.contact.kkt`);
        default 1e-10.
    max_iter : int or None
        Iteration (pivot) limit of each solve; None: the method's
        (``Method.default_max_iter``; pcg also stops a stalled solve).
    precision : {"double", "mixed"}
        ``"mixed"``: single-precision search-direction products (and stiffness CG);
        convergence is decided in double precision either way.
    load_tol : float
        Tolerance on the load under load control, ``|P(d) - P| <= load_tol P`` [-]
        (default :data:`LOAD_TOL`, 1e-8).
    retries : bool
        Solve again where a solve stops short (cold, then by pivoting;
        :mod:`roughcontact.contact.retries`); False returns a method's own result,
        for measuring a method.
    stiffness : bool
        Compute each step's tangent ``contact_stiffness`` ``dF/dd`` [N/m] (else NaN).
    stiffness_tol : float
        Estimated relative error of ``dF/dd`` at which the free-set CG of the
        stiffness stops (:mod:`roughcontact.contact.stiffness`); default 1e-6.
    extrapolate : bool
        Start each step from the extrapolated pressure (only the start changes).
    profile : bool
        Keep every solution's pressure and load profiles
        (:mod:`roughcontact.contact.validity`).
    return_fields : bool
        Keep the pressure fields ``(m, k, *surface shape)`` [Pa].
    """

    method: str = "auto"
    tol: float = 1e-10
    max_iter: int | None = None
    precision: str = "double"
    load_tol: float = LOAD_TOL
    retries: bool = True
    stiffness: bool = True
    stiffness_tol: float = 1e-6
    extrapolate: bool = True
    profile: bool = False
    return_fields: bool = False

    def __post_init__(self):
        checked = {"tol": checks.check_positive(self.tol),
                   "load_tol": checks.check_positive(self.load_tol, "load_tol")}
        checks.check_max_iter(self.max_iter)
        checks.check_precision(self.precision)
        checked["stiffness_tol"] = checks.check_positive(self.stiffness_tol, "stiffness_tol")
        for name in ("retries", "stiffness", "extrapolate", "profile", "return_fields"):
            checked[name] = bool(getattr(self, name))
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    def with_(self, **changes) -> SolverOptions:
        """These options with the fields ``changes`` replaced (checked again)."""
        return dataclasses.replace(self, **changes)


#: The options of a solve or sweep unless told otherwise: ``SolverOptions()``.
DEFAULT_OPTIONS = SolverOptions()
