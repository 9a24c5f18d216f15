"""The block under a study's surfaces is checked against them when the plan is made.

A 0.126 x 0.094 mm measured patch under the default 10 mm block (a slender
column, with the paper mesh's elements 1000 times deeper than wide) is
refused before any job, with the keys to change; each value offered is
followed here and plans. The check uses the finite-element model a build
solves (a matrix-free operator's coarse model too).
"""

import copy
import re

import numpy as np
import pytest
from scipy import ndimage

from roughcontact.elasticity.influence import (
    MAX_ELEMENT_ASPECT,
    MAX_SLENDERNESS,
    BlockGeometry,
    build_mesh,
    shape_problems,
)
from roughcontact.study.config import validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.settings import Study

PATCH_MM = (0.126, 0.0944)


@pytest.fixture(scope="module")
def patch(tmp_path_factory):
    """A rough 64 x 48 map of 1.97 um spacing: the size of a Wyko OPD measurement."""
    path = tmp_path_factory.mktemp("patch") / "patch.npy"
    rng = np.random.default_rng(5)
    np.save(path, ndimage.gaussian_filter(rng.standard_normal((48, 64)), 2.0) * 20.0)
    return path


def patch_config(path, body=None, **sweep) -> dict:
    surface = {"file": str(path), "format": "npy", "height_unit": "nm",
               "spacing_mm": [PATCH_MM[0] / 64, PATCH_MM[1] / 48]}
    return {"study_seed": 0, "figures": {},
            "surfaces": {"grid": 8, "size_mm": 1.0, "count": 1}, "body": dict(body or {}),
            "sweeps": {"opd": {"surface": surface, "pressure_MPa": [0.001, 0.01], **sweep}}}


def refusal(config) -> str:
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(validated(config)))
    return str(raised.value)


def follow(config: dict, text: str) -> dict:
    """``config`` with a remedy as the message writes it (``sweeps.opd.thickness_mm: patch``,
    ``body.mesh: refined``) applied literally."""
    path, value = text.split(": ")
    *parents, key = path.split(".")
    section = config
    for name in parents:
        section = section.setdefault(name, {})
    section[key] = value if not re.fullmatch(r"[0-9.e+-]+", value) else float(value)
    return config


def remedies(message: str) -> list[str]:
    return re.findall(r"((?:sweeps\.\w+|body)\.\w+: [\w.+-]+) \(a ", message)


def test_element_aspect_ratio_of_uniform_layers():
    # 5 layers of 1 mm under 0.1 mm elements: 10; a 0.1 mm block of one layer 0.02 mm
    # thick under 0.1 mm elements: 5
    thick = BlockGeometry(size=(1e-3, 1e-3), thickness=5e-3, grid=(10, 10), mesh="paper")
    thin = BlockGeometry(size=(1e-3, 1e-3), thickness=0.1e-3, grid=(10, 10), mesh="paper")
    assert build_mesh(thick).aspect_ratio == pytest.approx(10.0, rel=1e-12)
    assert build_mesh(thin).aspect_ratio == pytest.approx(5.0, rel=1e-12)


def test_the_papers_block_passes_and_the_patch_under_10_mm_does_not():
    assert shape_problems(BlockGeometry()) == []  # 9 mm, 10 mm thick, 60 x 60, paper mesh
    patch = BlockGeometry(size=(0.126e-3, 0.0944e-3), thickness=10e-3, grid=(64, 64))
    slender, elongated = shape_problems(patch)
    assert f"more than {MAX_SLENDERNESS:g}" in slender and "105.9 times" in slender
    assert f"more than {MAX_ELEMENT_ASPECT:g}" in elongated


