"""The grid-convergence study: extrapolation, kappa, and a tiny run from surfaces to table.

References independent of the code under test: sequences f_h = f0 + c h^p
written out here, a sweep whose area is exactly kappa p*, and for the tiny
run the same surface solved once more here on the finest grid at one
approach by a plain call of the solver.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np
import pandas as pd
import pytest
from matplotlib.image import imread

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.elasticity.halfspace import PeriodicHalfSpace
from roughcontact.errors import StoredFileError
from roughcontact.reports.grid_convergence import (
    KAPPA_REFERENCES,
    converged_grid,
    extrapolate,
    fit_kappa,
    grid_convergence_report,
    kappa_levels,
    plot_grid_convergence,
)
from roughcontact.study.config import GridConvergenceSettings, validated
from roughcontact.study.jobs.grid_convergence import (
    build_grid_surfaces,
    read_grid_contact,
    solve_grid,
)
from roughcontact.study.jobs.storage import read_surfaces

GRIDS = [32, 64, 128, 256]


@pytest.mark.parametrize("order", [1.0, 1.5, 2.0, 3.0])
def test_extrapolation_recovers_a_known_order(order):
    f0, c = 0.0321, -0.4
    values = [f0 + c * (1.0 / g) ** order for g in GRIDS]
    value, observed = extrapolate(GRIDS, values)
    assert observed == pytest.approx(order, rel=1e-9)
    assert value == pytest.approx(f0, rel=1e-9)
    # p = log2((f_4h - f_2h) / (f_2h - f_h)) written out
    assert observed == pytest.approx(math.log2((values[1] - values[2]) / (values[2] - values[3])))


def test_extrapolation_refuses_oscillation_and_uneven_refinement():
    assert all(math.isnan(v) for v in extrapolate(GRIDS, [1.0, 1.2, 0.9, 1.1]))
    assert all(math.isnan(v) for v in extrapolate([32, 64, 96, 256], [1, 2, 3, 3.5]))
    assert all(math.isnan(v) for v in extrapolate([64, 128], [1.0, 1.1]))


def test_converged_grid_is_the_coarsest_from_which_every_finer_grid_is_within():
    reference = 1.0
    values = [1.05, 0.995, 1.012, 1.004]  # 64 is within 1 %, 128 is not, 256 is
    assert converged_grid(GRIDS, values, reference, 0.01) == 256
    assert converged_grid(GRIDS, values, reference, 0.02) == 64
    assert math.isnan(converged_grid(GRIDS, values, math.nan, 0.01))
    assert math.isnan(converged_grid(GRIDS, [1.1, 1.1, 1.1, 1.1], reference, 0.01))


def test_kappa_is_the_slope_through_the_origin_over_the_known_levels():
    levels = np.array([0.0025, 0.005, 0.01, 0.02])
    area = np.array([[2.2 * 0.0025, 2.0 * 0.005, 2.1 * 0.01, 1.9 * 0.02],
                     [np.nan, 0.01, np.nan, np.nan]])
    kappa = fit_kappa(levels, area)
    expected = np.sum(area[0] * levels) / np.sum(levels**2)  # least squares written out
    assert kappa[0] == pytest.approx(expected, rel=1e-12)
    assert 1.9 < kappa[0] < 2.2
    assert math.isnan(kappa[1])  # one known level only


def test_kappa_levels_are_those_whose_mean_area_is_in_range():
    finest = np.array([[0.003, 0.008, 0.05, 0.2], [0.005, 0.012, 0.07, 0.18]])
    chosen = kappa_levels(np.arange(4), finest, (0.005, 0.1))
    assert chosen.tolist() == [False, True, True, False]  # means 0.4 %, 1 %, 6 %, 19 %


def test_literature_values():
    assert KAPPA_REFERENCES["Persson sqrt(8/pi)"] == pytest.approx(1.596, abs=1e-3)
    assert KAPPA_REFERENCES["asperity theory sqrt(2 pi)"] == pytest.approx(2.507, abs=1e-3)


# ---------------------------------------------------------------------------
# A tiny study: 32^2 .. 128^2, two surfaces, the cut-off at 4 .. 16 elements


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    root = tmp_path_factory.mktemp("gridconv")
    params = validated({"reports": {"grid_convergence": {
        "grids": [32, 64, 128], "surfaces": 2, "cutoff_mm": 0.125, "rolloff_mm": 0.5,
        "steps": 10}}})["reports"]["grid_convergence"]
    paths = []
    for grid in params["grids"]:
        build_grid_surfaces(params, 7, grid, root / f"surfaces_{grid}.h5")
        solve_grid(params, root / f"surfaces_{grid}.h5", grid, root / f"contact_{grid}.h5")
        paths.append(root / f"contact_{grid}.h5")
    table = grid_convergence_report(paths, root / "table.csv", root / "figure.png")
    return root, params, paths, table


def test_tiny_study_writes_its_table_and_figure(tiny):
    root, params, _, table = tiny
    stored = pd.read_csv(root / "table.csv")
    # grids x (5 quantities x 5 levels + the two kappas)
    assert len(stored) == len(table) == 3 * (5 * 5 + 2)
    assert set(stored["quantity"]) == {"real_area_fraction", "corrected_real_area_fraction",
                                       "max_pressure", "spot_count", "mean_gap", "kappa",
                                       "kappa_corrected"}
    assert (stored["unconverged_solves"] == 0).all()
    assert imread(root / "figure.png").shape[0] > 300
    area = stored[stored["quantity"] == "real_area_fraction"]
    # real area rises with the load on every grid, and covers about 0.5 .. 10 %
    for _, part in area.groupby("grid"):
        assert np.all(np.diff(part.sort_values("reduced_pressure")["mean"]) > 0)
    assert 0.002 < area["mean"].min() and area["mean"].max() < 0.2
    kappa = stored[stored["quantity"] == "kappa"]
    assert kappa["mean"].between(1.0, 4.0).all()
    # the refinement lowers the area at fixed load (coarse grids overestimate it)
    finest, coarsest = area[area["grid"] == 128], area[area["grid"] == 32]
    assert (finest["mean"].to_numpy() < coarsest["mean"].to_numpy()).sum() >= 4
    # the perimeter correction takes most of that overestimate away: from 32^2 to 128^2
    # the corrected area changes less than the element count at every level
    corrected = stored[stored["quantity"] == "corrected_real_area_fraction"]
    fine, coarse = corrected[corrected["grid"] == 128], corrected[corrected["grid"] == 32]
    count_change = np.abs(coarsest["mean"].to_numpy() / finest["mean"].to_numpy() - 1)
    corrected_change = np.abs(coarse["mean"].to_numpy() / fine["mean"].to_numpy() - 1)
    assert (corrected_change < count_change).all(), (corrected_change, count_change)
    assert (corrected["mean"].to_numpy() < area["mean"].to_numpy()).all()


def test_tiny_study_area_matches_a_direct_solve(tiny):
    """The finest grid's first surface at its third approach, solved again here."""
    root, params, paths, _ = tiny
    settings = GridConvergenceSettings.from_section(params)
    sweep, _ = read_grid_contact(paths[-1])
    heights = read_surfaces(root / "surfaces_128.h5")["heights"][0]
    operator = PeriodicHalfSpace((128, 128), (settings.size, settings.size), settings.E,
                                 settings.nu)
    result = contact.solve(operator, heights.max() - heights, sweep.approach[0, 2],
                           options=SolverOptions(tol=1e-10))
    assert result.real_area_fraction == pytest.approx(sweep.real_area_fraction[0, 2], abs=2e-4)
    assert result.nominal_pressure == pytest.approx(sweep.nominal_pressure[0, 2], rel=1e-5)


