"""Tests of the speed-against-error study (roughcontact.reports.speed) on small grids."""

import numpy as np
import pandas as pd
import pytest
import yaml
from matplotlib.image import imread

from roughcontact.contact.curves import PhysicalSweep
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.reports import speed
from roughcontact.study.config import SpeedReportSettings
from roughcontact.study.presets import ACCURACY_PRESETS, PRESETS_FILE

H = 0.15e-3  # contact element size of the paper's model [m]
PRESSURES = (0.3e6, 1e6, 3e6)


def small_block(grid: int = 12) -> BlockGeometry:
    """12 x 12 contact elements of 0.15 mm on a 2 mm thick block, the paper's mesh."""
    return BlockGeometry(size=(grid * H, grid * H), thickness=2e-3, grid=(grid, grid))


@pytest.fixture(scope="module")
def solver_table():
    geometry = small_block()
    unit = unit_modulus_influence(geometry)
    return speed.solver_speed_vs_error(
        unit, geometry, [(0.0, 3.0)], surfaces=3, generator=speed.CellSurfaces(b=0.3e-3, seed=1),
        sweep=speed.SweepSettings(pressures=PRESSURES, steps=8),
        comparison=speed.SolverComparison(
            methods=("exact", "cg", "steepest"),
            tolerances={"exact": (1e-12,), "cg": (1e-2, 1e-4, 1e-8, 1e-12), "steepest": (1e-4,)}))


def test_solver_table_shape_and_reference(solver_table):
    table = solver_table
    # reference + exact + 4 cg + 1 steepest, each at 3 pressures
    assert len(table) == 7 * len(PRESSURES)
    assert table["reference"].sum() == len(PRESSURES)
    for column in ("wall_s", "matvecs_per_solve", "iterations_per_solve", "load_error",
                   "real_area_error", "max_pressure_error", "k_P_error", "converged_fraction"):
        assert column in table, column
    assert (table["wall_s"] > 0).all()
    assert (table["converged_fraction"] == 1.0).all()


def test_exact_against_itself_has_no_error(solver_table):
    exact = solver_table[solver_table["method"] == "exact"]
    errors = exact[["load_error", "real_area_error", "max_pressure_error", "k_P_error"]]
    assert (errors.to_numpy() <= 1e-6).all()  # the stiffness CG tolerance differs (1e-6)
    assert (exact[["load_error", "real_area_error", "max_pressure_error"]].to_numpy()
            <= 1e-9).all()


def test_cg_error_decreases_as_tolerance_tightens(solver_table):
    cg = solver_table[solver_table["method"] == "cg"]
    worst = cg.groupby("tol")[["load_error", "max_pressure_error"]].max().sort_index(
        ascending=False)  # loose -> tight
    for column in worst:
        values = worst[column].to_numpy()
        assert values[-1] < values[0], column
        assert np.all(np.diff(values) <= 1e-12 + 1e-3 * values[:-1]), (column, values)
    assert worst["load_error"].iloc[-1] < 1e-8
    assert worst["load_error"].iloc[0] > 1e-6


def sweep_with_spread(m: int = 120, seed: int = 3) -> PhysicalSweep:
    """Synthetic power-law sweeps P = c d^1.5 with surface-to-surface scatter."""
    rng = np.random.default_rng(seed)
    d = np.geomspace(1e-6, 1e-4, 20)
    scale = 1.0 + 0.2 * rng.standard_normal((m, 1))
    P = scale * 1e6 * (d / 3e-5) ** 1.5
    ones = np.ones_like(P)
    return PhysicalSweep(
        approach=np.broadcast_to(d, P.shape).copy(), load=P * 1e-4, nominal_pressure=P,
        mean_plane_deflection=0.1 * d * ones, real_area_fraction=0.01 * scale * (P / 1e6),
        max_pressure=50 * P, contact_stiffness=1.5 * P / d * 1e-4,
        normalized_stiffness=1.5 * P / d * 1e-2, iterations=ones.astype(int),
        matvecs=ones.astype(int), residual=0 * ones, converged=ones.astype(bool),
        stiffness_converged=ones.astype(bool), sigma=1e-5, E=1e8, thickness=1e-2,
        nominal_area=1e-4)


