"""Measured surfaces: import of each format, units, holes, detrending, statistics,
bad files, the study's measured cells, and a measured surface through the workflow."""

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest
import yaml
from scipy import stats as scipy_stats

from roughcontact.errors import MeasurementError
from roughcontact.study.config import validated
from roughcontact.study.jobs.storage import read_surfaces
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.plan.cells import contact_jobs
from roughcontact.study.plan.checks import check_studies
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.records import MeasuredCell
from roughcontact.study.settings import Study
from roughcontact.study.sources import MeasurementImport
from roughcontact.surfaces import johnson, measured, preparation, readers, statistics
from roughcontact.surfaces.measured import ImportOptions

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "data" / "example_plateau_honed.xyz"
MM, UM = 1e-3, 1e-6


def rough_field(ny=12, nx=16, seed=3):
    """A rough, plane-free, zero-mean field with a heavy lower tail (arbitrary unit)."""
    rng = np.random.default_rng(seed)
    z = rng.standard_normal((ny, nx)) - 0.5 * rng.exponential(1.0, (ny, nx))
    return preparation.remove_plane(z, (1.0, 1.0))[0]


def with_plane(z, spacing, a=0.3, b=0.02, c=-0.05):
    """``z`` plus the plane a + b x + c y (x = ix dx, y = iy dy)."""
    ny, nx = z.shape
    y, x = np.mgrid[0:ny, 0:nx]
    return z + a + b * x * spacing[0] + c * y * spacing[1]


def write_xyz(path, z, dx, dy, drop=(), order=None, fmt="{:.10g} {:.10g} {:.17g}"):
    ny, nx = z.shape
    lines = ["# x y z", "# a test surface"]
    points = [(ix * dx, iy * dy, z[iy, ix]) for iy in range(ny) for ix in range(nx)
              if (iy, ix) not in drop]
    if order is not None:
        points = [points[k] for k in order(len(points))]
    lines += [fmt.format(*p) for p in points]
    path.write_text("\n".join(lines) + "\n")


# ------------------------------------------------------------------ round trips


def test_npy_round_trip_converts_units_and_keeps_the_orientation(tmp_path):
    z_um = with_plane(rough_field(), (0.1, 0.2))  # (ny, nx) = (12, 16), heights in um
    path = tmp_path / "map.npy"
    np.save(path, z_um)
    m = measured.load_measurement(path, ImportOptions("npy", height_unit="um",
                                                      spacing=(0.1 * MM, 0.2 * MM)))
    expected, _ = preparation.remove_plane(z_um * UM, (0.1 * MM, 0.2 * MM))
    assert m.heights.shape == (12, 16) and m.grid == (16, 12)
    assert m.spacing == pytest.approx((1e-4, 2e-4))
    assert m.size == pytest.approx((1.6e-3, 2.4e-3))
    assert np.allclose(m.heights, expected, rtol=0, atol=1e-18)
    assert m.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert m.filled == 0


@pytest.mark.parametrize("separator", [",", "\t", " ", ";"])
def test_text_grid_round_trip_with_comments_in_nanometres(tmp_path, separator):
    z_nm = rough_field(ny=7, nx=9) * 100.0
    path = tmp_path / "grid.csv"
    rows = [separator.join(f"{v:.17g}" for v in row) for row in z_nm]
    path.write_text("# exported by a profilometer\n# unit: nm\n\n" + "\n".join(rows[:3])
                    + "\n# a comment between rows\n" + "\n".join(rows[3:]) + "  # trailing\n")
    assert np.array_equal(readers.read_text_grid(path), z_nm)  # rows = y, columns = x
    m = measured.load_measurement(path, ImportOptions("text", height_unit="nm",
                                                      spacing=(2e-6, 2e-6)))
    assert np.allclose(m.heights, preparation.remove_plane(z_nm * 1e-9, (2e-6, 2e-6))[0],
                       rtol=0, atol=1e-21)
    assert m.grid == (9, 7)


def test_xyz_round_trip_infers_the_spacing_from_shuffled_points(tmp_path):
    z_mm = rough_field(ny=10, nx=14) * 1e-3  # heights in mm
    dx_um, dy_um = 2.5, 4.0
    path = tmp_path / "points.xyz"
    rng = np.random.default_rng(0)
    write_xyz(path, z_mm, dx_um, dy_um, order=rng.permutation)
    raw, spacing, absent = readers.read_xyz(path, "um")
    assert np.array_equal(raw, z_mm) and absent == 0
    assert spacing == pytest.approx((dx_um, dy_um), rel=1e-12)
    m = measured.load_measurement(path, ImportOptions("xyz", height_unit="mm", lateral_unit="um"))
    assert m.spacing == pytest.approx((2.5e-6, 4e-6), rel=1e-12)
    assert np.allclose(m.heights, preparation.remove_plane(z_mm * MM, m.spacing)[0],
                       rtol=0, atol=1e-18)


