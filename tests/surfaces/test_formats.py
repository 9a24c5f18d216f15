"""Instrument files are read in the format they claim, and noise is not a height map.

Random bytes named like an instrument's file, with every key the messages
ask for, are refused naming the file and the format; a real file under a
wrong suffix is refused too, and the advice (``format: instrument``) reads
it. A map of uncorrelated values is refused by the plausibility check
without advice towards a height unit; a smooth map read in the wrong unit
gets the unit that brings it into range, which then plans. A constant map
(or one that is its form) is refused as flat, in one message and before any
statistic of its rounding noise is taken.
"""

import logging
import shutil

import numpy as np
import pytest
from scipy import ndimage
from topographies import DATA, needs_data

from roughcontact.errors import MeasurementError
from roughcontact.study.config import validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.settings import Study
from roughcontact.surfaces.measured import ImportOptions, load_measurement


def random_file(path, size, seed=0):
    path.write_bytes(np.random.default_rng(seed).bytes(size))
    return path


def sweep_config(surface: dict) -> dict:
    return validated({
        "study_seed": 0, "figures": {},
        "surfaces": {"grid": 8, "size_mm": 1.0, "count": 1},
        "body": {"thickness_mm": 0.5},
        "sweeps": {"s": {"surface": surface, "pressure_MPa": [1.0, 5.0]}},
    })


@pytest.mark.parametrize(("suffix", "format_name"), [("x3p", "X3P"), ("sur", "Digital Surf")])
# 2 x 100^2 bytes: the size a reader without a signature (hgt) takes as a 100 x 100 map
@pytest.mark.parametrize("size", [2 * 100**2, 12_345])
def test_random_bytes_named_as_an_instrument_file_are_refused(tmp_path, suffix, format_name,
                                                              size):
    path = random_file(tmp_path / f"noise.{suffix}", size)
    # with the keys a file without units would need: still refused, by its format
    for keys in ({}, {"height_unit": "nm", "spacing": (1e-6, 1e-6)}):
        with pytest.raises(MeasurementError) as raised:
            load_measurement(path, ImportOptions(**keys))
        message = str(raised.value)
        assert str(path) in message and format_name in message and f".{suffix}" in message
        assert raised.value.path == str(path)
    # by content (format: instrument), no format claims it either
    with pytest.raises(MeasurementError, match="not a format SurfaceTopography recognises"):
        load_measurement(path, ImportOptions("instrument", height_unit="nm", spacing=(1e-6, 1e-6)))


def test_random_bytes_are_refused_when_the_plan_is_made(tmp_path):
    path = random_file(tmp_path / "noise.x3p", 2 * 100**2)
    config = sweep_config({"file": str(path), "format": "auto", "height_unit": "nm",
                           "spacing_mm": [1e-3, 1e-3]})
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(config))
    assert "s.surface" in str(raised.value) and str(path) in str(raised.value)
    assert "X3P" in str(raised.value)


def test_a_file_with_an_unclaimed_suffix_is_read_by_its_content_only(tmp_path):
    # the size of a 100 x 100 map of 16-bit heights: read as one only if named .hgt
    path = random_file(tmp_path / "noise.bin", 2 * 100**2)
    with pytest.raises(MeasurementError, match="hgt"):
        load_measurement(path, ImportOptions(height_unit="nm", spacing=(1e-6, 1e-6)))


@needs_data
def test_a_real_file_under_another_suffix_is_refused_and_format_instrument_reads_it(tmp_path):
    path = tmp_path / "renamed.sur"
    shutil.copy(DATA / "x3p-2.x3p", path)
    with pytest.raises(MeasurementError, match=r"Digital Surf SUR \(sur\)") as raised:
        load_measurement(path)
    assert "format: instrument" in str(raised.value)
    # the advice, followed: read by its content, as the X3P file it is
    m = load_measurement(path, ImportOptions("instrument"))
    assert m.preparation["reader"] == "X3PReader"
    assert m.grid == load_measurement(DATA / "x3p-2.x3p").grid


