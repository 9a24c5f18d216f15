"""Hard cases of the finite-element influence matrix (roughcontact.influence).

Near-incompressible material, the smallest grids, a block much thinner than
its contact elements, and a model far too large for memory.
"""

import logging
import tracemalloc

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.elasticity.influence import (
    MESH_PRESETS,
    BlockGeometry,
    MeshSpec,
    ModelTooLarge,
    check_memory,
    estimate_cost,
    influence_matrix,
    unit_modulus_influence,
)

H = 0.15e-3  # contact element size [m]


def block(grid, thickness, mesh, nu=0.0, **kwargs) -> BlockGeometry:
    size = (grid[0] * H, grid[1] * H)
    return BlockGeometry(size=size, thickness=thickness, grid=grid, nu=nu, mesh=mesh, **kwargs)


def assert_spd(C):
    np.testing.assert_array_equal(C, C.T)
    eigenvalues = np.linalg.eigvalsh(C)
    assert eigenvalues.min() > 0.0
    return eigenvalues


# --- nu = 0.49: volumetric locking -------------------------------------------


def test_quadratic_preset_does_not_lock_at_nu_049():
    # 6 x 6 over 0.9 mm, L = 1 mm. Reference: 27-node elements, 3 x 3 per contact
    # element (23 220 dofs). Measured diagonal / reference: "converged" (20-node)
    # 1.0003-1.0056, nearest neighbour 1.012; trilinear "refined" 0.734-0.763
    # (locking), its nearest neighbour 0.718.
    kwargs = {"grid": (6, 6), "thickness": 1e-3, "nu": 0.49}
    reference_mesh = MeshSpec(element="hex27", refinement=3, layers=None, top_layer=1.0,
                              growth=1.5, coarsen_at=1.0)
    reference = influence_matrix(block(mesh=reference_mesh, **kwargs))
    quadratic = influence_matrix(block(mesh="converged", **kwargs))
    trilinear = influence_matrix(block(mesh="refined", **kwargs))
    centre, neighbour = 3 * 6 + 3, 3 * 6 + 4
    ratio = np.diag(quadratic) / np.diag(reference)
    assert np.abs(ratio - 1.0).max() < 0.02
    # abs=0: approx's default abs=1e-12 would pass any m/Pa value
    assert quadratic[centre, neighbour] == pytest.approx(reference[centre, neighbour], rel=0.03,
                                                         abs=0.0)
    locked = np.diag(trilinear) / np.diag(reference)
    assert locked.max() < 0.85
    assert trilinear[centre, neighbour] < 0.85 * reference[centre, neighbour]
    # the stiffening is the material's doing: at nu = 0.3 the two presets agree
    # (measured trilinear / quadratic diagonal 0.97-1.03)
    kwargs["nu"] = 0.3
    ratio = (np.diag(influence_matrix(block(mesh="refined", **kwargs)))
             / np.diag(influence_matrix(block(mesh="converged", **kwargs))))
    assert np.abs(ratio - 1.0).max() < 0.05


# --- the smallest grids -------------------------------------------------------


@pytest.mark.parametrize("mesh", ["paper", "refined", "converged"])
@pytest.mark.parametrize("grid", [(1, 1), (2, 2)])
def test_one_and_two_element_grids(grid, mesh):
    geom = block(grid, 1e-3, mesh)
    C = influence_matrix(geom)
    n = grid[0] * grid[1]
    assert C.shape == (n, n)
    assert_spd(C)
    # nu = 0: uniform pressure is uniaxial stress, rows sum to L/E (Eq 38); for
    # 1 x 1 that is the one entry. Measured to 3e-14.
    np.testing.assert_allclose(C.sum(axis=1), geom.thickness / geom.E, rtol=1e-10)
    # and the contact solver takes it: a flat punch presses uniformly, p = E d / L
    d = 1e-6
    result = contact.solve(C, np.zeros(n), d, element_area=geom.spacing[0] * geom.spacing[1],
                           options=SolverOptions(method="exact"))
    assert result.converged
    np.testing.assert_allclose(result.pressure, geom.E * d / geom.thickness, rtol=1e-9)


def test_single_element_with_sliding_base_is_uniaxial_for_any_nu():
    for nu in (0.3, 0.49):
        geom = block((1, 1), 1e-3, "paper", nu=nu, base="sliding")
        assert influence_matrix(geom)[0, 0] == pytest.approx(1e-3 / geom.E, rel=1e-10, abs=0.0)