def test_a_changed_or_foreign_file_is_refused(tiny, tmp_path):
    root, params, paths, _ = tiny
    with pytest.raises(StoredFileError, match=r"surfaces_64\.h5: made for other parameters.*"
                                              r"grid = 64 in the file, 128 expected"):
        solve_grid(params, root / "surfaces_64.h5", 128, tmp_path / "c.h5")
    with pytest.raises(StoredFileError, match=r"surfaces = 2 in the file, 3 expected"):
        solve_grid(params | {"surfaces": 3}, root / "surfaces_64.h5", 64, tmp_path / "c.h5")
    damaged = tmp_path / "damaged.h5"
    damaged.write_bytes(paths[0].read_bytes())
    with h5py.File(damaged, "r+") as f:
        f["real_area_fraction"][0, 0] += 0.01
    with pytest.raises(StoredFileError, match="no longer match"):
        read_grid_contact(damaged)
    other = tmp_path / "other.h5"
    other.write_bytes(paths[1].read_bytes())
    with h5py.File(other, "r+") as f:
        changed = json.loads(f.attrs["params"])
        f.attrs["params"] = json.dumps(changed | {"surfaces": 3})
    with pytest.raises(ValueError, match="other settings"):
        grid_convergence_report([paths[0], other], tmp_path / "t.csv", tmp_path / "t.png")


def test_the_figure_draws_bands_in_range_and_typesets_its_symbols(tiny, tmp_path):
    _, _, _, table = tiny
    fig = plot_grid_convergence(table, tmp_path / "figure.png")
    area, pressure, kappa = fig.axes[:3]
    for ax in (area, pressure):
        for band in ax.collections:
            ys = np.concatenate([path.vertices[:, 1] for path in band.get_paths()])
            assert ys.min() > 0
    assert area.get_ylabel().startswith("real area fraction $A / A_0$")
    assert kappa.get_ylabel().startswith(r"$\kappa")
    assert all(text.get_text().startswith("$p^*$") for text in area.get_legend().get_texts())