def test_xyz_tolerates_coordinates_rounded_in_print(tmp_path):
    z = rough_field(ny=6, nx=30)
    path = tmp_path / "rounded.xyz"
    write_xyz(path, z, 1 / 30, 1 / 30, fmt="{:.4f} {:.4f} {:.17g}")  # 0.0333, 0.0667, ...
    raw, spacing, _ = readers.read_xyz(path)
    assert np.array_equal(raw, z)
    assert spacing == pytest.approx((1 / 30, 1 / 30), rel=2e-3)


# ------------------------------------------------------------------ detrending and statistics


def test_plane_removal_removes_an_added_plane_exactly():
    z = rough_field()
    spacing = (1e-4, 2e-4)
    tilted = with_plane(z, spacing, a=2e-6, b=3e-3, c=-1e-3)
    residual, (a, b, c) = preparation.remove_plane(tilted, spacing)
    assert np.allclose(residual, z, rtol=0, atol=1e-15)
    assert (a, b, c) == pytest.approx((2e-6, 3e-3, -1e-3), rel=1e-9)
    assert abs(residual.mean()) < 1e-15


def test_statistics_are_those_of_the_surface_module_and_the_johnson_fit():
    m = measured.load_measurement(EXAMPLE, ImportOptions("xyz", height_unit="um", fill_holes=0.01))
    s = measured.statistics(m)
    moments = statistics.height_stats(m.heights)
    assert s["sigma"] == pytest.approx(moments["sigma"], rel=1e-14)
    assert (s["skew"], s["kurt"]) == pytest.approx((moments["skew"], moments["kurt"]), rel=1e-14)
    bx, by = statistics.correlation_length(m.heights, m.spacing, periodic=False)
    assert (s["corr_length_x"], s["corr_length_y"]) == pytest.approx((bx, by))
    assert s["grid"] == [64, 64] and s["size"] == pytest.approx([6.4e-3, 6.4e-3])
    assert s["filled_points"] == 10 and s["filled_fraction"] == pytest.approx(10 / 4096)
    # the stand-in is strongly negatively skewed (plateau and valleys)
    assert s["skew"] < -1.0 and s["kurt"] > 5.0
    # the Johnson law reproduces the moments of the heights in units of sigma
    curve = johnson.JohnsonCurve(s["johnson_family"], *s["johnson_params"])
    assert curve.family == johnson.family_of(s["skew"], s["kurt"]) == "SB"
    assert curve.moments() == pytest.approx((0.0, 1.0, s["skew"], s["kurt"]), abs=1e-7)


@pytest.mark.parametrize("transform", ["sb", "su"])
def test_johnson_law_matches_scipy_moments(tmp_path, transform):
    """The fitted law, as scipy's johnsonsb / johnsonsu, has the measured moments."""
    rng = np.random.default_rng(5)
    field = rng.standard_normal((40, 40))
    z = -np.exp(0.6 * field) if transform == "sb" else np.sinh(0.9 * field + 0.4)
    path = tmp_path / "map.npy"
    np.save(path, z)
    s = measured.statistics(measured.load_measurement(path, ImportOptions("npy", height_unit="um",
                                                                          spacing=(1e-5, 1e-5))))
    gamma, delta, xi, lam = s["johnson_params"]
    family = s["johnson_family"]
    assert family == transform.upper()
    law = scipy_stats.johnsonsb if family == "SB" else scipy_stats.johnsonsu
    sign = 1.0 if lam > 0 else -1.0  # scipy's scale is positive: mirror x for lam < 0
    mean, var, skew, excess = law(gamma, delta, loc=sign * xi, scale=sign * lam).stats("mvsk")
    assert sign * mean == pytest.approx(0.0, abs=1e-6)
    assert var == pytest.approx(1.0, rel=1e-6)
    assert sign * skew == pytest.approx(s["skew"], abs=1e-5)
    assert excess + 3.0 == pytest.approx(s["kurt"], abs=1e-4)


# ------------------------------------------------------------------ holes


