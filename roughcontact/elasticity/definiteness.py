"""Certificates that an influence operator is symmetric positive definite (Eq 39).

Eq 27 of Kumar et al. (2006), ``min 1/2 p.C p - p.(d - f)`` over ``p >= 0``,
is a convex problem with one minimizer only when ``C`` is symmetric positive
definite. On an indefinite ``C`` a solver can still meet its tolerance at a
point that satisfies the KKT conditions (Eq 19-22): the iterative methods see
the curvature of ``C`` only along their own search directions and block
principal pivoting only on its contact sets, so ``converged=True`` proves
nothing about ``C``. The operator is therefore certified once, where it is
built or loaded (:func:`certify`), and the :class:`Certificate` is kept on it
(attribute ``spd_certificate``), so that later solves with the same operator
do not pay again:

- a dense matrix (``matrix``) of at most :data:`CHOLESKY_MAX_ELEMENTS`
  elements: symmetric to ``max|C - C^T| <= SYMMETRY_RTOL max|C|`` and its
  Cholesky factorization exists (LAPACK ``dpotrf``, n^3 / 3 flops and one
  copy of the matrix: 0.5-1 s at 60 x 60 on one core) with no squared pivot
  below :data:`DEFINITE_RTOL` of the largest diagonal entry. That is a proof,
  to rounding; a matrix singular to rounding is refused on every CPU,
  whatever the sign its last pivot happens to take. A dense matrix declared
  to have the uniform pressure as its zero mode (``mean_compliance = 0``,
  e.g. the dense form of a periodic half-space) is factored with that mode
  shifted into the spectrum, so the certificate holds on its complement,
  as for the circulant itself. A larger dense matrix is certified like a
  matrix-free operator.
- a circulant operator (``spectrum``: the periodic half-spaces of
  :mod:`roughcontact.elasticity.halfspace`): its spectrum *is* its
  eigenvalues, so the certificate is exact. With ``mean_compliance = 0`` the
  zero mode (uniform pressure, no mean displacement) is left out: the contact
  solver limits the approach for it
  (:func:`roughcontact.contact.checks.check_bounded`).
- any other operator: an estimate by :data:`LANCZOS_STEPS` Lanczos steps
  from a fixed random start. On a grid (``grid``) the steps run on
  ``S = M^(1/2) C M^(1/2)``, ``M`` the circulant with the symbol ``|q|`` (the
  half-space's inverse, which also preconditions
  :mod:`roughcontact.contact.pcg`), at the cost of one product with ``C``
  and one with ``M`` (two FFTs) per step: by Sylvester's law of inertia
  ``S`` has as many negative eigenvalues as ``C``, and its spectrum is
  compact (extreme eigenvalues within a factor of about 10 at 64 x 64 and
  256 x 256 for Love's half-space, against about 100 and 400 for ``C``), so
  a few steps single out a negative eigenvalue that plain Lanczos on ``C``
  would have to resolve from the cluster of its smallest eigenvalues (60
  steps at 256 x 256). Without a grid the steps run on ``C`` itself
  (:data:`PLAIN_LANCZOS_STEPS`). The smallest Ritz value bounds the
  smallest eigenvalue from above: a negative one proves the operator
  indefinite, a positive one is an estimate, not a proof. Symmetry is
  checked on two random vectors (``x.C y = y.C x``). With
  ``mean_compliance = 0`` the steps run on the complement of the uniform
  pressure, as for a circulant.

Cost (``benchmarks/bench_certify.py``, one thread on a 2-core machine under
a load of 7.5, so about 3 times the unloaded times): dense 60 x 60, 1.1 s
(0.13 s of it the symmetry check), against 0.07 s for one cold solve by
pivoting, 0.3 s by CG and 0.8 s for one surface's 10-step sweep; Love's
half-space and the hybrid block at 256 x 256, 0.28 s and 0.42 s (2.3 and
0.17 times one cold preconditioned CG solve, 12 % and 5 % of a sweep); at
1024 x 1024, 3.7 s and 4.4 s (1.2 and 0.5 times one solve, 6 % and 3 % of a
sweep). Paid once per operator object: a contact job pays it once for its
60 surfaces x 20 steps.

An operator that fails is refused with
:class:`roughcontact.errors.IndefiniteOperator`, which names it and gives
estimates of its smallest and largest eigenvalues.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy  # its submodules load on first use (scipy's lazy attributes)

from roughcontact.errors import IndefiniteOperator

__all__ = [
    "ATTRIBUTE",
    "CHOLESKY_MAX_ELEMENTS",
    "DEFINITE_RTOL",
    "LANCZOS_STEPS",
    "PLAIN_LANCZOS_STEPS",
    "SYMMETRY_RTOL",
    "Certificate",
    "asymmetry",
    "carry",
    "certificate_of",
    "certify",
    "check_symmetric",
    "from_eigenvalues",
]

#: Largest dense matrix (elements) certified by its Cholesky factorization;
#: the study's dense matrices go up to 64 x 64 (``operators.DENSE_MAX_ELEMENTS``).
CHOLESKY_MAX_ELEMENTS = 64 * 64
#: Lanczos steps on ``S = M^(1/2) C M^(1/2)`` for an operator on a grid.
LANCZOS_STEPS = 12
#: Lanczos steps on ``C`` for an operator without a grid.
PLAIN_LANCZOS_STEPS = 60
#: Relative asymmetry max|C - C^T| / max|C| accepted for a dense matrix, and
#: |x.C y - y.C x| / (|x| |C y| + |y| |C x|) for a matrix-free operator.
SYMMETRY_RTOL = 1e-8
#: An operator whose smallest eigenvalue (estimate) is at most this share of its
#: largest is refused: negative, or zero to rounding.
DEFINITE_RTOL = 1e-12
#: Dense matrices up to this many elements get their exact extreme eigenvalues
#: in a refusal (``eigvalsh``, under a second at 1024); larger ones an estimate.
EXACT_EIGENVALUES_MAX = 1024
#: A Lanczos step whose new direction is this small next to the operator's scale
#: ends the run: the Krylov space is invariant (to rounding).
INVARIANT_RTOL = 1e-10
#: A dense matrix declared to have the uniform pressure as its zero mode must have
#: row sums within this share of its largest absolute row sum.
ZERO_MODE_RTOL = 1e-8
#: The attribute that holds an operator's certificate.
ATTRIBUTE = "spd_certificate"
#: The seed of the random start vectors, so that a certificate is reproducible.
SEED = 20060101


@dataclass(frozen=True)
class Certificate:
    """How an operator was found symmetric positive definite.

    Attributes
    ----------
    method : str
        ``"cholesky"``, ``"spectrum"``, ``"lanczos"`` or ``"preconditioned lanczos"``.
    smallest, largest : float
        Estimates of the extreme eigenvalues [unit of C]: for ``"cholesky"``
        the smallest squared pivot (at least the smallest eigenvalue) and the
        largest diagonal entry (at most the largest); for ``"spectrum"`` the
        eigenvalues themselves (the zero mode of ``mean_compliance = 0``
        left out); for ``"lanczos"`` the extreme Ritz values (within the
        spectrum); for ``"preconditioned lanczos"`` the extreme Ritz values of
        ``S = M^(1/2) C M^(1/2)``, which has the signs of ``C``'s eigenvalues,
        not their sizes.
    steps : int
        Lanczos steps taken (0 for the exact methods).
    """

    method: str
    smallest: float
    largest: float
    steps: int = 0

    def scaled(self, factor: float) -> Certificate:
        """The certificate of ``factor * C`` (``factor > 0``), e.g. ``C = E C / E``."""
        return dataclasses.replace(self, smallest=self.smallest * factor,
                                   largest=self.largest * factor)


def certificate_of(operator) -> Certificate | None:
    """The certificate an operator (or the object it wraps, ``base``) carries, or None."""
    for holder in (operator, getattr(operator, "base", None)):
        found = getattr(holder, ATTRIBUTE, None) if holder is not None else None
        if isinstance(found, Certificate):
            return found
    return None


def _remember(operator, found: Certificate) -> None:
    """Keep ``found`` on the operator and on the object it wraps (``base``), which
    outlives a wrapper made per solve; objects that refuse attributes keep nothing."""
    for holder in (operator, getattr(operator, "base", None)):
        if holder is None or isinstance(holder, np.ndarray):
            continue
        try:
            object.__setattr__(holder, ATTRIBUTE, found)
        except (AttributeError, TypeError):
            pass


def carry(source, target, factor: float = 1.0) -> None:
    """Give ``target`` the certificate of ``source`` times ``factor`` (> 0), if it has one:
    ``target`` is ``factor`` times the same operator (a view, a rescaled copy)."""
    found = certificate_of(source)
    if found is not None:
        _remember(target, found if factor == 1.0 else found.scaled(factor))


def certify(operator, *, name: str = "the influence operator", unit: str = "m/Pa",
            advice: str | None = None) -> Certificate:
    """Certify ``operator`` symmetric positive definite, once; refuse it otherwise.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        A dense symmetric matrix, or an object with ``shape`` and ``matvec``
        (optional ``matrix``, ``spectrum``, ``grid``, ``size``,
        ``mean_compliance``), e.g. an
        :class:`~roughcontact.elasticity.protocol.InfluenceOperator`.
    name : str
        What the messages call the operator (e.g. the file it was read from).
    unit : str
        Unit of its entries, for the messages (m/Pa for C, m for E * C).
    advice : str, optional
        What to do about a refused operator; default: check how it was built.

    Returns
    -------
    Certificate
        Kept on the operator (not on a plain ndarray), and returned at once
        when it is certified again.

    Raises
    ------
    IndefiniteOperator
        When the operator has a negative (or zero) eigenvalue, with its
        estimates of the smallest and largest eigenvalues.
    ValueError
        When it is not symmetric.
    """
    found = certificate_of(operator)
    if found is not None:
        return found
    found = _measure(operator, name, unit, advice)
    _remember(operator, found)
    return found


# ---------------------------------------------------------------------------
# The three ways


def _measure(operator, name: str, unit: str, advice: str | None) -> Certificate:
    matrix = operator if isinstance(operator, np.ndarray) else getattr(operator, "matrix", None)
    if matrix is not None:
        matrix = np.asarray(matrix, dtype=float)
        check_symmetric(matrix, name)
        if matrix.shape[0] <= CHOLESKY_MAX_ELEMENTS:
            if getattr(operator, "mean_compliance", None) == 0.0 and matrix.shape[0] > 1:
                matrix = _without_zero_mode(matrix, name)
            return _cholesky(matrix, operator, name, unit, advice)
    spectrum = _spectrum_without_zero_mode(operator)
    if spectrum is not None:
        return _spectrum_certificate(spectrum, name, unit, advice)
    return _lanczos_certificate(_products(operator, matrix, name), name, unit, advice)


def _spectrum_certificate(values: np.ndarray, name: str, unit: str,
                          advice: str | None) -> Certificate:
    """``"spectrum"`` from an operator's eigenvalues, or the refusal of a non-positive one."""
    found = Certificate("spectrum", float(values.min()), float(values.max()))
    if not found.smallest > DEFINITE_RTOL * found.largest:
        _refuse(name, found.smallest, found.largest, unit, "its spectrum", advice)
    return found


