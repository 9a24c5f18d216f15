"""What the contact solvers return, and the work records they fill on the way.

:class:`ContactResult` (one surface at one approach) and :class:`SweepResult`
(m surfaces over k approaches) are the frozen results of every method: the
same fields whichever method solved, the method named in ``method``.
:class:`Batch` and :class:`SweepTable` are the mutable records the methods
fill (rows = surfaces) before the results are frozen. All quantities SI:
pressures in Pa, lengths in m, loads in N, stiffnesses in N/m.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from roughcontact.contact import interface, probes, validity
from roughcontact.contact.kkt import plastic_fraction
from roughcontact.contact.probes import ProbeColumns

__all__ = ["INTERFACE", "INTERFACE_SCALARS", "INTERFACE_UNITS", "METHOD_NAME", "Batch",
           "ContactResult",
           "InterfaceColumns", "ProbedColumns", "SweepResult", "SweepTable",
           "zero_plastic_area"]


@dataclass(frozen=True)
class ContactResult:
    """Solution of one displacement-controlled contact problem (Eq 27).

    Attributes
    ----------
    pressure : ndarray
        Contact pressure ``p`` [Pa], same shape as the ``gap0`` passed in.
    displacement : ndarray
        Elastic surface displacement ``u = C p`` [m] (Eq 16).
    gap : ndarray
        ``u + f - d`` [m]; zero in contact, positive outside (Eq 19-22).
    approach : float
        Rigid-body approach ``d`` [m].
    load : float
        Total force ``F = sum p dA`` [N].
    nominal_pressure : float
        ``P = F / A_n`` [Pa], ``A_n = n dA`` the nominal area.
    real_area_fraction : float
        Fraction of elements with ``p > 0`` [-] (saturated ones included).
    max_pressure : float
        Largest element pressure [Pa].
    mean_plane_deflection : float
        Mean of ``u`` [m], the bulk deflection ``d_b`` of Eq 35.
    iterations : int
        Iterations (pivots for ``"exact"`` and ``"pivot"``) performed.
    matvecs : int
        Applications of ``C`` to a pressure field, counting partial
        (column-subset) products by their share of a full product, rounded up.
    residual : float
        Dimensionless KKT residual (:mod:`roughcontact.contact.kkt`) of the
        returned ``p``.
    converged : bool
        ``residual <= tol``.
    method : str
        The method whose solution this is: the one asked for, or the fallback that
        answered where it did not converge (:mod:`roughcontact.contact.retries`).
    tol : float
        Requested tolerance on ``residual``.
    plastic_area_fraction : float
        Fraction of elements at the cap, ``p = H`` [-]; 0 without a cap.
    hardness : float or None
        Pressure cap ``H`` [Pa] of the solve; None without a cap.
    """

    pressure: np.ndarray
    displacement: np.ndarray
    gap: np.ndarray
    approach: float
    load: float
    nominal_pressure: float
    real_area_fraction: float
    max_pressure: float
    mean_plane_deflection: float
    iterations: int
    matvecs: int
    residual: float
    converged: bool
    method: str
    tol: float
    plastic_area_fraction: float = 0.0
    hardness: float | None = None

    @property
    def contact_set(self) -> np.ndarray:
        """The elements in contact, ``p > 0`` (bool, shape of ``pressure``)."""
        return self.pressure > 0.0


@dataclass(frozen=True, kw_only=True)
class InterfaceColumns:
    """The interface quantities (:mod:`roughcontact.contact.interface`) a sweep or a
    record may hold, None when not recorded: ``spot_count``, ``mean_spot_area``,
    ``perimeter``, ``corrected_real_area_fraction``, ``mean_gap`` (m, k) and the
    ``spot_area_quantiles`` (m, k, S) and ``gap_quantiles`` (m, k, G)."""

    spot_count: np.ndarray | None = None
    mean_spot_area: np.ndarray | None = None
    perimeter: np.ndarray | None = None
    corrected_real_area_fraction: np.ndarray | None = None
    mean_gap: np.ndarray | None = None
    spot_area_quantiles: np.ndarray | None = None
    gap_quantiles: np.ndarray | None = None


@dataclass(frozen=True, kw_only=True)
class ProbedColumns:
    """The columns of the probes (:mod:`roughcontact.contact.probes`) a sweep or a record
    holds: ``probe_columns``, name -> (m, k) array, empty without probes."""

    probe_columns: ProbeColumns = field(default_factory=ProbeColumns)

    def column(self, name: str) -> np.ndarray:
        """The per-step array ``name``: a field, or a probe column."""
        if name in self.probe_columns:
            return self.probe_columns[name]
        return getattr(self, name)


#: The interface quantities' names (the fields of :class:`InterfaceColumns`), the (m, k)
#: ones among them, and the unit of each.
INTERFACE = tuple(field.name for field in fields(InterfaceColumns))
INTERFACE_SCALARS = tuple(name for name in INTERFACE if not name.endswith("_quantiles"))
INTERFACE_UNITS = {"spot_count": "1", "mean_spot_area": "m^2", "perimeter": "m",
                   "corrected_real_area_fraction": "1", "mean_gap": "m",
                   "spot_area_quantiles": "m^2", "gap_quantiles": "m"}


@dataclass(frozen=True)
class SweepResult(InterfaceColumns, ProbedColumns):
    """Force-deflection sweep of m surfaces over k approaches.

    Every array has shape (m, k): surface by approach step, except
    ``pressure`` ``(m, k, *surface shape)``, present only when fields were asked
    for.

    Attributes
    ----------
    approach : ndarray
        Rigid-body approach ``d`` [m].
    load : ndarray
        Total force ``F`` [N].
    nominal_pressure : ndarray
        ``P = F / A_n`` [Pa].
    mean_plane_deflection : ndarray
        Mean of ``u`` [m] (Eq 35).
    real_area_fraction : ndarray
        Fraction of elements in contact, ``p > 0`` [-] (saturated ones included).
    max_pressure : ndarray
        Largest element pressure [Pa].
    contact_stiffness : ndarray
        ``dF/dd`` [N/m] at fixed contact set (and, with a cap, fixed
        saturated set), see :func:`roughcontact.contact.tangent_stiffness`;
        NaN where it was not computed. The normalized stiffness of Eq 33 is
        ``k_P = (L / A_n) dF/dd``.
    iterations, matvecs : ndarray of int
        Work of the contact solve at each step.
    residual : ndarray
        KKT residual of each solution.
    converged : ndarray of bool
        Contact solve converged.
    stiffness_converged : ndarray of bool
        The free-set solve for ``contact_stiffness`` converged.
    pressure : ndarray or None
        Pressure fields [Pa] when ``return_fields=True``.
    method : str
        Contact method asked for (``"auto"`` resolved).
    tol : float
        Contact tolerance.
    plastic_area_fraction : ndarray
        Fraction of elements at the cap, ``p = H`` [-]; zeros without a cap
        (also when not given to the constructor).
    hardness : float or None
        Pressure cap ``H`` [Pa] of the sweep; None without a cap.
    profile_ranks : ndarray of int or None
        Ranks of the profiles, (R,), when ``profile=True``.
    pressure_profile : ndarray or None
        (m, k, R): the ``r``-th largest element pressure [Pa] of each solution
        at the ranks ``r`` of ``profile_ranks``.
    load_profile : ndarray or None
        (m, k, R): share of the load on the ``r`` most loaded elements [-].
    solved_by : ndarray of str
        (m, k): the method whose solution each step holds: ``method``, or the
        fallback that answered where it did not converge
        (:mod:`roughcontact.contact.retries`); ``method`` everywhere when not given.
    counter_deflection : ndarray or None
        (m, k): the mean-plane deflection of the counter body [m] of a pair of
        elastic bodies (``w . p``, the ``counter_weights`` of the ``interface``
        grid; :mod:`roughcontact.contact.counterface`); the first body's is
        ``mean_plane_deflection - counter_deflection``. None without one.
    spot_count, mean_spot_area, perimeter, corrected_real_area_fraction, mean_gap : ndarray or None
        (m, k): the interface quantities of :mod:`roughcontact.contact.interface`
        (number of contact spots, their mean area [m^2], the Manhattan perimeter
        [m], the perimeter-corrected real area fraction [-] and the mean gap
        [m]) when an ``interface`` grid was given; None otherwise.
    spot_area_quantiles, gap_quantiles : ndarray or None
        (m, k, S) and (m, k, G): spot areas [m^2] at
        :data:`~roughcontact.contact.interface.SPOT_PROBABILITIES` and gaps [m] at
        :data:`~roughcontact.contact.interface.GAP_PROBABILITIES`, likewise.
    probe_columns : ProbeColumns
        (m, k) each: the columns of the ``interface`` grid's probes
        (:mod:`roughcontact.contact.probes`), by name; empty without probes.
    """

    approach: np.ndarray
    load: np.ndarray
    nominal_pressure: np.ndarray
    mean_plane_deflection: np.ndarray
    real_area_fraction: np.ndarray
    max_pressure: np.ndarray
    contact_stiffness: np.ndarray
    iterations: np.ndarray
    matvecs: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    stiffness_converged: np.ndarray
    pressure: np.ndarray | None
    method: str
    tol: float
    plastic_area_fraction: np.ndarray | None = None
    hardness: float | None = None
    profile_ranks: np.ndarray | None = None
    pressure_profile: np.ndarray | None = None
    load_profile: np.ndarray | None = None
    counter_deflection: np.ndarray | None = None
    solved_by: np.ndarray | None = None

    def __post_init__(self):
        zero_plastic_area(self)
        if self.solved_by is None:
            object.__setattr__(self, "solved_by",
                               np.full(np.shape(self.approach), self.method, dtype=METHOD_NAME))


def zero_plastic_area(result) -> None:
    """Give a frozen result built without ``plastic_area_fraction`` zeros (no cap) of
    its ``approach``'s shape (the ``__post_init__`` of the sweep results)."""
    if result.plastic_area_fraction is None:
        object.__setattr__(result, "plastic_area_fraction", np.zeros(np.shape(result.approach)))