# --- a block much thinner than its contact elements ---------------------------


def test_thin_block_is_nearly_diagonal_with_the_confined_compliance():
    # L = 0.01 mm under 0.15 mm contact elements (4 x 4). A thin bonded layer
    # compresses column by column: C -> (L / E) I for nu = 0 and, for nu > 0, the
    # confined (oedometric) compliance L (1 + nu)(1 - 2 nu) / ((1 - nu) E).
    # The graded presets refine in plan to elements no wider than L (15 per
    # contact element here). Before that rule "converged" gave an indefinite C
    # (smallest / largest eigenvalue -0.03) and "refined" a diagonal 1.3-1.6 L/E.
    # Measured now: diagonal L/E to 3e-5, largest off-diagonal / diagonal 7e-6.
    thickness = 1e-5
    geom = block((4, 4), thickness, "converged")
    assert geom.mesh_spec.refinement == 15
    assert geom.mesh_spec == MeshSpec("hex20", 15, None, 1.0, 1.5, 1.0)
    C = influence_matrix(geom)
    eigenvalues = assert_spd(C)
    assert eigenvalues.min() > 0.9 * eigenvalues.max()
    np.testing.assert_allclose(C.sum(axis=1), thickness / geom.E, rtol=1e-10)
    diagonal = np.diag(C)
    np.testing.assert_allclose(diagonal, thickness / geom.E, rtol=1e-3)
    off = np.abs(C - np.diag(diagonal)).max(axis=1)
    assert (off < 1e-3 * diagonal).all()

    nu = 0.3
    confined = thickness * (1 + nu) * (1 - 2 * nu) / ((1 - nu) * geom.E)
    C = influence_matrix(block((4, 4), thickness, "refined", nu=nu))
    assert_spd(C)
    np.testing.assert_allclose(np.diag(C), confined, rtol=1e-3)  # measured 1.1e-4


def test_thin_block_keeps_the_paper_mesh_and_says_it_is_coarse(caplog):
    # The paper's mesh (5 trilinear layers, one element per contact element) is
    # kept as the paper's model: still symmetric positive definite with rows
    # L/E, but far from diagonal (measured off-diagonal / diagonal 0.34,
    # diagonal up to 58 % below L/E); a warning names the problem and the remedy.
    geom = block((4, 4), 1e-5, "paper")
    assert geom.mesh_spec == MESH_PRESETS["paper"]
    with caplog.at_level(logging.WARNING, logger="roughcontact.influence"):
        C = influence_matrix(geom)
    assert_spd(C)
    np.testing.assert_allclose(C.sum(axis=1), geom.thickness / geom.E, rtol=1e-10)
    assert any("do not resolve" in r.getMessage() and "at least 15" in r.getMessage()
               for r in caplog.records)


def test_thick_blocks_keep_the_presets_unchanged():
    for name, spec in MESH_PRESETS.items():
        assert BlockGeometry(mesh=name).mesh_spec == spec  # the paper's 10 mm block
        assert block((6, 6), 1e-3, name).mesh_spec == spec  # L = 6.7 h


# --- a model far too large ----------------------------------------------------


@pytest.mark.parametrize("mesh", ["paper", "converged"])
def test_huge_model_is_refused_before_anything_is_built(mesh):
    geom = BlockGeometry(grid=(400, 400), mesh=mesh)  # 160 000 contact elements
    tracemalloc.start()
    try:
        cost = estimate_cost(geom)
        _, peak_estimate = tracemalloc.get_traced_memory()
        tracemalloc.reset_peak()
        with pytest.raises(ModelTooLarge) as refused:
            check_memory(geom, 16e9)
        with pytest.raises(ModelTooLarge):
            unit_modulus_influence(geom)  # default limit 16 GB
        _, peak_refusal = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # the dense 160 000^2 matrix alone is 205 GB; nothing near that was allocated
    assert cost.peak_bytes > 8.0 * 160_000**2
    assert peak_estimate < 100e6 and peak_refusal < 100e6
    message = str(refused.value)
    assert f"{cost.peak_bytes / 1e9:.1f} GB" in message
    assert "Options" in message and "max_bytes" in message and "smaller grid" in message
    assert isinstance(refused.value, MemoryError)