def from_eigenvalues(matrix: np.ndarray, values: np.ndarray, *,
                     name: str = "the influence operator", unit: str = "m/Pa",
                     advice: str | None = None) -> Certificate:
    """The certificate of a dense matrix whose eigenvalues are already known (e.g. from
    ``eigvalsh``): symmetry checked as by :func:`certify`, then ``"spectrum"``,
    or refused as :func:`certify` refuses. Spares the Cholesky factorization of a
    caller that computed the spectrum anyway."""
    check_symmetric(matrix, name)
    return _spectrum_certificate(np.asarray(values), name, unit, advice)


def check_symmetric(matrix: np.ndarray, name: str = "the influence operator") -> None:
    """Refuse a dense matrix with ``max|C - C^T| > SYMMETRY_RTOL max|C|``, naming it."""
    scale = float(np.abs(matrix).max())
    difference = asymmetry(matrix)
    if difference > SYMMETRY_RTOL * scale:
        raise ValueError(
            f"operator must be symmetric (Eq 39): {name} has max|C - C^T| / max|C| = "
            f"{difference / scale:.3g} > {SYMMETRY_RTOL:g}; symmetrize with (C + C.T) / 2")


def asymmetry(matrix: np.ndarray, block: int = 128) -> float:
    """``max|C - C^T|`` of a square matrix, compared in square tiles (cache-friendly:
    about 5 matrix-vector products of time, against 60 for whole rows and columns)."""
    size = matrix.shape[0]
    worst = 0.0
    for start in range(0, size, block):
        rows = slice(start, start + block)
        for other in range(start, size, block):
            cols = slice(other, other + block)
            worst = max(worst, float(np.abs(matrix[rows, cols] - matrix[cols, rows].T).max()))
    return worst


