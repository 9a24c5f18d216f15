"""Input checks of the contact solvers: each message names the argument at fault.

The public entry points (:func:`roughcontact.contact.solve`,
:func:`~roughcontact.contact.solve_many`, :func:`~roughcontact.contact.sweep`,
:func:`~roughcontact.contact.kkt_residual`,
:func:`~roughcontact.contact.tangent_stiffness`) check their arguments here
once (the solves through :meth:`roughcontact.contact.problem.Problem.of` and
:class:`~roughcontact.contact.problem.SolverOptions`), and view the influence
operator they were given through
:class:`roughcontact.elasticity.protocol.InfluenceOperator` (:func:`as_operator`):
past this point no solver asks which operator it got.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from roughcontact.contact.products import PRECISIONS
from roughcontact.elasticity import definiteness
from roughcontact.elasticity.definiteness import SYMMETRY_RTOL
from roughcontact.elasticity.protocol import (
    DenseInfluence,
    InfluenceOperator,
    MatrixFreeInfluence,
    PreconditionedOperator,
)

__all__ = [
    "SYMMETRY_RTOL",
    "approach_steps",
    "as_operator",
    "check_approach",
    "check_bounded",
    "check_definite",
    "check_element_area",
    "check_hardness",
    "check_initial_pressure",
    "check_control",
    "check_max_iter",
    "check_mean_pressure",
    "check_positive",
    "check_precision",
    "check_pressure",
    "check_surfaces",
    "given_matrix",
    "preconditioned_operator",
]


# ---------------------------------------------------------------------------
# The operator


def check_element_area(element_area) -> float:
    """The element area ``dA`` [m^2] as a finite positive float."""
    try:
        area = float(element_area)
    except (TypeError, ValueError):
        raise ValueError(
            f"element_area must be a positive area in m^2, got {element_area!r}"
        ) from None
    if not np.isfinite(area) or area <= 0.0:
        raise ValueError(f"element_area must be a finite positive area in m^2, got {area!r}")
    return area


def _check_dense(matrix: np.ndarray) -> None:
    """Validate a dense influence matrix: square, finite, symmetric, C_ii > 0."""
    if matrix.ndim != 2 or matrix.shape[0] != matrix.shape[1] or matrix.shape[0] == 0:
        raise ValueError(f"operator must be a square (n, n) matrix, got shape {matrix.shape}")
    if not np.isfinite(matrix).all():
        raise ValueError("operator must contain only finite influence coefficients (NaN/inf found)")
    diagonal = np.diag(matrix)
    if (diagonal <= 0.0).any():
        i = int(np.argmin(diagonal))
        raise ValueError(
            f"operator must have a positive diagonal (self-compliance C_ii > 0 m/Pa), "
            f"got C[{i}, {i}] = {diagonal[i]!r}"
        )
    definiteness.check_symmetric(matrix, "the matrix")


def given_matrix(operator):
    """The dense matrix an ``operator`` argument stands for, or None if it is matrix-free.

    A plain array (anything without ``matvec``) is the matrix itself; an
    :class:`~roughcontact.elasticity.protocol.InfluenceOperator` tells by its
    ``matrix``; any other object with ``matvec`` is matrix-free.
    """
    if not hasattr(operator, "matvec"):
        return operator
    return operator.matrix if isinstance(operator, InfluenceOperator) else None


def preconditioned_operator(operator) -> PreconditionedOperator | None:
    """The grid FFT operator an operator argument is (or wraps), or None.

    A :class:`~roughcontact.elasticity.protocol.PreconditionedOperator`
    (half-space, periodic, spectral, hybrid block), possibly wrapped by
    :func:`as_operator` (its ``base``); None for a dense matrix or any other
    matrix-free operator.
    """
    base = getattr(operator, "base", operator)
    if isinstance(base, PreconditionedOperator) and getattr(base, "grid", None) is not None:
        return base
    return None


def _grid(operator, n: int) -> tuple[int, int] | None:
    """The operator's ``grid = (nx, ny)`` if it has one of ``n`` elements, else None."""
    grid = getattr(operator, "grid", None)
    if grid is None:
        return None
    nx, ny = (int(g) for g in grid)
    return (nx, ny) if nx * ny == n else None


