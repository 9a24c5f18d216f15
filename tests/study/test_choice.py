"""operator: auto resolved once, by a measured choice: a geometry that resolves to the
model it had keeps that model's key and files."""

import json

import numpy as np
import pytest

from roughcontact.elasticity import influence, operators
from roughcontact.errors import StoredFileError
from roughcontact.study.config import BuildSettings
from roughcontact.study.jobs import influence as jobs
from roughcontact.study.jobs.storage import read_choice
from roughcontact.study.records import Geometry, InfluenceModel, coarse_geometry

TOLERANCE = (("k_P", 0.02), ("max_pressure", 0.05), ("real_area", 0.05))


def geometry(operator=InfluenceModel.DENSE, grid=(8, 8), mesh="paper", tolerance=()):
    return Geometry(nu=0.0, size=(1e-3, 1e-3), thickness=10e-3, grid=grid, base="clamped",
                    mesh=mesh, operator=operator, halfspace_tolerance=tolerance)


def test_an_auto_geometry_resolves_to_the_key_of_the_model_it_becomes():
    dense = geometry()
    auto = geometry(InfluenceModel.AUTO, tolerance=TOLERANCE)
    assert auto.key != dense.key  # the choice is still to be made
    planned, halfspace = auto.candidates(16e9)
    assert planned == dense and planned.key == dense.key == "nu0_L1x1mm_t10mm_g8x8_clamped_paper"
    assert halfspace.key == dense.key + "_halfspace"
    assert halfspace.influence_cost(BuildSettings("auto", 16e9)).peak_bytes == 0.0
    assert dense.candidates(16e9) == (dense,)
    big = geometry(InfluenceModel.AUTO, grid=(128, 128), mesh="refined", tolerance=TOLERANCE)
    assert big.candidates(16e9)[0].key.endswith("_g128x128_clamped_refined_hybrid")


@pytest.fixture(scope="module")
def dense_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("choice") / f"{geometry().key}.h5"
    jobs.build_influence(geometry().params(), path, solver="auto", max_memory_gb=16.0)
    return path


@pytest.mark.parametrize(("tolerance", "chosen"), [
    ((("k_P", None), ("max_pressure", None), ("real_area", None)), "halfspace"),
    ((("k_P", 1e-9), ("max_pressure", None), ("real_area", None)), "dense"),
])
def test_the_choice_is_measured_on_the_planned_model_and_names_the_resolved_file(
        dense_file, tmp_path, tolerance, chosen):
    auto = geometry(InfluenceModel.AUTO, tolerance=tolerance)
    out = tmp_path / "choices" / f"{auto.key}.json"
    choice = jobs.choose_influence(auto.params(), geometry().params(), dense_file, out)
    assert json.loads(out.read_text()) == json.loads(json.dumps(choice))
    assert choice["operator"] == chosen
    resolved = auto.resolved(InfluenceModel(chosen))
    assert choice["resolved_key"] == resolved.key and choice["resolved"] == resolved.params()
    assert set(choice["halfspace_errors"]) == {"k_P", "real_area", "max_pressure"}
    assert choice["halfspace_errors"]["k_P"] > 1e-9  # measured, not assumed
    assert read_choice(out, geometry=auto.params())["operator"] == chosen
    other = geometry(InfluenceModel.AUTO, tolerance=TOLERANCE)
    with pytest.raises(StoredFileError, match=r"made for other parameters.*halfspace_tolerance"
                                              r".k_P = "):
        read_choice(out, geometry=other.params())


def test_the_choice_refuses_a_planned_file_made_for_another_geometry(dense_file, tmp_path):
    auto = geometry(InfluenceModel.AUTO, mesh="refined", tolerance=TOLERANCE)
    planned = auto.candidates(16e9)[0]
    with pytest.raises(StoredFileError, match=r'mesh = "paper" in the file, "refined" expected'):
        jobs.choose_influence(auto.params(), planned.params(), dense_file, tmp_path / "c.json")


def test_a_hybrid_operator_gives_back_the_coarse_matrix_its_choice_is_measured_on():
    planned = geometry(InfluenceModel.HYBRID, mesh="refined")
    coarse = coarse_geometry(planned.block())
    fe = influence.unit_modulus_influence(coarse)
    op = operators.hybrid_operator(planned.block(), fe.copy(), coarse)
    again, model = jobs._criterion_matrix(op, planned)
    assert model == coarse
    np.testing.assert_allclose(again, 0.5 * (fe + fe.T), rtol=0, atol=1e-12 * np.abs(fe).max())