def _without_zero_mode(matrix: np.ndarray, name: str) -> np.ndarray:
    """``C + (s / n) 1 1^T`` for a matrix declared to have the uniform pressure as its
    zero mode (``mean_compliance = 0``), ``s`` its largest diagonal entry.

    The rows of ``C`` must sum to zero (to :data:`ZERO_MODE_RTOL` of the largest
    absolute row sum), so that ``1`` is an eigenvector with eigenvalue 0 to
    rounding; the shift moves that eigenvalue to ``s``, inside the spectrum,
    and leaves every other eigenvector (orthogonal to ``1``) and eigenvalue as
    it is. A Cholesky factorization of the shifted matrix then proves ``C``
    positive definite on the complement of the uniform pressure, the space
    displacement control solves in (:func:`roughcontact.contact.checks.check_bounded`)
    whatever the sign of the rounding in the zero eigenvalue, which differs
    between CPUs (FFT and BLAS kernels).
    """
    n = matrix.shape[0]
    row_sums = matrix.sum(axis=1)
    scale = float(np.abs(matrix).sum(axis=1).max())
    worst = float(np.abs(row_sums).max())
    if not worst <= ZERO_MODE_RTOL * scale:
        raise ValueError(
            f"{name} is declared to have the uniform pressure as its zero mode "
            f"(mean_compliance = 0), but its rows sum to up to {worst:.3g} against "
            f"{scale:.3g} for their absolute values; give the operator's own "
            f"mean_compliance (its row sum), or None if the rows differ")
    return matrix + float(np.diag(matrix).max()) / n


