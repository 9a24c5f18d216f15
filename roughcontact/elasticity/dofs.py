"""Equations of the supported block: support conditions and hanging-node ties.

The bottom face ``z = -L`` rests on a rigid plate (``SUPPORTS``: bonded or
frictionless); where a fine slab of the mesh rests on a coarser one, the
fine slab's bottom nodes follow the coarse face's interpolation (hanging
nodes). ``dof_map`` numbers the remaining free dofs as equations and gives
the tying matrix from them to every node dof (``3 * node + component``,
``roughcontact.elasticity.mesh``).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import scipy.sparse as sp

from roughcontact.elasticity.elements import reference_top_face
from roughcontact.elasticity.mesh import HexMesh, numbered_slabs


@dataclass(frozen=True)
class Support:
    """How the bottom face ``z = -L`` is held.

    Attributes
    ----------
    components : tuple of int
        Displacement components (0: x, 1: y, 2: z) fixed at every bottom node.
    pins_rigid_body : bool
        Also remove the three in-plane rigid-body motions by a statically
        determinate set: ``ux = uy = 0`` at the bottom corner ``(0, 0)`` and
        ``uy = 0`` at ``(Lx, 0)``.
    """

    components: tuple[int, ...]
    pins_rigid_body: bool = False

    def fixed_dofs(self, plane: np.ndarray) -> np.ndarray:
        """Sorted fixed dofs ``3 * node + component`` of the bottom plane's node numbers.

        ``plane`` is the bottom lattice plane (y, x) of node numbers, -1 where
        there is no node.
        """
        bottom = plane[plane >= 0]
        fixed = (3 * bottom[:, None] + np.asarray(self.components)).ravel()
        if self.pins_rigid_body:
            corner_a, corner_b = plane[0, 0], plane[0, -1]
            fixed = np.concatenate([fixed, [3 * corner_a, 3 * corner_a + 1, 3 * corner_b + 1]])
        return np.unique(fixed)

    def fixed_count(self, bottom_nodes: int) -> int:
        """Number of dofs ``fixed_dofs`` returns for a bottom plane of ``bottom_nodes``."""
        return len(self.components) * bottom_nodes + (3 if self.pins_rigid_body else 0)


#: Base condition (``BlockGeometry.base``) -> its ``Support``.
#:
#: - ``"clamped"``: all three components of every bottom node (bonded to a
#:   rigid plate).
#: - ``"sliding"``: the normal component of every bottom node (frictionless
#:   rigid support) plus the in-plane rigid-body motions. Normal loads on the
#:   top face exert no in-plane force or moment, so these constraints carry
#:   no reaction and do not change the normal displacements.
SUPPORTS = MappingProxyType({
    "clamped": Support((0, 1, 2)),
    "sliding": Support((2,), pins_rigid_body=True),
})


def constrained_dofs(mesh: HexMesh, base: str) -> np.ndarray:
    """Dofs fixed by the support on the bottom face ``z = -L`` (global numbering).

    Parameters
    ----------
    mesh : HexMesh
        The structured mesh.
    base : {"clamped", "sliding"}
        Key of ``SUPPORTS``.

    Returns
    -------
    ndarray of int
        Sorted dof numbers ``3 * node + component``.
    """
    if base not in SUPPORTS:
        raise ValueError(f"base must be one of {tuple(SUPPORTS)}, got {base!r}")
    _, numbers, _ = numbered_slabs(mesh)
    return SUPPORTS[base].fixed_dofs(numbers[0][0])


def _hanging_nodes(
    fine: HexMesh, fine_numbers: np.ndarray, coarse: HexMesh, coarse_numbers: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node-level constraints tying a fine slab's bottom plane to the coarse slab below.

    Returns
    -------
    slave, master, weight : ndarray
        Triplets: the displacement of node ``slave`` is the sum of
        ``weight * displacement of master`` over its rows (the coarse top face's
        interpolation at the fine node).
    """
    p = fine.order
    ratio = (len(fine.x_edges) - 1) // (len(coarse.x_edges) - 1)
    span = p * ratio  # fine lattice steps per coarse element
    dx = coarse.x_edges[1] - coarse.x_edges[0]
    dy = coarse.y_edges[1] - coarse.y_edges[0]
    local = np.arange(span + 1) / span
    gy, gx = np.meshgrid(local, local, indexing="ij")
    face = reference_top_face(coarse.element, dx, dy, np.column_stack([gx.ravel(), gy.ravel()]))
    plane = fine_numbers[0]
    ky, kx = np.nonzero(plane >= 0)
    ecx = np.minimum(kx // span, len(coarse.x_edges) - 2)
    ecy = np.minimum(ky // span, len(coarse.y_edges) - 2)
    point = (ky - ecy * span) * (span + 1) + (kx - ecx * span)
    weight = face.values[point]  # (slaves, face nodes)
    top = coarse_numbers[-1]
    master = top[p * ecy[:, None] + face.offsets[:, 1], p * ecx[:, None] + face.offsets[:, 0]]
    slave = np.broadcast_to(plane[ky, kx][:, None], weight.shape)
    keep = np.abs(weight) > 1e-13
    return slave[keep], master[keep], weight[keep]


@dataclass(frozen=True)
class DofMap:
    """From the global node dofs to the equations of the supported, tied block.

    Attributes
    ----------
    equation : ndarray of int, shape (n_dofs,)
        Equation number of each dof ``3 * node + component``; -1 for dofs fixed
        by the support and for hanging (constrained) dofs.
    tying : scipy.sparse.csr_array or None, shape (n_dofs, n_free)
        ``u_all = tying @ u_free`` (None for a single-slab mesh, where it is
        the selection given by ``equation``).
    n_free : int
        Number of equations.
    """

    equation: np.ndarray
    tying: sp.csr_array | None
    n_free: int


def dof_map(mesh: HexMesh, base: str) -> DofMap:
    """Equation numbering after the support and the coarse-fine ties are applied."""
    parts, numbers, n_nodes = numbered_slabs(mesh)
    is_free = np.ones(3 * n_nodes, dtype=bool)
    is_free[constrained_dofs(mesh, base)] = False
    ties = [_hanging_nodes(parts[k], numbers[k], parts[k - 1], numbers[k - 1])
            for k in range(1, len(parts))]
    for slave, _, _ in ties:
        is_free[(3 * slave[:, None] + np.arange(3)).ravel()] = False
    equation = np.full(3 * n_nodes, -1, dtype=np.int64)
    n_free = int(np.count_nonzero(is_free))
    equation[is_free] = np.arange(n_free)
    if not ties:
        return DofMap(equation, None, n_free)
    rows = [np.flatnonzero(is_free)]
    cols = [equation[is_free]]
    vals = [np.ones(n_free)]
    for slave, master, weight in ties:
        for c in range(3):
            rows.append(3 * slave + c)
            cols.append(equation[3 * master + c])
            vals.append(weight)
    tying = sp.coo_array(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(3 * n_nodes, n_free),
    ).tocsr()
    return DofMap(equation, tying, n_free)
