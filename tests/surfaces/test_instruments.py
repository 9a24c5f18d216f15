"""Measured topographies from real instruments' files, checked against SurfaceTopography.

The instrument files are read in place from the shared data folder (see its
README.md); the reference values come from SurfaceTopography itself, never
from the loader under test. Text grids, NumPy files, a line scan and a dome
are built here with NumPy.
"""

import functools
import logging
import math
import os
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from topographies import DATA, needs_data

from roughcontact.errors import MeasurementError
from roughcontact.surfaces import measured
from roughcontact.surfaces.measured import ImportOptions, load_measurement, statistics
from roughcontact.surfaces.preparation import remove_polynomial
from roughcontact.surfaces.readers import read_instrument, read_text_grid

FILES = ("di-1.di", "frt-1.frt", "matrix-3.txt", "opd-1.opd", "plu-1.plu", "sur-2.sur",
         "x3p-2.x3p")
UNMASKED = ("di-1.di", "matrix-3.txt", "plu-1.plu", "x3p-2.x3p")
MASKED = ("frt-1.frt", "opd-1.opd", "sur-2.sur")
#: Metres per unit SurfaceTopography reports (written out here, not taken from the library).
METRES = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6, "nm": 1e-9}


@functools.cache
def reference(name):
    """SurfaceTopography's reader class name, topography and metres per unit for a file."""
    from SurfaceTopography import open_topography

    reader = open_topography(str(DATA / name))
    topography = reader.topography()
    return type(reader).__name__, topography, METRES[topography.unit]


@functools.cache
def loaded(name):
    """The loader's default import of a shared file (holes filled where there are any)."""
    return load_measurement(DATA / name, ImportOptions(fill_holes=0.4))


def plane_removed(z, spacing):
    """``z`` (ny, nx) less its least-squares plane in x = ix dx, y = iy dy, zero mean."""
    ny, nx = z.shape
    y, x = np.mgrid[0:ny, 0:nx]
    design = np.column_stack([np.ones(z.size), x.ravel() * spacing[0], y.ravel() * spacing[1]])
    coefficients, *_ = np.linalg.lstsq(design, z.ravel(), rcond=None)
    residual = z - (design @ coefficients).reshape(z.shape)
    return residual - residual.mean()


def reference_heights_m(name):
    """SurfaceTopography's heights of an unmasked file, (ny, nx), in metres."""
    _, topography, scale = reference(name)
    raw = topography.heights()
    assert not np.ma.getmaskarray(raw).any()
    return np.asarray(np.ma.getdata(raw), dtype=float).T * scale


# --------------------------------------------------------------------------- instrument files


@needs_data
def test_the_shared_data_folder_is_where_the_tests_look():
    assert (DATA / "README.md").is_file()
    for name in FILES:
        assert (DATA / name).is_file(), name


@needs_data
@pytest.mark.parametrize("name", FILES)
def test_grid_size_reader_and_mask_agree_with_surfacetopography(name):
    reader_name, topography, scale = reference(name)
    m = loaded(name)
    nx, ny = topography.nb_grid_pts
    assert m.grid == (nx, ny)
    assert m.heights.shape == (ny, nx)
    expected_size = [float(s) * scale for s in topography.physical_sizes]
    assert m.size == pytest.approx(expected_size, rel=1e-9, abs=0.0)
    assert m.spacing == pytest.approx([expected_size[0] / nx, expected_size[1] / ny], rel=1e-9,
                                      abs=0.0)
    assert m.preparation["reader"] == reader_name
    masked = int(np.ma.getmaskarray(topography.heights()).sum())
    assert m.preparation["masked_points"] == masked
    assert m.filled == masked
    assert np.isfinite(m.heights).all()


@needs_data
@pytest.mark.parametrize("name", UNMASKED)
@pytest.mark.filterwarnings("ignore:Function/property `Sq` is deprecated:DeprecationWarning")
def test_sigma_is_surfacetopography_rms_height_after_plane_removal(name):
    _, topography, scale = reference(name)
    expected = topography.detrend(detrend_mode="height").rms_height_from_area() * scale
    assert statistics(loaded(name))["sigma"] == pytest.approx(expected, rel=1e-9, abs=0.0)


