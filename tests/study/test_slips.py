"""Input slips a seal engineer makes, each refused before any job naming its key, and
each piece of advice followed here: the plan then passes in one round.

The slips: a seal length in metres typed into its mm key; a pressure drop in Pa; a
number in a form YAML 1.1 reads as text (``1e-3``); a kurtosis no generator reaches;
a counter map of another size; a memory refusal for a body already matrix-free; an
entry with two bad values; a block thickness in metres; a study smaller than four
elements.
"""

import copy
import re

import numpy as np
import pytest
from scipy import ndimage
from snakemake.common.configfile import _load_configfile
from test_counterface_checks import follow  # a config with an advice "key: value" set

from roughcontact.study.config import ConfigError, validated, yaml_number_forms
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.plan.machine import machine_problems
from roughcontact.study.settings import Study

SWEEP = {"sigma_um": 10.0, "b_mm": 0.5, "pressure_MPa": [0.1, 2.0], "count": 2}
# 8 x 8 elements over 1.2 mm: elements 0.15 mm wide
BASE = {"study_seed": 0, "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 2},
        "body": {"thickness_mm": 2.0, "E_MPa": 500.0}, "figures": {}, "reports": {},
        "sweeps": {"pad": SWEEP}}
FLOW = {"enabled": True}
STEEL = {"kind": "block", "E_MPa": 210000.0, "nu": 0.3}


def raw(flow=None, **sweep) -> dict:
    out = copy.deepcopy(BASE)
    out["sweeps"]["pad"] = {**SWEEP, **sweep}
    if flow is not None:
        out["flow"] = {**FLOW, **flow}
    return out


def plan(cfg: dict):
    return study_plan(Study.from_config(validated(cfg)))


def refusal(cfg: dict) -> list[str]:
    with pytest.raises(ConfigProblems) as raised:
        plan(cfg)
    assert "no job was started" in str(raised.value)
    return raised.value.problems


def guesses(problem: str) -> list[str]:
    """The ``then write key: value`` advices of a unit-slip message."""
    return re.findall(r"then write (\S+: [^;)]+)", problem)


# ---------------------------------------------------------------------------
# 1-2. The seal's values: a plausible lower bound, unit guesses only where plausible


@pytest.mark.parametrize(("value", "meant"), [(0.002, 2.0), (0.1, 100.0)])
def test_a_seal_length_in_metres_is_refused_below_one_element_and_its_advice_plans(
        value, meant):
    (problem,) = refusal(raw(flow={"seal_length_mm": value}))
    # one element along the flow: 1.2 mm / 8 = 0.15 mm
    assert problem.startswith(f"flow.seal_length_mm: {value:g} is shorter than one contact "
                              "element (0.15 mm along the flow")
    assert guesses(problem) == [f"flow.seal_length_mm: {meant:g}"]
    plan(follow(raw(flow={"seal_length_mm": value}), guesses(problem)[0]))
    # a narrow band of a few elements is a seal (a lip's): it plans
    plan(raw(flow={"seal_length_mm": 0.3}))
    plan({**raw(flow={"seal_length_mm": value}), "plausibility_check": False})


@pytest.mark.parametrize(("key", "value", "advised"), [
    ("pressure_drop_MPa", 1e6, ["flow.pressure_drop_MPa: 1"]),  # Pa meant; kPa: 1000 MPa
    ("pressure_drop_MPa", 2e5, ["flow.pressure_drop_MPa: 0.2"]),  # kPa: 200 MPa
    ("viscosity_Pa_s", 5e4, ["flow.viscosity_Pa_s: 50"]),  # mPa s meant
])
def test_a_unit_slip_of_the_seal_is_told_only_the_plausible_readings(key, value, advised):
    (problem,) = refusal(raw(flow={key: value}))
    assert problem.startswith(f"flow.{key}: {value:g} is outside the plausible")
    assert guesses(problem) == advised
    plan(follow(raw(flow={key: value}), advised[0]))


# ---------------------------------------------------------------------------
# 3. Numbers YAML 1.1 reads as text