def test_a_measured_patch_under_the_default_block_is_refused_and_each_remedy_plans(patch):
    message = refusal(patch_config(patch))
    assert "sweeps.opd" in message and "10 mm thick" in message and "slender column" in message
    offered = remedies(message)
    assert "sweeps.opd.thickness_mm: patch" in offered
    assert any(r.startswith("sweeps.opd.thickness_mm: 0.") for r in offered)
    assert "surface.crop_mm" in message
    for remedy in offered:
        plan = study_plan(Study.from_config(validated(follow(patch_config(patch), remedy))))
        (geometry,) = plan.geometries.values()
        value = remedy.split(": ")[1]
        expected = max(PATCH_MM) if value == "patch" else float(value)
        assert geometry.thickness == pytest.approx(expected * 1e-3, rel=1e-9)


def test_a_refined_mesh_is_not_offered_where_it_does_not_help(patch):
    # 10 mm under 0.094 mm stays a slender column whatever the mesh
    message = refusal(patch_config(patch, body={"mesh": "refined"}))
    assert "body.mesh: refined" not in message
    assert "sweeps.opd.thickness_mm: patch" in remedies(message)


def test_a_thin_enough_block_with_the_paper_mesh_is_offered_the_refined_mesh(patch):
    # 0.5 mm: slender enough (5.3), but 5 paper layers of 0.1 mm under 2 um elements
    message = refusal(patch_config(patch, thickness_mm=0.5))
    offered = remedies(message)
    assert "body.mesh: refined" in offered
    plan = study_plan(Study.from_config(validated(follow(patch_config(patch, thickness_mm=0.5),
                                       "body.mesh: refined"))))
    assert {g.mesh for g in plan.geometries.values()} == {"refined"}


def test_the_matrix_free_operator_is_checked_on_its_coarse_model(patch):
    # operator auto: the hybrid's coarse finite-element model is the block that is built
    message = refusal(patch_config(patch, body={"operator": "auto", "mesh": "refined"}))
    assert "slender column" in message
    assert study_plan(Study.from_config(validated(patch_config(patch, body={"operator": "auto"},
                                             thickness_mm="patch")))).jobs


def test_generated_surfaces_too_small_for_the_body_are_refused_with_body_keys():
    config = {"study_seed": 0, "figures": {},
              "surfaces": {"grid": 16, "size_mm": 0.5, "count": 2},
              "body": {"thickness_mm": 10.0},
              "sweeps": {"small": {"sigma_um": 0.1, "b_mm": 0.2, "pressure_MPa": [0.01, 0.1]}}}
    message = refusal(config)
    offered = remedies(message)
    assert offered and all(r.startswith("body.") for r in offered)
    for remedy in offered:
        assert study_plan(Study.from_config(
                validated(follow(dict(config, body=dict(config["body"])),
                                           remedy)))).jobs


def test_a_generated_study_may_name_its_blocks_thickness_and_the_advice_names_it():
    config = {"study_seed": 0, "figures": {},
              "surfaces": {"grid": 16, "size_mm": 0.5, "count": 2},
              "sweeps": {"g": {"sigma_um": 0.1, "b_mm": 0.1, "pressure_MPa": [0.1, 1.0],
                               "thickness_mm": 10.0}}}  # 20 times the patch's side
    message = refusal(copy.deepcopy(config))
    offered = remedies(message)
    assert any(r.startswith("sweeps.g.thickness_mm: ") for r in offered)
    for remedy in offered:  # each followed: planned, on the study's own block
        plan = study_plan(Study.from_config(validated(follow(copy.deepcopy(config),
                                                             remedy))))
        thickness = {c.geometry.thickness for c in plan.cells["g"]}
        if remedy.startswith("sweeps.g.thickness_mm: "):
            assert thickness == {float(remedy.split(": ")[1]) * 1e-3}
    with pytest.raises(ConfigProblems, match="g: compare_synthetic needs a measured surface"):
        study_plan(Study.from_config(validated(
            {"study_seed": 0, "figures": {},
             "sweeps": {"g": {"sigma_um": 1.0, "pressure_MPa": [0.1, 1.0],
                              "compare_synthetic": True}}})))
