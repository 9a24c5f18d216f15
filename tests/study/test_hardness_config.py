"""A hardness in the config: checked cells, capped cells and their contact keys."""

import copy

import pytest

from roughcontact.study.config import load_config, validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.settings import Study

STUDY = {"sigma_um": [10.0, 20.0], "b_mm": 0.5, "pressure_MPa": [0.1, 2.0]}
BASE = {"study_seed": 0,
        "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 2},
        "body": {"thickness_mm": 2.0, "E_MPa": 500.0},
        "figures": {"fig07": STUDY}}


def config(**changes):
    raw = copy.deepcopy(BASE)
    for section, values in changes.items():
        raw.setdefault(section, {}).update(values)
    return validated(raw)


def test_without_a_hardness_cells_keys_and_settings_are_unchanged():
    default = load_config("config/config.yaml")
    assert default["body"]["hardness_MPa"] is None and default["contact"]["cap"] is False
    for name in ("fig07", "fig11", "fig14", "table_Eu"):
        for cell in contact_cells(Study.from_config(default), name):
            assert cell.hardness is None and cell.checked_hardness == ()
            assert "hardness_MPa" not in cell.params() and "cap_MPa" not in cell.params()
            assert "__cap" not in cell.contact_key
    assert "cap" not in Study.from_config(
            default).contact.params()  # not a solver setting: no rerun


def test_a_hardness_checks_every_elastic_cell_and_solves_nothing_more():
    plain = contact_cells(Study.from_config(
                                            config()), "fig07")
    checked = contact_cells(Study.from_config(
            config(body={"hardness_MPa": [50.0, 200.0]})), "fig07")
    assert [c.contact_key for c in checked] == [c.contact_key for c in plain]
    assert all(c.checked_hardness == (50e6, 200e6) and c.hardness_threshold == 0.05
               and c.params()["hardness_MPa"] == [50.0, 200.0] for c in checked)
    assert study_plan(Study.from_config(config(body={"hardness_MPa": 50.0}))).jobs.keys() == \
        study_plan(Study.from_config(config())).jobs.keys()


def test_cap_both_adds_one_capped_cell_per_hardness_keyed_by_its_cap():
    cfg = config(body={"hardness_MPa": [50.0, 200.0]}, contact={"cap": "both"})
    cells = contact_cells(Study.from_config(cfg), "fig07")
    elastic = [c for c in cells if c.hardness is None]
    capped = [c for c in cells if c.hardness is not None]
    assert len(elastic) == 2 and len(capped) == 4
    jobs = study_plan(Study.from_config(cfg)).jobs
    assert len(jobs) == 6
    for cell in capped:
        key = cell.contact_key
        # H L / (E sigma), computed here from the cell's values in the config's units
        params = cell.params()
        cap = params["cap_MPa"] * 2.0e-3 / (500.0 * params["sigma_um"] * 1e-6)
        assert key.endswith(f"__cap{cap:.7g}")
        assert jobs[key].nondim_hardness == pytest.approx(cap, rel=1e-12)
        assert jobs[key].params()["hardness"] == jobs[key].nondim_hardness
    only_capped = contact_cells(Study.from_config(
            config(body={"hardness_MPa": 50.0}, contact={"cap": True})),
                                "fig07")
    assert [c.hardness for c in only_capped] == [50e6, 50e6]
    assert [c.params()["cap_MPa"] for c in only_capped] == [50.0, 50.0]


def test_capped_cells_share_a_job_only_when_their_cap_is_the_same():
    """sigma and E rescale a capped solution only where H L / (E sigma) is unchanged."""
    study_cells = {"sigma_um": [10.0], "E_MPa": [500.0], "b_mm": 0.5,
                   "pressure_MPa": [0.1, 2.0], "hardness_MPa": 50.0, "cap": True}
    twin = {**study_cells, "sigma_um": [20.0], "E_MPa": [250.0]}   # same E sigma
    other = {**study_cells, "sigma_um": [20.0]}                     # E sigma doubled
    cfg = validated({**BASE, "figures": {}, "sweeps": {"a": study_cells, "b": twin,
                                                       "c": other}})
    key = {name: contact_cells(Study.from_config(cfg), name)[0].contact_key for name in "abc"}
    assert key["a"] == key["b"] != key["c"]


def test_a_cap_without_a_hardness_and_a_hardness_figure_without_both_are_refused():
    with pytest.raises(ConfigProblems, match="body.hardness_MPa"):
        study_plan(Study.from_config(config(contact={"cap": True})))
    raw = copy.deepcopy(BASE)
    raw["figures"]["hardness"] = {**STUDY, "hardness_MPa": 100.0}
    with pytest.raises(ConfigProblems, match="cap: both"):
        study_plan(Study.from_config(validated(raw)))