def written_yaml(tmp_path, key: str, text: str) -> dict:
    """The configuration of :func:`raw` with ``key`` (``section.key``) written as ``text``
    in a YAML file, loaded as Snakemake loads a --configfile."""
    import yaml

    section, name = key.split(".")
    cfg = raw(flow={}) if section == "flow" else raw()
    cfg[section][name] = "@VALUE@"
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(cfg).replace("'@VALUE@'", text))
    return _load_configfile(str(path))


@pytest.mark.parametrize(("key", "text", "number"), [
    ("flow.viscosity_Pa_s", "1e-3", 1e-3),
    ("flow.seal_width_mm", "1.0e2", 100.0),
    ("body.E_MPa", "5.11E2", 511.0),
    ("body.thickness_mm", "-2e0", None),  # text, and negative: the schema's bound too
])
def test_a_number_yaml_reads_as_text_is_told_forms_it_reads_as_numbers(tmp_path, key, text,
                                                                      number):
    loaded = written_yaml(tmp_path, key, text)
    section, name = key.split(".")
    assert loaded[section][name] == text  # YAML 1.1: an exponent needs a point and a sign
    with pytest.raises(ConfigError) as raised:
        validated(loaded)
    (line,) = [t.strip() for t in str(raised.value).splitlines() if t.startswith(f"  {key}")]
    assert line.startswith(f'{key}: "{text}" is not a number (YAML reads {text} as text')
    if number is None:
        return
    forms = line.split("write ")[1].rstrip(")").split(" or ")
    assert forms and all(f != text for f in forms)
    for form in forms:  # each advised form, written into the file as Snakemake reads it
        fixed = written_yaml(tmp_path, key, form)
        assert fixed[section][name] == pytest.approx(number, rel=1e-15)
        plan(fixed)


def test_the_number_forms_are_read_back_as_the_number():
    assert yaml_number_forms(1e-3) == ["0.001", "1.0e-3"]
    assert yaml_number_forms(1e5) == ["100000.0", "1.0e+5"]
    assert yaml_number_forms(1e-7) == ["1.0e-7"]
    assert yaml_number_forms(1000.0, integer=True) == ["1000"]


# ---------------------------------------------------------------------------
# 4. A kurtosis below every distribution's: the bound of the generator used


@pytest.mark.parametrize(("where", "method"), [("sweep", "filter"), ("counter", "filter"),
                                               ("sweep", "paper"), ("sweep", "exact")])
def test_an_impossible_kurtosis_is_told_the_generators_bound_and_following_it_plans(
        where, method):
    def config(kurt, skew=2.0):
        cfg = raw()  # 16 x 16 over 2.4 mm: b = 0.2 L, a window the calibration solves
        cfg["surfaces"].update(method=method, grid=[16, 16], size_mm=[2.4, 2.4])
        if where == "sweep":
            cfg["sweeps"]["pad"]["moments"] = [[skew, kurt]]
        else:
            cfg["sweeps"]["pad"]["counterface"] = {
                "surface": {"sigma_um": 1.0, "skew": skew, "kurt": kurt}, "body": STEEL}
        return cfg

    (problem,) = refusal(config(3.0))
    advised = float(re.search(r"[Rr]aise kurt to at least ([\d.]+)", problem).group(1))
    assert "above 5" not in problem
    if method == "exact":  # limited only by Eq 14: Ku >= Sk^2 + 1 = 5
        assert advised == 5.0
        skew = re.search(r"reduce \|skew\| to at most (\d+(?:\.\d+)?)", problem).group(1)
        assert 1.414 <= float(skew) <= 2.0**0.5  # Ku 3 >= Sk^2 + 1
        plan(config(3.0, float(skew)))  # the other advice, followed
    else:
        assert advised > 2.0**2 + 1.0 + 0.5  # the filter's bound, far above Eq 14's 5
    plan(config(advised))  # followed: the plan passes


# ---------------------------------------------------------------------------
# 5. A counter map of another size: one round


