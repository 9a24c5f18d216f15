"""Two rough, elastic bodies as one: the equivalent problem of Eq 17-18.

Kumar, Sadeghi & Krousgrill (2006) write the contact of two bodies with the
total displacement ``u_z = u_z1 + u_z2`` and the prescribed approach
``d_z = d_z1 + d_z2`` (Eq 17-18), and reduce it to "a rigid smooth surface and
an equivalent deforming rough surface". For frictionless contact with small
slopes the reduction is exact:

- the **equivalent surface** is the sum of the two height maps, each measured
  from its body's mean plane as a protrusion towards the other body, on the
  same ``(ny, nx)`` grid as seen from the first body (a map measured looking
  at the second body from outside is mirrored in x, or y, before it is
  given here);
- the **equivalent compliance** is the sum of the two bodies' influence
  operators, ``C = C1 + C2`` [m/Pa]: the same pressure acts on both surfaces,
  so their displacements add. On half-spaces this is the composite modulus
  ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2``; on finite blocks, the sum of
  the two finite-element models (the mean-plane deflection of Eq 44 becomes
  ``P (L1/E1 + L2/E2)`` for nu = 0).

A rigid counter body (``None``) adds nothing: the first operator and heights
are returned as they are, so a one-body problem gives today's numbers bit for
bit. The solution of the equivalent problem is that of the pair; each body's
share of the displacement is ``C_i p`` (:func:`body_displacements`).

A counter body as a value (:class:`Body`): its surface (:class:`RoughSurface`,
or the null :data:`SMOOTH`) and its compliance (:class:`CompliantBody` with its
modulus ratio, a pair summed once, :class:`SummedPair`, or the null
:data:`RIGID`); :data:`RIGID_FLAT` is the rigid smooth flat of the paper.
:func:`pair` makes the one contact problem of a first body and any counter body
(:class:`Pair`), so code that builds a problem never asks whether there is one.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from roughcontact.contact.checks import as_operator, given_matrix
from roughcontact.elasticity.protocol import DenseInfluence, RestrictedInfluence
from roughcontact.surfaces.statistics import height_stats

__all__ = ["RIGID", "RIGID_FLAT", "SMOOTH", "Body", "CompliantBody", "Pair", "PairModel",
           "RoughSurface", "ScaledInfluence", "SumInfluence", "SummedPair", "body_displacements",
           "compliance_share", "deflection_weights", "densified", "equivalent_heights",
           "equivalent_operator", "pair", "pair_model", "scaled"]

log = logging.getLogger("roughcontact.contact")

#: Relative tolerance on the two operators' element areas.
AREA_RTOL = 1e-9


class _OnTheSameElements:
    """What a matrix-free operator made of another (``_base``) shares with it: its
    elements (shape, area, grid), no dense ``matrix``, and the protocol's ``@`` and
    ``restrict`` (:class:`~roughcontact.elasticity.protocol.InfluenceOperator`)."""

    matrix = None

    @property
    def _base(self):
        raise NotImplementedError

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self._base.shape)

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(float)

    @property
    def element_area(self) -> float:
        return float(self._base.element_area)

    @property
    def grid(self):
        return self._base.grid

    def __matmul__(self, pressure) -> np.ndarray:
        return self.matvec(pressure)

    def restrict(self, indices):
        """The operator restricted to the elements ``indices``."""
        return RestrictedInfluence(self, np.asarray(indices))


@dataclass(frozen=True)
class SumInfluence(_OnTheSameElements):
    """``C = C1 + C2`` of two influence operators on the same elements, without forming
    a dense matrix (an :class:`~roughcontact.elasticity.protocol.InfluenceOperator`).

    ``matrix`` is None (a dense pair is summed by :func:`equivalent_operator`);
    ``mean_compliance`` is the sum of the two when both fix it, else None.
    """

    first: Any
    second: Any

    @property
    def _base(self):
        return self.first

    @property
    def mean_compliance(self) -> float | None:
        values = (self.first.mean_compliance, self.second.mean_compliance)
        return None if None in values else float(sum(values))

    def matvec(self, pressure) -> np.ndarray:
        """``C1 p + C2 p`` [m]."""
        return (np.asarray(self.first.matvec(pressure), dtype=float)
                + np.asarray(self.second.matvec(pressure), dtype=float))

    def diagonal(self) -> np.ndarray:
        """``C1_ii + C2_ii`` [m/Pa]."""
        return (np.asarray(self.first.diagonal(), dtype=float)
                + np.asarray(self.second.diagonal(), dtype=float))


@dataclass(frozen=True)
class ScaledInfluence(_OnTheSameElements):
    """``factor * C`` of a matrix-free influence operator (an
    :class:`~roughcontact.elasticity.protocol.InfluenceOperator`): a unit-modulus body
    ``E2 C2`` [m] made ``(E1 / E2) E2 C2`` to add to a first body of modulus ``E1``."""

    operator: Any
    factor: float

    @property
    def mean_compliance(self) -> float | None:
        value = self.operator.mean_compliance
        return None if value is None else float(value) * self.factor

    @property
    def _base(self):
        return self.operator

    def matvec(self, pressure) -> np.ndarray:
        return np.asarray(self.operator.matvec(pressure), dtype=float) * self.factor

    def diagonal(self) -> np.ndarray:
        return np.asarray(self.operator.diagonal(), dtype=float) * self.factor


def scaled(operator, factor: float, *, element_area: float | None = None):
    """``factor * C`` of an influence operator (dense: a
    :class:`~roughcontact.elasticity.protocol.DenseInfluence`; else a
    :class:`ScaledInfluence`), ``factor`` > 0: the second body's unit-modulus
    operator in the first body's unit, ``factor = E1 / E2``."""
    factor = float(factor)
    if not (np.isfinite(factor) and factor > 0.0):
        raise ValueError(f"factor must be a finite positive number, got {factor!r}")
    op = as_operator(operator, element_area)
    if op.matrix is not None:
        mean = op.mean_compliance
        return DenseInfluence(op.matrix * factor, op.element_area, op.grid,
                              None if mean is None else mean * factor)
    return ScaledInfluence(op, factor)