@needs_data
@pytest.mark.parametrize("name", MASKED)
def test_raw_heights_are_surfacetopography_heights_with_nan_where_masked(name):
    _, topography, _ = reference(name)
    raw = topography.heights()
    mask = np.ma.getmaskarray(raw).T
    values = np.asarray(np.ma.getdata(raw), dtype=float).T
    assert mask.any()
    data = read_instrument(DATA / name)
    assert data.heights.shape == values.shape
    assert data.masked == int(mask.sum())
    assert data.unit == topography.unit
    np.testing.assert_array_equal(np.isnan(data.heights), mask)
    np.testing.assert_allclose(data.heights[~mask], values[~mask], rtol=1e-12, atol=0)


def test_a_line_scan_is_refused(tmp_path):
    from SurfaceTopography import open_topography

    x = np.arange(64) * 0.5e-6
    path = tmp_path / "profile.txt"
    np.savetxt(path, np.column_stack([x, 1e-8 * np.sin(x / 3e-6)]))
    assert open_topography(str(path)).default_channel.dim == 1  # a profile for ST too
    with pytest.raises(MeasurementError, match="line scan") as err:
        load_measurement(path, ImportOptions(height_unit="m", spacing=(0.5e-6, 0.5e-6)))
    assert err.value.path == str(path)
    with pytest.raises(MeasurementError, match="line scan"):
        read_instrument(path)


# --------------------------------------------------------------------------- text grids


def _grid_text(z, separator, comma):
    rows = [separator.join(f"{v:.6f}" for v in row) for row in z]
    text = "\n".join(rows) + "\n"
    return text.replace(".", ",") if comma else text


def test_decimal_commas_and_points_read_the_same_grid(tmp_path):
    rng = np.random.default_rng(11)
    z = 0.018 * rng.standard_normal((48, 64))  # heights [um], 64 x 48 (nx x ny)
    # the values the text says, parsed by Python from the decimal-point rows
    expected = np.array([[float(f"{v:.6f}") for v in row] for row in z])
    files = {
        "semicolon_comma.txt": _grid_text(z, ";", comma=True),
        "semicolon_point.txt": _grid_text(z, ";", comma=False),
        "tab_comma.txt": _grid_text(z, "\t", comma=True),
    }
    assert "," in files["tab_comma.txt"] and "." not in files["tab_comma.txt"]
    sigmas = []
    for name, text in files.items():
        path = tmp_path / name
        path.write_text(text)
        grid = read_text_grid(path)
        assert grid.shape == (48, 64), name
        np.testing.assert_array_equal(grid, expected, err_msg=name)
        m = load_measurement(path, ImportOptions(format="text", height_unit="um",
                                                 spacing=(1e-5, 1e-5)))
        assert m.grid == (64, 48)
        sigmas.append(statistics(m)["sigma"])
    independent = plane_removed(expected * 1e-6, (1e-5, 1e-5)).std()
    assert sigmas == pytest.approx([independent] * 3, rel=1e-9, abs=0.0)


def test_an_ambiguous_decimal_comma_line_is_refused_unless_decimal_says(tmp_path):
    path = tmp_path / "ambiguous.txt"
    path.write_text("# heights in um\n1,234 2,345 3,456\n")
    with pytest.raises(MeasurementError) as err:
        read_text_grid(path, decimal="auto")
    message = str(err.value)
    assert "line 2" in message
    assert "decimal" in message
    assert err.value.line == 2
    grid = read_text_grid(path, decimal=",")
    assert grid.shape == (1, 3)
    np.testing.assert_array_equal(grid[0], [1.234, 2.345, 3.456])


def test_a_header_line_in_a_text_grid_is_refused_naming_it(tmp_path):
    path = tmp_path / "with_header.csv"
    path.write_text("x y z\n" + "\n".join(" ".join(["0.1"] * 6) for _ in range(6)) + "\n")
    with pytest.raises(MeasurementError, match="header"):
        read_text_grid(path)
    with pytest.raises(MeasurementError, match="header"):
        load_measurement(path, ImportOptions(height_unit="um", spacing=(1e-5, 1e-5)))


# --------------------------------------------------------------------------- form