# ---------------------------------------------------------------------------
# Work records


#: The dtype of a method's name in the per-step records (``solved_by``).
METHOD_NAME = "<U16"


@dataclass
class Batch:
    """Per-surface outputs of a batched solve at one approach (mutable), rows = surfaces;
    ``solved_by`` the method whose solution each row holds (set by
    :func:`roughcontact.contact.retries.settle`; None before)."""

    pressure: np.ndarray
    displacement: np.ndarray
    iterations: np.ndarray
    matvecs: np.ndarray
    residual: np.ndarray
    converged: np.ndarray
    solved_by: np.ndarray | None = None

    @classmethod
    def empty(cls, m: int, n: int) -> Batch:
        return cls(
            pressure=np.zeros((m, n)),
            displacement=np.zeros((m, n)),
            iterations=np.zeros(m, dtype=int),
            matvecs=np.zeros(m),
            residual=np.zeros(m),
            converged=np.zeros(m, dtype=bool),
        )

    def store(self, target, pressure, displacement, iterations, matvecs, residual,
              tol: float) -> None:
        """The solutions of the surfaces ``target`` (rows of the batch)."""
        self.pressure[target] = pressure
        self.displacement[target] = displacement
        self.iterations[target] = iterations
        self.matvecs[target] = matvecs
        self.residual[target] = residual
        self.converged[target] = residual <= tol

    def count_whole_products(self) -> None:
        """Round the product counts up to whole products (partial ones count by share)."""
        self.matvecs = np.ceil(self.matvecs - 1e-9).astype(int)

    def contact_result(self, j: int, rigid_j, element_area: float, shape, method: str,
                       tol: float, approach, hardness=None) -> ContactResult:
        """The :class:`ContactResult` of surface ``j`` (rigid interference ``d - f``
        of ``rigid_j`` [m]), fields in ``shape``."""
        p = self.pressure[j]
        u = self.displacement[j]
        n = p.size
        load = float(p.sum() * element_area)
        return ContactResult(
            pressure=p.reshape(shape).copy(),
            displacement=u.reshape(shape).copy(),
            gap=(u + rigid_j).reshape(shape),
            approach=float(approach),
            load=load,
            nominal_pressure=load / (n * element_area),
            real_area_fraction=float(np.count_nonzero(p > 0.0)) / n,
            max_pressure=float(p.max()),
            mean_plane_deflection=float(u.mean()),
            iterations=int(self.iterations[j]),
            matvecs=int(self.matvecs[j]),
            residual=float(self.residual[j]),
            converged=bool(self.converged[j]),
            method=method,
            tol=tol,
            plastic_area_fraction=float(plastic_fraction(p, hardness)),
            hardness=hardness,
        )