#: Columns of a matrix-free operator applied at once by :func:`densified`.
DENSIFY_COLUMNS = 512


def densified(operator) -> DenseInfluence:
    """The dense matrix of a matrix-free influence operator, as a
    :class:`~roughcontact.elasticity.protocol.DenseInfluence` (its columns ``C e_j``,
    :data:`DENSIFY_COLUMNS` at a time, symmetrized: the operators of elasticity are
    symmetric, and a product by FFT is so to round-off only).

    For a counter body that meets a dense first body: the pair is then one dense
    matrix, which block principal pivoting solves several times faster than CG
    solves the sum, at the memory the first body's matrix already takes.
    """
    op = as_operator(operator)
    if op.matrix is not None:
        return op
    n = op.shape[0]
    matrix = np.empty((n, n))
    for start in range(0, n, DENSIFY_COLUMNS):
        stop = min(n, start + DENSIFY_COLUMNS)
        block = np.zeros((n, stop - start))
        block[np.arange(start, stop), np.arange(stop - start)] = 1.0
        matrix[:, start:stop] = np.asarray(op.matvec(block), dtype=float).reshape(n, -1)
    matrix = 0.5 * (matrix + matrix.T)
    return DenseInfluence(matrix, op.element_area, op.grid, op.mean_compliance)


def deflection_weights(operator) -> np.ndarray:
    """``w = C^T 1 / n``: the weights whose product with a pressure ``p`` is the mean
    displacement ``mean(C p) = w . p`` of the body of influence ``C`` (n elements).

    A dense matrix gives its column sums exactly; a matrix-free operator its
    row sums ``C 1``, equal for the symmetric operators of elasticity
    (reciprocity; every influence model is certified symmetric).
    """
    if isinstance(operator, np.ndarray):
        return np.asarray(operator, dtype=float).sum(axis=0) / operator.shape[0]
    op = as_operator(operator)
    n = op.shape[0]
    if op.matrix is not None:
        return np.asarray(op.matrix, dtype=float).sum(axis=0) / n
    return np.asarray(op.matvec(np.ones(n)), dtype=float) / n