def test_band_half_width_shrinks_with_count():
    table = speed.band_vs_count(sweep_with_spread(), PRESSURES, (5, 10, 20, 40, 60, 120),
                                draws=50)
    assert sorted(table["count"].unique()) == [5, 10, 20, 40, 60, 120]
    for _, group in table.groupby("pressure_Pa"):
        for name in ("k_P", "real_area"):
            widths = group.sort_values("count")[f"{name}_relative_half_width"].to_numpy()
            assert np.all(np.diff(widths) < 0), (name, widths)
            # roughly 1/sqrt(n): 5 -> 120 surfaces narrows by about sqrt(24) ~ 5 (t: more)
            assert 3.5 < widths[0] / widths[-1] < 10
    assert (table.loc[table["count"] == 120, "draws"] == 1).all()


def test_counts_above_the_solved_set_are_skipped():
    table = speed.band_vs_count(sweep_with_spread(m=30), (1e6,), (5, 30, 60), draws=5)
    assert sorted(table["count"]) == [5, 30]


def synthetic_tables():
    mesh = pd.DataFrame({
        "mesh": ["paper", "cheap_ok", "dear_ok", "converged"],
        "build_s": [1.0, 10.0, 50.0, 200.0],
        "peak_memory_GB": [0.5, 1.0, 2.0, 8.0],
        "k_P_error": [0.10, 0.01, 0.005, 0.0],
        "real_area_error": [0.8, 0.04, 0.01, 0.0],
        "max_pressure_error": [3.0, 0.02, 0.01, 0.0],
        "reference": "converged",
    })
    solver = pd.DataFrame({
        "influence": "m", "method": ["cg", "cg", "cg", "steepest"],
        "tol": [1e-4, 1e-6, 1e-8, 1e-6], "precision": "mixed", "reference": False,
        "wall_s": [1.0, 2.0, 3.0, 1.5], "converged_fraction": [1.0, 1.0, 1.0, 1.0],
        "load_error": [1e-2, 1e-4, 1e-6, 1e-4], "k_P_error": [0.05, 1e-3, 1e-5, 1e-3],
        "real_area_error": [0.1, 0.01, 0.0, 0.01],
    })
    grid = pd.DataFrame({
        "grid": [30, 30, 60, 60, 120, 120], "pressure_Pa": [1e6, 3e6] * 3,
        "k_P_change": [0.05, 0.04, 0.01, 0.015, 0.0, 0.0],
        "real_area_change": [-0.3, -0.2, -0.04, -0.03, 0.0, 0.0],
        "build_s": [1.0, 1.0, 3.0, 3.0, 20.0, 20.0], "solve_s": [1.0, 1.0, 5.0, 5.0, 60, 60],
        "surfaces": 4,
    })
    counts = pd.DataFrame({
        "count": [5, 10, 20, 40], "pressure_Pa": 1e6, "surfaces_solved": 40,
        "k_P_relative_half_width": [0.05, 0.03, 0.015, 0.01],
        "real_area_relative_half_width": [0.2, 0.1, 0.06, 0.04],
    })
    return solver, mesh, grid, counts


def test_recommend_picks_the_cheapest_option_meeting_the_tolerance():
    solver, mesh, grid, counts = synthetic_tables()
    table = speed.recommend(solver, mesh, grid, counts, tol_kP=0.02, tol_area=0.05)
    choice = table.set_index("component")
    assert choice.loc["mesh", "choice"] == "cheap_ok"
    assert choice.loc["grid", "choice"] == "60 per side"
    # cg 1e-6 (2 s) and steepest 1e-6 (1.5 s) both meet it; steepest is cheaper
    assert choice.loc["solver", "choice"].startswith("steepest tol 1e-06")
    assert choice.loc["surfaces", "choice"] == "40 per cell"
    assert choice.loc[["mesh", "grid", "solver", "surfaces"], "meets"].all()
    assert choice.loc["mesh", "options_meeting"] == 3
    assert "combined" in choice.index
    assert "k_P within 2 %" in table.attrs["text"]


