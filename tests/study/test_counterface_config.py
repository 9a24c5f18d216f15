"""The counter body of a study (Eq 17-18): planned from the config, refused when unusable.

A smooth rigid counter body is no counter body at all (today's jobs and keys); a
generated counter surface is another realisation than the surfaces it meets; a
measured counter surface on another grid, a half-space with a block's keys and a
counter block that cannot be built are refused before any job, with the keys that
fix them (each followed here); a pair of identical bodies sums to twice the
compliance, and a much stiffer counter body is treated as rigid.
"""

import copy
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from roughcontact.contact import counterface
from roughcontact.contact.cell import BULK_FACTOR
from roughcontact.elasticity.protocol import DenseInfluence
from roughcontact.study.config import ConfigError, validated
from roughcontact.study.contact_records import ContactJob, StudyCell
from roughcontact.study.counter_records import (
    NO_COMPLIANCE,
    NO_COUNTER_BODY,
    CounterBody,
    JobCounter,
)
from roughcontact.study.jobs.contact import contact_problem
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.settings import Study
from roughcontact.surfaces.synthetic import derive_seeds

SWEEP = {"sigma_um": 24.5, "b_mm": 0.5, "pressure_MPa": [0.1, 3.0], "count": 3}
BASE = {"study_seed": 3, "surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4]},
        "figures": {}, "reports": {}}


def config(**sweep) -> dict:
    return validated({**copy.deepcopy(BASE), "sweeps": {"pair": {**SWEEP, **sweep}}})


def test_a_smooth_rigid_counter_body_plans_todays_jobs():
    today = study_plan(Study.from_config(config()))
    explicit = study_plan(Study.from_config(
            config(counterface={"surface": "smooth", "body": "rigid"})))
    assert list(explicit.jobs) == list(today.jobs)
    assert all(cell.counterface is NO_COUNTER_BODY for cell in explicit.cells["pair"])
    assert all(job.counter is NO_COUNTER_BODY and set(job.files()) == {"surfaces", "influence"}
               for job in today.jobs.values())
    assert all("counterface" not in cell.params() and "counter" not in cell.columns()
               for cell in explicit.cells["pair"])
    assert all("__cf" not in key for key in today.jobs)


def test_a_counter_surface_is_another_realisation_of_its_statistics():
    plan = study_plan(Study.from_config(config(counterface={"surface": {"sigma_um": 10.0},
                                          "body": {"kind": "halfspace", "E_MPa": 2000.0}})))
    (cell,) = plan.cells["pair"]
    first, counter = cell.surface, cell.counterface.heights.cell
    assert (counter.skew, counter.kurt, counter.corr_length) == (
        first.skew, first.kurt, first.corr_length)
    assert counter.statistics_key != first.statistics_key
    seeds = [derive_seeds(3, c.statistics_key, 3) for c in (first, counter)]
    assert not set(seeds[0]) & set(seeds[1])
    assert counter.key in plan.surfaces and first.key in plan.surfaces
    assert cell.height_scale == pytest.approx(np.hypot(24.5e-6, 10e-6), rel=1e-15)
    job = cell.job
    assert isinstance(cell.counterface, CounterBody) and isinstance(job.counter, JobCounter)
    assert cell.counterface.sigma == 10.0 * 1e-6 and cell.counterface.E == 2000e6
    assert job.counter.sigma_ratio == pytest.approx(10.0 / 24.5)
    assert job.counter.modulus_ratio == pytest.approx(511.0 / 2000.0)
    assert job.counter.heights == cell.counterface.heights  # the same sources, scaled
    assert cell.columns()["counter"] == "half-space E 2000 MPa nu 0 (sigma 10 um)"
    # a half-space on a dense first body: the pair is summed once, its file the job's
    assert set(job.files()) == {"surfaces", "influence", "counter_surfaces", "counter_influence"}
    assert job.files()["counter_influence"].path.startswith("results/influence/pairs/")
    assert job.files()["counter_surfaces"].path == f"results/surfaces/{counter.key}.h5"
    assert ContactJob.from_params(job.params()) == job
    assert StudyCell.from_params(cell.params()) == cell