def compliance_share(first, second) -> float:
    """The counter body's share of the pair's compliance [-]: the larger of its share of
    the mean-plane deflection under a uniform pressure, ``1^T C2 1 / 1^T (C1 + C2) 1``,
    and of the local (diagonal) compliance, ``sum diag C2 / sum diag (C1 + C2)``.

    A counter body whose share is small changes the contact little: the measured
    changes of k_P, real area and peak pressure against a rigid counter body are
    in ``results/benchmarks/counter_rigid.md`` (:data:`roughcontact.study` treats
    such a body as rigid below its ``counterface.rigid_share``).
    """
    a, b = (as_operator(op, 1.0 if isinstance(op, np.ndarray) else None)
            for op in (first, second))
    n = a.shape[0]
    ones = np.ones(n)
    mean_a, mean_b = float(np.sum(a.matvec(ones))), float(np.sum(b.matvec(ones)))
    diag_a, diag_b = float(np.sum(a.diagonal())), float(np.sum(b.diagonal()))
    return max(mean_b / (mean_a + mean_b), diag_b / (diag_a + diag_b))


def equivalent_operator(first, second=None, *, element_area: float | None = None):
    """The equivalent compliance ``C1 + C2`` [m/Pa] of two bodies (module docstring).

    Parameters
    ----------
    first, second : ndarray (n, n) or influence operator
        The two bodies' influence operators on the same ``n`` contact elements
        (:class:`~roughcontact.elasticity.protocol.InfluenceOperator`; a dense
        ndarray needs ``element_area``). ``second`` None: a rigid counter body,
        ``first`` is returned unchanged.
    element_area : float, optional
        Element area [m^2] of dense ndarrays.

    Returns
    -------
    operator
        ``first`` (rigid counter body); a
        :class:`~roughcontact.elasticity.protocol.DenseInfluence` of ``C1 + C2``
        when both hold a dense matrix; else a :class:`SumInfluence`.

    Raises
    ------
    ValueError
        If the two operators do not act on the same elements (shape, grid or
        element area differ): the message names both.
    """
    if second is None:
        return first
    a, b = as_operator(first, element_area), as_operator(second, element_area)
    if tuple(a.shape) != tuple(b.shape):
        raise ValueError(f"the two bodies' operators act on different element counts: "
                         f"{tuple(a.shape)} and {tuple(b.shape)}; build both on the same "
                         f"contact grid")
    if a.grid is not None and b.grid is not None and tuple(a.grid) != tuple(b.grid):
        raise ValueError(f"the two bodies' contact grids differ: (nx, ny) = {tuple(a.grid)} "
                         f"and {tuple(b.grid)}; build both on the same grid")
    if abs(a.element_area - b.element_area) > AREA_RTOL * a.element_area:
        raise ValueError(f"the two bodies' contact elements differ in area: "
                         f"{a.element_area:.6g} and {b.element_area:.6g} m^2; both bodies "
                         f"need the same plan size and grid")
    if a.matrix is not None and b.matrix is not None:
        means = (a.mean_compliance, b.mean_compliance)
        return DenseInfluence(a.matrix + b.matrix, a.element_area,
                              a.grid if a.grid is not None else b.grid,
                              None if None in means else float(sum(means)))
    return SumInfluence(a, b)


def equivalent_heights(first, second=None) -> np.ndarray:
    """The equivalent surface ``h1 + h2`` [m] of two height maps (module docstring).

    ``first``, ``second``: heights (ny, nx) or stacks (m, ny, nx) [m], each a
    protrusion towards the other body on the first body's grid; ``second`` None
    (a smooth counter body) returns ``first`` unchanged. A single counter map is
    added to every surface of a stack.

    Raises
    ------
    ValueError
        If the grids differ (naming both shapes).
    """
    if second is None:
        return first
    a, b = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    if a.shape[-2:] != b.shape[-2:] or b.ndim > a.ndim:
        raise ValueError(f"the counter surface's grid {b.shape} does not match the first "
                         f"surface's {a.shape} (ny, nx): both must be sampled on the same "
                         f"grid and size (resample the measured one)")
    if b.ndim == a.ndim and a.ndim == 3 and b.shape[0] != a.shape[0]:
        raise ValueError(f"{a.shape[0]} first surfaces but {b.shape[0]} counter surfaces: "
                         f"give one counter surface per surface, or a single one")
    return a + b