class SweepTable:
    """The (m, k) columns of a :class:`SweepResult` being filled step by step (mutable).

    ``columns`` holds every array field of the result by name; ``probe_columns``
    the columns of the interface grid's probes (:mod:`roughcontact.contact.probes`;
    empty without); ``fields`` the pressure fields ``(m, k, *shape)`` or None;
    ``ranks`` the profile ranks or None; ``interface`` the
    :class:`~roughcontact.contact.interface.InterfaceGrid` of the interface quantities,
    or None.
    """

    def __init__(self, m: int, k: int, shape, return_fields: bool, profile: bool,
                 interface_grid: interface.InterfaceGrid | None = None):
        n = int(np.prod(shape))
        self.shape = tuple(shape)
        self.interface = interface_grid
        self.surfaces = m
        #: step -> {surface: (pressure, gap)} of the surfaces recorded one at a time
        #: (block principal pivoting), described together once the step is complete
        self._pending: dict[int, dict[int, tuple]] = {}
        if interface_grid is not None:  # fields of (ny, nx): checked by Problem.of
            columns = {name: np.zeros((m, k)) for name in INTERFACE_SCALARS}
            columns["spot_count"] = np.zeros((m, k), dtype=int)
            columns["spot_area_quantiles"] = np.zeros((m, k, len(interface.SPOT_PROBABILITIES)))
            columns["gap_quantiles"] = np.zeros((m, k, len(interface.GAP_PROBABILITIES)))
            if interface_grid.counter_weights is not None:
                columns["counter_deflection"] = np.zeros((m, k))
            self.probe_columns = ProbeColumns.allocated(interface_grid.probes, (m, k))
        else:
            columns = {}
            self.probe_columns = ProbeColumns()
        names = ("load", "nominal_pressure", "mean_plane_deflection", "real_area_fraction",
                 "max_pressure", "residual", "plastic_area_fraction")
        self.columns = {name: np.zeros((m, k)) for name in names}
        self.columns["contact_stiffness"] = np.full((m, k), np.nan)
        for name in ("iterations", "matvecs"):
            self.columns[name] = np.zeros((m, k), dtype=int)
        for name in ("converged", "stiffness_converged"):
            self.columns[name] = np.zeros((m, k), dtype=bool)
        self.columns["solved_by"] = np.full((m, k), "", dtype=METHOD_NAME)
        self.fields = np.zeros((m, k, *shape)) if return_fields else None
        self.ranks = validity.rank_grid(n) if profile else None
        if profile:
            self.columns["pressure_profile"] = np.zeros((m, k, self.ranks.size))
            self.columns["load_profile"] = np.zeros((m, k, self.ranks.size))
        self.columns.update(columns)

    def record(self, rows, step: int, pressure, displacement, residual, element_area: float,
               hardness=None, gap=None) -> None:
        """A step's summary columns for ``rows`` (a surface or a slice), from the solved
        pressure [Pa] and displacement [m] (last axis: elements); with profiles, also
        its pressure and load profiles (:mod:`roughcontact.contact.validity`); with an
        interface grid, the interface quantities of the gap ``u + f - d`` [m]
        (:mod:`roughcontact.contact.interface`); with fields, the pressure field."""
        columns = self.columns
        mean_u = displacement.mean(axis=-1)
        if self.interface is not None:
            if isinstance(rows, int | np.integer):  # one surface: wait for its step's others
                pending = self._pending.setdefault(step, {})
                pending[int(rows)] = (np.array(pressure), np.array(gap), mean_u)
                if len(pending) == self.surfaces:
                    self._describe_pending(step)
            else:
                self._describe(rows, step, pressure, gap, mean_u)
        n = pressure.shape[-1]
        load = pressure.sum(axis=-1) * element_area
        columns["load"][rows, step] = load
        columns["nominal_pressure"][rows, step] = load / (n * element_area)
        columns["mean_plane_deflection"][rows, step] = mean_u
        if "counter_deflection" in columns:  # a pair of bodies: w . p (counterface)
            columns["counter_deflection"][rows, step] = pressure @ self.interface.counter_weights
        columns["real_area_fraction"][rows, step] = np.count_nonzero(pressure > 0.0, axis=-1) / n
        columns["max_pressure"][rows, step] = pressure.max(axis=-1)
        columns["plastic_area_fraction"][rows, step] = plastic_fraction(pressure, hardness)
        columns["residual"][rows, step] = residual
        if self.ranks is not None:
            values, shares = validity.pressure_profile(pressure, self.ranks)
            columns["pressure_profile"][rows, step] = values
            columns["load_profile"][rows, step] = shares
        if self.fields is not None:
            self.fields[rows, step] = pressure.reshape(*np.shape(pressure)[:-1],
                                                       *self.fields.shape[2:])

    def _describe(self, rows, step: int, pressure, gap, mean_u) -> None:
        """The interface quantities of ``rows`` at ``step`` (:mod:`.interface`), and the
        columns of the interface grid's probes (:mod:`.probes`), which read the fields
        at the nominal separations ``mean(g) - mean(u) = mean(f) - d`` of the flat and
        the undeformed mean plane (``mean_u``: the mean of each displacement field)."""
        pressure = np.reshape(pressure, (*np.shape(pressure)[:-1], *self.shape))
        gap = np.reshape(gap, (*np.shape(gap)[:-1], *self.shape))
        summary = interface.describe(pressure, gap, self.interface)
        for name in INTERFACE:
            self.columns[name][rows, step] = getattr(summary, name)
        fields = probes.SolvedFields(pressure, gap, summary.mean_gap - mean_u,
                                     self.interface.spacing, self.interface.periodic)
        for name, values in probes.measure(self.probe_columns.probes, fields).items():
            self.probe_columns[name][rows, step] = values

    def _describe_pending(self, step: int) -> None:
        """The surfaces of ``step`` recorded one at a time, described together (one call
        for many small fields costs a fraction of one call each)."""
        pending = self._pending.pop(step)
        rows = np.fromiter(pending, dtype=np.intp)
        self._describe(rows, step, np.stack([pending[j][0] for j in rows]),
                       np.stack([pending[j][1] for j in rows]),
                       np.array([pending[j][2] for j in rows]))

    def record_work(self, rows, step: int, iterations, matvecs, converged,
                    solved_by=None) -> None:
        """The work of a step's contact solve for ``rows``, and the method whose solution
        each holds (None: the sweep's)."""
        self.columns["iterations"][rows, step] = iterations
        self.columns["matvecs"][rows, step] = matvecs
        self.columns["converged"][rows, step] = converged
        if solved_by is not None:
            self.columns["solved_by"][rows, step] = solved_by

    def record_stiffness(self, rows, step: int, stiffness, converged) -> None:
        """A step's tangent ``dF/dd`` [N/m] for ``rows`` and whether its solve converged."""
        self.columns["contact_stiffness"][rows, step] = stiffness
        self.columns["stiffness_converged"][rows, step] = converged

    def result(self, steps, method: str, tol: float, hardness=None) -> SweepResult:
        """The frozen :class:`SweepResult` at approaches ``steps`` (m, k) [m]."""
        for step in list(self._pending):  # a step some surface never reached
            self._describe_pending(step)
        unnamed = self.columns["solved_by"] == ""
        self.columns["solved_by"][unnamed] = method
        return SweepResult(approach=np.array(steps), pressure=self.fields, method=method,
                           tol=tol, hardness=hardness, profile_ranks=self.ranks,
                           probe_columns=self.probe_columns, **self.columns)
