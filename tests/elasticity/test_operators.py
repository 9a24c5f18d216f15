"""Matrix-free influence operators (roughcontact.elasticity.operators) against dense references."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import PeriodicHalfSpace, halfspace_influence
from roughcontact.elasticity.hybrid import hybrid_unit_modulus_influence
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.elasticity.protocol import DenseInfluence, InfluenceOperator
from roughcontact.study import jobs as pipeline
from roughcontact.study.config import BuildSettings, validated
from roughcontact.study.jobs.storage import influence_sha256, read_influence
from roughcontact.study.records import Geometry

SIZE = (9e-3, 7.5e-3)


@pytest.fixture(scope="module")
def small_hybrid():
    """A 24 x 20 block, refined mesh, with its coarse (12 x 10) correction, and the
    dense hybrid matrix built by the independent sparse-Kronecker route."""
    geom = BlockGeometry(grid=(24, 20), size=SIZE, mesh="refined")
    dense = hybrid_unit_modulus_influence(geom, coarsening=2)
    op = operators.block_operator(geom, coarse_grid=(12, 10))
    return geom, op, dense


def test_block_operator_equals_dense_hybrid(small_hybrid):
    _, op, dense = small_hybrid
    assert op.kind == "hybrid"
    assert np.abs(op.to_dense() - dense).max() <= 1e-12 * np.abs(dense).max()
    np.testing.assert_allclose(op.diagonal(), np.diag(dense), rtol=1e-12)


def test_block_operator_batched_and_single_products_agree(small_hybrid):
    _, op, dense = small_hybrid
    p = np.random.default_rng(1).random((op.shape[0], 3))
    batched = op.matvec(p)
    assert batched.shape == p.shape
    for j in range(3):
        np.testing.assert_allclose(op @ p[:, j], batched[:, j], rtol=1e-12, atol=0)
    np.testing.assert_allclose(batched, dense @ p, rtol=1e-11)
    with pytest.raises(ValueError, match="pressure must have shape"):
        op.matvec(np.ones(op.shape[0] + 1))


def test_halfspace_operator_equals_love_matrix():
    """Zero-padded FFT convolution = the dense Love (1929) matrix, rectangular elements."""
    grid = (17, 11)
    op = operators.halfspace_operator(grid, SIZE, 0.3)
    love = halfspace_influence(grid, SIZE, 1.0, 0.3)
    assert op.kind == "halfspace"
    assert np.abs(op.to_dense() - love).max() <= 1e-13 * love.max()
    np.testing.assert_allclose(op.diagonal(), np.diag(love), rtol=1e-13)


def test_hybrid_rows_sum_to_thickness_for_nu0(small_hybrid):
    """Eq 38: uniform pressure on a nu = 0 block with a clamped base gives u = P L / E.

    The half-space alone does not have this property (its mean is about 0.8 L
    here); the correction restores it to within 2.5 % on this 12 x 10 coarse
    grid (0.4 % measured at 256 x 256 from 64 x 64).
    """
    geom, op, _ = small_hybrid
    uniform = op.matvec(np.ones(op.shape[0]))
    assert np.abs(uniform / geom.thickness - 1.0).max() < 0.025
    half = operators.halfspace_operator(geom.grid, geom.size, 0.0).matvec(np.ones(op.shape[0]))
    assert abs(half.mean() / geom.thickness - 1.0) > 0.1


def test_contact_with_operator_equals_contact_with_its_matrix(small_hybrid):
    _, op, dense = small_hybrid
    rng = np.random.default_rng(3)
    gaps = rng.random((3, op.shape[0])) * 1e-5
    approach = np.array([2e-6, 4e-6, 6e-6])
    a = contact.solve_many(op, gaps, approach, options=SolverOptions(tol=1e-10))
    b = contact.solve_many(dense, gaps, approach, element_area=op.element_area,
                           options=SolverOptions(tol=1e-10))
    for ra, rb in zip(a, b, strict=True):
        assert ra.converged and rb.converged
        np.testing.assert_allclose(ra.pressure, rb.pressure, rtol=1e-6,
                                   atol=1e-7 * rb.pressure.max())


def test_every_operator_offers_the_influence_protocol(small_hybrid):
    """Dense matrix, hybrid block, half-space and periodic FFT operators: one interface,
    whose restrict(A) is the operator C_AA on a contact set A (the submatrix)."""
    geom, op, dense = small_hybrid
    n = op.shape[0]
    half = operators.halfspace_operator(geom.grid, geom.size, 0.3)
    periodic = PeriodicHalfSpace(geom.grid, geom.size, 1.0, 0.3)
    cases = [(DenseInfluence(dense, op.element_area, geom.grid), dense), (op, dense),
             (half, half.to_dense()), (periodic, periodic.matvec(np.eye(n)))]
    rng = np.random.default_rng(5)
    subset = np.sort(rng.choice(n, 40, replace=False))
    p = rng.random((40, 2))
    full = rng.random(n)
    for operator, matrix in cases:
        assert isinstance(operator, InfluenceOperator)
        assert operator.shape == (n, n) and operator.dtype == np.float64
        assert operator.grid == geom.grid
        assert operator.element_area == pytest.approx(geom.spacing[0] * geom.spacing[1],
                                                      rel=1e-6, abs=0.0)
        np.testing.assert_allclose(operator.matvec(full), matrix @ full, rtol=1e-10)
        restricted = operator.restrict(subset)
        assert isinstance(restricted, InfluenceOperator) and restricted.shape == (40, 40)
        expected = matrix[np.ix_(subset, subset)]
        np.testing.assert_allclose(restricted.matvec(p), expected @ p, rtol=1e-10)
        np.testing.assert_allclose(restricted @ p[:, 1], expected @ p[:, 1], rtol=1e-10)
        np.testing.assert_allclose(restricted.diagonal(), np.diag(expected), rtol=1e-12)
        inner = restricted.restrict([0, 5, 7])
        np.testing.assert_allclose(inner.matvec(np.ones(3)),
                                   expected[np.ix_([0, 5, 7], [0, 5, 7])].sum(axis=1),
                                   rtol=1e-10)
    assert np.array_equal(cases[0][0].restrict(subset).matrix, dense[np.ix_(subset, subset)])
    assert op.matrix is None and half.matrix is None and periodic.matrix is None
    assert periodic.mean_compliance == 0.0 and op.mean_compliance is None


def test_hybrid_refuses_inaccurate_coarse_meshes():
    geom = BlockGeometry(grid=(8, 8), mesh="paper")
    with pytest.raises(ValueError, match="82 %"):
        operators.block_operator(geom)


@pytest.mark.parametrize(("grid", "coarse"), [
    (1, 1), (30, 30), (64, 64), (65, 33), (97, 49), (120, 60), (128, 64), (256, 64), (512, 64),
])
def test_default_coarse_grid(grid, coarse):
    assert operators.default_coarse_grid((grid, grid)) == (coarse, coarse)


BODY = {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0, "mesh": "refined"}


def complete(body: dict) -> dict:
    """``body`` completed by the schema's defaults, as the workflow sees it."""
    minimal = {"study_seed": 0, "figures": {}, "body": body,
               "surfaces": {"grid": 8, "size_mm": 1.0, "count": 1}}
    return validated(minimal)["body"]


