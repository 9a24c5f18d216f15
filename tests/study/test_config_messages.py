"""Schema refusals in plain words: the key's place in the configuration, the value found
and what is expected (not the schema's own text), and no refusal of a valid config."""

from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from roughcontact.study.config import ConfigError, schema_errors, validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.records import MeasuredCell
from roughcontact.study.settings import Study
from roughcontact.units import MM

REPO = Path(__file__).resolve().parents[2]

SCHEMA_WORDS = ("is a required property", "should not be valid under", "is not valid under",
                "{'required'", "'from' is a required")


def errors(config):
    lines = schema_errors(config)
    assert not any(words in line for line in lines for words in SCHEMA_WORDS), lines
    return lines


def measured_sweep(surface):
    return {"sweeps": {"rough": {"surface": surface, "pressure_MPa": [0.1, 1.0]}},
            "figures": {}}


def test_an_npy_map_with_its_spacing_and_no_format_is_accepted(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    # a correlated map (white noise is refused as no height map at all)
    noise = np.random.default_rng(4).standard_normal((12, 16))
    heights = ndimage.gaussian_filter(noise, 3.0, mode="wrap") * 1e-6
    np.save(tmp_path / "map.npy", heights)
    surface = {"file": "map.npy", "spacing_mm": [0.01, 0.02], "height_unit": "m"}
    config = measured_sweep(surface)
    config["sweeps"]["rough"]["thickness_mm"] = "patch"  # a block that fits the 0.16 mm patch
    config = validated(config)  # format defaults to auto: not xyz
    assert config["sweeps"]["rough"]["surface"]["format"] == "auto"
    plan = study_plan(Study.from_config(config))
    (cell,) = (c for c in plan.surfaces.values() if isinstance(c, MeasuredCell))
    assert cell.grid == (16, 12)
    assert cell.size == pytest.approx((16 * 0.01 * MM, 12 * 0.02 * MM))


def test_an_xyz_list_with_a_spacing_is_refused_in_plain_words():
    surface = {"file": "map.xyz", "format": "xyz", "spacing_mm": 0.01}
    assert errors(measured_sweep(surface)) == [
        "sweeps.rough.surface: 'spacing_mm' applies to npy and text grids; an xyz file's "
        "spacing comes from its points: remove spacing_mm (or give the file's format: npy "
        "or text)"]
    # the advice, followed: without the spacing the xyz entry passes
    assert errors(measured_sweep({"file": "map.xyz", "format": "xyz"})) == []


def test_a_sweep_without_its_pressure_range_names_pressure_MPa():
    lines = errors({"sweeps": {"small": {"sigma_um": 24.5}}})
    assert lines == ["sweeps.small: 'pressure_MPa' is missing ([P_min, P_max] of the "
                     "nominal pressure axis)"]
    assert errors({"figures": {"fig07": {"surface": {"file": "a.npy"}}}}) == [
        "figures.fig07: 'pressure_MPa' is missing ([P_min, P_max] of the nominal pressure "
        "axis)"]
    # nothing begun: every way to write a study is named
    assert errors({"sweeps": {"small": {"count": 4}}}) == [
        "sweeps.small: needs one of: 'from'; 'sigma_um' with 'pressure_MPa'; 'surface' with "
        "'pressure_MPa'"]
    # the advice, followed
    assert errors({"sweeps": {"small": {"sigma_um": 24.5, "pressure_MPa": [0.5, 2.0]}}}) == []


@pytest.mark.parametrize(("config", "line"), [
    ({"body": {"thickness_mm": -1}}, "body.thickness_mm: -1 is out of range: it must be above 0"),
    ({"surfaces": {"grid": [3, 40]}},
     "surfaces.grid[0]: 3 is out of range: it must be at least 4"),
    ({"body": {"mesh": "fine"}},
     "body.mesh: \"fine\" is not one of 'paper', 'graded', 'refined' or 'converged'"),
    ({"sweeps": {"s": {"sigma_um": 1.0, "pressure_MPa": [1.0]}}},
     "sweeps.s.pressure_MPa: [1.0] has 1 item, at least 2 expected"),
    ({"sweeps": {"s": {"sigma_um": 1.0, "pressure_MPa": [0.1, 1], "moments": [[0, 3, 1]]}}},
     "sweeps.s.moments[0]: [0, 3, 1] has 3 items, at most 2 expected"),
    ({"sweeps": {"s": {"sigma_um": "a", "pressure_MPa": [0.1, 1.0]}}},
     "sweeps.s.sigma_um: \"a\" is not a number or a list"),
    ({"surfaces": {"spectrum": {"kind": "table"}}},
     "surfaces.spectrum: 'file' is missing (CSV file with the columns q_per_mm,C, relative "
     "to the working directory)"),
    (measured_sweep({"file": "a.npy", "decimate": 2, "resample_grid": 32}),
     "sweeps.rough.surface: 'decimate' and 'resample_grid' both set the contact grid: keep "
     "one of them"),
    ({"figures": {"fig05": {"bins": 20}}},
     "figures: 'fig05' draws the height distributions of fig04's surfaces: add fig04 "
     "(sigma_um, b_mm, moments) or remove fig05"),
])
def test_each_kind_of_refusal_names_the_key_in_plain_words(config, line):
    assert errors(config) == [line]


def test_an_unknown_key_is_named_with_the_key_it_was_likely_meant_for():
    (line,) = errors({"sweeps": {"s": {"sigma_um": 1.0, "pressure_MPa": [0.1, 1], "bmm": 1}}})
    assert line.startswith("sweeps.s: unknown key 'bmm' (did you mean 'b_mm'?); the keys "
                           "here are 'from', ")
    (line,) = errors({"surfacs": {}})
    assert line.startswith("the configuration: unknown key 'surfacs' (did you mean "
                           "'surfaces'?)")
    with pytest.raises(ConfigError, match=r"unknown key 'surfacs'.*\nKeys, units and "
                                          r"defaults: config/schema.yaml"):
        validated({"surfacs": {}})


@pytest.mark.parametrize("name", ["config", "quick", "large", "measured", "gridconv", "two_bodies",
                                  "seal", "fig11_resolved", "accuracy"])
def test_the_defaults_filled_are_snakemakes(name):
    """apply_schema fills the schema's defaults itself, on the schema parsed once: the
    result equals snakemake.utils.validate's on the same config (each config of
    config/, and a partial one)."""
    import copy as copy_module

    import yaml
    from snakemake.utils import validate

    from roughcontact.study.config import SCHEMA, apply_schema

    path = REPO / "config" / f"{name}.yaml"
    raw = ({"figures": {"fig07": {"sigma_um": 20.0, "b_mm": 1.0,
                                  "pressure_MPa": [0.1, 2.0]}}, "accuracy": "fast"}
           if name == "accuracy" else yaml.safe_load(path.read_text()))
    ours = apply_schema(copy_module.deepcopy(raw))
    theirs = copy_module.deepcopy(raw)
    validate(theirs, str(SCHEMA))
    assert ours == theirs
