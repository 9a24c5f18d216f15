"""Sparse direct solves of the block: ``left K^-1 right^T`` without forming K^-1.

The influence matrix is a dense condensation of the sparse stiffness K onto
the contact grid; it is computed as the Schur complement of the bordered
matrix ``[[K, B], [B^T, 0]]``, which is ``-B^T K^-1 B``, so no right-hand
side is solved. Two routines compute it (``SOLVERS``): MKL PARDISO, loaded
at run time from the PyPI package ``mkl`` (which ``pypardiso`` installs)
and called through ctypes because ``pypardiso`` does not expose the Schur
option, and scipy's SuperLU as the fallback.
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import os
from types import MappingProxyType

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from roughcontact.errors import FactorizationError


def pardiso_available() -> bool:
    """True when MKL PARDISO loads (PyPI package ``mkl``, a dependency of ``pypardiso``)."""
    try:
        _pardiso_library()
    except (ImportError, OSError):
        return False
    return True


def _mkl_runtime_path() -> str | None:
    """Path of MKL's single runtime library, from the environment or the ``mkl`` wheel."""
    path = os.environ.get("PYPARDISO_MKL_RT")
    if path:
        return path
    try:
        files = importlib.metadata.files("mkl") or []
    except importlib.metadata.PackageNotFoundError:
        return None
    found = sorted(str(f.locate()) for f in files if f.name.startswith(("libmkl_rt", "mkl_rt")))
    return found[0] if found else None


def _pardiso_library():
    """The ``pardiso`` entry point of MKL with its argument types (raises ImportError)."""
    path = _mkl_runtime_path()
    if path is not None:
        library = ctypes.CDLL(path)
    else:  # let pypardiso search (slower: it may run the system linker cache)
        from pypardiso import PyPardisoSolver

        library = PyPardisoSolver().libmkl
    pardiso = library.pardiso
    i32 = ctypes.POINTER(ctypes.c_int32)
    pardiso.argtypes = (
        [ctypes.POINTER(ctypes.c_int64)] + [i32] * 5 + [ctypes.c_void_p] + [i32] * 6
        + [ctypes.c_void_p, ctypes.c_void_p, i32]
    )
    pardiso.restype = None
    return pardiso


def _augmented_upper(stiffness_upper: sp.csr_array, coupling: sp.csr_array) -> sp.csr_array:
    """Upper triangle of ``[[K, B], [B^T, 0]]`` with the zero diagonal stored explicitly."""
    n, nb = stiffness_upper.shape[0], coupling.shape[1]
    top = sp.hstack([stiffness_upper, coupling], format="csr")
    top.sort_indices()
    indptr = np.concatenate([top.indptr, top.indptr[-1] + np.arange(1, nb + 1)])
    indices = np.concatenate([top.indices, np.arange(n, n + nb)])
    data = np.concatenate([top.data, np.zeros(nb)])
    return sp.csr_array(
        (data, indices.astype(np.int32), indptr.astype(np.int32)), shape=(n + nb, n + nb)
    )