def _dome(tmp_path):
    """A sphere cap (R = 5 mm, 2 um sag) plus 20 nm of correlated roughness, in um, on a
    128 x 256 window (nx x ny, 1 um spacing) centred on the apex.

    The window is twice as long in y as in x on purpose: on a square window the
    non-periodic ACF of a plane-removed paraboloid does fall to 10 % along x, at
    0.9 of half the window (lag 57 of 64 points, checked by a direct sum), so
    a 10 % lag exists there; on this window the y form keeps the ACF along x
    above 0.85 at every lag.
    """
    nx, ny, dx = 128, 256, 1e-6
    rng = np.random.default_rng(5)
    rough = ndimage.gaussian_filter(rng.standard_normal((ny, nx)), 2.0)
    rough *= 0.02 / rough.std()
    y, x = np.meshgrid((np.arange(ny) - (ny - 1) / 2) * dx, (np.arange(nx) - (nx - 1) / 2) * dx,
                       indexing="ij")
    radius = 5e-3
    cap = (np.sqrt(radius**2 - x**2 - y**2) - radius) / 1e-6
    assert np.ptp(cap) > 50 * rough.std()  # the form dominates
    path = tmp_path / "dome.npy"
    np.save(path, cap + rough)
    return path, (nx * dx, ny * dx)


def test_a_dome_left_in_gives_nan_correlation_length_and_a_warning(tmp_path, caplog):
    path, _ = _dome(tmp_path)
    m = load_measurement(path, ImportOptions(height_unit="um", spacing=(1e-6, 1e-6)))
    with caplog.at_level(logging.WARNING, logger=measured.__name__):
        stats = statistics(m)
    assert math.isnan(stats["corr_length_x"])  # not the domain length, not half of it
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert any("corr_length_x" in w and " x " in w and "form_degree" in w for w in warnings), \
        warnings


def test_removing_the_quadratic_form_gives_finite_correlation_lengths(tmp_path, caplog):
    path, side = _dome(tmp_path)
    m = load_measurement(path, ImportOptions(height_unit="um", spacing=(1e-6, 1e-6), form_degree=2))
    with caplog.at_level(logging.WARNING, logger=measured.__name__):
        stats = statistics(m)
    for key, length in zip(("corr_length_x", "corr_length_y"), side, strict=True):
        assert math.isfinite(stats[key]), key
        assert 0 < stats[key] < length / 2, key
    assert not [r for r in caplog.records if r.levelno >= logging.WARNING]


def test_remove_polynomial_removes_an_exact_quadratic():
    ny, nx = 40, 60
    y, x = np.mgrid[0:ny, 0:nx].astype(float)
    x, y = x * 2e-6, y * 3e-6
    quadratic = 1e-6 * (0.3 + 2e3 * x - 1e3 * y + 4e8 * x**2 + 2e8 * x * y - 3e8 * y**2)
    residual, coefficients = remove_polynomial(quadratic, (2e-6, 3e-6), 2)
    assert len(coefficients) == 6
    assert np.abs(residual).max() < 1e-12 * np.ptp(quadratic)
    plane_only, _ = remove_polynomial(quadratic, (2e-6, 3e-6), 1)  # the check can fail
    assert np.abs(plane_only).max() > 1e-3 * np.ptp(quadratic)


# --------------------------------------------------------------------------- contradictions


@needs_data
def test_a_height_unit_contradicting_the_file_is_refused():
    with pytest.raises(ValueError, match="contradicts") as err:
        load_measurement(DATA / "x3p-2.x3p", ImportOptions(height_unit="nm"))
    assert not isinstance(err.value, MeasurementError)
    assert load_measurement(DATA / "x3p-2.x3p", ImportOptions(height_unit="m")).grid == (650, 650)


@needs_data
def test_a_spacing_contradicting_the_file_is_refused():
    _, topography, scale = reference("x3p-2.x3p")
    nx, ny = topography.nb_grid_pts
    lx, ly = (float(s) * scale for s in topography.physical_sizes)
    with pytest.raises(ValueError, match="contradicts") as err:
        load_measurement(DATA / "x3p-2.x3p", ImportOptions(spacing=(1.1 * lx / nx, ly / ny)))
    assert not isinstance(err.value, MeasurementError)
    agreeing = ImportOptions(spacing=(lx / nx, ly / ny))
    m = load_measurement(DATA / "x3p-2.x3p", agreeing)  # accepted
    assert m.size == pytest.approx([lx, ly], rel=1e-9, abs=0.0)


