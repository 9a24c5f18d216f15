"""Each advice about a measured surface, followed literally, works.

Missing points: the smallest ``fill_holes`` and the ``crop_mm`` of the
largest window without them. A correlation that does not decay: the
``form_degree`` that removes the form (not "2 or more" when 3 is needed),
or ``compare_synthetic: false``. Spikes and dropouts: reported with the
``outliers_sigma`` that removes them. The instrument's masked points are
counted in the window used. A clipped filter is reported once per cell.
"""

import logging
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from topographies import DATA, needs_data

from roughcontact.errors import MeasurementError
from roughcontact.study.config import validated
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.plan.checks import check_studies
from roughcontact.study.records import GeneratedCell, Generator
from roughcontact.study.settings import Study
from roughcontact.surfaces.measured import ImportOptions, load_measurement, statistics
from roughcontact.surfaces.statistics import height_stats

REPO = Path(__file__).resolve().parents[2]


def smooth(shape, corr=2.0, seed=0):
    field = ndimage.gaussian_filter(np.random.default_rng(seed).standard_normal(shape), corr)
    return field / field.std()


def save(path, z):
    np.save(path, z)
    return path


NPY = {"format": "npy", "height_unit": "um", "spacing": (1e-5, 1e-5)}


# ------------------------------------------------------------------ missing points


def test_holes_at_the_edge_are_refused_with_a_crop_that_leaves_them_out(tmp_path):
    z = smooth((40, 50))
    z[:, :3] = np.nan  # the instrument lost the first three columns and a corner
    z[-5:, -4:] = np.nan
    path = save(tmp_path / "edge.npy", z)
    with pytest.raises(MeasurementError) as raised:
        load_measurement(path, ImportOptions(**NPY))
    message = str(raised.value)
    crop = [float(v) for v in re.search(r"crop_mm: \[([^\]]+)\]", message)[1].split(",")]
    fill = float(re.search(r"fill_holes to at least ([0-9.e-]+)", message)[1])
    # both, followed: no point missing in the window; every point filled with fill_holes
    window = load_measurement(path, ImportOptions(**NPY, crop=[v * 1e-3 for v in crop]))
    # columns 3-45, every row (43 x 40), larger than columns 3-49 above the corner (47 x 35)
    assert window.filled == 0 and window.grid == (43, 40)
    assert load_measurement(path, ImportOptions(**NPY, fill_holes=fill)).filled == 120 + 20


def test_a_suggested_fill_holes_is_rounded_up_so_that_it_admits_the_holes(tmp_path):
    z = smooth((37, 41))
    z.ravel()[::997] = np.nan  # 2 of 1517: 0.13184 %
    path = save(tmp_path / "holes.npy", z)
    with pytest.raises(MeasurementError) as raised:
        load_measurement(path, ImportOptions(**NPY))
    fill = float(re.search(r"fill_holes to at least ([0-9.e-]+)", str(raised.value))[1])
    assert fill >= 2 / 1517
    assert load_measurement(path, ImportOptions(**NPY, fill_holes=fill)).filled == 2


@needs_data
def test_the_sur_refusal_names_crop_mm_and_it_works():
    with pytest.raises(MeasurementError, match=r"crop_mm: \[") as raised:
        load_measurement(DATA / "sur-2.sur")
    crop = [float(v) * 1e-3 for v in
            re.search(r"crop_mm: \[([^\]]+)\]", str(raised.value))[1].split(",")]
    m = load_measurement(DATA / "sur-2.sur", ImportOptions(crop=crop))
    assert m.filled == 0 and m.preparation["masked_points"] == 0


@needs_data
def test_masked_points_are_counted_in_the_cropped_window():
    from SurfaceTopography import open_topography

    topography = open_topography(str(DATA / "sur-2.sur")).topography()
    mask = np.ma.getmaskarray(topography.heights()).T  # (ny, nx)
    metres = {"mm": 1e-3, "µm": 1e-6}[topography.unit]
    dx = topography.physical_sizes[0] / topography.nb_grid_pts[0] * metres
    start, points = round(0.1e-3 / dx), round(1.5e-3 / dx)
    inside = int(mask[start:start + points, start:start + points].sum())
    m = load_measurement(DATA / "sur-2.sur", ImportOptions(crop=(0.1e-3, 0.1e-3, 1.5e-3, 1.5e-3),
                                                           fill_holes=0.01))
    assert m.preparation["masked_points"] == inside == m.filled == 10
    assert m.preparation["file_masked_points"] == int(mask.sum()) == 117