def _dense_operator(operator, matrix, element_area) -> DenseInfluence:
    if element_area is None:
        element_area = getattr(operator, "element_area", None)
    if element_area is None:
        raise ValueError("element_area must be given (m^2) when operator is a dense matrix")
    area = check_element_area(element_area)
    if isinstance(operator, DenseInfluence) and \
            operator.grid == _grid(operator, operator.shape[0]):  # kept, with its certificate
        if definiteness.certificate_of(operator) is None:
            _check_dense(operator.matrix)
        if area == operator.element_area:
            return operator
        same = dataclasses.replace(operator, element_area=area)
        definiteness.carry(operator, same)
        return same
    try:
        matrix = np.ascontiguousarray(matrix, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            "operator must be a dense (n, n) matrix or an object with matvec"
        ) from None
    _check_dense(matrix)
    dense = DenseInfluence(matrix, area, _grid(operator, matrix.shape[0]),
                           getattr(operator, "mean_compliance", None))
    definiteness.carry(operator, dense)
    return dense


def _check_diagonal(diagonal, n: int) -> np.ndarray:
    """The self-compliances ``C_ii`` [m/Pa] as a float array, checked finite, positive, (n,)."""
    diagonal = np.asarray(diagonal, dtype=float).reshape(-1)
    if diagonal.shape != (n,) or not np.isfinite(diagonal).all() or (diagonal <= 0.0).any():
        raise ValueError(
            "operator must have a finite positive diagonal (C_ii > 0 m/Pa) of length n"
        )
    return diagonal


def _matrix_free_operator(operator, element_area) -> MatrixFreeInfluence:
    if isinstance(operator, MatrixFreeInfluence):  # kept: its base keeps the certificate
        _check_diagonal(operator.self_compliance, operator.shape[0])
        if element_area is None or check_element_area(element_area) == operator.element_area:
            return operator
        return dataclasses.replace(operator, element_area=check_element_area(element_area))
    missing = [name for name in ("shape", "diagonal") if not hasattr(operator, name)]
    if missing:
        raise ValueError(
            f"operator must provide matvec, shape, diagonal() and element_area; missing {missing}"
        )
    shape = tuple(operator.shape)
    if len(shape) != 2 or shape[0] != shape[1] or shape[0] < 1:
        raise ValueError(f"operator.shape must be (n, n), got {shape}")
    n = int(shape[0])
    if element_area is None:
        if not hasattr(operator, "element_area"):
            raise ValueError("element_area must be given (m^2): operator has no element_area")
        element_area = operator.element_area
    area = check_element_area(element_area)
    diagonal = _check_diagonal(operator.diagonal(), n)
    return MatrixFreeInfluence(operator, area, diagonal, _grid(operator, n),
                               getattr(operator, "mean_compliance", None))


def as_operator(operator, element_area=None) -> InfluenceOperator:
    """Check ``operator`` and view it as an :class:`InfluenceOperator`, once per call.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        A dense symmetric matrix [m/Pa] (checked square, finite, symmetric,
        with a positive diagonal), an ``InfluenceOperator``, or any object
        with ``shape == (n, n)``, ``diagonal()`` and ``matvec`` accepting
        (n,) and (n, m) (optional ``element_area``, ``grid``,
        ``mean_compliance``).
    element_area : float, optional
        Element area [m^2]; default the operator's own (required for a plain
        matrix).

    Returns
    -------
    InfluenceOperator
        A :class:`DenseInfluence` when a dense matrix is at hand, else a
        :class:`MatrixFreeInfluence` with the checked diagonal and area.
    """
    matrix = given_matrix(operator)
    if matrix is not None:
        return _dense_operator(operator, matrix, element_area)
    return _matrix_free_operator(operator, element_area)


