"""What an engineer reads off a contact interface: spots, perimeter, corrected area, gap.

From a solution's pressure ``p`` and gap ``g = u + f - d`` on a grid of
``(ny, nx)`` elements of sides ``(dx, dy)`` [m]:

*contact spots*
    connected clusters of elements in contact (``p > 0``), two elements
    being connected when they share an edge (4-connectivity: elements that
    touch only at a corner are separate spots). On a periodic grid (a cell
    that repeats, e.g. :class:`~roughcontact.elasticity.halfspace.PeriodicHalfSpace`)
    the last column neighbours the first and the last row the first, so a
    spot that crosses the boundary is one spot. A finite block's edges are
    the body's edges: nothing connects across them. Reported: the number of
    spots, their mean area ``A_c / N_spots`` [m^2] and the spot-area
    quantiles at :data:`SPOT_PROBABILITIES` (by number of spots; 1.0 is the
    largest spot).
*perimeter*
    the length of the contact/non-contact interface as the grid draws it
    (the "Manhattan" perimeter ``P'``): every pair of edge-neighbours of
    which one is in contact and the other not contributes the shared edge,
    ``dy`` between x-neighbours and ``dx`` between y-neighbours [m]. The
    edges of a non-periodic grid are not counted.
*corrected real area*
    Counting elements in contact overestimates the true area along every
    contact edge. Yastrebov, Anciaux & Molinari (2017, "On the accurate
    computation of the true contact-area in mechanical contact of random
    rough surfaces", Tribology International 114, 161-171; arXiv 1701.02727)
    correct the count by the perimeter:

        ``A = A' - c_P P' dx``,  ``c_P = (pi - 1 + ln 2) / 24`` (about 0.118),

    with ``A'`` the element count times the element area and ``P'`` the
    Manhattan perimeter on a grid of square elements of side ``dx``. Each
    switch between contact and non-contact then removes ``c_P dx^2``; on
    rectangular elements we remove ``c_P dx dy`` per switch (the same
    formula, per element area). Reported as a fraction of the nominal area,
    beside the uncorrected ``real_area_fraction``.
*gap*
    the mean interfacial separation ``mean(g)`` [m] (what a seal leaks
    through) and the gap quantiles at :data:`GAP_PROBABILITIES` over the
    nominal area (elements in contact have ``g = 0`` to the solver's
    tolerance, so quantiles below the contact fraction are about zero).

All quantities are computed for a stack of fields at once (leading axes:
surfaces, steps), in O(n) per field.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from roughcontact.contact.probes import Probe, column_names

__all__ = [
    "GAP_PROBABILITIES",
    "SPOT_PROBABILITIES",
    "PERIMETER_CORRECTION",
    "InterfaceGrid",
    "InterfaceSummary",
    "corrected_area_fraction",
    "describe",
    "label_spots",
    "perimeter_switches",
]

#: Perimeter correction of the element count, Yastrebov, Anciaux & Molinari (2017).
PERIMETER_CORRECTION = (math.pi - 1.0 + math.log(2.0)) / 24.0
#: Probabilities (by number of spots) of the stored spot-area quantiles; 1.0: the largest.
SPOT_PROBABILITIES = (0.1, 0.25, 0.5, 0.75, 0.9, 1.0)
#: Probabilities (by area) of the stored gap quantiles; 1.0: the largest gap.
GAP_PROBABILITIES = (0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.95, 0.99, 1.0)
#: Largest field whose gap quantiles are read off a full sort (above: a partition).
SORT_LIMIT = 1 << 16


@dataclass(frozen=True)
class InterfaceGrid:
    """The grid the interface quantities are measured on.

    Parameters
    ----------
    spacing : (float, float)
        Element sides ``(dx, dy)`` [m] (``dx`` along the last axis of a field).
    periodic : bool
        The grid repeats (spots connect across its edges, and the edges' switches
        count in the perimeter).
    counter_weights : ndarray (n,), optional
        Of two elastic bodies (:mod:`roughcontact.contact.counterface`): the
        weights ``w`` whose product with a solution's pressure is the counter
        body's mean-plane deflection, ``mean(C2 p) = w . p``
        (:func:`~roughcontact.contact.counterface.deflection_weights`); a sweep
        then records it as ``counter_deflection``. None (default): no counter body,
        or a rigid one.
    probes : tuple of Probe
        What a sweep records at every step beyond the interface quantities
        (:mod:`roughcontact.contact.probes`, e.g. the flow through the gap,
        :class:`~roughcontact.transport.probe.FlowProbe`), their columns' names
        distinct; empty (default): nothing more.
    """

    spacing: tuple[float, float]
    periodic: bool = False
    counter_weights: np.ndarray | None = field(default=None, compare=False, repr=False)
    probes: tuple[Probe, ...] = ()

    def __post_init__(self):
        dx, dy = (float(s) for s in self.spacing)
        if not (math.isfinite(dx) and math.isfinite(dy) and dx > 0.0 and dy > 0.0):
            raise ValueError(f"spacing must be two positive element sides (dx, dy) [m], "
                             f"got {self.spacing!r}")
        object.__setattr__(self, "spacing", (dx, dy))
        object.__setattr__(self, "periodic", bool(self.periodic))
        object.__setattr__(self, "probes", tuple(self.probes))
        column_names(self.probes)  # distinct

    @classmethod
    def of(cls, operator, size) -> InterfaceGrid:
        """The grid of ``operator`` (its ``grid`` ``(nx, ny)``) over a surface of ``size``
        ``(Lx, Ly)`` [m]; periodic when the operator's mean displacement is fixed to
        zero (``mean_compliance == 0``: a periodic cell carries no uniform mode)."""
        if operator.grid is None:
            raise ValueError("the operator does not know its grid (nx, ny): give "
                             "InterfaceGrid(spacing=(dx, dy), periodic=...) yourself")
        nx, ny = operator.grid
        lx, ly = size
        return cls((lx / nx, ly / ny), operator.mean_compliance == 0.0)

    @property
    def element_area(self) -> float:
        """``dx dy`` [m^2]."""
        return self.spacing[0] * self.spacing[1]


@dataclass(frozen=True)
class InterfaceSummary:
    """The interface quantities of a stack of solutions (leading axes of the fields).

    Attributes
    ----------
    spot_count : ndarray of int
        Number of contact spots.
    mean_spot_area : ndarray
        Contact area over spot count [m^2]; NaN without contact.
    spot_area_quantiles : ndarray, (..., len(SPOT_PROBABILITIES))
        Spot areas [m^2] at :data:`SPOT_PROBABILITIES`; NaN without contact.
    perimeter : ndarray
        Manhattan perimeter ``P'`` [m].
    real_area_fraction : ndarray
        Elements in contact over all elements [-].
    corrected_real_area_fraction : ndarray
        ``(A' - c_P P' dx) / A_n`` [-] (Yastrebov et al. 2017).
    mean_gap : ndarray
        Mean of the gap field [m].
    gap_quantiles : ndarray, (..., len(GAP_PROBABILITIES))
        Gap [m] at :data:`GAP_PROBABILITIES` (by area).
    """

    spot_count: np.ndarray
    mean_spot_area: np.ndarray
    spot_area_quantiles: np.ndarray
    perimeter: np.ndarray
    real_area_fraction: np.ndarray
    corrected_real_area_fraction: np.ndarray
    mean_gap: np.ndarray
    gap_quantiles: np.ndarray


def _fields(array, name: str) -> np.ndarray:
    a = np.asarray(array)
    if a.ndim < 2 or a.shape[-1] < 1 or a.shape[-2] < 1:
        raise ValueError(f"{name} must hold fields of shape (..., ny, nx), got shape {a.shape}")
    return a


#: 4-connectivity within a field and none across the fields of a stack (fields, ny, nx).
_STRUCTURE = np.zeros((3, 3, 3), dtype=bool)
_STRUCTURE[1] = [[0, 1, 0], [1, 1, 1], [0, 1, 0]]


def _spots(mask: np.ndarray, periodic: bool) -> tuple[np.ndarray, np.ndarray]:
    """Spot labels of a stack of contact sets ``mask`` (fields, ny, nx), numbered 1, 2, ...
    over the whole stack in the order of their first element (row-major, field by
    field), and the number of spots of each field.

    The clusters of each field are labelled by :func:`scipy.ndimage.label`
    (4-connectivity, one C pass over the stack); on a periodic grid the clusters that
    meet across an edge (both elements of a wrap-around pair in contact) are then
    merged into the one of lowest label (:func:`scipy.sparse.csgraph.connected_components`
    on the clusters, not on the elements).
    """
    import scipy.ndimage

    labels, total = scipy.ndimage.label(mask, structure=_STRUCTURE)
    if periodic and total:
        pairs = []
        for first, last in ((labels[:, :, 0], labels[:, :, -1]),
                            (labels[:, 0, :], labels[:, -1, :])):
            both = (first > 0) & (last > 0) & (first != last)
            pairs.append(np.stack([first[both], last[both]]))
        pairs = np.concatenate(pairs, axis=1)
        if pairs.size:
            import scipy.sparse
            import scipy.sparse.csgraph

            graph = scipy.sparse.coo_matrix(
                (np.ones(pairs.shape[1], dtype=np.int8), (pairs[0], pairs[1])),
                shape=(total + 1, total + 1))
            _, component = scipy.sparse.csgraph.connected_components(graph, directed=False)
            lowest = np.full(component.max() + 1, total + 1)
            np.minimum.at(lowest, component, np.arange(total + 1))
            root = lowest[component]  # each cluster's lowest label in its spot
            kept = np.unique(root[1:])  # the spots, by lowest label = first appearance
            renumber = np.zeros(total + 1, dtype=labels.dtype)
            renumber[1:] = np.searchsorted(kept, root[1:]) + 1
            labels, total = renumber[labels], kept.size
    # labels increase field by field: a field's spots are the labels above the last
    # field's highest
    highest = np.maximum.accumulate(labels.reshape(labels.shape[0], -1).max(axis=1))
    counts = np.diff(highest, prepend=0)
    return labels, counts


def _offsets(counts: np.ndarray) -> np.ndarray:
    """The number of spots before each field's (its labels are offset + 1 .. offset +
    count in :func:`_spots`' numbering)."""
    return np.concatenate(([0], np.cumsum(counts)[:-1]))