# ------------------------------------------------------------------ the form


def cubic_form(tmp_path):
    """A rough map on a cubic form in y: the plane and the quadratic leave it (a correlation
    length is NaN), the cubic removes it."""
    z = smooth((64, 64), corr=1.5, seed=3)
    y = np.linspace(-1.0, 1.0, 64)[:, None]
    return save(tmp_path / "cubic.npy", z + 40.0 * (y**3 - 0.6 * y))


def test_the_form_advice_names_the_degree_that_works(tmp_path, caplog):
    path = cubic_form(tmp_path)
    for degree in (1, 2):
        with caplog.at_level(logging.WARNING):
            stats = statistics(load_measurement(path, ImportOptions(**NPY, form_degree=degree)))
        assert not np.isfinite([stats["corr_length_x"], stats["corr_length_y"]]).all()
        assert "surface.form_degree: 3 removes it" in caplog.text
        caplog.clear()
    with caplog.at_level(logging.WARNING):  # followed
        stats = statistics(load_measurement(path, ImportOptions(**NPY, form_degree=3)))
    assert np.isfinite([stats["corr_length_x"], stats["corr_length_y"]]).all()
    assert "autocorrelation" not in caplog.text


def twin_config(path, **sweep):
    return validated({
        "study_seed": 0, "figures": {"measured": {"from": "m"}},
        "surfaces": {"grid": 8, "size_mm": 1.0, "count": 2, "method": "exact"},
        "body": {"thickness_mm": 0.5, "mesh": "refined"},
        "sweeps": {"m": {"surface": {"file": str(path), "format": "npy", "height_unit": "um",
                                     "spacing_mm": [0.01, 0.01], **sweep.pop("surface", {})},
                         "compare_synthetic": True, "count": 2,
                         "pressure_MPa": [0.01, 0.1], **sweep}}})


def test_the_twin_refusal_offers_the_form_degree_and_no_twin_and_both_work(tmp_path):
    path = cubic_form(tmp_path)
    (problem,) = check_studies(Study.from_config(twin_config(path)), ["m"])
    assert "no synthetic twin can be made" in problem
    assert "surface.form_degree: 3" in problem and "compare_synthetic: false" in problem
    assert "2 or more" not in problem
    assert check_studies(Study.from_config(
            twin_config(path, surface={"form_degree": 3})), ["m"]) == []
    assert check_studies(Study.from_config(twin_config(path, compare_synthetic=False)), ["m"]) == []


# ------------------------------------------------------------------ spikes and dropouts


def stand_in(tmp_path, *args):
    out = tmp_path / "stand_in.xyz"
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_example_measurement.py"),
                    "--out", str(out), *args], check=True, capture_output=True)
    return out


XYZ = {"format": "xyz", "height_unit": "um", "fill_holes": 0.01}


def test_dropouts_are_reported_with_the_outliers_sigma_that_removes_them(tmp_path, caplog):
    clean = height_stats(load_measurement(stand_in(tmp_path), ImportOptions(**XYZ)).heights)["kurt"]
    path = stand_in(tmp_path, "--spikes", "3")  # 3 points written at -20 um
    with caplog.at_level(logging.WARNING):
        m = load_measurement(path, ImportOptions(**XYZ))
    kurt = height_stats(m.heights)["kurt"]
    assert kurt > 100 and m.preparation["spikes"] == 3
    assert f"Ku = {kurt:.4g}" in caplog.text and str(path) in caplog.text
    sigmas = float(re.search(r"surface\.outliers_sigma: ([0-9.]+)", caplog.text)[1])
    caplog.clear()
    with caplog.at_level(logging.WARNING):  # followed
        m = load_measurement(path, ImportOptions(**XYZ, outliers_sigma=sigmas))
    assert "spikes" not in caplog.text and m.preparation["outliers"] == 3
    assert height_stats(m.heights)["kurt"] == pytest.approx(clean, rel=0.02)