def test_recommend_says_when_nothing_meets_the_tolerance():
    solver, mesh, grid, counts = synthetic_tables()
    table = speed.recommend(solver, mesh, grid, counts, tol_kP=1e-6, tol_area=1e-6)
    choice = table.set_index("component")
    assert not choice.loc["solver", "meets"]
    assert "none meets" in choice.loc["solver", "note"]
    assert not choice.loc["surfaces", "meets"]
    assert "more than 40" in choice.loc["surfaces", "note"]
    assert "does NOT meet" in table.attrs["text"]
    # the mesh reference meets any tolerance by definition; the finest grid does not
    assert choice.loc["mesh", "choice"] == "converged"
    assert not choice.loc["grid", "meets"]
    assert choice.loc["grid", "choice"] == "120 per side"
    assert "not shown converged" in choice.loc["grid", "note"]


def test_mesh_errors_fallback_and_table(tmp_path):
    fallback = speed.mesh_errors(None)
    assert set(fallback["mesh"]) >= {"paper", "refined", "converged"}
    assert (fallback["source"] == "FALLBACK_MESH_ERRORS").all()
    rows = []
    for mesh, k, a, p in (("paper", (0.03, 0.11), (-0.80, -0.84), (2.3, 3.7)),
                          ("converged", (0.0, 0.0), (0.0, 0.0), (0.0, 0.0))):
        for i in range(2):
            rows.append({"mesh": mesh, "kind": "fe", "build_s": 5.0, "peak_memory_GB": 1.0,
                         "k_P_Pa_error": k[i], "real_area_fraction_error": a[i],
                         "max_pressure_Pa_error": p[i], "reference": "converged"})
    path = tmp_path / "conv.csv"
    pd.DataFrame(rows).to_csv(path, index=False)
    table = speed.mesh_errors(path).set_index("mesh")
    assert table.loc["paper", "k_P_error"] == pytest.approx(0.11)
    assert table.loc["paper", "real_area_error"] == pytest.approx(0.84)
    assert table.loc["paper", "real_area_range"] == "-84.0...-80.0 %"


def test_grid_study_nested_is_zero_change_on_the_finest(tmp_path):
    table = speed.grid_study(small_block(), [(0.0, 3.0)], grids=(6, 12), surfaces=2,
                             generator=speed.CellSurfaces(b=0.3e-3, seed=1),
                             sweep=speed.SweepSettings(pressures=(1e6,), steps=8),
                             options=speed.GridOptions(influence="halfspace"))
    assert sorted(table["grid"]) == [6, 12]
    finest = table[table["grid"] == 12]
    assert (finest[["k_P_change", "real_area_change"]].to_numpy() == 0).all()
    assert np.isfinite(table["k_P_change"]).all()


def test_grid_study_self_affine_spectrum_and_fft_halfspace_match_dense():
    spectrum = dict(acf="self-affine", hurst=0.8, rolloff_wavelength=0.9e-3,
                    cutoff_wavelength=0.6e-3)
    generator = speed.CellSurfaces(seed=1, spectrum=spectrum)
    common = dict(grids=(6, 12), surfaces=2,
                  sweep=speed.SweepSettings(pressures=(1e6,), steps=8, tol=1e-10,
                                            precision="double"))
    dense = speed.grid_study(small_block(), generator=generator,
                             options=speed.GridOptions(influence="halfspace"), **common)
    fft = speed.grid_study(small_block(), generator=generator,
                           options=speed.GridOptions(influence="halfspace_fft"), **common)
    assert fft.attrs["spectrum"] == spectrum
    for column in ("k_P_Pa", "real_area_fraction", "max_pressure_Pa"):
        np.testing.assert_allclose(fft[column], dense[column], rtol=1e-6)
    exponential = speed.grid_study(small_block(), generator=speed.CellSurfaces(seed=1),
                                   options=speed.GridOptions(influence="halfspace"), **common)
    assert not np.allclose(exponential["k_P_Pa"], dense["k_P_Pa"])