def smooth_field(ny=40, nx=50):
    y, x = np.mgrid[0:ny, 0:nx] / 10.0
    return np.sin(x) * np.cos(0.7 * y) + 0.3 * x - 0.1 * y


def test_hole_filling_reproduces_a_smooth_field_and_records_the_count(tmp_path):
    z = smooth_field()
    holes = z.copy()
    holes[10:13, 20:23] = np.nan  # an interior hole of 9 points
    holes[0, 0] = holes[-1, 7] = holes[25, -1] = np.nan  # at a corner and on two edges
    path = tmp_path / "holes.csv"
    path.write_text("\n".join(",".join("nan" if np.isnan(v) else f"{v:.17g}" for v in row)
                              for row in holes))
    m = measured.load_measurement(path, ImportOptions("text", height_unit="um",
                                                      spacing=(1e-4, 1e-4), fill_holes=0.01))
    assert m.filled == 12 and m.filled_fraction == pytest.approx(12 / 2000)
    s = measured.statistics(m)
    assert s["filled_points"] == 12 and s["filled_fraction"] == pytest.approx(0.006)
    truth = preparation.remove_plane(z * UM, (1e-4, 1e-4))[0]
    error = np.abs(m.heights - truth) / np.ptp(truth)
    assert error[10:13, 20:23].max() < 0.005  # second order inside a hole
    assert error.max() < 0.05  # first order at the edges (zero normal slope there)
    filled, count = preparation.fill_missing(holes, 0.01)
    assert count == 12 and np.array_equal(filled[~np.isnan(holes)], z[~np.isnan(holes)])
    # a plane is filled exactly, at the edges too
    plane = with_plane(np.zeros_like(z), (1.0, 1.0), a=1.0, b=0.2, c=-0.3)
    plane_holes = np.where(np.isnan(holes), np.nan, plane)
    filled, count = preparation.fill_missing(plane_holes, 0.01)
    assert count == 12 and np.allclose(filled, plane, rtol=0, atol=1e-12)


def test_too_many_holes_are_refused_with_count_and_fraction(tmp_path):
    z = smooth_field(10, 10)
    z[2:5, 2:5] = np.nan
    path = tmp_path / "holey.npy"
    np.save(path, z)
    with pytest.raises(MeasurementError, match=r"holey\.npy: 9 of 100 points \(9 %\) are "
                                               r"missing.*fill_holes = 0\.05"):
        measured.load_measurement(path, ImportOptions("npy", height_unit="um",
                                                      spacing=(1e-4, 1e-4), fill_holes=0.05))
    with pytest.raises(MeasurementError, match=r"fill_holes is 0"):
        measured.load_measurement(path, ImportOptions("npy", height_unit="um",
                                                      spacing=(1e-4, 1e-4)))
    m = measured.load_measurement(path, ImportOptions("npy", height_unit="um",
                                                      spacing=(1e-4, 1e-4), fill_holes=0.1))
    assert m.filled == 9


def test_points_missing_from_an_xyz_list_are_counted_and_filled(tmp_path):
    z = smooth_field(20, 20)
    path = tmp_path / "gappy.xyz"
    write_xyz(path, z, 0.1, 0.1, drop={(3, 4), (10, 10), (19, 19)})
    with pytest.raises(MeasurementError, match=r"gappy\.xyz: 3 of 400 points \(0\.75 %\).*"
                                               r"3 grid points absent from the point list"):
        measured.load_measurement(path, ImportOptions("xyz", height_unit="um"))
    m = measured.load_measurement(path, ImportOptions("xyz", height_unit="um", fill_holes=0.01))
    assert m.filled == 3


# ------------------------------------------------------------------ bad files


