"""Every input error of a counter body is refused before any job, naming its key.

The counter body (Eq 17-18) gets the checks of the first body, by the same code: the
schema's defaults, the plausibility (unit slips) of E, sigma and thickness, the
block's geometry limits, the surface's window, the measured import; a list axis
refuses duplicates. Each refusal names the configuration key (the section's
``counterface.body.E_MPa`` or a study's ``sweeps.pad.counterface[1].surface.sigma_um``)
and, where it gives advice, the advice is followed here and the plan then passes.
"""

import copy
import logging
import re

import numpy as np
import pytest
import yaml
from scipy import ndimage

from roughcontact.study.config import ConfigError, validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.plan.counter_entries import BlockEntry, GeneratedEntry, counterface_entries
from roughcontact.study.records import InfluenceModel
from roughcontact.study.settings import Study

SWEEP = {"sigma_um": 24.5, "b_mm": 0.5, "pressure_MPa": [0.1, 3.0], "count": 3}
BASE = {"study_seed": 3, "surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4]},
        "figures": {}, "reports": {}}


def raw(**sweep) -> dict:
    return {**copy.deepcopy(BASE), "sweeps": {"pad": {**SWEEP, **sweep}}}


def config(**sweep) -> dict:
    return validated(raw(**sweep))


def test_the_schema_fills_the_static_defaults_and_one_function_the_body_sections():
    entry = config(counterface={"surface": {"sigma_um": 1.0},
                                "body": {"kind": "block", "E_MPa": 511.0}})
    written = entry["sweeps"]["pad"]["counterface"]
    assert written["surface"] == {"sigma_um": 1.0, "skew": 0.0, "kurt": 3.0}
    assert written["body"] == {"kind": "block", "E_MPa": 511.0, "operator": "dense"}
    (resolved,) = counterface_entries(Study.from_config(entry), "pad")
    body = entry["body"]
    assert resolved.body == BlockEntry(E_MPa=511.0, nu=body["nu"], base=body["base"],
                                       thickness_mm=body["thickness_mm"], mesh=body["mesh"],
                                       operator=InfluenceModel.DENSE)
    assert resolved.body.inherited == ("nu", "thickness_mm", "base", "mesh")
    assert resolved.surface == GeneratedEntry(sigma_um=1.0, skew=0.0, kurt=3.0)
    assert resolved.surface.b_mm is None  # the first surface's
    assert (resolved.surface_key, resolved.body_key) == ("sweeps.pad.counterface.surface",
                                                        "sweeps.pad.counterface.body")
    # a half-space takes no block default; a smooth rigid section none at all
    half = config(counterface={"body": {"kind": "halfspace", "E_MPa": 2e5, "nu": 0.3}})
    assert half["sweeps"]["pad"]["counterface"]["body"] == {"kind": "halfspace",
                                                             "E_MPa": 2e5, "nu": 0.3}
    assert half["counterface"]["surface"] == "smooth" and half["counterface"]["body"] == "rigid"
    (entry,) = counterface_entries(Study.from_config(half), "pad")
    assert (entry.surface_key, entry.body_key) == ("counterface.surface",
                                                   "sweeps.pad.counterface.body")
    # the plan is the one of the values written out
    explicit = config(counterface={"surface": {"sigma_um": 1.0, "skew": 0.0, "kurt": 3.0},
                                   "body": {"kind": "block", "E_MPa": 511.0, "nu": 0.0,
                                            "thickness_mm": 10.0, "base": "clamped",
                                            "mesh": "paper", "operator": "dense"}})
    defaults = config(counterface={"surface": {"sigma_um": 1.0},
                                   "body": {"kind": "block", "E_MPa": 511.0}})
    assert list(study_plan(Study.from_config(
            explicit)).jobs) == list(study_plan(Study.from_config(defaults)).jobs)