def label_spots(contact, periodic: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Contact spots of a stack of contact sets (4-connectivity, module docstring).

    Parameters
    ----------
    contact : ndarray of bool, (..., ny, nx)
        Elements in contact.
    periodic : bool
        Connect across the grid's edges.

    Returns
    -------
    labels : ndarray of int, (..., ny, nx)
        0 outside contact; spots numbered 1, 2, ... within each field, in the
        order of their first element (row-major).
    counts : ndarray of int, (...)
        Number of spots in each field.
    """
    mask = _fields(contact, "contact").astype(bool)
    stack = mask.shape[:-2]
    labels, counts = _spots(mask.reshape(-1, *mask.shape[-2:]), periodic)
    local = np.where(labels > 0, labels - _offsets(counts)[:, None, None], 0)
    return local.reshape(mask.shape), counts.reshape(stack)


def perimeter_switches(contact, periodic: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Numbers of contact/non-contact switches between x-neighbours and between
    y-neighbours of each field of ``contact`` (..., ny, nx) (module docstring)."""
    mask = _fields(contact, "contact").astype(bool)
    switches = []
    for axis in (-1, -2):
        if periodic:
            differ = mask != np.roll(mask, -1, axis=axis)
        elif axis == -1:
            differ = mask[..., :, 1:] != mask[..., :, :-1]
        else:
            differ = mask[..., 1:, :] != mask[..., :-1, :]
        switches.append(np.count_nonzero(differ, axis=(-2, -1)))
    return switches[0], switches[1]


def corrected_area_fraction(contact, periodic: bool = False) -> np.ndarray:
    """``(N_c - c_P (s_x + s_y)) / n``: the element count corrected by its perimeter
    (Yastrebov, Anciaux & Molinari 2017; module docstring), per field [-]."""
    mask = _fields(contact, "contact").astype(bool)
    count = np.count_nonzero(mask, axis=(-2, -1))
    return _corrected(count, *perimeter_switches(mask, periodic), mask.shape[-1] * mask.shape[-2])


def _corrected(count, sx, sy, n: int) -> np.ndarray:
    """``(count - c_P (sx + sy)) / n`` [-] (:func:`corrected_area_fraction`)."""
    return np.asarray((count - PERIMETER_CORRECTION * (sx + sy)) / n, dtype=float)


def _ranks(probabilities, count):
    """The 1-based ranks ``max(ceil(q count), 1)`` of the order statistics at ``q``
    (the lower quantile: no interpolation between elements or spots)."""
    q = np.asarray(probabilities, dtype=float)
    return np.maximum(np.ceil(q * np.asarray(count)[..., None] - 1e-9).astype(np.int64), 1)


def describe(pressure, gap, grid: InterfaceGrid) -> InterfaceSummary:
    """The interface quantities (module docstring) of solutions on ``grid``.

    Parameters
    ----------
    pressure : ndarray, (..., ny, nx)
        Element pressures [Pa] (any unit: only ``p > 0`` is used).
    gap : ndarray, (..., ny, nx)
        Gaps ``u + f - d`` [m] of the same solutions.
    grid : InterfaceGrid
        Element sides and periodicity.

    Returns
    -------
    InterfaceSummary
    """
    p = _fields(pressure, "pressure")
    g = _fields(gap, "gap")
    if p.shape != g.shape:
        raise ValueError(f"pressure {p.shape} and gap {g.shape} must have the same shape")
    contact = p > 0.0
    dx, dy = grid.spacing
    stack, shape = p.shape[:-2], p.shape[-2:]
    n = shape[0] * shape[1]
    labels, counts_flat = _spots(contact.reshape(-1, *shape), grid.periodic)
    fields = counts_flat.size
    # spot sizes (elements) sorted within each field: the spots of a field are the
    # consecutive labels offset + 1 .. offset + count
    sizes = np.bincount(labels.ravel())[1:]
    owner = np.repeat(np.arange(fields), counts_flat)
    order = np.lexsort((sizes, owner))
    offsets = _offsets(counts_flat)
    ranks = _ranks(SPOT_PROBABILITIES, counts_flat)  # (fields, S), 1-based
    picks = np.minimum(offsets[:, None] + ranks - 1, max(sizes.size - 1, 0))
    spot_quantiles = (sizes[order][picks] if sizes.size else np.zeros(picks.shape)) * 1.0
    spot_quantiles[counts_flat == 0] = np.nan
    spot_quantiles *= grid.element_area
    in_contact = np.count_nonzero(contact, axis=(-2, -1)).reshape(fields)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_spot = np.where(counts_flat > 0, in_contact * grid.element_area / counts_flat,
                             np.nan)
    sx, sy = perimeter_switches(contact, grid.periodic)
    perimeter = sx * dy + sy * dx
    ranks = _ranks(GAP_PROBABILITIES, n)
    # the order statistics: a sort is faster than a 9-fold partition on small fields
    ordered = (np.sort(g.reshape(fields, n), axis=1) if n <= SORT_LIMIT
               else np.partition(g.reshape(fields, n), ranks - 1, axis=1))
    gap_quantiles = ordered[:, ranks - 1]
    return InterfaceSummary(
        spot_count=counts_flat.reshape(stack),
        mean_spot_area=mean_spot.reshape(stack),
        spot_area_quantiles=spot_quantiles.reshape(*stack, len(SPOT_PROBABILITIES)),
        perimeter=np.asarray(perimeter, dtype=float),
        real_area_fraction=(in_contact / n).reshape(stack),
        corrected_real_area_fraction=_corrected(in_contact.reshape(stack), sx, sy, n),
        mean_gap=g.reshape(fields, n).mean(axis=1).reshape(stack),
        gap_quantiles=gap_quantiles.reshape(*stack, len(GAP_PROBABILITIES)),
    )