def test_noise_is_refused_without_advice_towards_a_height_unit(tmp_path):
    path = tmp_path / "noise.npy"
    rng = np.random.default_rng(1)
    np.save(path, rng.integers(-32768, 32767, (100, 100)).astype(float))
    for unit in ("um", "nm"):  # sigma 19 mm, or 19 um: in range, still noise
        config = sweep_config({"file": str(path), "format": "npy", "height_unit": unit,
                               "spacing_mm": [0.01, 0.01]})
        with pytest.raises(ConfigProblems) as raised:
            study_plan(Study.from_config(config))
        message = str(raised.value)
        assert "uncorrelated" in message and str(path) in message
        assert "height_unit:" not in message and "typed in" not in message
    # the escape for a real surface sampled that coarsely
    config["plausibility_check"] = False
    assert study_plan(Study.from_config(config)).jobs


def test_a_smooth_map_in_the_wrong_unit_gets_the_unit_that_fits(tmp_path):
    path = tmp_path / "smooth.npy"
    rng = np.random.default_rng(2)
    z = ndimage.gaussian_filter(rng.standard_normal((64, 64)), 3, mode="wrap")
    np.save(path, z * 5000 / z.std())  # sigma 5000 nm, declared in um: 5 mm
    surface = {"file": str(path), "format": "npy", "height_unit": "um",
               "spacing_mm": [0.01, 0.01]}
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(sweep_config(surface)))
    message = str(raised.value)
    assert "measured sigma" in message and "height_unit: nm" in message
    assert "typed in" not in message
    # the advice, followed: a few um (5 um less the plane the import removes)
    plan = study_plan(Study.from_config(sweep_config({**surface, "height_unit": "nm"})))
    (cell,) = plan.cells["s"]
    assert 3e-6 < cell.sigma < 5e-6


@pytest.mark.parametrize("compare_synthetic", [False, True])
@pytest.mark.parametrize(("name", "write"), [
    ("flat.npy", lambda path, z: np.save(path, z)),
    ("flat.csv", lambda path, z: np.savetxt(path, z, delimiter=";")),
])
def test_a_constant_map_is_refused_alone_as_flat(tmp_path, caplog, compare_synthetic, name,
                                                 write):
    path = tmp_path / name
    write(path, np.full((32, 32), 3.0))  # 3 um everywhere
    surface = {"file": str(path), "height_unit": "um", "spacing_mm": [0.01, 0.01]}
    config = sweep_config(surface)
    config["sweeps"]["s"]["compare_synthetic"] = compare_synthetic
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(config))
    (problem,) = raised.value.problems  # alone: no NaN correlation length, no form_degree
    assert problem.startswith(f"s.surface: {path}: the heights are flat (a constant or a "
                              "plane): with the least-squares plane removed their standard "
                              "deviation is ")
    sigma_um = float(problem.split("standard deviation is ")[1].split(" um")[0])
    assert 0.0 <= sigma_um < 1e-12 * 3.0
    assert "heights of up to 3 um" in problem and "surface.channel" in problem
    assert not any(word in problem for word in ("NaN", "nan", "form_degree", "autocorrelation"))
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING]  # nothing before it
    # the advice, followed: the file holds a height map, which plans
    rough = ndimage.gaussian_filter(np.random.default_rng(5).standard_normal((32, 32)), 2.0,
                                    mode="wrap")
    write(path, 3.0 + rough / rough.std())
    assert study_plan(Study.from_config(config)).jobs


def test_a_map_that_is_its_form_or_zero_is_flat(tmp_path):
    y, x = np.mgrid[0:24, 0:24] * 0.01
    maps = {"bowl": (5.0 + 2.0 * x - y + 30.0 * (x - 0.1) ** 2, 2),  # a cylinder's form
            "zero": (np.zeros((24, 24)), 1)}
    for name, (heights, degree) in maps.items():
        np.save(tmp_path / f"{name}.npy", heights)
        form = "a plane" if degree == 1 else f"a polynomial of degree {degree}"
        with pytest.raises(MeasurementError, match=f"{name}.npy: the heights are flat "
                                                   rf"\(a constant or {form}\)"):
            load_measurement(tmp_path / f"{name}.npy", ImportOptions("npy", height_unit="um",
                                                                     spacing=(1e-5, 1e-5),
                                                                     form_degree=degree))