def test_bad_hardness_values_are_named_by_the_schema():
    with pytest.raises(ValueError, match="hardness_MPa"):
        config(body={"hardness_MPa": -5.0})
    with pytest.raises(ValueError, match="cap"):
        config(contact={"cap": "yes"})


@pytest.mark.parametrize("cap", [False, True, "both"])
def test_a_hardness_below_the_pressures_is_refused_as_a_unit_slip(cap):
    """0 <= p <= H everywhere, so no nominal pressure exceeds H: a 0.05 MPa hardness under
    pressures up to 5 MPa is 0.05 GPa typed into hardness_MPa, whatever the cap mode."""
    raw = copy.deepcopy(BASE)
    raw["figures"] = {"fig07": {**STUDY, "pressure_MPa": [0.1, 5.0]},
                      "fig12": {"from": "fig07"}}
    raw["body"]["hardness_MPa"] = 0.05
    raw["contact"] = {"cap": cap}
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(validated(raw)))
    (problem,) = raised.value.problems  # once, though fig12 draws fig07's cells
    assert problem.startswith("figures.fig07: pressure_MPa up to 5 lies above "
                              "body.hardness_MPa = 0.05: no contact carries a nominal pressure "
                              "above the hardness")
    assert ("cannot reach P_max" in problem) == (cap is not False)
    assert ("checked against it" in problem) == (cap is not True)
    assert problem.endswith("Fix: typed in GPa? then write body.hardness_MPa: 50; or give a "
                            "hardness of at least 5 MPa")
    # the advice, followed, plans (P_max = H is allowed: the mean pressure at its bound)
    raw["body"]["hardness_MPa"] = 50.0
    assert study_plan(Study.from_config(validated(raw))).jobs
    raw["body"]["hardness_MPa"] = 5.0
    assert study_plan(Study.from_config(validated(raw))).jobs


def test_a_studys_own_hardness_list_is_named_and_only_its_slips_are_scaled():
    raw = copy.deepcopy(BASE)
    raw["sweeps"] = {"scan": {**STUDY, "pressure_MPa": [0.01, 5.0],
                              "hardness_MPa": [0.05, 100.0]}}
    raw["body"]["hardness_MPa"] = 500.0  # the study's own list is the one used
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(validated(raw)))
    (problem,) = raised.value.problems
    assert "above sweeps.scan.hardness_MPa = [0.05, 100]" in problem
    fixes = problem.split("Fix: ")[1].split("; or ")
    assert fixes == ["typed in GPa? then write sweeps.scan.hardness_MPa: [50, 100]",
                     "give a hardness of at least 5 MPa",
                     "nominal pressures up to it, sweeps.scan.pressure_MPa: [0.01, 0.05]"]
    for scan, pressures in (([50.0, 100.0], [0.01, 5.0]), ([0.05, 100.0], [0.01, 0.05])):
        raw["sweeps"]["scan"].update(hardness_MPa=scan, pressure_MPa=pressures)
        assert study_plan(Study.from_config(validated(raw))).jobs


def test_cap_meshes_caps_only_the_listed_meshes_and_refuses_one_not_solved():
    two_meshes = {**STUDY, "meshes": ["paper", "refined"]}
    cfg = config(body={"hardness_MPa": 100.0},
                 figures={"fig07": {**two_meshes, "cap": "both", "cap_meshes": ["refined"]}})
    cells = contact_cells(Study.from_config(cfg), "fig07")
    capped = [c for c in cells if c.hardness is not None]
    elastic = [c for c in cells if c.hardness is None]
    assert {c.geometry.mesh for c in capped} == {"refined"} and len(capped) == 2
    assert {c.geometry.mesh for c in elastic} == {"paper", "refined"} and len(elastic) == 4
    assert all(c.checked_hardness == (100e6,) for c in elastic)  # validity map on both
    # cap: true replaces the listed meshes' cells only; the others stay elastic
    replaced = contact_cells(Study.from_config(
            config(body={"hardness_MPa": 100.0}, figures={"fig07": {
        **two_meshes, "cap": True, "cap_meshes": ["refined"]}})), "fig07")
    assert sorted((c.geometry.mesh, c.hardness is not None) for c in replaced) == \
        [("paper", False)] * 2 + [("refined", True)] * 2
    # the default, null: every mesh capped
    every = contact_cells(Study.from_config(config(body={"hardness_MPa": 100.0},
                                 figures={"fig07": {**two_meshes, "cap": "both"}})), "fig07")
    assert {c.geometry.mesh for c in every if c.hardness is not None} == {"paper", "refined"}
    with pytest.raises(ConfigProblems, match=r"cap_meshes lists \['converged'\], which the "
                                             r"study does not solve"):
        study_plan(Study.from_config(config(body={"hardness_MPa": 100.0}, figures={"fig07": {
            **two_meshes, "cap": "both", "cap_meshes": ["converged"]}})))