def test_report_files_have_the_expected_sections(tmp_path, solver_table):
    _, mesh, grid, _ = synthetic_tables()
    counts = speed.band_vs_count(sweep_with_spread(m=20), PRESSURES, (5, 10, 20), draws=5)
    recommendation = speed.recommend(solver_table, mesh, grid, counts)
    md, csv = tmp_path / "r" / "speed.md", tmp_path / "r" / "speed.csv"
    pngs = [tmp_path / "r" / "solver.png", tmp_path / "r" / "counts.png"]
    speed.write_report(solver_table, mesh, grid, counts, recommendation, md, csv, pngs,
                       notes=["a note on the method"])
    text = md.read_text()
    for section in ("# Speed against error", "## Recommendation", "## How it was measured",
                    "## Solver", "## Mesh", "## Contact grid", "## Surfaces per cell",
                    "## Accuracy presets"):
        assert section in text, section
    assert "a note on the method" in text
    assert "cheap_ok" in text
    tidy = pd.read_csv(csv)
    assert set(tidy["table"]) == {"solver", "mesh", "grid", "surfaces", "recommendation"}
    assert len(tidy) == (len(solver_table) + len(mesh) + len(grid) + len(counts)
                         + len(recommendation))
    for png in pngs:
        assert imread(png).shape[0] > 100
    single = tmp_path / "one.png"
    speed.write_report(solver_table, mesh, None, counts, recommendation, md, csv, single)
    assert imread(single).shape[0] > 100
    assert not list((tmp_path / "r").glob(".*tmp*"))  # no temporary files left


def test_accuracy_presets_are_documented_constants():
    assert set(ACCURACY_PRESETS) == {"paper", "fast", "converged"}
    paper = ACCURACY_PRESETS["paper"]
    assert (paper["mesh"], paper["grid_per_9mm"], paper["method"], paper["tol"]) == (
        "paper", 60, "cg", 1e-8)
    for preset in ACCURACY_PRESETS.values():
        for key in ("mesh", "tol", "surfaces", "k_P_error", "real_area_error",
                    "max_pressure_error", "source"):
            assert key in preset
    assert ACCURACY_PRESETS["converged"]["k_P_error"] == 0.0


def test_recommend_shares_tighten_a_component():
    solver, mesh, grid, counts = synthetic_tables()
    table = speed.recommend(solver, mesh, grid, counts, shares={"solver": 0.1})
    choice = table.set_index("component")
    # 10 % of the tolerance: area 0.5 %, k_P 0.2 % -> only cg 1e-8 (area error 0)
    assert choice.loc["solver", "choice"].startswith("cg tol 1e-08")


#: The grid study's spectrum in the scaled-down report (the workflow test runs the
#: report with the exponential ACF): the cut-off two spacings of the finest grid.
REPORT_SPECTRUM = {"acf": "self-affine", "hurst": 0.8, "rolloff_wavelength": 0.9e-3,
                   "cutoff_wavelength": 2 * H}


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    """The Snakemake entry point, scaled down (seconds): output folder and tables."""
    out = tmp_path_factory.mktemp("speed") / "reports"
    tables = speed.speed_vs_error_report(
        speed.ReportFiles(out / "s.md", out / "s.csv", out / "s.png"),
        SpeedReportSettings(surfaces=2, grids=(6, 12), count_surfaces=8, counts=(4, 8)),
        speed.SpeedSpecimen.of_block(small_block(), cells=((0.0, 3.0),),
                                     generator=speed.CellSurfaces(b=0.3e-3, seed=1)),
        speed.SpeedOptions(
            comparison=speed.SolverComparison(tolerances={"cg": (1e-4, 1e-8),
                                                          "steepest": (1e-4,)}),
            steps=6, grid_spectrum=REPORT_SPECTRUM))
    return out, tables


def test_speed_vs_error_report_end_to_end(quick_report):
    """The Snakemake entry point, scaled down: every section produced from scratch."""
    out, tables = quick_report
    assert set(tables) == {"solver", "mesh", "grid", "surfaces", "recommendation"}
    assert (tables["mesh"]["source"] == "FALLBACK_MESH_ERRORS").all()
    assert sorted(tables["grid"]["grid"].unique()) == [6, 12]
    assert sorted(tables["surfaces"]["count"].unique()) == [4, 8]
    text = (out / "s.md").read_text()
    assert "## Recommendation" in text and "Total wall time" in text
    # the grid study ran on the spectrum given, and the notes say so
    assert tables["grid"].attrs["spectrum"] == REPORT_SPECTRUM
    assert "spectrum: self-affine (hurst 0.8, rolloff_wavelength 0.0009" in text
    assert imread(out / "s.png").shape[0] > 100


def structure(presets) -> dict:
    """Sections -> entry names -> key names, in file order."""
    return {section: {name: list(values) for name, values in entries.items()}
            for section, entries in presets.items()}