def test_dense_geometry_keys_unchanged_and_operators_keyed():
    surfaces = {"grid": [60, 60], "size_mm": [9.0, 9.0]}
    dense = Geometry.from_params({**complete(BODY), **surfaces})
    assert "operator" not in dense.params()
    assert dense.key == "nu0_L9x9mm_t10mm_g60x60_clamped_refined"
    hybrid = Geometry.from_params({**complete({**BODY, "operator": "hybrid"}), **surfaces})
    assert hybrid.key.endswith("_refined_hybrid")
    auto = Geometry.from_params({**complete({**BODY, "operator": "auto",
                                             "halfspace_tolerance": {"k_P": None}}), **surfaces})
    assert auto.params()["halfspace_tolerance"] == {"k_P": None, "max_pressure": 0.05,
                                                    "real_area": 0.05}
    assert auto.key.endswith("_autox-0.05-0.05")
    assert auto.planned_model(16e9).value == "dense"
    big = Geometry.from_params({**complete({**BODY, "operator": "auto"}), **surfaces,
                                "grid": [256, 256]})
    assert big.planned_model(16e9).value == "hybrid"
    # the build's memory is that of the 64 x 64 coarse model, not of a 34 GB matrix
    assert big.influence_cost(BuildSettings("auto", 16e9)).peak_bytes < 4e9


def _build(tmp_path, body, grid, monkeypatch, coarse_max=None):
    if coarse_max is not None:
        monkeypatch.setattr(operators, "COARSE_MAX", coarse_max)
    params = Geometry.from_params({**complete(body), "grid": [grid, grid], "size_mm": [4.8, 4.8]})
    path = tmp_path / f"{params.key}.h5"
    attrs = pipeline.build_influence(params.params(), path, solver="auto", max_memory_gb=16.0)
    unit, stored = read_influence(path)
    return params, attrs, unit, stored


def test_build_and_read_hybrid_operator(tmp_path, monkeypatch):
    params, attrs, unit, stored = _build(
        tmp_path, {**BODY, "operator": "hybrid"}, 16, monkeypatch, coarse_max=8)
    assert attrs["operator"] == stored["operator"] == "hybrid"
    assert isinstance(unit, operators.BlockOperator)
    assert unit.coarse_grid == (8, 8) and unit.grid == (16, 16)
    assert stored["content_sha256"] == influence_sha256(unit)
    geom = params.block()
    reference = hybrid_unit_modulus_influence(dataclasses.replace(geom), coarsening=2)
    assert np.abs(unit.to_dense() - reference).max() <= 1e-12 * reference.max()


def test_auto_picks_halfspace_only_when_its_measured_errors_allow(tmp_path, monkeypatch):
    strict = {**BODY, "operator": "auto"}
    _, attrs, unit, _ = _build(tmp_path, strict, 16, monkeypatch)
    assert attrs["operator"] == "dense" and isinstance(unit, np.ndarray)
    assert attrs["halfspace_errors"]["k_P"] > 0.1
    loose = {**strict, "halfspace_tolerance": {"k_P": None, "real_area": 0.5,
                                               "max_pressure": 0.5}}
    _, attrs, unit, _ = _build(tmp_path, loose, 16, monkeypatch)
    assert attrs["operator"] == "halfspace"
    assert isinstance(unit, operators.BlockOperator) and unit.correction is None
    love = halfspace_influence((16, 16), (4.8e-3, 4.8e-3), 1.0, 0.0)
    assert np.abs(unit.to_dense() - love).max() <= 1e-13 * love.max()