def bad_text(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("name", "fmt", "text", "pattern"),
    [
        ("ragged.csv", "text", "# header\n1,2,3,4\n1,2,3,4\n1,2,3\n1,2,3,4\n",
         r"ragged\.csv, line 4: 3 values, but the first data row \(line 2\) has 4"),
        ("word.txt", "text", "1 2 3 4\n1 2 3 4\n1 2 x7 4\n1 2 3 4\n",
         r"word\.txt, line 3, column 3: 'x7', which is not a number"),
        ("empty.csv", "text", "1,2,3,4\n1,,3,4\n1,2,3,4\n1,2,3,4\n",
         r"empty\.csv, line 2, column 2: an empty field"),
        ("inf.txt", "text", "1 2 3 4\n1 2 3 4\n1 2 3 4\n1 inf 3 4\n",
         r"inf\.txt, line 4, column 2: 'inf' is infinite"),
        ("header.xyz", "xyz", "x y z\n0 0 1\n", r"header\.xyz, line 1, column 1: 'x'"),
        ("four.xyz", "xyz", "# c\n0 0 1\n1 0 2 9\n", r"four\.xyz, line 3: 4 values, expected 3"),
        ("comments.txt", "text", "# only\n# comments\n", r"comments\.txt: no data rows"),
        ("tiny.txt", "text", "1 2 3\n4 5 6\n7 8 9\n", r"tiny\.txt: a 3 x 3 grid"),
    ],
)
def test_bad_text_files_name_the_file_and_the_line(tmp_path, name, fmt, text, pattern):
    path = bad_text(tmp_path, name, text)
    spacing = None if fmt == "xyz" else (1e-4, 1e-4)
    with pytest.raises(MeasurementError, match=pattern) as info:
        measured.load_measurement(path, ImportOptions(fmt, height_unit="um", spacing=spacing))
    assert isinstance(info.value, ValueError) and info.value.path == str(path)


def test_non_uniform_spacing_names_the_axis_and_the_spacings(tmp_path):
    xs = [0.0, 0.1, 0.2, 0.35, 0.45, 0.55]
    lines = [f"{x} {y} {np.sin(x + y):.6f}" for y in (0.0, 0.2, 0.4, 0.6) for x in xs]
    path = bad_text(tmp_path, "stretched.xyz", "\n".join(lines))
    with pytest.raises(MeasurementError,
                       match=r"stretched\.xyz: the x spacing is not uniform: spacings seen "
                             r"0\.1, 0\.15 mm"):
        measured.load_measurement(path, ImportOptions("xyz", height_unit="um"))
    # a missing column is not a non-uniform grid: it is missing points
    lines = [f"{x} {y} 1" for y in (0.0, 0.1, 0.2, 0.3) for x in (0.0, 0.1, 0.3, 0.4)]
    path = bad_text(tmp_path, "column.xyz", "\n".join(lines))
    with pytest.raises(MeasurementError, match=r"4 of 20 points \(20 %\)"):
        measured.load_measurement(path, ImportOptions("xyz", height_unit="um"))


def test_repeated_point_names_both_lines(tmp_path):
    lines = [f"{x} {y} {x * y}" for y in range(4) for x in range(4)] + ["2 1 5"]
    path = bad_text(tmp_path, "twice.xyz", "\n".join(lines))
    with pytest.raises(MeasurementError, match=r"twice\.xyz, line 17: the point \(x, y\) = "
                                               r"\(2, 1\) mm repeats line 7"):
        measured.load_measurement(path, ImportOptions("xyz", height_unit="um"))


def test_bad_npy_files_and_options(tmp_path):
    path = tmp_path / "cube.npy"
    np.save(path, np.zeros((4, 4, 4)))
    with pytest.raises(MeasurementError, match=r"cube\.npy: expected a 2-D array.*\(4, 4, 4\)"):
        measured.load_measurement(path, ImportOptions("npy", height_unit="um",
                                                      spacing=(1e-4, 1e-4)))
    flat = tmp_path / "flat.npy"
    np.save(flat, np.add.outer(np.arange(5.0), np.arange(6.0)))
    with pytest.raises(MeasurementError,
                       match=r"flat\.npy: the heights are flat \(a constant or a plane\)"):
        measured.load_measurement(flat, ImportOptions("npy", height_unit="um",
                                                      spacing=(1e-4, 1e-4)))
    with pytest.raises(ValueError, match="needs its spacing"):
        measured.load_measurement(flat, ImportOptions("npy", height_unit="um"))
    with pytest.raises(ValueError, match="height_unit"):
        measured.load_measurement(flat, ImportOptions("npy", height_unit="inch",
                                                      spacing=(1e-4, 1e-4)))
    with pytest.raises(MeasurementError, match=r"missing\.npy: no such file"):
        measured.load_measurement(tmp_path / "missing.npy", ImportOptions("npy", height_unit="um",
                                                                          spacing=(1e-4, 1e-4)))


# ------------------------------------------------------------------ the study's measured cells


def measured_config(path, **study):
    config = yaml.safe_load((REPO / "config" / "measured.yaml").read_text())
    entry = config["sweeps"]["plateau_honed"]
    entry["surface"]["file"] = str(path)
    entry.update(study)
    return validated(config)  # the schema's defaults, as the workflow applies them