def test_an_npy_file_needs_a_height_unit(tmp_path):
    path = tmp_path / "heights.npy"
    np.save(path, np.random.default_rng(2).standard_normal((8, 8)))
    with pytest.raises(ValueError, match="height_unit") as err:
        load_measurement(path, ImportOptions(spacing=(1e-6, 1e-6)))
    assert not isinstance(err.value, MeasurementError)


# --------------------------------------------------------------------------- preparation


def grid_and_spacing(name):
    """SurfaceTopography's (nx, ny) and pixel size (dx, dy) [m] of a shared file."""
    _, topography, scale = reference(name)
    nx, ny = topography.nb_grid_pts
    return (nx, ny), tuple(float(s) * scale / n for s, n in
                           zip(topography.physical_sizes, (nx, ny), strict=True))


@needs_data
def test_crop_takes_the_window_rounded_to_whole_points():
    (nx, ny), (dx, dy) = grid_and_spacing("plu-1.plu")
    x0, y0, lx, ly = 100e-6, 50e-6, 500e-6, 300e-6
    m = load_measurement(DATA / "plu-1.plu", ImportOptions(crop=(x0, y0, lx, ly)))
    ix0, iy0, cx, cy = round(x0 / dx), round(y0 / dy), round(lx / dx), round(ly / dy)
    assert m.grid == (cx, cy)
    assert m.preparation["crop_points"] == [ix0, iy0, cx, cy]
    assert m.preparation["file_grid"] == [nx, ny]
    window = reference_heights_m("plu-1.plu")[iy0:iy0 + cy, ix0:ix0 + cx]
    expected = plane_removed(window, (dx, dy))
    np.testing.assert_allclose(m.heights, expected, rtol=0, atol=1e-9 * expected.std())


@needs_data
def test_a_crop_outside_the_measurement_is_refused():
    with pytest.raises(MeasurementError, match="crop window"):
        load_measurement(DATA / "plu-1.plu", ImportOptions(crop=(1e-3, 0.0, 0.5e-3, 0.5e-3)))


@needs_data
def test_decimate_by_4_averages_blocks_and_multiplies_the_spacing():
    _, (dx, dy) = grid_and_spacing("matrix-3.txt")
    m = load_measurement(DATA / "matrix-3.txt", ImportOptions(decimate_by=4))
    assert m.grid == (64, 64)
    assert m.spacing == pytest.approx([4 * dx, 4 * dy], rel=1e-12, abs=0.0)
    assert m.preparation["decimated_by"] == 4
    full = plane_removed(reference_heights_m("matrix-3.txt"), (dx, dy))
    blocks = full.reshape(64, 4, 64, 4).mean(axis=(1, 3))
    blocks -= blocks.mean()
    np.testing.assert_allclose(m.heights, blocks, rtol=0, atol=1e-9 * blocks.std())


@needs_data
def test_resample_keeps_the_physical_size():
    _, topography, scale = reference("matrix-3.txt")
    size = [float(s) * scale for s in topography.physical_sizes]
    m = load_measurement(DATA / "matrix-3.txt", ImportOptions(resample_grid=(100, 80)))
    assert m.heights.shape == (80, 100)
    assert m.size == pytest.approx(size, rel=1e-12, abs=0.0)
    assert m.spacing == pytest.approx([size[0] / 100, size[1] / 80], rel=1e-12, abs=0.0)
    assert abs(m.heights.mean()) < 1e-12 * m.heights.std()


@needs_data
def test_outliers_are_counted_and_lower_the_kurtosis():
    before = statistics(load_measurement(DATA / "sur-2.sur", ImportOptions(fill_holes=0.01)))
    m = load_measurement(DATA / "sur-2.sur", ImportOptions(fill_holes=0.01, outliers_sigma=5))
    after = statistics(m)
    assert before["kurt"] > 500  # the file's spikes (Ku ~ 786)
    assert m.preparation["outliers"] > 0
    assert after["kurt"] < 0.1 * before["kurt"]
    assert after["sigma"] < before["sigma"]


# --------------------------------------------------------------------------- spectral