def _cholesky(matrix, operator, name, unit, advice) -> Certificate:
    """Cholesky of the lower triangle (the transpose of a C-ordered matrix is Fortran
    ordered, so LAPACK reads it in place and factors a copy).

    The smallest squared pivot bounds the smallest eigenvalue from above (each
    is a diagonal entry of a Schur complement of ``C``, whose eigenvalues are
    at least ``C``'s smallest), so a factorization whose smallest squared pivot is at most
    :data:`DEFINITE_RTOL` of the largest diagonal entry is refused like a
    failed one: the matrix is singular to rounding, and whether LAPACK's last
    pivot came out positive or negative is the sign of a rounding error,
    which differs between CPUs.
    """
    factor, info = scipy.linalg.lapack.dpotrf(matrix.T, lower=False, clean=False,
                                              overwrite_a=False)
    largest = float(np.diag(matrix).max())
    if info == 0:
        smallest = float(np.diag(factor).min()) ** 2
        if smallest > DEFINITE_RTOL * largest:
            return Certificate("cholesky", smallest, largest)
        info = int(np.argmin(np.abs(np.diag(factor)))) + 1
        evidence = (f"its Cholesky factorization has a pivot of {smallest:.3g} {unit} at row "
                    f"{info}, zero to rounding against {largest:.3g} {unit}")
    else:
        evidence = f"its Cholesky factorization fails at row {info}"
    del factor
    if info < 0 or matrix.shape[0] <= EXACT_EIGENVALUES_MAX:
        values = scipy.linalg.eigvalsh(matrix)
        smallest, largest = float(values[0]), float(values[-1])
    else:
        smallest, largest = _estimates(_products(operator, matrix, name))
    _refuse(name, smallest, largest, unit, evidence, advice)


def _spectrum_without_zero_mode(operator) -> np.ndarray | None:
    """The eigenvalues of a circulant operator (its ``spectrum``), the zero mode left
    out when ``mean_compliance`` is 0; None for any other operator."""
    holder = getattr(operator, "base", operator)
    spectrum = getattr(holder, "spectrum", None)
    if spectrum is None:
        return None
    values = np.asarray(spectrum, dtype=float).ravel()
    if getattr(holder, "mean_compliance", None) == 0.0 and values.size > 1:
        values = values[1:]  # the rfft2 layout puts q = 0 first
    return values


# ---------------------------------------------------------------------------
# Lanczos