def surface_entry(**surface) -> dict:
    """A study's ``surface:`` entry completed by the schema's defaults."""
    config = validated({"study_seed": 0, "figures": {},
                        "surfaces": {"grid": 8, "size_mm": 1.0, "count": 1},
                        "body": {"thickness_mm": 10.0, "E_MPa": 511.0, "nu": 0.0},
                        "sweeps": {"s": {"surface": surface, "pressure_MPa": [0.1, 1.0]}}})
    return config["sweeps"]["s"]["surface"]


def cell_key(entry: dict) -> str:
    """The key of the surface cell of a measured ``surface:`` entry."""
    return MeasuredCell.from_source(MeasurementImport.from_params(entry)).key


def test_measured_key_follows_content_and_options_not_the_name(tmp_path):
    copy = tmp_path / "elsewhere" / "example_plateau_honed.xyz"
    copy.parent.mkdir()
    copy.write_bytes(EXAMPLE.read_bytes())
    entry = surface_entry(file=str(EXAMPLE), format="xyz", height_unit="um", fill_holes=0.01)
    key = cell_key(entry)
    assert key.startswith("measured-example-plateau-honed_") and key.endswith("_n1")
    assert cell_key({**entry, "file": str(copy)}) == key
    assert cell_key({**entry, "fill_holes": 0.02}) != key
    assert cell_key({**entry, "height_unit": "nm"}) != key
    copy.write_text(EXAMPLE.read_text().replace("SYNTHETIC", "Synthetic", 1))
    assert cell_key({**entry, "file": str(copy)}) != key


def test_measured_study_cells_follow_the_measurement():
    config = measured_config(EXAMPLE)
    assert check_studies(Study.from_config(config), ["plateau_honed"]) == []
    cells = contact_cells(Study.from_config(config), "plateau_honed")
    assert len(cells) == 2
    meas, twin = (c.surface for c in cells)
    assert meas.method.value == "measured" and meas.count == 1
    assert twin.method.value == config["surfaces"]["method"] and twin.count == 5
    for key in ("skew", "kurt", "corr_length", "grid", "size"):
        assert getattr(twin, key) == getattr(meas, key), key
    for cell in cells:
        assert cell.geometry.grid == (64, 64)
        assert cell.geometry.params()["size_mm"] == [6.4, 6.4]
        assert cell.sigma == pytest.approx(meas.sigma)
    assert len(contact_jobs(cells)) == 2
    # an explicit sigma rescales both; no twin without compare_synthetic
    config = measured_config(EXAMPLE, sigma_um=[1.0, 2.0], compare_synthetic=False)
    assert [c.params()["sigma_um"] for c in contact_cells(Study.from_config(
            config), "plateau_honed")] == [1.0, 2.0]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"moments": [[0.0, 3.0]]}, "remove moments"),
        ({"surface": {"file": "no/such.xyz", "format": "xyz", "height_unit": "um"}},
         "no/such.xyz: no such file"),
        ({"surface": {"file": str(EXAMPLE), "format": "xyz", "height_unit": "um"}},
         r"10 of 4096 points"),
    ],
)
def test_check_studies_reports_unusable_measured_studies(change, message):
    config = measured_config(EXAMPLE, **change)
    problems = check_studies(Study.from_config(config), ["plateau_honed"])
    assert len(problems) == 1 and message in problems[0], problems


def test_measured_cell_file_has_the_generated_layout(tmp_path):
    config = measured_config(EXAMPLE)
    surface = contact_cells(Study.from_config(config), "plateau_honed")[0].surface
    path = tmp_path / "cell.h5"
    build_surface_cell(surface.params(), 7, path, config=config)
    cell = read_surfaces(path)
    m = measured.load_measurement(EXAMPLE, ImportOptions("xyz", height_unit="um", fill_holes=0.01))
    s = measured.statistics(m)
    assert cell["heights"].shape == (1, 64, 64)
    assert np.allclose(cell["heights"][0] * s["sigma"], m.heights, rtol=0, atol=1e-18)
    assert cell["stats"]["sigma"] == pytest.approx([1.0]) and cell["seeds"].tolist() == [-1]
    attrs = cell["attrs"]
    assert attrs["source_sha256"] == hashlib.sha256(EXAMPLE.read_bytes()).hexdigest()
    assert attrs["measured_sigma_m"] == pytest.approx(s["sigma"])
    assert attrs["filled_points"] == 10
    assert json.loads(attrs["import_options"])["fill_holes"] == 0.01
    assert attrs["johnson_family"] == "SB" and attrs["cell"] == surface.key


# ------------------------------------------------------------------ the workflow