def test_a_list_of_counter_bodies_is_an_axis():
    plan = study_plan(Study.from_config(config(counterface=[
        {"body": {"kind": "block", "E_MPa": 511.0}},
        {"body": {"kind": "block", "E_MPa": 1022.0}},
        {"body": "rigid"}])))
    cells = plan.cells["pair"]
    assert [c.counterface.E for c in cells[:2]] == [511e6, 1022e6]
    assert cells[2].counterface is NO_COUNTER_BODY
    assert len({c.contact_key for c in cells}) == 3


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    """A 24 x 24 map over 2.4 mm: the study's plan size on another grid."""
    path = tmp_path_factory.mktemp("counter") / "disc.npy"
    rng = np.random.default_rng(8)
    np.save(path, ndimage.gaussian_filter(rng.standard_normal((24, 24)), 1.5) * 2.0)
    return path


def measured_entry(path, **options):
    return {"surface": {"measured": {"file": str(path), "format": "npy",
                                     "height_unit": "um", "spacing_mm": 0.1, **options}}}


def test_a_measured_counter_surface_on_another_grid_is_refused_with_its_fix(measured):
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(config(counterface=measured_entry(measured))))
    message = str(raised.value)
    assert "disc.npy: 24 x 24 points over 2.4 mm x 2.4 mm" in message
    assert "16 x 16 over 2.4 mm x 2.4 mm" in message
    assert "resample_grid: [16, 16]" in message
    # the advice, followed
    plan = study_plan(Study.from_config(
            config(counterface=measured_entry(measured, resample_grid=[16, 16]))))
    (cell,) = plan.cells["pair"]
    assert cell.counterface.heights.cell.grid == (16, 16)
    assert cell.counterface.sigma == pytest.approx(cell.counterface.heights.cell.sigma)
    # measured face up like the first surface, the map meets every surface mirrored in x
    z1 = np.random.default_rng(3).standard_normal((3, 16, 16))
    z2 = np.random.default_rng(4).standard_normal((1, 16, 16))
    r = cell.job.counter.sigma_ratio
    facing = cell.job.counter.heights.cell.facing(z2, r, "x")
    problem = contact_problem(cell.job, z1, None, counterface.Body(facing))
    np.testing.assert_allclose(problem.heights, (z1 + r * z2[:, :, ::-1]) / np.hypot(1, r),
                               rtol=1e-14)


def test_a_measured_counter_surface_of_another_size_is_told_to_crop(measured):
    with pytest.raises(ConfigProblems, match=r"crop_mm: \[0, 0, 1\.2, 1\.2\]"):
        validated_plan = config(counterface=measured_entry(measured, resample_grid=[8, 8]))
        validated_plan["surfaces"]["size_mm"] = [1.2, 1.2]
        validated_plan["surfaces"]["grid"] = [8, 8]
        study_plan(Study.from_config(validated_plan))
    plan = config(counterface=measured_entry(measured, crop_mm=[0, 0, 1.2, 1.2],
                                             resample_grid=[8, 8]))
    plan["surfaces"]["size_mm"] = [1.2, 1.2]
    plan["surfaces"]["grid"] = [8, 8]
    (cell,) = study_plan(Study.from_config(plan)).cells["pair"]
    assert cell.counterface.heights.cell.grid == (8, 8)


def test_counter_entries_that_mix_kinds_are_refused_in_plain_words(measured):
    with pytest.raises(ConfigError, match="a half-space counter body has only E_MPa and nu"):
        config(counterface={"body": {"kind": "halfspace", "E_MPa": 1e3, "thickness_mm": 5}})
    with pytest.raises(ConfigError, match="counter body is rigid, {kind: block"):
        config(counterface={"body": "elastic"})
    with pytest.raises(ConfigError, match="generated counter surface needs its sigma_um"):
        config(counterface={"surface": {"skew": 0.5}})
    with pytest.raises(ConfigError, match="measured counter surface takes its statistics"):
        config(counterface={"surface": {**measured_entry(measured)["surface"], "kurt": 4}})