def body_displacements(first, second, pressure) -> tuple[np.ndarray, np.ndarray]:
    """Each body's displacement ``C1 p`` and ``C2 p`` [m] under the contact pressure
    ``p`` [Pa] of the equivalent problem (same shape as ``pressure``; the pair's
    displacement is their sum). ``second`` None (rigid): zeros for it."""
    p = np.asarray(pressure, dtype=float)
    flat = p.reshape(-1)
    u1 = np.asarray(first.matvec(flat), dtype=float).reshape(p.shape)
    if second is None:
        return u1, np.zeros_like(u1)
    return u1, np.asarray(second.matvec(flat), dtype=float).reshape(p.shape)


# ---------------------------------------------------------------------------
# A counter body as a value, and the one problem of a pair


@dataclass(frozen=True)
class PairModel:
    """The elastic part of a contact of two bodies (Eq 17-18), in the first body's
    unit: ``unit`` the pair's operator ``E1 C1 + (E1 / E2) E2 C2`` [m] (None: the
    first body's own, the counter body rigid or treated as rigid), ``weights`` the
    counter body's deflection weights [m] (``mean(C2 p) E1 = w . p``; None when
    rigid), ``bulk_ratio`` the pair's largest row weight over the first body's (1
    when rigid) and ``attrs`` the compliance share and the choice (none for a rigid
    counter body)."""

    unit: object
    weights: np.ndarray | None
    bulk_ratio: float
    attrs: dict = field(default_factory=dict)

    def operator(self, first):
        """The operator to solve with: the pair's, or ``first`` where rigid."""
        return first if self.unit is None else self.unit

    def interface(self, grid, thickness: float):
        """The interface ``grid`` with the counter body's deflection weights, made
        dimensionless by the first body's ``thickness`` [m] (unchanged where rigid)."""
        if self.weights is None:
            return grid
        return replace(grid, counter_weights=self.weights / thickness)


def pair_model(first, second, modulus_ratio: float, rigid_share: float) -> PairModel:
    """The :class:`PairModel` of a first body's unit-modulus operator ``first`` [m] and
    a counter body's ``second`` [m] of modulus ratio E1 / E2.

    A matrix-free counter body that meets a dense first body is made dense
    (:func:`densified`: the pair is then pivoted, at the memory of the first body's
    matrix). A counter body whose share of the compliance (:func:`compliance_share`)
    is below ``rigid_share`` is treated as rigid, and the choice logged.
    """
    if given_matrix(first) is not None:
        second = densified(second)
    second = scaled(second, modulus_ratio)
    share = compliance_share(first, second)
    rigid = share < rigid_share
    attrs = {"counter_compliance_share": share, "counter_treated_as_rigid": rigid}
    log.info("counter body, E1/E2 = %.4g: %.3g of the pair's compliance; %s", modulus_ratio,
             share, f"below counterface.rigid_share {rigid_share:g}: treated as rigid"
             if rigid else "solved as an elastic pair")
    if rigid:
        return PairModel(None, None, 1.0, attrs)
    first_weights = deflection_weights(first)
    weights = deflection_weights(second)
    # the mean-plane deflection is at most max(w) times the load: the pair's largest
    # weight over the first body's raises the sweep's end alike
    ratio = float((first_weights + weights).max() / first_weights.max())
    return PairModel(equivalent_operator(first, second), weights, ratio, attrs)


class _Rigid:
    """The null compliance: a rigid counter body adds nothing."""

    def join(self, first, rigid_share: float) -> PairModel:
        return PairModel(None, None, 1.0)


#: A rigid counter body.
RIGID = _Rigid()


@dataclass(frozen=True)
class CompliantBody:
    """A counter body's unit-modulus operator ``unit`` ``E2 C2`` [m] and the modulus
    ratio E1 / E2: joined to the first body by :func:`pair_model`."""

    unit: object
    modulus_ratio: float

    def join(self, first, rigid_share: float) -> PairModel:
        return pair_model(first, self.unit, self.modulus_ratio, rigid_share)