@dataclass(frozen=True)
class _Products:
    """The products Lanczos takes: ``C x`` and the preconditioner ``M x`` (None: none),
    on the complement of the uniform pressure when ``zero_mean``."""

    n: int
    matvec: Callable[[np.ndarray], np.ndarray]
    precondition: Callable[[np.ndarray], np.ndarray] | None
    zero_mean: bool
    name: str

    def project(self, x: np.ndarray) -> np.ndarray:
        return x - x.mean() if self.zero_mean else x

    def operator(self, x: np.ndarray) -> np.ndarray:
        """``C x``, projected."""
        return self.project(np.asarray(self.matvec(x), dtype=float).reshape(-1))

    def preconditioned(self, x: np.ndarray) -> np.ndarray:
        """``M x`` (``x`` without a preconditioner), projected."""
        return self.project(x if self.precondition is None else self.precondition(x))


def _products(operator, matrix, name: str) -> _Products:
    n = int(operator.shape[0]) if matrix is None else matrix.shape[0]
    matvec = (lambda x: matrix @ x) if matrix is not None else operator.matvec
    grid = getattr(operator, "grid", None)
    size = getattr(operator, "size", None) or getattr(getattr(operator, "base", None), "size",
                                                       None)
    precondition = None
    if grid is not None and int(grid[0]) * int(grid[1]) == n and n > 1:
        precondition = _circulant_q(grid, size)
    return _Products(n, matvec, precondition, getattr(operator, "mean_compliance", None) == 0.0,
                     name)


def _circulant_q(grid, size) -> Callable[[np.ndarray], np.ndarray]:
    """``M x``: the circulant with symbol ``|q|`` on the ``(ny, nx)`` grid (spacing
    from ``size`` [m], or square elements), its zero mode given the smallest non-zero
    ``|q|`` so that ``M`` is positive definite."""
    nx, ny = (int(g) for g in grid)
    lx, ly = (float(s) for s in size) if size is not None else (float(nx), float(ny))
    qx = np.fft.rfftfreq(nx, lx / nx)
    qy = np.fft.fftfreq(ny, ly / ny)
    q = np.hypot(qx[None, :], qy[:, None])
    q[0, 0] = q[q > 0].min()

    def precondition(x: np.ndarray) -> np.ndarray:
        return scipy.fft.irfft2(scipy.fft.rfft2(x.reshape(ny, nx)) * q, s=(ny, nx)).reshape(-1)

    return precondition


def _lanczos(products: _Products, steps: int, *, plain: bool = False, combine=None):
    """Lanczos on ``S = M^(1/2) C M^(1/2)`` (``C`` itself when ``plain`` or without ``M``).

    Runs in ``p_j = M^(-1/2) q_j`` and ``z_j = M p_j = M^(1/2) q_j`` (``q_j`` the
    Lanczos vectors of ``S``), so that it needs ``C`` and ``M`` only, one product of
    each per step: ``alpha_j = z_j.C z_j``, ``beta_(j+1) p_(j+1) = C z_j - alpha_j p_j
    - beta_j p_(j-1)``, ``beta_(j+1)^2 = p_(j+1).M p_(j+1)``; one local
    re-orthogonalization per step. Every vector is projected (the products' zero
    mode cannot come back by rounding); the run stops early when the Krylov space
    is invariant (few distinct eigenvalues, such as a small circulant). Starts
    from a fixed random vector. Returns the diagonal and off-diagonal of the
    tridiagonal matrix and, when ``combine`` (coefficients of the Lanczos
    vectors) is given, ``y = sum combine[j] z_j = M^(1/2) x`` for the Ritz vector
    ``x`` of ``S`` they describe (``y.C y`` has the sign of ``x.S x``).
    """
    precondition = products.project if plain else products.preconditioned
    p = products.project(np.random.default_rng(SEED).standard_normal(products.n))
    z = precondition(p)
    scale = math.sqrt(float(p @ z))
    p, z = p / scale, z / scale
    previous = np.zeros_like(p)
    beta = 0.0
    alphas, betas, probes = [], [], []
    vector = None if combine is None else np.zeros_like(p)
    for step in range(steps):
        if vector is not None:
            vector += combine[step] * z
        product = products.operator(z)
        if step < 2:
            probes.append((z, product))
        w = product - beta * previous
        alpha = float(z @ w)
        w -= alpha * p
        again = float(z @ w)
        w = products.project(w - again * p)
        alphas.append(alpha + again)
        following = precondition(w)
        beta = math.sqrt(max(float(w @ following), 0.0))
        if step == steps - 1 or beta <= INVARIANT_RTOL * max(abs(a) for a in alphas):
            break  # the Krylov space is invariant: its Ritz values are eigenvalues
        betas.append(beta)
        previous, p, z = p, w / beta, following / beta
    if len(probes) == 2:
        _check_symmetric(*probes, name=products.name)
    return np.array(alphas), np.array(betas), vector