def test_report_writes_presets_with_the_stored_structure(quick_report):
    out, tables = quick_report
    fresh = yaml.safe_load((out / "accuracy_presets.yaml").read_text())
    stored = yaml.safe_load(PRESETS_FILE.read_text())
    assert structure(fresh) == structure(stored)
    paper, stored_paper = fresh["accuracy_presets"]["paper"], stored["accuracy_presets"]["paper"]
    # measured by this run: cg at the paper preset's tol 1e-8 against the exact solution
    solver = tables["solver"]
    cg = solver[(solver["method"] == "cg") & (solver["tol"] == 1e-8)]
    assert paper["solver_k_P_error"] == pytest.approx(cg["k_P_error"].max(), rel=1e-2)
    # not measured (fallback mesh table, no run with 60 surfaces): the stored numbers
    for key in ("mesh", "tol", "description", "k_P_error", "sampling_k_P"):
        assert paper[key] == stored_paper[key], key
    assert fresh["fallback_mesh_errors"] == stored["fallback_mesh_errors"]
    assert "accuracy_presets.yaml" in (out / "s.md").read_text()


def test_derive_presets_takes_what_the_tables_measure():
    solver, mesh, grid, counts = synthetic_tables()
    mesh["source"] = "conv.csv"
    mesh.loc[mesh["mesh"] == "paper", "mesh"] = "refined"
    grid["element_size_m"] = 9e-3 / grid["grid"]
    counts["count"] = [5, 10, 40, 60]
    stored = {"accuracy_presets": {"paper": dict(ACCURACY_PRESETS["paper"]),
                                   "fast": dict(ACCURACY_PRESETS["fast"])},
              "fallback_mesh_errors": {"refined": {"build_s": 12.8, "k_P_error": 0.5},
                                       "graded": {"build_s": 14.6, "k_P_error": 0.049}}}
    fresh = speed.derive_presets(solver, mesh, grid, counts, stored)
    assert structure(fresh) == structure(stored)
    paper, fast = fresh["accuracy_presets"]["paper"], fresh["accuracy_presets"]["fast"]
    # cg 1e-8 and 1e-6 rows of the solver table
    assert (paper["solver_k_P_error"], paper["solver_real_area_error"]) == (1e-5, 0.0)
    assert (fast["solver_k_P_error"], fast["solver_real_area_error"]) == (1e-3, 0.01)
    # 60 per 9 mm against the finest (120): largest |change| over the pressures
    assert (paper["grid_change_k_P"], paper["grid_change_real_area"]) == (0.015, 0.04)
    # 60 surfaces measured (paper), 20 not (fast keeps the stored numbers)
    assert (paper["sampling_k_P"], paper["sampling_real_area"]) == (0.01, 0.04)
    assert fast["sampling_k_P"] == ACCURACY_PRESETS["fast"]["sampling_k_P"]
    # mesh errors: "refined" measured (fast), "paper" no longer in the table (kept)
    assert (fast["k_P_error"], fast["max_pressure_error"]) == (0.1, 3.0)
    assert paper["k_P_error"] == ACCURACY_PRESETS["paper"]["k_P_error"]
    assert fresh["fallback_mesh_errors"]["refined"] == {"build_s": 1.0, "k_P_error": 0.1}
    assert fresh["fallback_mesh_errors"]["graded"] == {"build_s": 14.6, "k_P_error": 0.049}
    for preset in ("paper", "fast"):
        for key in ("mesh", "tol", "surfaces", "description", "source"):
            assert fresh["accuracy_presets"][preset][key] == ACCURACY_PRESETS[preset][key]


def test_report_builds_each_named_influence():
    """A solver mesh of the report is a preset, "hybrid:<preset>" or Love's "halfspace"."""
    from roughcontact.elasticity.halfspace import halfspace_influence
    from roughcontact.reports.speed.report import _build_influence

    geometry = small_block(6)
    unit, geom = _build_influence(geometry, "halfspace")
    np.testing.assert_array_equal(unit, halfspace_influence(geometry.grid, geometry.size, 1.0,
                                                            geometry.nu))
    assert geom == geometry
    unit, geom = _build_influence(geometry, "paper")
    assert geom.mesh == "paper" and unit.shape == (36, 36)
    np.testing.assert_array_equal(unit, unit_modulus_influence(geom))