def check_definite(op: InfluenceOperator) -> None:
    """Refuse an operator that is not symmetric positive definite (Eq 39).

    Certified once per operator (:func:`roughcontact.elasticity.definiteness.certify`:
    Cholesky for a dense matrix, the spectrum of a periodic one, a Lanczos
    estimate for any other) and the certificate kept on it, so that the
    solves that follow with the same operator object (a
    :class:`~roughcontact.elasticity.protocol.DenseInfluence`, a grid
    operator) pay nothing; a plain ndarray is certified at every call.

    Raises
    ------
    roughcontact.errors.IndefiniteOperator
        With estimates of its smallest and largest eigenvalues [m/Pa].
    """
    definiteness.certify(op)


def check_bounded(op: InfluenceOperator, gaps: np.ndarray, d: np.ndarray, name: str,
                  hardness=None) -> None:
    """Reject approaches with no solution for an operator with zero row sums.

    If ``C 1 = 0`` (mean displacement fixed to zero, ``mean_compliance = 0``),
    ``V(p + c 1) = V(p) - c sum(d - f)``, so Eq 27 has no minimizer (the load
    is unbounded) unless ``d < mean(f)``. With a cap ``hardness`` [Pa] every
    approach has one (``V`` is minimized over the box ``0 <= p <= H``).
    """
    if op.mean_compliance != 0.0 or hardness is not None:
        return
    mean_gap = gaps.mean(axis=1)
    if (d >= mean_gap).any():
        j = int(np.argmax(d - mean_gap))
        raise ValueError(
            f"{name} must be below the mean initial separation ({mean_gap[j]:.6g} m) for an "
            f"operator with zero mean displacement (mean_compliance = 0): beyond it the load "
            f"is unbounded; got {d[j]:.6g} m"
        )


# ---------------------------------------------------------------------------
# Surfaces, approaches, pressures


def check_surfaces(gaps0, op: InfluenceOperator, name: str, batched: bool):
    """Return the gaps as an (m, n) array and the shape of one surface as given.

    A single surface may be (ny, nx) or flat (n,); a batch (m, ny, nx) or (m, n).
    """
    gaps = np.asarray(gaps0, dtype=float)
    n = op.shape[0]
    expected = "(m, ny, nx) or (m, n)" if batched else "(ny, nx) or (n,)"
    if batched and (gaps.ndim not in (2, 3) or gaps.shape[0] < 1):
        raise ValueError(f"{name} must have shape {expected} with n = {n}, got {gaps.shape}")
    surface_shape = gaps.shape[1:] if batched else gaps.shape
    ok = math.prod(surface_shape) == n and len(surface_shape) in (1, 2)
    if ok and len(surface_shape) == 2 and op.grid is not None:
        nx, ny = op.grid
        ok = tuple(surface_shape) == (ny, nx)
        expected = f"{expected} with (ny, nx) = {(ny, nx)}"
    if not ok:
        raise ValueError(f"{name} must have shape {expected} with n = {n}, got {gaps.shape}")
    if not np.isfinite(gaps).all():
        raise ValueError(f"{name} must be finite (NaN or inf heights found)")
    return np.ascontiguousarray(gaps.reshape(-1, n)), tuple(surface_shape)


def _per_surface(value, m: int, name: str) -> np.ndarray:
    """``value`` as an (m,) float array (a scalar is shared)."""
    values = np.asarray(value, dtype=float)
    if values.ndim == 0:
        values = np.full(m, float(values))
    if values.shape != (m,):
        raise ValueError(
            f"{name} must be a scalar or an array of length m = {m}, got {values.shape}")
    return values


def check_approach(approach, m: int, name: str = "approach") -> np.ndarray:
    """Approaches ``d >= 0`` [m] as an (m,) array (a scalar is shared)."""
    d = _per_surface(approach, m, name)
    if not np.isfinite(d).all():
        raise ValueError(f"{name} must be finite (m)")
    if (d < 0.0).any():
        raise ValueError(f"{name} must be non-negative (rigid approach d >= 0 m), got {d.min()!r}")
    return d


def check_control(approach, mean_pressure, names=("approach", "mean_pressure")) -> None:
    """Exactly one of the displacement control ``approach`` [m] and the load control
    ``mean_pressure`` [Pa] is given (the messages use ``names``)."""
    if (approach is None) == (mean_pressure is None):
        raise ValueError(f"give exactly one of {names[0]} (m, displacement control) and "
                         f"{names[1]} (Pa, load control)")