def smooth_map(path, n, spacing):
    """A correlated n x n height map [um] (no noise: the plausibility check refuses noise)."""
    z = ndimage.gaussian_filter(np.random.default_rng(8).standard_normal((n, n)), 1.5,
                                mode="wrap") * 2.0
    np.save(path, z)
    return {"file": str(path), "format": "npy", "height_unit": "um", "spacing_mm": spacing}


@pytest.mark.parametrize(("points", "surfaces", "body", "changed", "grid"), [
    # the case: a 6.4 mm map under 9 mm surfaces on 10 mm refined blocks, whose
    # elements would be over 20 times longer than wide under 6.4 mm: thinner blocks too
    (64, {"grid": [60, 60], "size_mm": [9.0, 9.0]}, {"thickness_mm": 10.0, "mesh": "refined"},
     {"body.thickness_mm", "sweeps.pad.counterface.body.thickness_mm"}, (43, 43)),
    # a 0.8 mm map under 2.4 mm surfaces: a 10 mm paper block is 12.5 times as thick as
    # 0.8 mm, and b = 0.5 mm is longer than half of it; the counter block inherits the
    # first's thickness (one key)
    (8, {"grid": [16, 16], "size_mm": [2.4, 2.4]}, {"thickness_mm": 10.0},
     {"body.thickness_mm", "sweeps.pad.b_mm"}, (5, 5)),
])
def test_a_counter_map_smaller_than_the_surfaces_gets_advice_that_plans_in_one_round(
        tmp_path, points, surfaces, body, changed, grid):
    entry = smooth_map(tmp_path / "disc.npy", points, 0.1)
    counter = {**STEEL, "thickness_mm": 10.0} if points == 64 else STEEL
    cfg = raw(counterface={"surface": {"measured": entry}, "body": counter})
    cfg["surfaces"] = {**surfaces, "count": 2}
    cfg["body"] = body
    (problem,) = refusal(cfg)
    key = "sweeps.pad.counterface.surface.measured"
    head, options = problem.split(f"set in {key}: ")
    advice = re.findall(r"(\S+(?:size_mm|thickness_mm|b_mm): [\d.]+)",
                        head.split("make the study's area one it has")[1])
    assert advice[0] == f"sweeps.pad.size_mm: {points / 10:g}"
    assert {a.split(": ")[0] for a in advice[1:]} == changed
    for item in advice:
        cfg = follow(cfg, item)
    for option in options.split(" and "):
        cfg = follow(cfg, f"{key}.{option}")
    (cell,) = plan(cfg).cells["pad"]  # one round
    assert cell.surface.grid == cell.counterface.heights.cell.grid == grid


# ---------------------------------------------------------------------------
# 6. Never advise what is already set


@pytest.mark.parametrize("operator", ["dense", "auto"])
def test_a_memory_refusal_does_not_advise_operator_auto_to_a_body_that_has_it(operator):
    cfg = raw()
    cfg["body"]["operator"] = operator
    problems = machine_problems(plan(cfg), total_mb=1.0)  # every job over 1 MB
    contact = [p for p in problems if p.startswith("contact job")]
    assert len(contact) == 1
    assert ("body.operator: auto" in contact[0]) is (operator == "dense")


# ---------------------------------------------------------------------------
# 7. One round per mistake


@pytest.mark.parametrize("counterface", [
    {"body": {**STEEL, "nu": 0.5, "E_MPa": -10}},
    [{"body": "rigid"}, {"body": {**STEEL, "nu": 0.5, "E_MPa": -10}}],
])
def test_every_bad_value_of_a_counter_block_is_reported_in_one_round(counterface):
    with pytest.raises(ConfigError) as raised:
        plan(raw(counterface=counterface))
    key = ("sweeps.pad.counterface.body" if isinstance(counterface, dict)
           else "sweeps.pad.counterface[1].body")
    lines = [t.strip() for t in str(raised.value).splitlines() if t.startswith("  ")]
    assert lines == [f"{key}.E_MPa: -10 is out of range: it must be above 0",
                     f"{key}.nu: 0.5 is out of range: it must be below 0.5"]
    fixed = copy.deepcopy(counterface)
    body = (fixed if isinstance(fixed, dict) else fixed[1])["body"]
    body.update(nu=0.3, E_MPa=210000.0)  # both fixed at once: the plan passes
    plan(raw(counterface=fixed))