def _pardiso_schur(
    stiffness_upper: sp.csr_array, coupling: sp.csr_array, stats: dict | None = None
) -> np.ndarray:
    """``B^T K^-1 B`` as the (negated) Schur complement of ``[[K, B], [B^T, 0]]``.

    MKL PARDISO factorizes the K block (nested-dissection ordering, symmetric
    indefinite driver; K itself is positive definite so no pivot is perturbed)
    and returns the dense Schur complement ``0 - B^T K^-1 B`` of the trailing
    block (``iparm[35] = 1``), so no right-hand side is ever solved.
    """
    pardiso = _pardiso_library()
    a = _augmented_upper(stiffness_upper, coupling)
    n, nb = a.shape[0], coupling.shape[1]
    pt = np.zeros(64, dtype=np.int64)
    iparm = np.zeros(64, dtype=np.int32)
    iparm[0] = 1  # use the values below, defaults elsewhere
    iparm[1] = 2  # METIS nested dissection
    iparm[9] = 8  # pivot perturbation 1e-8 (never triggered for an SPD block)
    iparm[17] = -1  # report the factor's nonzeros (MKL fills iparm[17] only when negative)
    iparm[18] = -1  # report the factorization's MFLOP (likewise)
    iparm[34] = 1  # zero-based indices
    iparm[35] = 1  # Schur complement of the rows flagged in perm
    perm = np.zeros(n, dtype=np.int32)
    perm[n - nb:] = 1
    schur = np.zeros((nb, nb))
    rhs = np.zeros(n)
    error = ctypes.c_int32(0)
    i32 = ctypes.POINTER(ctypes.c_int32)

    def call(phase: int) -> None:
        pardiso(
            pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
            ctypes.byref(ctypes.c_int32(1)),
            ctypes.byref(ctypes.c_int32(1)),
            ctypes.byref(ctypes.c_int32(-2)),
            ctypes.byref(ctypes.c_int32(phase)),
            ctypes.byref(ctypes.c_int32(n)),
            a.data.ctypes.data,
            a.indptr.ctypes.data_as(i32),
            a.indices.ctypes.data_as(i32),
            perm.ctypes.data_as(i32),
            ctypes.byref(ctypes.c_int32(1)),
            iparm.ctypes.data_as(i32),
            ctypes.byref(ctypes.c_int32(0)),
            rhs.ctypes.data,
            schur.ctypes.data,
            ctypes.byref(error),
        )

    try:
        call(12)
        if error.value != 0:
            raise _pardiso_error(int(error.value))
        if iparm[13] != 0:
            raise FactorizationError(
                f"PARDISO perturbed {iparm[13]} pivots of the stiffness matrix: it is not "
                f"definite, so the finite-element model does not resolve the body. "
                f"{SINGULAR_ADVICE}", "pardiso", 0)
        if stats is not None:
            stats.update(factor_nonzeros=int(iparm[17]), gflop=float(iparm[18]) / 1e3,
                         peak_kb=int(max(iparm[14], iparm[15] + iparm[16])))
    finally:
        call(-1)
    return np.negative(schur, out=schur)


#: What MKL PARDISO's error codes mean (its reference manual).
PARDISO_ERRORS = MappingProxyType({
    -1: "input inconsistent", -2: "not enough memory", -3: "reordering problem",
    -4: "zero pivot (numerical factorization)", -5: "unclassified internal error",
    -6: "reordering failed", -7: "diagonal matrix is singular",
    -8: "32-bit integer overflow", -9: "not enough memory for out-of-core",
    -10: "cannot open out-of-core files", -11: "out-of-core read/write error",
})
#: What to change when the stiffness matrix is singular or not definite.
SINGULAR_ADVICE = ("A mesh that does not resolve the block gives such a matrix: set body.mesh "
                   "to refined or converged, or make the block thinner next to the patch "
                   "(thickness_mm).")
#: What to change when the factorization runs out of memory or integers.
MEMORY_ADVICE = ("Lower the finite-element model's size (a coarser contact grid, or "
                 "body.mesh: refined rather than converged), or set body.solver: superlu "
                 "(slower, a different memory profile).")


def _pardiso_error(code: int) -> FactorizationError:
    """The error of a failed PARDISO factorization: the code, its meaning, the advice."""
    meaning = PARDISO_ERRORS.get(code, "unknown error")
    advice = SINGULAR_ADVICE if code in (-4, -7) else MEMORY_ADVICE if code in (-2, -8, -9) \
        else "Try body.solver: superlu, which factorizes the same model another way."
    return FactorizationError(f"PARDISO factorization failed with error {code} ({meaning}). "
                              f"{advice}", "pardiso", code)


def full_from_upper(upper: sp.csr_array) -> sp.csc_array:
    """Symmetric matrix from its upper triangle, keeping explicitly stored zeros.

    The stored pattern is the element connectivity; with nu = 0 some
    stiffness entries are exactly zero, and dropping them misleads the
    minimum-degree ordering (four times the fill at 60 x 60).
    """
    coo = upper.tocoo()
    off = coo.row != coo.col
    rows = np.concatenate([coo.row, coo.col[off]])
    cols = np.concatenate([coo.col, coo.row[off]])
    vals = np.concatenate([coo.data, coo.data[off]])
    return sp.coo_array((vals, (rows, cols)), shape=upper.shape).tocsc()


def _splu(matrix, **options):
    """scipy's ``splu``, its failure ("Factor is exactly singular") as FactorizationError."""
    try:
        return splu(matrix, **options)
    except RuntimeError as err:
        raise FactorizationError(f"SuperLU factorization failed ({err}). {SINGULAR_ADVICE}",
                                 "superlu") from err