def check_mean_pressure(mean_pressure, m: int, name: str = "mean_pressure") -> np.ndarray:
    """Mean pressures ``P >= 0`` [Pa] as an (m,) array (a scalar is shared)."""
    P = _per_surface(mean_pressure, m, name)
    if not np.isfinite(P).all() or (P < 0.0).any():
        raise ValueError(f"{name} must be finite and non-negative (Pa)")
    return P


def approach_steps(approaches, m: int, unit: str, name: str = "approaches") -> np.ndarray:
    """Approaches (or the steps ``name``) as an (m, k) array, shared (k,) ones broadcast;
    checked finite and >= 0."""
    steps = np.asarray(approaches, dtype=float)
    if steps.ndim == 1:
        steps = np.broadcast_to(steps, (m, steps.size))
    if steps.ndim != 2 or steps.shape[0] != m or steps.shape[1] < 1:
        raise ValueError(
            f"{name} must have shape (k,) or (m, k) with m = {m}, got {np.shape(approaches)}"
        )
    if not np.isfinite(steps).all() or (steps < 0.0).any():
        raise ValueError(f"{name} must be finite and non-negative ({unit})")
    return steps


def check_pressure(pressure, n: int) -> np.ndarray:
    """A finite pressure field of ``n`` values [Pa], flattened to (1, n)."""
    p = np.asarray(pressure, dtype=float)
    if p.size != n or not np.isfinite(p).all():
        raise ValueError(f"pressure must be finite with n = {n} values, got {p.shape}")
    return p.reshape(1, n)


def check_initial_pressure(p0, m: int, n: int, name: str = "p0",
                           hardness: float | None = None) -> np.ndarray:
    """Starting pressures as (m, n) [Pa]; clipped to ``hardness`` when there is a cap."""
    if p0 is None:
        return np.zeros((m, n))
    p = np.asarray(p0, dtype=float)
    if p.size != n * m:
        raise ValueError(
            f"{name} must have the shape of the gaps ({m * n} values), got {p.shape}"
        )
    if not np.isfinite(p).all() or (p < 0.0).any():
        raise ValueError(f"{name} must be finite and non-negative (Pa)")
    p = p.reshape(m, n).copy()
    if hardness is not None:
        np.minimum(p, hardness, out=p)
    return p


def check_hardness(hardness) -> float | None:
    """The pressure cap ``H`` [Pa] as a float, or None for no cap (None or +inf).

    Raises
    ------
    ValueError
        Naming ``hardness`` unless it is None or a positive real number (not
        NaN, not a bool, string or array).
    """
    if hardness is None:
        return None
    value = float("nan")
    if not isinstance(hardness, (bool, np.bool_, str, bytes)) and np.ndim(hardness) == 0:
        try:
            value = float(hardness)
        except (TypeError, ValueError):
            pass
    if not value > 0.0:  # also NaN
        raise ValueError(
            f"hardness must be None or a positive pressure cap in Pa, got {hardness!r}"
        )
    return None if math.isinf(value) else value


# ---------------------------------------------------------------------------
# Options


def check_positive(value, name: str = "tol") -> float:
    """``value`` (a tolerance, by default named ``tol``) as a finite positive float."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite positive number, got {value!r}") from None
    if not np.isfinite(number) or number <= 0.0:
        raise ValueError(f"{name} must be a finite positive number, got {value!r}")
    return number


def check_max_iter(max_iter) -> None:
    """``max_iter`` is None or a non-negative integer (not a bool)."""
    if max_iter is None:
        return
    try:
        valid = not isinstance(max_iter, bool) and int(max_iter) == max_iter >= 0
    except (TypeError, ValueError):
        valid = False
    if not valid:
        raise ValueError(f"max_iter must be a non-negative integer or None, got {max_iter!r}")


def check_precision(precision) -> None:
    """``precision`` is one of :data:`~roughcontact.contact.products.PRECISIONS`."""
    if precision not in PRECISIONS:
        raise ValueError(f"precision must be one of {PRECISIONS}, got {precision!r}")
