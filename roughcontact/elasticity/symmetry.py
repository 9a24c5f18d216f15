"""Mirror symmetry of the block: the condensation ``R K^-1 F^T`` one symmetry class at a time.

The block, its structured mesh, the clamped base and the contact grid are
symmetric about the mid-planes ``x = Lx / 2`` and ``y = Ly / 2``. Each mirror
acts on the displacement equations as a signed permutation P (the mirror
node, the displacement component normal to the plane reversed) and on the
contact elements as a permutation Q; the stiffness commutes with P, and the
observation and load operators satisfy ``R P = Q R``, ``F P = Q F``. The
k commuting mirrors (k = 2, or 0 for the sliding base, whose corner pins
are not symmetric) generate a group of 2^k signed permutations ``P_g`` and
split every vector into 2^k symmetry classes, one per sign pattern
``chi`` (symmetric or antisymmetric about each plane), with the orthogonal
projectors ``Pi_chi = 2^-k sum_g chi(g) P_g`` (sum over the group, chi(g)
the product of the signs of the mirrors composing g). They commute with
K^-1, so with W_chi a basis of the class (orbit sums, entries +-1) and
``K_chi = W_chi^T K W_chi``

    R K^-1 F^T = sum_chi R Pi_chi K^-1 Pi_chi F^T
               = sum_chi R W_chi K_chi^-1 W_chi^T F^T
               = sum_chi V_chi (G_chi K_chi^-1 H_chi^T) V_chi^T,

where ``G_chi`` and ``H_chi`` are the rows of ``R W_chi`` and ``F W_chi`` at
one representative contact element per orbit and ``V_chi`` spreads them
over the orbit with the class's signs (exact, since ``R W_chi`` lies in the
class). Each bracket is the condensation (``sparse_solve``) of a problem
with about 1/2^k of the equations and of the border.

Cost at the paper's 60 x 60 block, "converged" mesh (470 916 equations,
2 cores): four factorizations of about 118 000 equations, about 1e8 factor
nonzeros and 190 GFLOP each (1.1 GB in MKL PARDISO), against one of 6.0e8
nonzeros and 2 500 GFLOP (6.1 GB) for the whole bordered matrix. The
result equals the single factorization's to round-off (3e-14 of the
largest entry), not bit for bit.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from roughcontact.elasticity.dofs import dof_map
from roughcontact.elasticity.mesh import HexMesh, numbered_slabs
from roughcontact.elasticity.sparse_solve import condensed_flexibility


@dataclass(frozen=True)
class Mirror:
    """A mirror plane of the block, as it acts on the equations and on the contact grid.

    Attributes
    ----------
    image : ndarray of int, shape (n_free,)
        Equation of the mirror image of each equation (the same component at
        the mirror node).
    sign : ndarray of float, shape (n_free,)
        -1 for the displacement component normal to the plane, +1 otherwise:
        ``(P u)[image[i]] = sign[i] u[i]``.
    element_image : ndarray of int, shape (n,)
        Contact element (row-major over y then x) of each element's mirror image.
    """

    image: np.ndarray
    sign: np.ndarray
    element_image: np.ndarray


def block_mirrors(mesh: HexMesh, base: str, grid: tuple[int, int]) -> tuple[Mirror, ...]:
    """The mid-planes ``x = Lx/2`` and ``y = Ly/2`` under which the supported block is symmetric.

    A plane is kept when every free equation's mirror image is free, i.e. when
    the support and the hanging-node ties are symmetric about it (the clamped
    base: both planes; the sliding base pins two corners: none).

    Parameters
    ----------
    mesh : HexMesh
        The structured mesh (symmetric in plan by construction).
    base : {"clamped", "sliding"}
        Support of the bottom face.
    grid : (nx, ny)
        Contact elements along x and y.
    """
    _, numbers, n_nodes = numbered_slabs(mesh)
    equation = dof_map(mesh, base).equation
    free = np.flatnonzero(equation >= 0)
    node, component = np.divmod(free, 3)
    elements = np.arange(grid[0] * grid[1]).reshape(grid[1], grid[0])
    mirrors = []
    for axis in (0, 1):  # x, y; the lattice arrays are ordered (z, y, x)
        node_image = np.empty(n_nodes, dtype=np.int64)
        for lattice in numbers:
            present = lattice >= 0
            node_image[lattice[present]] = np.flip(lattice, axis=2 - axis)[present]
        target = equation[3 * node_image[node] + component]
        if (target < 0).any():
            continue
        mirrors.append(Mirror(image=target, sign=np.where(component == axis, -1.0, 1.0),
                              element_image=np.flip(elements, axis=1 - axis).ravel()))
    return tuple(mirrors)


def _group(mirrors: tuple[Mirror, ...], equations: bool) -> list[tuple]:
    """Every element of the group the mirrors generate, as ``(word, image, sign)``.

    ``word`` holds the exponent (0 or 1) of each mirror; ``image`` and ``sign``
    are the element's signed permutation of the equations (``equations``) or
    its permutation of the contact elements (sign 1).
    """
    if equations:
        generators = [(m.image, m.sign) for m in mirrors]
    else:
        generators = [(m.element_image, np.ones(m.element_image.size)) for m in mirrors]
    size = generators[0][0].size
    elements = []
    for word in itertools.product((0, 1), repeat=len(generators)):
        image, sign = np.arange(size), np.ones(size)
        for (mirror_image, mirror_sign), used in zip(generators, word, strict=True):
            if used:  # the mirrors commute: the order of composition does not matter
                image, sign = mirror_image[image], sign * mirror_sign[image]
        elements.append((word, image, sign))
    return elements


def _class_basis(group: list[tuple], chi: tuple[int, ...]) -> tuple[sp.csc_array, np.ndarray]:
    """Basis of the symmetry class ``chi`` and the representative of each basis vector.

    Column j is the orbit sum ``sum_g chi(g) P_g e_r`` of representative r
    (the smallest index of its orbit), ``chi(g)`` the product of the class's
    signs over the mirrors composing g; orbits whose sum vanishes (e.g. the
    component normal to a plane lying on it, in the class symmetric about
    that plane) have no column. Columns are scaled to 1 at the representative
    (the sum counts it once per group element fixing it), so every entry is +-1.
    """
    size = group[0][1].size
    rows = np.concatenate([image for _, image, _ in group])
    cols = np.tile(np.arange(size), len(group))
    vals = np.concatenate([np.prod(np.power(chi, word)) * sign for word, _, sign in group])
    orbit_sums = sp.csc_array((vals, (rows, cols)), shape=(size, size))
    orbit_sums.sum_duplicates()
    orbit_sums.eliminate_zeros()
    smallest = np.min(np.stack([image for _, image, _ in group]), axis=0)
    columns = np.flatnonzero((smallest == np.arange(size)) & (np.diff(orbit_sums.indptr) > 0))
    basis = sp.csc_array(orbit_sums[:, columns])
    basis.sort_indices()  # the representative is the first row of its column
    basis.data /= np.repeat(basis.data[basis.indptr[:-1]], np.diff(basis.indptr))
    return basis, columns


def _class_stiffness(stiffness_upper: sp.csr_array, basis: sp.csc_array) -> sp.csr_array:
    """Upper triangle of ``W^T K W`` from the upper triangle U of K (``K = U + U^T - D``)."""
    folded = (basis.T @ (stiffness_upper @ basis)).tocsr()
    diagonal = basis.T @ (stiffness_upper.diagonal()[:, None] * basis)
    block = sp.triu(folded + folded.T - diagonal, format="csr")
    block.sort_indices()
    return block


def _add_spread(result: np.ndarray, part: np.ndarray, spread: sp.csc_array,
                rows_at_once: int = 256) -> None:
    """``result += V part V^T`` for the class's spreading V (one +-1 per element row at most).

    Row blocks keep the temporaries at ``rows_at_once`` rows of the result.
    """
    by_row = spread.tocsr()
    present = np.diff(by_row.indptr) > 0
    orbit = np.zeros(result.shape[0], dtype=np.int64)
    sign = np.zeros(result.shape[0])
    orbit[present] = by_row.indices
    sign[present] = by_row.data
    columns = part[:, orbit] * sign
    for start in range(0, result.shape[0], rows_at_once):
        rows = slice(start, start + rows_at_once)
        result[rows] += sign[rows, None] * columns[orbit[rows]]


def mirror_condensed_flexibility(
    stiffness_upper: sp.csr_array,
    left: sp.csr_array,
    right: sp.csr_array | None,
    mirrors: tuple[Mirror, ...],
    solver: str = "auto",
) -> np.ndarray:
    """Dense ``left K^-1 right^T`` as the sum of its symmetry classes (module docstring).

    Parameters
    ----------
    stiffness_upper : scipy.sparse.csr_array, shape (N, N)
        Upper triangle of the symmetric positive definite stiffness [N/m],
        commuting with every mirror's signed permutation.
    left, right : scipy.sparse.csr_array, shape (n, N)
        Observation and load operators, mirror-equivariant; ``right = left``
        when None.
    mirrors : tuple of Mirror
        The block's mirror planes (``block_mirrors``); none: one condensation
        of the whole problem.
    solver : {"auto", "pardiso", "superlu"}
        Sparse solver of each class (``sparse_solve.condensed_flexibility``).

    Returns
    -------
    ndarray, shape (n, n)
        ``left K^-1 right^T`` [m/N for a stiffness in N/m].
    """
    if not mirrors:
        return condensed_flexibility(stiffness_upper, left, right, solver=solver)
    equation_group = _group(mirrors, equations=True)
    element_group = _group(mirrors, equations=False)
    result = np.zeros((left.shape[0], left.shape[0]))
    for chi in itertools.product((1, -1), repeat=len(mirrors)):
        spread, representatives = _class_basis(element_group, chi)
        if representatives.size == 0:  # no contact element has a component in this class
            continue
        basis, _ = _class_basis(equation_group, chi)
        block = _class_stiffness(stiffness_upper, basis)
        observe = sp.csr_array((left @ basis)[representatives])
        load = None if right is None else sp.csr_array((right @ basis)[representatives])
        del basis
        part = condensed_flexibility(block, observe, load, solver=solver)
        del block
        _add_spread(result, part, spread)
    return result