def _superlu_schur(stiffness_upper: sp.csr_array, coupling: sp.csr_array) -> np.ndarray:
    """``B^T K^-1 B`` with scipy's SuperLU, as the Schur complement of ``[[K, B], [B^T, 0]]``.

    SuperLU has no Schur-complement option, so the bordered matrix is factorized
    in a fixed order (``permc_spec="NATURAL"``, diagonal pivots): K's dofs in
    the fill-reducing order SuperLU chooses for K alone (minimum degree on
    ``K^T + K``, from a first factorization of K), then the border. The trailing
    blocks of the factors then hold the Schur complement, ``L22 U22 =
    -B^T K^-1 B``. About ten times faster than block solves with n
    right-hand sides.
    """
    full = full_from_upper(stiffness_upper)
    options = {"SymmetricMode": True}
    first = _splu(full, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options=options)
    position = first.perm_c.copy()
    del first
    n, nb = full.shape[0], coupling.shape[1]
    order = np.concatenate([np.argsort(position), np.arange(n, n + nb)])
    bordered = sp.bmat([[full, coupling], [coupling.T, None]], format="csr")
    del full
    bordered = bordered[order][:, order].tocsc()
    lu = _splu(bordered, permc_spec="NATURAL", diag_pivot_thresh=0.0, options=options)
    del bordered
    tail = np.arange(n, n + nb)
    if not (np.array_equal(lu.perm_c[n:], tail) and np.array_equal(lu.perm_r[n:], tail)):
        raise RuntimeError("SuperLU reordered the border; the Schur complement is not trailing")
    lower = lu.L[n:, n:].toarray()
    upper = lu.U[n:, n:].toarray()
    del lu
    schur = lower @ upper
    return np.negative(schur, out=schur)


#: Sparse solver name -> the routine computing ``B^T K^-1 B`` from K's upper triangle and B.
SCHUR_COMPLEMENTS = MappingProxyType({"pardiso": _pardiso_schur, "superlu": _superlu_schur})

#: Accepted ``solver`` arguments: a key of ``SCHUR_COMPLEMENTS`` or "auto".
SOLVERS = ("auto", *SCHUR_COMPLEMENTS)


def resolve_solver(solver: str) -> str:
    """The key of ``SCHUR_COMPLEMENTS`` that ``solver`` selects.

    ``"auto"`` selects PARDISO when it loads (``pardiso_available``), SuperLU
    otherwise; the other names select themselves. Raises ``ValueError`` for a
    name not in ``SOLVERS``.
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if solver == "auto":
        return "pardiso" if pardiso_available() else "superlu"
    return solver


def condensed_flexibility(
    stiffness_upper: sp.csr_array,
    left: sp.csr_array,
    right: sp.csr_array | None = None,
    solver: str = "auto",
) -> np.ndarray:
    """Dense ``left K^-1 right^T`` from one sparse factorization of K.

    Parameters
    ----------
    stiffness_upper : scipy.sparse.csr_array, shape (N, N)
        Upper triangle of the symmetric positive definite stiffness [N/m].
    left, right : scipy.sparse.csr_array, shape (n, N)
        Observation and load operators; ``right = left`` when omitted (then the
        result is symmetric and the PARDISO path condenses onto n, not 2n, dofs).
    solver : {"auto", "pardiso", "superlu"}
        Both compute the Schur complement of the bordered matrix
        ``[[K, B], [B^T, 0]]``, ``B = [right^T, left^T]`` (or ``left^T``),
        which is ``-B^T K^-1 B``; no right-hand side is solved.
        ``"pardiso"``: during one factorization by MKL PARDISO (the PyPI
        package ``mkl``, which ``pypardiso`` installs; called directly because
        ``pypardiso`` does not expose the Schur option), multithreaded;
        ``"superlu"``: scipy's SuperLU with the border ordered last (two
        factorizations, single-threaded, about 5-10 times slower and 3-4 times
        the memory); ``"auto"``: PARDISO when it loads, SuperLU otherwise.

    Returns
    -------
    ndarray, shape (n, n)
        ``left K^-1 right^T`` [m/N for a stiffness in N/m].
    """
    schur = SCHUR_COMPLEMENTS[resolve_solver(solver)]
    if right is None:
        return schur(stiffness_upper, sp.csr_array(left.T))
    n = left.shape[0]
    full = schur(stiffness_upper, sp.csr_array(sp.vstack([right, left]).T))
    return np.ascontiguousarray(full[n:, :n])
