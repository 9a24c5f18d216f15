"""Tests of the condensation by mirror-symmetry class (roughcontact.elasticity.symmetry)."""

import numpy as np
import pytest
import scipy.sparse as sp

from roughcontact.elasticity import sparse_solve
from roughcontact.elasticity.assembly import assemble_stiffness, top_face_operators
from roughcontact.elasticity.influence import (
    BlockGeometry,
    MeshSpec,
    build_mesh,
    estimate_cost,
    mirror_classes,
    unit_modulus_influence,
)
from roughcontact.elasticity.symmetry import block_mirrors

H = 0.15e-3  # contact element size of the paper's model [m]
COARSENED_HEX20 = MeshSpec("hex20", refinement=2, layers=None, top_layer=1.0, growth=1.5,
                           coarsen_at=1.0)


def small_block(grid, thickness, **kwargs) -> BlockGeometry:
    return BlockGeometry(size=(grid[0] * H, grid[1] * H), thickness=thickness, grid=grid,
                         **kwargs)


def signed_permutation(image: np.ndarray, sign: np.ndarray) -> sp.csr_array:
    """The matrix P with ``(P u)[image[i]] = sign[i] u[i]``."""
    return sp.csr_array((sign, (image, np.arange(image.size))), shape=(image.size,) * 2)


@pytest.mark.parametrize(
    "geom",
    [
        # the paper's mesh: loads match observations, one border of n
        small_block((8, 8), 8 * H, mesh="paper"),
        # "converged"'s element and layout, plan coarsening (hanging nodes), border of 2n
        small_block((6, 4), 6 * H, nu=0.3, mesh=COARSENED_HEX20),
        # odd grid: elements and nodes on the mid-planes (orbits of 2 and 1)
        small_block((5, 3), 4 * H, nu=0.2, mesh="refined"),
        # odd refinement: the centre point inside a finite-element face
        small_block((3, 3), 3 * H, nu=0.25, mesh=MeshSpec("hex27", refinement=3, layers=3)),
    ],
    ids=["paper", "hex20-coarsened", "odd-grid", "hex27-r3"],
)
def test_mirror_split_gives_the_single_factorization_matrix(geom):
    """The class-by-class condensation is the same matrix to round-off (the
    measured difference is 4e-15 to 9e-14 of the largest entry)."""
    assert len(block_mirrors(build_mesh(geom), geom.base, geom.grid)) == 2
    whole = unit_modulus_influence(geom, symmetric=False, split_by_mirrors=False)
    split = unit_modulus_influence(geom, symmetric=False)
    np.testing.assert_allclose(split, whole, rtol=0, atol=1e-12 * np.abs(whole).max())


def test_mirrors_commute_with_the_stiffness_and_map_the_operators():
    geom = small_block((6, 4), 6 * H, nu=0.3, mesh=COARSENED_HEX20)
    mesh = build_mesh(geom)
    upper = assemble_stiffness(mesh, geom.nu, geom.base, upper=True)
    stiffness = sparse_solve.full_from_upper(upper)
    load, centre = top_face_operators(mesh, geom.grid, geom.base)
    scale = abs(stiffness).max()
    for mirror in block_mirrors(mesh, geom.base, geom.grid):
        P = signed_permutation(mirror.image, mirror.sign)
        Q = signed_permutation(mirror.element_image, np.ones(geom.n_elements))
        assert abs(P @ stiffness @ P.T - stiffness).max() < 1e-14 * scale
        assert abs(centre @ P - Q @ centre).max() == 0
        assert abs(load @ P - Q @ load).max() < 1e-15 * abs(load).max()


def test_sliding_base_is_not_split():
    """The sliding base pins two corners (not mirror-symmetric): one factorization."""
    geom = small_block((4, 4), 4 * H, mesh="paper", base="sliding")
    assert block_mirrors(build_mesh(geom), geom.base, geom.grid) == ()
    clamped = small_block((4, 4), 4 * H, mesh="paper")
    assert len(block_mirrors(build_mesh(clamped), clamped.base, clamped.grid)) == 2
    # the estimate counts the classes without building the mesh
    assert (mirror_classes(geom), mirror_classes(clamped)) == (1, 4)
    np.testing.assert_array_equal(unit_modulus_influence(geom),
                                  unit_modulus_influence(geom, split_by_mirrors=False))


def test_split_estimate_is_smaller_and_names_the_single_factorization_otherwise():
    geom = BlockGeometry(grid=(60, 60), mesh="converged")
    split = estimate_cost(geom)
    whole = estimate_cost(geom, split_by_mirrors=False)
    assert split.dofs == whole.dofs
    assert split.peak_bytes < 4e9 < whole.peak_bytes  # measured: 2.3 GB and 7.4 GB
    sliding = BlockGeometry(grid=(60, 60), mesh="converged", base="sliding")
    assert estimate_cost(sliding).peak_bytes > 4e9


@pytest.mark.skipif(not sparse_solve.pardiso_available(),
                    reason="PARDISO (pypardiso) not installed")
def test_pardiso_reports_the_factor_size():
    geom = small_block((4, 4), 4 * H, mesh="paper")
    mesh = build_mesh(geom)
    upper = assemble_stiffness(mesh, geom.nu, geom.base, upper=True)
    _, centre = top_face_operators(mesh, geom.grid, geom.base)
    stats = {}
    sparse_solve._pardiso_schur(upper, sp.csr_array(centre.T), stats)
    assert stats["factor_nonzeros"] > upper.nnz
    assert stats["gflop"] > 0
    assert stats["peak_kb"] > 0