@dataclass(frozen=True)
class SummedPair:
    """A pair summed once, before the contact (the pair file of a dense first body):
    its :class:`PairModel` as stored."""

    model: PairModel

    def join(self, first, rigid_share: float) -> PairModel:
        log.info("counter body: %.3g of the pair's compliance (rigid_share %g): %s",
                 self.model.attrs["counter_compliance_share"], rigid_share,
                 "treated as rigid" if self.model.unit is None
                 else "solved as an elastic pair")
        return self.model


class _Smooth:
    """The null counter surface: a smooth counter body adds no heights."""

    def add_to(self, heights) -> tuple[np.ndarray, dict]:
        return heights, {}


#: A smooth counter surface.
SMOOTH = _Smooth()


@dataclass(frozen=True)
class RoughSurface:
    """A counter surface facing the first: ``heights`` in units of its own rms height
    (one map (ny, nx), added to every first surface, or one per surface) on the first
    body's grid, and ``sigma_ratio`` sigma2 / sigma1. ``content_sha256``: its file's
    hash, recorded with the result."""

    heights: np.ndarray
    sigma_ratio: float
    content_sha256: str = ""

    @classmethod
    def face_up(cls, heights, sigma_ratio: float, content_sha256: str = "") -> RoughSurface:
        """A map measured face up, like the first surface: facing the first body it is
        mirrored in x."""
        return cls(np.asarray(heights)[..., ::-1], sigma_ratio, content_sha256)

    def add_to(self, heights) -> tuple[np.ndarray, dict]:
        """The equivalent surface ``(z1 + r z2) / sqrt(1 + r^2)`` in units of the composite
        rms height ``sqrt(sigma1^2 + sigma2^2)``, and its sample moments (means over the
        surfaces) to record."""
        r = self.sigma_ratio
        combined = equivalent_heights(heights, r * self.heights) * (1.0 / float(np.hypot(1.0, r)))
        stats = height_stats(combined)
        attrs = {"counter_surfaces_content_sha256": self.content_sha256,
                 "equivalent_sigma_over_scale": float(stats["sigma"].mean()),
                 "equivalent_skew": float(stats["skew"].mean()),
                 "equivalent_kurt": float(stats["kurt"].mean())}
        log.info("equivalent surface: (z1 + %.4g z2) / %.4g; sample sigma / scale %.4f, "
                 "Sk %.4f, Ku %.4f (means over surfaces)", r, float(np.hypot(1.0, r)),
                 attrs["equivalent_sigma_over_scale"], attrs["equivalent_skew"],
                 attrs["equivalent_kurt"])
        return combined, attrs


@dataclass(frozen=True)
class Body:
    """The body the surfaces are pressed against (Eq 17-18): its ``surface``
    (:class:`RoughSurface` or :data:`SMOOTH`) and its ``compliance``
    (:class:`CompliantBody`, :class:`SummedPair` or :data:`RIGID`), with the
    ``rigid_share`` below which a compliant one is treated as rigid."""

    surface: Any = SMOOTH
    compliance: Any = RIGID
    rigid_share: float = 0.001


#: The paper's counter body: a rigid smooth flat.
RIGID_FLAT = Body()


@dataclass(frozen=True)
class Pair:
    """The one contact problem of a first body and a counter body: the equivalent
    ``heights``, the elastic ``model`` (:class:`PairModel`) and the ``attrs`` that say
    what was modelled (none against the rigid smooth flat)."""

    heights: np.ndarray
    model: PairModel
    attrs: dict


def pair(heights, first, second: Body = RIGID_FLAT) -> Pair:
    """The contact problem of a first body (its ``heights`` in units of its rms height,
    its unit-modulus operator ``first`` [m]) pressed against ``second``: the heights
    summed and scaled (:meth:`RoughSurface.add_to`), the compliances joined
    (:func:`pair_model`, or the pair summed once); against :data:`RIGID_FLAT` the first
    body's own problem, unchanged."""
    combined, attrs = second.surface.add_to(heights)
    model = second.compliance.join(first, second.rigid_share)
    return Pair(combined, model, {**attrs, **model.attrs})