def test_a_counter_body_that_cannot_be_built_is_refused_with_its_fix():
    hybrid = {"kind": "block", "E_MPa": 511.0, "operator": "hybrid", "mesh": "paper"}
    with pytest.raises(ConfigProblems, match=r"sweeps.pair.counterface.body: operator hybrid "
                                             r".*sweeps.pair.counterface.body.mesh one of"):
        study_plan(Study.from_config(
                                     config(counterface={"body": hybrid})))
    study_plan(Study.from_config(
            config(counterface={"body": {**hybrid, "mesh": "refined"}})))  # followed
    slender = {"kind": "block", "E_MPa": 511.0, "thickness_mm": 200.0}
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(config(counterface={"body": slender})))
    (problem,) = raised.value.problems
    assert problem.startswith("sweeps.pair.counterface.body (a counter block): the block "
                              "under the surfaces (2.4 x 2.4 mm, 16 x 16 elements, 200 mm "
                              "thick, paper mesh) cannot be solved reliably")
    fix = problem.split("Change sweeps.pair.counterface.body.thickness_mm: ")[1].split(" ")[0]
    study_plan(Study.from_config(
            config(counterface={"body": {**slender, "thickness_mm": float(fix)}})))


def _unit(n):
    rng = np.random.default_rng(1)
    a = rng.uniform(0.0, 0.1, (n, n))
    return DenseInfluence(np.eye(n) + a @ a.T / n, 0.15e-3**2, (16, 16))


def test_identical_bodies_double_the_compliance_and_a_stiff_one_is_rigid():
    plan = study_plan(Study.from_config(config(counterface=[
        {"body": {"kind": "block", "E_MPa": 511.0}},
        {"body": {"kind": "block", "E_MPa": 511.0e4}}])))
    twin, stiff = (cell.job for cell in plan.cells["pair"])
    n = 16 * 16
    heights = np.random.default_rng(2).standard_normal((3, 16, 16))
    unit = _unit(n)
    (pair,) = twin.pairs().values()
    assert pair.first == twin.geometry  # summed once
    model = counterface.pair_model(unit, unit, 1.0, 0.001)
    problem = contact_problem(twin, heights, unit,
                              counterface.Body(compliance=counterface.SummedPair(model)))
    np.testing.assert_allclose(problem.unit.matrix, 2 * unit.matrix, rtol=1e-15)
    assert problem.attrs["counter_compliance_share"] == pytest.approx(0.5)
    assert problem.attrs["counter_treated_as_rigid"] is False
    assert problem.bulk_factor == pytest.approx(2 * BULK_FACTOR)
    np.testing.assert_allclose(problem.interface.counter_weights,
                               unit.matrix.sum(axis=0) / n / twin.geometry.thickness, rtol=1e-14)
    rigid = contact_problem(stiff, heights, unit, counterface.Body(
        compliance=counterface.CompliantBody(unit, 1e-4), rigid_share=0.001))
    assert rigid.attrs["counter_compliance_share"] == pytest.approx(1 / 10001)
    assert rigid.attrs["counter_treated_as_rigid"] is True
    assert rigid.unit is unit and rigid.heights is heights
    assert rigid.interface.counter_weights is None


def test_the_two_bodies_config_plans_a_pair_beside_each_rigid_flat():
    import yaml

    root = Path(__file__).resolve().parents[2]
    raw = yaml.safe_load((root / "config" / "two_bodies.yaml").read_text())
    plan = study_plan(Study.from_config(validated(raw)))
    for name in ("pad_on_disc", "steel_plates"):
        pair, flat = plan.cells[name]
        assert flat.counterface is NO_COUNTER_BODY
        assert pair.counterface.compliance is not NO_COMPLIANCE
        assert pair.surface == flat.surface  # the same surfaces, against each body
    kinds = {g.operator.value for n in plan.studies for c in plan.cells[n]
             for g in c.counterface.geometries().values()}
    assert kinds == {"halfspace", "dense"}