def test_a_heavy_tailed_surface_is_not_reported(caplog):
    # the plateau-honed stand-in: Ku 7.8 from its grooves, no spike
    with caplog.at_level(logging.WARNING):
        m = load_measurement(REPO / "data" / "example_plateau_honed.xyz", ImportOptions(**XYZ))
    assert m.preparation["spikes"] == 0 and "spikes" not in caplog.text


@needs_data
def test_the_dropouts_of_the_sur_file_are_reported_and_removed(caplog):
    window = {"crop": (0.1e-3, 0.1e-3, 1.5e-3, 1.5e-3), "fill_holes": 0.01}
    with caplog.at_level(logging.WARNING):
        m = load_measurement(DATA / "sur-2.sur", ImportOptions(**window))
    assert height_stats(m.heights)["kurt"] > 300 and "spikes or dropouts" in caplog.text
    sigmas = float(re.search(r"surface\.outliers_sigma: ([0-9.]+)", caplog.text)[1])
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        m = load_measurement(DATA / "sur-2.sur", ImportOptions(**window, outliers_sigma=sigmas))
    assert "spikes" not in caplog.text and height_stats(m.heights)["kurt"] < 4


# ------------------------------------------------------------------ one warning per cell


@pytest.mark.parametrize("method", ["filter", "paper", "exact"])
def test_a_clipped_filter_is_reported_once_per_cell(tmp_path, caplog, method):
    # b = 0.6 L, exponential ACF, periodic: 6 negative spectral values on 16 x 16
    cell = GeneratedCell(skew=0.0, kurt=3.0, corr_length=(0.6e-3, 0.6e-3), grid=(16, 16),
                         size=(1e-3, 1e-3), acf="exponential", periodic=True,
                         method=Generator(method), count=5)
    with caplog.at_level(logging.WARNING):
        build_surface_cell(cell.params(), 1, tmp_path / "cell.h5")
    assert caplog.text.count("negative spectral values") == 1
    assert "clips 6 negative spectral values" in caplog.text


# ------------------------------------------------------------------ no twin


def test_the_measured_summary_without_a_twin_lists_the_measurement_alone():
    import pandas as pd

    from roughcontact.reports.plotting import measured_against_twin

    levels = np.geomspace(1e5, 1e6, 5)
    table = pd.DataFrame({"cell": 0, "nominal_pressure": levels,
                          **{f"{q}_mean": v for q, v in (("normalized_stiffness", 2e8),
                                                         ("real_area_fraction", 0.05),
                                                         ("max_pressure", 3e8))}})
    text = measured_against_twin(table, {0: "measured"})
    assert text.startswith("no synthetic twin (compare_synthetic: false)")
    assert "twin " not in text.split("\n", 1)[1] and text.count("measured") == 13
    assert "real_area_fraction     P =     0.1 MPa: measured         5 %" in text


@pytest.mark.workflow
def test_the_measured_figure_without_a_twin_is_drawn(tmp_path):
    """The advice 'compare_synthetic: false', followed: the figure and its notebook run."""
    import yaml

    path = save(tmp_path / "patch.npy", smooth((24, 24), seed=7))
    config = {"study_seed": 0, "figures": {"measured": {"from": "m"}},
              "surfaces": {"grid": [24, 24], "size_mm": [0.24, 0.24], "count": 2},
              "body": {"thickness_mm": 0.24, "mesh": "paper"},
              "contact": {"steps": 8, "pressure_levels": 5},
              "sweeps": {"m": {"surface": {"file": str(path), "format": "npy",
                                           "height_unit": "um", "spacing_mm": [0.01, 0.01]},
                               "compare_synthetic": False, "pressure_MPa": [1.0, 10.0]}}}
    config_path = tmp_path / "config.yaml"
    config_path.write_text(yaml.safe_dump(config))
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(tmp_path), "--configfile", str(config_path), "--cores", "2"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-4000:]
    figures = tmp_path / "results" / "figures"
    assert (figures / "measured.png").stat().st_size > 10_000
    executed = next(figures.glob("measured*.ipynb")).read_text()
    assert "no synthetic twin (compare_synthetic: false)" in executed