@pytest.mark.parametrize(("counterface", "key"), [
    ({"surface": {"sigma_um": "1.5"}}, "sweeps.pad.counterface.surface.sigma_um"),
    ([{"body": "rigid"}, {"surface": {"sigma_um": "1.5"}}],
     "sweeps.pad.counterface[1].surface.sigma_um"),
])
def test_a_counter_value_of_the_wrong_type_names_its_key_and_that_a_number_is_expected(
        counterface, key):
    with pytest.raises(ConfigError) as raised:
        config(counterface=counterface)
    (line,) = [t.strip() for t in str(raised.value).splitlines() if t.startswith("  ")]
    assert line == f'{key}: "1.5" is not a number (text: write 1.5 without quotes)'
    # the section's own, and the advice followed
    with pytest.raises(ConfigError, match=r'\n  counterface.surface.sigma_um: "1.5" is not a '
                                          r"number \(text: write 1.5 without quotes\)\n"):
        validated({**raw(), "counterface": {"surface": {"sigma_um": "1.5"}}})
    fixed = copy.deepcopy(counterface)
    (fixed if isinstance(fixed, dict) else fixed[1])["surface"]["sigma_um"] = 1.5
    study_plan(Study.from_config(config(counterface=fixed)))


def smooth_map(path, n=16, spacing=0.15):
    """A correlated n x n height map [um] (no noise: the plausibility check refuses noise)."""
    z = ndimage.gaussian_filter(np.random.default_rng(8).standard_normal((n, n)), 1.5,
                                mode="wrap") * 2.0
    np.save(path, z)
    return {"file": str(path), "format": "npy", "height_unit": "um", "spacing_mm": spacing}


def refusal(cfg) -> list[str]:
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(cfg))
    return raised.value.problems


def test_a_counter_map_that_cannot_be_imported_is_refused_naming_its_file_key(tmp_path):
    missing = {"file": str(tmp_path / "nope.npy")}
    assert refusal(config(counterface=[{"body": "rigid"},
                                       {"surface": {"measured": missing}}])) == [
        f"sweeps.pad.counterface[1].surface.measured.file: {missing['file']}: no such file"]
    headed = tmp_path / "disc.csv"
    heights = np.load(smooth_map(tmp_path / "disc.npy")["file"])
    rows = "\n".join(",".join(f"{v:.6f}" for v in row) for row in heights)
    headed.write_text("h1,h2\n" + rows + "\n")
    entry = {"file": str(headed), "height_unit": "um", "spacing_mm": 0.15}
    section = {**raw(), "counterface": {"surface": {"measured": entry}}}
    (problem,) = refusal(validated(section))
    assert problem.startswith(f"counterface.surface.measured.file: {headed}, line 1: the first "
                              "data line is not numbers ('h1,h2'): a header? Start header "
                              "lines with #")
    headed.write_text("# h1,h2\n" + rows + "\n")  # the advice, followed
    (cell,) = study_plan(Study.from_config(validated(section))).cells["pad"]
    assert cell.counterface.heights.cell.grid == (16, 16)


def test_an_axis_that_names_a_value_twice_is_refused_naming_the_repeat():
    twice = [{"body": {"kind": "block", "E_MPa": 511.0}}, {"body": "rigid"},
             {"surface": "smooth", "body": "rigid"}]
    assert refusal(config(counterface=twice)) == [
        'sweeps.pad.counterface[2]: {"surface": "smooth", "body": "rigid"} repeats '
        "sweeps.pad.counterface[1]: the same cells twice (a list axis names each value "
        "once); remove sweeps.pad.counterface[2]"]
    assert len(study_plan(Study.from_config(
            config(counterface=twice[:2]))).cells["pad"]) == 2  # followed
    for key, values, repeat in (("b_mm", [0.5, 0.4, 0.5], 2), ("sigma_um", [24.5, 24.50], 1),
                                ("moments", [[0.0, 3.0], [0, 3]], 1),
                                ("meshes", ["paper", "paper"], 1)):
        (problem,) = refusal(config(**{key: values}))
        assert problem.startswith(f"sweeps.pad.{key}[{repeat}]: ")
        assert problem.endswith(f"remove sweeps.pad.{key}[{repeat}]")
        study_plan(Study.from_config(config(**{key: values[:repeat] + values[repeat + 1:]})))
    figure = {"sigma_um": 24.5, "b_mm": [0.5, 0.5]}
    (problem,) = refusal(validated({**raw(), "figures": {"fig03": figure}}))
    assert problem.startswith("figures.fig03.b_mm[1]: 0.5 repeats figures.fig03.b_mm[0]")
    study_plan(Study.from_config(
            validated({**raw(), "figures": {"fig03": {**figure, "b_mm": [0.5]}}})))