# ---------------------------------------------------------------------------
# 8. Messages that read as sentences, and a study smaller than four elements


@pytest.mark.parametrize("counter", [False, True])
def test_a_thickness_in_metres_too_thick_for_the_patch_is_told_the_thickest_it_carries(
        counter):
    cfg = raw()
    if counter:
        cfg["sweeps"]["pad"]["counterface"] = {"body": {**STEEL, "thickness_mm": 0.05,
                                                        "mesh": "refined"}}
        key = "sweeps.pad.counterface.body.thickness_mm"
    else:
        cfg["body"] = {"thickness_mm": 0.05, "mesh": "refined", "E_MPa": 500.0}
        key = "body.thickness_mm"
    (problem,) = refusal(cfg)
    assert "else" not in problem
    assert problem.startswith(f"{key} = 0.05 is thinner than one contact element (0.15 mm); "
                              "typed in m, it would be 50 mm, too thick for the 1.2 x 1.2 mm "
                              "patch")
    (advice,) = re.findall(r"write (\S+: [\d.]+)$", problem)
    assert advice.startswith(f"{key}: ")
    thickest = float(advice.split(": ")[1])
    assert 0.15 <= thickest <= 10 * 1.2  # at most 10 times the patch's side
    plan(follow(cfg, advice))


def test_a_thickness_in_metres_that_fits_keeps_its_guess_as_a_sentence():
    cfg = raw(counterface={"body": {**STEEL, "thickness_mm": 0.002, "mesh": "refined"}})
    (problem,) = refusal(cfg)
    assert problem == ("sweeps.pad.counterface.body.thickness_mm = 0.002 is thinner than one "
                       "contact element (0.15 mm); typed in m? then write "
                       "sweeps.pad.counterface.body.thickness_mm: 2; otherwise give a block "
                       "at least 0.15 mm thick")
    plan(follow(cfg, guesses(problem)[0]))


@pytest.mark.parametrize(("size", "key"), [(0.3, "sweeps.pad.size_mm"),
                                           ([1.2, 0.15], "sweeps.pad.size_mm[1]")])
def test_a_study_smaller_than_four_elements_is_refused_and_its_advice_plans(size, key):
    """Below four elements the study would be solved on elements finer than the
    surfaces' spacing (0.15 mm) the schema promises; the flow's grid check could never
    see its grid."""
    cfg = raw(size_mm=size, b_mm=0.2)
    (problem,) = refusal(cfg)
    assert problem.startswith(f"{key} = {size if isinstance(size, float) else size[1]:g} "
                              "holds ")
    assert "fewer than 4" in problem
    (advice,) = re.findall(rf"write ({re.escape(key)}: [\d.]+)", problem)
    side = float(advice.split(": ")[1])
    assert side >= 4 * 0.15 - 1e-12 and side / 0.15 == pytest.approx(round(side / 0.15))
    planned = plan(follow(cfg, advice))
    assert all(min(c.surface.grid) >= 4 for c in planned.cells["pad"])


def test_a_kurtosis_the_calibration_cannot_draw_on_a_small_window_is_refused_in_words():
    """On 8 x 8 over 1.2 mm with b = 0.5 mm (0.42 L) the process near the filter's bound
    at Sk 2 gives no finite sample moments on the way (where the calibration's steps go
    depends on the CPU's rounding): refused in words, either as not calibrated or with
    the bound it found (never a nan skewness), and the generator it names plans."""
    cfg = raw(moments=[[2.0, 6.0]])
    (problem,) = refusal(cfg)
    assert not re.search(r"\bnan\b", problem, flags=re.IGNORECASE)
    assert ("could not be calibrated for the filter" in problem
            or "Raise kurt to at least" in problem)
    assert "method='exact'" in problem
    cfg["surfaces"]["method"] = "exact"
    plan(cfg)