@needs_data
def test_spectral_statistics_agree_with_surfacetopography():
    _, topography, scale = reference("x3p-2.x3p")
    assert scale == 1.0  # the file is in metres, so the slope needs no conversion
    stats = statistics(loaded("x3p-2.x3p"), spectral=True)
    expected = topography.detrend(detrend_mode="height").rms_gradient()
    assert stats["rms_slope"] == pytest.approx(expected, rel=1e-6)
    q, c = np.asarray(stats["psd_q"]), np.asarray(stats["psd_C"])
    assert q.size > 10 and q.size == c.size
    assert np.isfinite(q).all() and np.isfinite(c).all()
    assert (q > 0).all() and (c > 0).all()
    assert math.isfinite(stats["rms_curvature"]) and stats["rms_curvature"] > 0


@needs_data
def test_the_frt_dome_gives_a_nan_correlation_length_with_a_warning(caplog):
    # the frt measurement's form is a dome: with only the plane removed its x
    # autocorrelation stays far above 10 % over half the window
    with caplog.at_level(logging.WARNING, logger="roughcontact.surfaces.measured"):
        stats = statistics(loaded("frt-1.frt"))
    assert math.isnan(stats["corr_length_x"])
    assert any("x autocorrelation" in r.getMessage() and "form_degree" in r.getMessage()
               for r in caplog.records)


# ------------------------------------------------------------------ the workflow

REPO = Path(__file__).resolve().parents[2]


def instrument_config(file, grid=24, count=3):
    """A Digital Surf measurement, cropped, form and outliers removed, resampled, beside
    its synthetic twin on the paper's mesh, under a block as thick as the 1.5 mm patch
    (the measured sigma of a few nm: pressures up to P L / (E sigma) of about 0.3)."""
    return {
        "study_seed": 11,
        "surfaces": {"grid": [grid, grid], "size_mm": [1.5, 1.5], "method": "exact",
                     "count": count},
        "body": {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0, "mesh": "paper"},
        "contact": {"steps": 12, "pressure_levels": 6},
        "figures": {"measured": {"from": "sur"}},
        "sweeps": {"sur": {
            "surface": {"file": str(file), "format": "auto", "fill_holes": 0.01,
                        "crop_mm": [0.1, 0.1, 1.5, 1.5], "form_degree": 2,
                        "outliers_sigma": 5, "resample_grid": [grid, grid]},
            "compare_synthetic": True, "count": count, "thickness_mm": "patch",
            "pressure_MPa": [5e-5, 5e-4]}},
    }


@needs_data
@pytest.mark.workflow
def test_an_instrument_file_runs_end_to_end_beside_its_twin(tmp_path):
    import subprocess
    import sys

    import h5py
    import pandas as pd
    import yaml

    path = tmp_path / "instrument.yaml"
    path.write_text(yaml.safe_dump(instrument_config(DATA / "sur-2.sur")))
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(tmp_path), "--configfile", str(path), "--cores", "2"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    assert proc.returncode == 0, proc.stderr[-4000:]
    (stored,) = (tmp_path / "results" / "surfaces").glob("measured-sur-2_*.h5")
    with h5py.File(stored, "r") as f:
        attrs = dict(f.attrs)
        heights = f["heights"][()]
        psd = f["stats/psd_C"][()]
    # the file's own reader, pixel size and mask; the window, form and grid asked for
    prep = __import__("json").loads(attrs["preparation"])
    name, topography, metres = reference("sur-2.sur")
    assert prep["reader"] == name and prep["file_grid"] == list(topography.nb_grid_pts)
    assert prep["file_spacing_m"] == pytest.approx(
        [s * metres / n for s, n in zip(topography.physical_sizes, topography.nb_grid_pts,
                                        strict=True)], rel=1e-12, abs=0.0)
    assert prep["crop_points"][2:] == [round(1.5e-3 / (s * metres / n)) for s, n in
                                       zip(topography.physical_sizes,
                                           topography.nb_grid_pts, strict=True)]
    assert prep["resampled_to"] == [24, 24] and prep["outliers"] > 0
    assert heights.shape == (1, 24, 24) and (psd > 0).all()
    assert attrs["measured_rms_slope"] > 0
    table = pd.read_csv(tmp_path / "results" / "aggregates" / "sur.csv")
    assert (table["unconverged_steps"] == 0).all()
    assert table.groupby("contact_key")["surfaces"].first().sort_values().tolist() == [1, 3]
    assert set(table["coverage"]) <= {"all surfaces", "some surfaces",
                                      "below the first solved step"}
    assert (tmp_path / "results" / "figures" / "measured.png").stat().st_size > 10_000