def test_a_single_surface_study_is_warned_once_at_plan_time(caplog):
    single = raw()
    del single["sweeps"]["pad"]["count"]
    single["surfaces"]["count"] = 1
    single["sweeps"]["again"] = {"from": "pad"}
    with caplog.at_level(logging.WARNING, logger="roughcontact"):
        study_plan(Study.from_config(validated(single)))
    (record,) = [r for r in caplog.records if "one surface per cell" in r.getMessage()]
    assert record.getMessage().startswith("sweeps.pad: one surface per cell "
                                          "(surfaces.count = 1): a single-surface cell has "
                                          "no confidence band")
    caplog.clear()
    single["surfaces"]["count"] = 2  # the advice, followed
    with caplog.at_level(logging.WARNING, logger="roughcontact"):
        study_plan(Study.from_config(validated(single)))
    assert not [r for r in caplog.records if "one surface per cell" in r.getMessage()]


def follow(cfg: dict, advice: str) -> dict:
    """``cfg`` (as written) with ``key: value`` of an advice set (``a.b[1].c: 2``)."""
    key, value = advice.split(": ", 1)
    parts = [int(p) if p.isdigit() else p for p in re.split(r"\.|\[|\]\.?", key) if p != ""]
    out = copy.deepcopy(cfg)
    node = out
    for part in parts[:-1]:
        node = node.setdefault(part, {}) if isinstance(part, str) else node[part]
    node[parts[-1]] = yaml.safe_load(value)
    return out


def advices(problem: str) -> list[str]:
    """The ``then write key: value`` advices of a plausibility message."""
    return re.findall(r"then write (\S+: [^;]+)", problem)


STEEL = {"kind": "block", "E_MPa": 210000.0, "nu": 0.3}


@pytest.mark.parametrize(("written", "key", "message", "advice"), [
    # GPa typed into the counter plate's MPa key: the first body's P / E check
    ({"pressure_MPa": [1.0, 30.0], "counterface": {"body": {**STEEL, "E_MPa": 210}}},
     "sweeps.pad.counterface.body.E_MPa",
     "sweeps.pad.pressure_MPa up to 30 on sweeps.pad.counterface.body.E_MPa = 210 is P / E "
     "= 0.143, beyond 0.1, where the linear elastic model has no meaning",
     "sweeps.pad.counterface.body.E_MPa: 210000"),
    ({"counterface": [{"body": "rigid"}, {"body": {**STEEL, "E_MPa": 2.1e11}}]},
     "sweeps.pad.counterface[1].body.E_MPa",
     "sweeps.pad.counterface[1].body.E_MPa = 2.1e+11 lies outside 0.001-1e+07 MPa",
     "sweeps.pad.counterface[1].body.E_MPa: 210000"),
    ({"counterface": {"surface": {"sigma_um": 0.0008}, "body": STEEL}},
     "sweeps.pad.counterface.surface.sigma_um",
     "sweeps.pad.counterface.surface.sigma_um = 0.0008 lies outside 0.001-1000 um",
     "sweeps.pad.counterface.surface.sigma_um: 0.8"),
    # metres typed into the counter block's mm key: thinner than one element
    ({"counterface": {"body": {**STEEL, "thickness_mm": 0.01, "mesh": "refined"}}},
     "sweeps.pad.counterface.body.thickness_mm",
     "sweeps.pad.counterface.body.thickness_mm = 0.01 is thinner than one contact element "
     "(0.15 mm)", "sweeps.pad.counterface.body.thickness_mm: 10"),
    # the same slips on the first body: the same code, the first body's keys
    ({"E_MPa": 2.1e11}, "sweeps.pad.E_MPa",
     "sweeps.pad.E_MPa = 2.1e+11 lies outside 0.001-1e+07 MPa", "sweeps.pad.E_MPa: 210000"),
    ({"E_MPa": [511.0, 0.5], "pressure_MPa": [0.1, 3.0]}, "sweeps.pad.E_MPa[1]",
     "sweeps.pad.pressure_MPa up to 3 on sweeps.pad.E_MPa[1] = 0.5 is P / E = 6",
     "sweeps.pad.E_MPa[1]: 500"),
])
def test_a_unit_slip_on_either_body_is_refused_by_the_same_check_and_its_advice_plans(
        written, key, message, advice):
    cfg = raw(**written)
    (problem,) = refusal(validated(cfg))
    assert problem.startswith(message)
    assert advice in advices(problem)
    study_plan(Study.from_config(validated(follow(cfg, advice))))  # the advice, followed
    # and the escape for the rare real case
    study_plan(Study.from_config(validated({**cfg, "plausibility_check": False})))