def _ritz(alphas, betas):
    """Eigenvalues and eigenvectors of the Lanczos tridiagonal matrix."""
    if alphas.size == 1:
        return alphas.copy(), np.ones((1, 1))
    return scipy.linalg.eigh_tridiagonal(alphas, betas)


def _check_symmetric(first, second, name: str) -> None:
    """Refuse ``C`` unless ``x.C y = y.C x`` for the first two vectors ``x``, ``y`` of a
    Lanczos run and their products (``C x``, ``C y``), to rounding."""
    (x, cx), (y, cy) = first, second
    scale = np.linalg.norm(x) * np.linalg.norm(cy) + np.linalg.norm(y) * np.linalg.norm(cx)
    difference = abs(float(x @ cy) - float(y @ cx))
    if difference > SYMMETRY_RTOL * scale:
        raise ValueError(
            f"operator must be symmetric (Eq 39): {name} gives x.Cy - y.Cx = "
            f"{difference / scale:.3g} of |x||Cy| + |y||Cx| > {SYMMETRY_RTOL:g}; its product "
            f"must be the same read by rows or by columns")


def _lanczos_certificate(products: _Products, name, unit, advice) -> Certificate:
    if products.zero_mean and products.n == 1:
        return Certificate("lanczos", math.nan, math.nan)  # nothing beside the zero mode
    plain = products.precondition is None
    steps = min(PLAIN_LANCZOS_STEPS if plain else LANCZOS_STEPS, products.n)
    alphas, betas, _ = _lanczos(products, steps)
    values, vectors = _ritz(alphas, betas)
    method = "lanczos" if plain else "preconditioned lanczos"
    found = Certificate(method, float(values[0]), float(values[-1]), int(alphas.size))
    if found.smallest > DEFINITE_RTOL * abs(found.largest):
        return found
    smallest, largest = _estimates(products, (alphas.size, vectors[:, 0]))
    _refuse(name, smallest, largest, unit,
            f"a {found.steps}-step {method} estimate", advice)


def _estimates(products: _Products, ritz=None) -> tuple[float, float]:
    """Estimates of the smallest and largest eigenvalues of ``C`` itself, for a refusal:
    the extremes of plain Lanczos steps on ``C`` and, with a preconditioner, the
    Rayleigh quotient of ``M^(1/2) x`` for the smallest Ritz vector ``x`` of ``S``
    (``ritz``: its steps and coefficients; found by a run here if not given)."""
    alphas, betas, _ = _lanczos(products, min(PLAIN_LANCZOS_STEPS, products.n), plain=True)
    plain = _ritz(alphas, betas)[0]
    smallest, largest = float(plain[0]), float(plain[-1])
    if products.precondition is None:
        return smallest, largest
    if ritz is None:
        alphas, betas, _ = _lanczos(products, min(LANCZOS_STEPS, products.n))
        ritz = (alphas.size, _ritz(alphas, betas)[1][:, 0])
    steps, coefficients = ritz
    _, _, vector = _lanczos(products, steps, combine=coefficients)
    quotient = float(vector @ products.operator(vector) / (vector @ vector))
    return min(smallest, quotient), largest


def _refuse(name, smallest, largest, unit, evidence, advice):
    raise IndefiniteOperator(
        f"operator must be positive definite (Eq 39), but {name} has a negative or zero "
        f"eigenvalue: smallest about {smallest:.4g} {unit}, largest about {largest:.4g} "
        f"{unit} ({evidence}). Eq 27 is then not a convex problem: a solver can meet its "
        f"tolerance at a point that is not its solution. "
        + (advice or "Check how C was built: the influence matrix of an elastic body is "
                     "symmetric positive definite."),
        name=name, smallest=smallest, largest=largest)