def run_snakemake(workdir, config_path, *args):
    cmd = [sys.executable, "-m", "snakemake", "--snakefile", str(REPO / "Snakefile"),
           "--directory", str(workdir), "--configfile", str(config_path), "--cores", "2", *args]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)


def test_shipped_measured_config_validates_and_plans(tmp_path):
    from snakemake.utils import validate

    config = yaml.safe_load((REPO / "config" / "measured.yaml").read_text())
    validate(config, str(REPO / "config" / "schema.yaml"))
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / EXAMPLE.name).write_bytes(EXAMPLE.read_bytes())
    proc = run_snakemake(tmp_path, REPO / "config" / "measured.yaml", "--dry-run")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "measured-example-plateau-honed_" in proc.stdout


@pytest.mark.workflow
def test_measured_surface_runs_end_to_end_beside_its_twin(tmp_path):
    """config/measured.yaml, made tiny: a 32 x 32 stand-in, the paper's mesh, 3 twins."""
    data = tmp_path / "stand_in.xyz"
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_example_measurement.py"),
                    "--grid", "32", "--dropouts", "3", "--out", str(data)],
                   check=True, capture_output=True)
    config = measured_config(data, count=3)
    config["surfaces"].update(grid=[32, 32], size_mm=[3.2, 3.2])
    config["body"]["mesh"] = "paper"
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(config))
    proc = run_snakemake(tmp_path, path)
    assert proc.returncode == 0, proc.stderr[-4000:]

    # the measured cell stores the file's detrended statistics and its provenance
    m = measured.load_measurement(data, ImportOptions("xyz", height_unit="um", fill_holes=0.01))
    s = measured.statistics(m)
    cells = contact_cells(Study.from_config(config), "plateau_honed")
    meas_key, twin_key = (c.surface.key for c in cells)
    with h5py.File(tmp_path / "results" / "surfaces" / f"{meas_key}.h5", "r") as f:
        attrs = dict(f.attrs)
        heights = f["heights"][()]
    stored = statistics.height_stats(heights[0] * attrs["measured_sigma_m"])
    assert stored["sigma"] == pytest.approx(s["sigma"], rel=1e-12)
    assert (stored["skew"], stored["kurt"]) == pytest.approx((s["skew"], s["kurt"]), rel=1e-12)
    assert (attrs["measured_skew"], attrs["measured_kurt"]) == pytest.approx(
        (s["skew"], s["kurt"]), rel=1e-12)
    assert attrs["source_sha256"] == m.sha256 and attrs["filled_points"] == 3

    # the twin realises the measured moments and correlation length
    twin = read_surfaces(tmp_path / "results" / "surfaces" / f"{twin_key}.h5")
    assert twin["heights"].shape == (3, 32, 32)
    assert np.mean(twin["stats"]["skew"]) == pytest.approx(s["skew"], abs=0.1)
    assert np.mean(twin["stats"]["kurt"]) == pytest.approx(s["kurt"], rel=0.1)
    assert np.mean(twin["stats"]["corr_length_x"]) == pytest.approx(s["corr_length_x"], rel=0.3)

    # both went through the same contact and aggregate rules
    table = pd.read_csv(tmp_path / "results" / "aggregates" / "plateau_honed.csv")
    assert (table["unconverged_steps"] == 0).all()
    by_source = {key.startswith("measured-"): part for key, part in table.groupby("contact_key")}
    assert set(by_source) == {True, False}
    assert by_source[True]["surfaces"].iloc[0] == 1 and by_source[False]["surfaces"].iloc[0] == 3
    for part in by_source.values():
        for quantity in ("normalized_stiffness", "real_area_fraction", "max_pressure"):
            assert np.isfinite(part[f"{quantity}_mean"]).all(), quantity
        area = part["real_area_fraction_mean"].to_numpy()
        assert np.all(np.diff(area) > 0) and 0 < area[0] < area[-1] < 1
    assert (tmp_path / "results" / "figures" / "measured.png").stat().st_size > 1000
    audit = pd.read_csv(tmp_path / "results" / "audit" / "audit.csv", dtype={"flags": str})
    assert not audit["flags"].fillna("").str.contains("changed|unconverged|missing").any()
    # the twins come from the exact generator: their moments are the targets
    assert not audit["flags"].fillna("").str.contains("off target").any()
    # legends tell the measurement from its twin
    labels = {key.startswith("measured-"): part["label"].iloc[0]
              for key, part in table.groupby("contact_key")}
    assert labels[True].startswith("measured ") and not labels[False].startswith("measured")