def test_a_thin_inherited_counter_block_names_the_body_key_once():
    cfg = raw(counterface={"body": {**STEEL, "mesh": "refined"}})
    cfg["body"] = {"thickness_mm": 0.01, "mesh": "refined"}
    (problem,) = refusal(validated(cfg))  # the first and the counter block: one message
    assert problem.startswith("body.thickness_mm = 0.01 is thinner than one contact element")
    study_plan(Study.from_config(validated(follow(cfg, advices(problem)[0]))))


def test_a_generated_counter_surface_longer_in_b_than_half_the_surface_is_refused():
    cfg = raw(counterface={"surface": {"sigma_um": 1.0, "b_mm": 2.0}, "body": STEEL})
    (problem,) = refusal(validated(cfg))
    assert problem.startswith("sweeps.pad.counterface.surface: b_mm = 2 is longer than half "
                              "the surface, surfaces.size_mm = 2.4 (L / 2 = 1.2 mm)")
    advice = problem.split("Fix: ")[1].split(" or shorter")[0]
    assert advice == "sweeps.pad.counterface.surface.b_mm: 1.2"
    study_plan(Study.from_config(validated(follow(cfg, advice))))
    # b by default the first surface's: judged with it, once, under the study's key
    cfg = raw(b_mm=2.0, counterface={"surface": {"sigma_um": 1.0}, "body": STEEL})
    (problem,) = refusal(validated(cfg))
    assert problem.startswith("sweeps.pad: b_mm = 2 is longer than half the surface")


def test_a_counter_map_smaller_than_the_surface_is_told_an_area_both_have(tmp_path):
    """The issue's 6.4 mm map under 9 mm surfaces, small: a 1.6 mm map (16 points at
    0.1 mm) under 2.4 mm surfaces (16 x 16, 0.15 mm): no window of the map has 2.4 mm,
    so cropping it cannot help; a study area of 1.6 mm on the surfaces' spacing can."""
    entry = smooth_map(tmp_path / "disc.npy", n=16, spacing=0.1)
    cfg = raw(counterface={"surface": {"measured": entry}, "body": STEEL})
    (problem,) = refusal(validated(cfg))
    key = "sweeps.pad.counterface.surface.measured"
    assert problem.startswith(f"{key}: {entry['file']}: 16 x 16 points over 1.6 mm x 1.6 mm, "
                              "but the surface it meets")
    assert "crop_mm" not in problem
    size = re.search(r"(sweeps\.pad\.size_mm: [\d.]+) ", problem).group(1)
    options = problem.split(f"set in {key}: ")[1].split(" and ")
    assert (size, options) == ("sweeps.pad.size_mm: 1.6", ["resample_grid: [11, 11]"])
    followed = follow(follow(cfg, size), f"{key}.{options[0]}")
    (cell,) = study_plan(Study.from_config(validated(followed))).cells["pad"]
    assert cell.surface.grid == cell.counterface.heights.cell.grid == (11, 11)


def test_a_counter_map_whose_spacing_does_not_divide_the_surface_gets_a_window_it_has(
        tmp_path):
    """A 3.9 mm map (30 points at 0.13 mm) under 2.4 mm surfaces: a crop to 2.4 mm would
    take 18 points, 2.34 mm, and fail again; the advice is a 2.34 mm area and window."""
    entry = smooth_map(tmp_path / "disc.npy", n=30, spacing=0.13)
    cfg = raw(counterface={"surface": {"measured": entry}, "body": STEEL})
    (problem,) = refusal(validated(cfg))
    key = "sweeps.pad.counterface.surface.measured"
    size = re.search(r"(sweeps\.pad\.size_mm: [\d.]+) ", problem).group(1)
    options = problem.split(f"set in {key}: ")[1].split(" and ")
    assert size == "sweeps.pad.size_mm: 2.34"
    assert options == ["crop_mm: [0, 0, 2.34, 2.34]", "resample_grid: [16, 16]"]
    followed = follow(cfg, size)
    for option in options:
        followed = follow(followed, f"{key}.{option}")
    (cell,) = study_plan(Study.from_config(validated(followed))).cells["pad"]
    assert cell.counterface.heights.cell.grid == cell.surface.grid == (16, 16)
