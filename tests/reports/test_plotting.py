"""Figure helpers of the notebooks: tables as CSV and as figures, 3-D surface panels,
curves against nominal pressure per mesh or per cell, two bodies, the study summary."""

import json

import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from roughcontact.errors import StoredFileError  # noqa: E402
from roughcontact.hashes import file_sha256  # noqa: E402
from roughcontact.reports.plotting import (  # noqa: E402
    cells_at_pressures,
    describe_study,
    draw_surfaces,
    draw_table,
    plot_by_mesh,
    plot_cells,
    plot_cells_panels,
    save_table,
    surface_moments,
)
from roughcontact.reports.study_figures import (  # noqa: E402
    leakage_pressures,
    load_percolation,
    load_studies,
    plot_leakage,
    plot_two_bodies,
)
from roughcontact.study.jobs import storage  # noqa: E402


def test_save_table_writes_the_csv_and_clears_stale_temporaries(tmp_path):
    frame = pd.DataFrame({"nu": [0.0, 0.3], "E_u_mean_MPa": [511.0, 523.2095484676289]})
    stale = tmp_path / ".table_Eu.tmp999999999.csv"  # no such process
    stale.write_text("half")
    save_table(frame, tmp_path / "table_Eu.csv")
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "table_Eu.csv"), frame)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["table_Eu.csv"]


def test_draw_table_holds_every_cell_under_its_header():
    frame = pd.DataFrame({r"$\nu$": ["0", "0.3"], "$E_u$ [MPa]": ["511.00 ± 0.00",
                                                                  "523.21 ± 0.01"]})
    fig = draw_table(frame, title="$E_u$")
    (table,) = fig.axes[0].tables
    cells = table.get_celld()
    assert [cells[0, j].get_text().get_text() for j in range(2)] == list(frame.columns)
    assert cells[2, 1].get_text().get_text() == "523.21 ± 0.01"
    fig.canvas.draw()  # the mathtext headers render
    renderer = fig.canvas.get_renderer()
    for j in range(2):  # each column as wide as its widest entry
        width = cells[0, j].get_window_extent(renderer).width
        assert all(cells[i, j].get_text().get_window_extent(renderer).width < width
                   for i in range(3))
    plt.close(fig)


@pytest.mark.parametrize("panels", [2, 5])
def test_surface_panel_titles_are_legible(monkeypatch, panels):
    """Fig 3 and 4: two-line titles neither overlap each other or another panel nor
    leave the figure, and stay legible (5 pt or more) on a page 7 in wide, whatever
    the number of panels (a row of five panels shrank them to 3 pt)."""
    rng = np.random.default_rng(0)

    def fake_read(path, count=None, cell=None):
        return {"spec": {"size": [4.8e-3, 4.8e-3]}, "heights": rng.standard_normal((1, 16, 16))}

    monkeypatch.setattr(storage, "read_surfaces", fake_read)
    titles = [f"target Sk = -0.8, Ku = {k}\nrealised Sk = -0.75, Ku = 3.53" for k in range(panels)]
    fig = draw_surfaces([f"s{k}.h5" for k in range(panels)], 40.0, titles)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    boxes = [ax.title.get_window_extent(renderer) for ax in fig.axes]
    assert [ax.get_title() for ax in fig.axes] == titles
    shrink = min(1.0, 7.0 / fig.get_figwidth())
    assert all(ax.title.get_fontsize() * shrink >= 5.0 for ax in fig.axes)
    for k, box in enumerate(boxes):
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1
        for j, other in enumerate(boxes):
            assert j == k or not box.overlaps(other), (k, j)
        for j, ax in enumerate(fig.axes):  # nor the panel above (its axis labels)
            below = ax.get_tightbbox(renderer)
            assert j == k or not box.overlaps(below), (k, j)
    plt.close(fig)


def aggregate_table() -> pd.DataFrame:
    """Two cells on each of two meshes, three pressure levels each (an aggregate table)."""
    rows = []
    for cell, (mesh, skew, kurt) in enumerate([("paper", 0.0, 3.0), ("paper", -0.8, 4.0),
                                               ("refined", 0.0, 3.0), ("refined", -0.8, 4.0)]):
        for level, P in enumerate((1e5, 1e6, 5e6)):
            rows.append({"cell": cell, "mesh": mesh, "skew": skew, "kurt": kurt, "b_mm": 0.5,
                         "label": f"Sk {skew:g}, Ku {kurt:g}, {mesh} mesh", "surfaces": 4,
                         "unconverged_steps": cell, "nominal_pressure": P,
                         "normalized_stiffness_mean": (cell + 1) * 1e8 * (level + 1),
                         "normalized_stiffness_half_width": 1e7,
                         "normalized_stiffness_count": 4})
    return pd.DataFrame(rows)


def test_plot_by_mesh_draws_one_panel_per_mesh_with_a_curve_per_cell():
    table = aggregate_table()
    validity = pd.DataFrame({"cell": [3, 3], "flagged": [False, True],
                             "nominal_pressure": [1e6, 5e6], "threshold": [0.05, 0.05],
                             "hardness_MPa": [80.0, 80.0]})
    fig = plot_by_mesh(table, validity, "normalized_stiffness", y_scale=1e-6,
                       ylabel="$k_P$ [MPa]", title="Fig 7", log_y=True)
    paper, refined = fig.axes
    assert [ax.get_title() for ax in fig.axes] == ["Fig 7 (paper mesh)", "Fig 7 (refined mesh)"]
    assert paper.get_ylabel() == "$k_P$ [MPa]"
    assert all(ax.get_xscale() == "log" and ax.get_yscale() == "log" for ax in fig.axes)
    assert [t.get_text() for t in paper.get_legend().get_texts()] == [
        "Sk = 0, Ku = 3", "Sk = -0.8, Ku = 4"]
    np.testing.assert_allclose(paper.lines[1].get_ydata(), [200.0, 400.0, 600.0])
    assert not paper.texts and len(refined.texts) == 1  # cell 3 flagged from 5 MPa
    assert "H = 80 MPa" in refined.texts[0].get_text()
    plt.close(fig)


def test_plot_cells_labels_each_cell_from_its_row():
    table = aggregate_table()
    fig = plot_cells(table[table["mesh"] == "paper"], "normalized_stiffness", y_scale=1e-6,
                     ylabel="$k_P$ [MPa]", title="Fig 11", label="Sk {skew:g}, $b$ = {b_mm:g} mm",
                     legend_fontsize=8)
    (ax,) = fig.axes
    assert ax.get_title() == "Fig 11" and ax.get_xscale() == "log"
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [
        "Sk 0, $b$ = 0.5 mm", "Sk -0.8, $b$ = 0.5 mm"]
    assert ax.get_legend().get_texts()[0].get_fontsize() == 8
    plt.close(fig)


def b_table() -> pd.DataFrame:
    """Three correlation lengths at three levels: k_P and real area with half widths."""
    rows = []
    for cell, b in enumerate((2.0, 0.5, 1.0)):
        for P in (1e5, 1e6, 5e6):
            rows.append({"cell": cell, "b_mm": b, "nominal_pressure": P, "surfaces": 4,
                         "normalized_stiffness_mean": 3e8 + 1e7 * b,
                         "normalized_stiffness_half_width": 4e6,
                         "normalized_stiffness_count": 4,
                         "real_area_fraction_mean": 0.01 * b,
                         "real_area_fraction_half_width": 1e-3,
                         "real_area_fraction_count": 4})
    return pd.DataFrame(rows)


def test_plot_cells_panels_draws_each_quantity_with_a_curve_per_cell():
    panels = [("normalized_stiffness", 1e-6, "$k_P$ [MPa]", False),
              ("real_area_fraction", 100.0, "area [%]", True)]
    fig = plot_cells_panels(b_table(), panels, label="$b$ = {b_mm:g} mm", title="Fig 11")
    stiffness, area = fig.axes
    assert (stiffness.get_ylabel(), area.get_ylabel()) == ("$k_P$ [MPa]", "area [%]")
    assert stiffness.get_yscale() == "linear" and area.get_yscale() == "log"
    assert [t.get_text() for t in stiffness.get_legend().get_texts()] == [
        "$b$ = 2 mm", "$b$ = 0.5 mm", "$b$ = 1 mm"]
    np.testing.assert_allclose(area.lines[1].get_ydata(), [0.5, 0.5, 0.5])
    assert fig.get_suptitle() == "Fig 11"
    plt.close(fig)


def test_cells_at_pressures_reads_the_nearest_level_and_compares_the_extremes():
    at = cells_at_pressures(b_table(), ["normalized_stiffness", "real_area_fraction"],
                            [1.2e6, 4e6], by="b_mm").set_index(["quantity", "nominal_pressure"])
    assert list(at.index.get_level_values(1)) == [1e6, 5e6, 1e6, 5e6]
    row = at.loc[("normalized_stiffness", 1e6)]
    assert [row[f"b_mm={b:g} mean"] for b in (0.5, 1.0, 2.0)] == [3.05e8, 3.1e8, 3.2e8]
    # extremes 1.5e7 apart, half width of the difference sqrt(2) * 4e6 = 5.7e6
    assert row["spread"] == pytest.approx(1.5e7 / np.mean([3.05e8, 3.1e8, 3.2e8]))
    assert row["separated"]
    area = at.loc[("real_area_fraction", 5e6)]
    assert area["separated"] and area["spread"] == pytest.approx(0.015 / (0.035 / 3))
    wide = b_table().assign(normalized_stiffness_half_width=1.1e7)  # sqrt(2) * 1.1e7 > 1.5e7
    assert not cells_at_pressures(wide, ["normalized_stiffness"], [1e6],
                                  by="b_mm")["separated"].iloc[0]


def test_describe_study_names_every_cell_under_the_note():
    lines = describe_study(aggregate_table()).splitlines()
    assert lines[0].startswith("4-4 surfaces per curve") and lines[0].endswith("excluded: 6")
    assert lines[1] == "cells:"
    assert lines[2:] == ["   Sk 0, Ku 3, paper mesh", "   Sk -0.8, Ku 4, paper mesh",
                         "   Sk 0, Ku 3, refined mesh", "   Sk -0.8, Ku 4, refined mesh"]


def test_surface_moments_are_those_of_each_files_first_surface(monkeypatch):
    """Figs 3 and 4: realised std [um], Sk and Ku of the surface each panel shows."""
    stored = {"a.h5": {"sigma": [0.9, 1.1], "skew": [0.1, 0.2], "kurt": [2.9, 3.1]},
              "b.h5": {"sigma": [1.05], "skew": [-0.75], "kurt": [3.5]}}
    monkeypatch.setattr(storage, "read_surfaces",
                        lambda path, count=None, cell=None: {"stats": stored[path]})
    table = surface_moments(["a.h5", "b.h5"], 40.0)
    assert list(table.columns) == ["file", "sigma_um", "skew", "kurt"]
    assert table["file"].tolist() == ["a.h5", "b.h5"]
    np.testing.assert_allclose(table["sigma_um"], [36.0, 42.0])
    assert table["skew"].tolist() == [0.1, -0.75] and table["kurt"].tolist() == [2.9, 3.5]


def test_the_figures_draw_only_surfaces_made_for_their_cells(tmp_path):
    cell = {"skew": 0.0, "kurt": 3.0, "b_mm": [0.5, 0.5], "grid": [4, 4], "size_mm": [1, 1],
            "acf": "exponential", "periodic": True, "method": "filter", "count": 1}
    path = tmp_path / "cell.h5"
    storage.write_surfaces(path, {"heights": np.zeros((1, 4, 4)), "seeds": np.zeros(1),
                                  "stats/sigma": [1.0], "stats/skew": [0.0],
                                  "stats/kurt": [3.0]},
                           {"spec": "{}", "params": json.dumps(cell)})
    assert surface_moments([path], 40.0, cells=[cell])["kurt"].tolist() == [3.0]
    with pytest.raises(StoredFileError, match=r"cell\.h5: made for other parameters.*kurt = 3 "
                                              r"in the file, 4 expected"):
        surface_moments([path], 40.0, cells=[cell | {"kurt": 4.0}])
    with pytest.raises(StoredFileError, match="kurt = 3 in the file, 4 expected"):
        draw_surfaces([path], 40.0, ["t"], cells=[cell | {"kurt": 4.0}])


#: The counter columns of a cell pressed against a half-space, a block, or nothing (the
#: rigid smooth flat: named, its other counter columns NaN), as the aggregate tables
#: write them.
HALFSPACE = {"counter": "half-space E 110000 MPa nu 0.26 (sigma 1.5 um)",
             "counter_body": "half-space E 110000 MPa nu 0.26", "counter_sigma_um": 1.5,
             "counter_skew": 0.0, "counter_kurt": 3.0}
BLOCK = {"counter": "block E 210000 MPa nu 0.3 10 mm refined (sigma 0.8 um)",
         "counter_body": "block E 210000 MPa nu 0.3 10 mm refined", "counter_sigma_um": 0.8,
         "counter_skew": 0.0, "counter_kurt": 3.0}
FLAT = {"counter": "rigid smooth flat", "counter_body": float("nan"),
        "counter_sigma_um": float("nan"), "counter_skew": float("nan"),
        "counter_kurt": float("nan")}


def two_bodies_table(counters, shares, k_P, E_MPa) -> pd.DataFrame:
    """A two-bodies study: one cell per counter body (its share of d_b, None where it is
    not reported), three levels, k_P [Pa], real area, mean gap and the counter columns."""
    rows = []
    for cell, (counter, share, k) in enumerate(zip(counters, shares, k_P, strict=True)):
        for level, P in enumerate((1e6, 3e6, 1e7)):
            reported = share is not None
            rows.append({"cell": cell, "nominal_pressure": P, "surfaces": 5, "mesh": "refined",
                         "sigma_um": 5.0, "E_MPa": E_MPa, "nu": 0.25, "thickness_mm": 10.0,
                         "normalized_stiffness_mean": k * (1 + level),
                         "normalized_stiffness_half_width": 0.02 * k,
                         "normalized_stiffness_count": 5,
                         "real_area_fraction_mean": 0.01 * (1 + level) * (1 + cell),
                         "real_area_fraction_half_width": 1e-3,
                         "real_area_fraction_count": 5,
                         "mean_gap_mean": 4e-6 / (1 + level), "mean_gap_half_width": 2e-7,
                         "mean_gap_count": 5,
                         "counter_share_mean": share if reported else np.nan,
                         "counter_share_half_width": 1e-3 if reported else np.nan,
                         "counter_share_count": 5 if reported else 0, **counter})
    return pd.DataFrame(rows)


def test_plot_two_bodies_draws_each_counter_body_beside_the_rigid_flat():
    """A row per study, four panels: k_P, real area, mean gap and the shares of d_b; a
    curve and band per cell in the first three, the counter body's share and the first
    body's (1 - share) for each modelled counter body, none for the flat or a counter
    body treated as rigid; the legend names each counter body."""
    tables = {"pad_on_disc": two_bodies_table([HALFSPACE, FLAT], [0.015, None], [1e9, 1.1e9],
                                              2000.0),
              "steel_plates": two_bodies_table([BLOCK, HALFSPACE | {"counter_E_MPa": 1e7}, FLAT],
                                               [0.5, None, None], [7e10, 1.2e11, 1.3e11],
                                               210000.0)}
    fig = plot_two_bodies(tables)
    assert len(fig.axes) == 8
    pad, plates = fig.axes[:4], fig.axes[4:]
    assert [t.get_text() for t in pad[0].get_legend().get_texts()] == [
        "half-space E 110000 MPa nu 0.26 (sigma 1.5 um)", "rigid smooth flat"]
    assert [t.get_text() for t in plates[0].get_legend().get_texts()] == [
        "block E 210000 MPa nu 0.3 10 mm refined (sigma 0.8 um)",
        "half-space E 110000 MPa nu 0.26 (sigma 1.5 um) (treated as rigid)",
        "rigid smooth flat"]
    for row, cells in ((pad, 2), (plates, 3)):
        for ax in row[:3]:  # a curve and a band per cell
            assert len(ax.lines) == len(ax.collections) == cells
            assert ax.get_xscale() == "log"
        assert row[1].get_yscale() == "log" and row[2].get_yscale() == "linear"
        assert row[0].lines[-1].get_color() == "k"  # the rigid smooth flat
    # the shares: the counter body's and the first body's, in per cent, with their bands
    assert len(pad[3].lines) == len(pad[3].collections) == 2
    np.testing.assert_allclose(pad[3].lines[0].get_ydata(), [1.5] * 3)
    np.testing.assert_allclose(pad[3].lines[1].get_ydata(), [98.5] * 3)
    assert pad[3].lines[1].get_linestyle() == "--"
    assert len(plates[3].lines) == 2  # the block's; none for the half-space treated as rigid
    np.testing.assert_allclose(plates[3].lines[1].get_ydata(), [50.0] * 3)
    assert [t.get_text() for t in pad[3].get_legend().get_texts()] == [
        "half-space E 110000 MPa nu 0.26 (sigma 1.5 um)", "counter body", "first body"]
    # units: MPa for the pad, GPa for the steel (above 10 GPa); the row names its study
    assert pad[0].get_ylabel() == "normalized stiffness $k_P$ [MPa]"
    assert plates[0].get_ylabel() == "normalized stiffness $k_P$ [GPa]"
    np.testing.assert_allclose(plates[0].lines[0].get_ydata(), [70.0, 140.0, 210.0])
    assert pad[0].get_title(loc="left").startswith("pad_on_disc: first body")
    assert "$E$ = 2000 MPa" in pad[0].get_title(loc="left")
    assert plates[3].get_ylabel() == "share of the mean-plane deflection $d_b$ [%]"
    plt.close(fig)
    # the legend is the table's counter column, as written
    named = two_bodies_table([HALFSPACE | {"counter": "the disc"}, FLAT], [0.015, None],
                             [1e9, 1.1e9], 2000.0)
    fig = plot_two_bodies({"pad_on_disc": named})
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == [
        "the disc", "rigid smooth flat"]
    plt.close(fig)
    # a study of one body only (no counter columns): no share, said so, on its P axis
    one = two_bodies_table([FLAT], [None], [1e9], 255.5)
    fig = plot_two_bodies({"half": one.drop(columns=[c for c in one if "counter" in c])})
    assert fig.axes[0].get_legend().get_texts()[0].get_text() == "rigid smooth flat"
    share = fig.axes[3]
    assert not share.lines and share.texts[0].get_text() == "no counter body modelled"
    assert share.get_xlim() == fig.axes[0].get_xlim()
    plt.close(fig)


def test_load_studies_reads_four_files_per_study_in_order(tmp_path):
    paths = []
    for name, k in (("a", 1.0), ("b", 2.0)):
        table, moduli = tmp_path / f"{name}.csv", tmp_path / f"{name}.moduli.csv"
        pd.DataFrame({"cell": [0], "k": [k]}).to_csv(table, index=False)
        pd.DataFrame({"cell": [0]}).to_csv(moduli, index=False)
        meta = tmp_path / f"{name}.json"
        meta.write_text(json.dumps({"table_sha256": file_sha256(table),
                                    "moduli_sha256": file_sha256(moduli)}))
        paths += [table, moduli, meta, tmp_path / f"{name}.validity.csv"]
    tables = load_studies(paths, ["a", "b"])
    assert list(tables) == ["a", "b"] and tables["b"]["k"].tolist() == [2.0]
    with pytest.raises(ValueError, match="7 aggregate files for 2 studies"):
        load_studies(paths[:7], ["a", "b"])


#: Leak rate [m^3/s] along x of two cells at five levels: the first seals at the fourth.
LEAK = {0: [4e-6, 1e-7, 1e-9, 0.0, 0.0], 1: [6e-6, 5e-7, 3e-8, 2e-10, 5e-12]}


def leakage_table(directions=("x", "y")) -> pd.DataFrame:
    """A leakage study of two cells, (Sk, Ku) = (0, 3) and (-0.8, 4), five levels, every
    level on all 4 surfaces; the leak rate of :data:`LEAK` (y: half of x), flow factor,
    real area and the share of surfaces still leaking (0 once sealed)."""
    rows = []
    for cell, (skew, kurt) in enumerate(((0.0, 3.0), (-0.8, 4.0))):
        for level, P in enumerate((1e5, 3e5, 1e6, 3e6, 1e7)):
            row = {"cell": cell, "skew": skew, "kurt": kurt, "nominal_pressure": P,
                   "surfaces": 4, "sigma_um": 5.0, "b_mm": 0.5, "E_MPa": 511.0,
                   "coverage": "all surfaces",
                   "real_area_fraction_mean": 0.1 * (level + 1),
                   "real_area_fraction_half_width": 0.01, "real_area_fraction_count": 4,
                   "mean_gap_mean": 5e-6 / (level + 1), "mean_gap_half_width": 1e-7,
                   "mean_gap_count": 4}
            for d, scale in zip(directions, (1.0, 0.5), strict=False):
                leak = scale * LEAK[cell][level]
                row |= {f"leak_rate_{d}_mean": leak, f"leak_rate_{d}_half_width": 0.1 * leak,
                        f"leak_rate_{d}_count": 4,
                        f"flow_factor_{d}_mean": 0.8 * leak / LEAK[1][0],
                        f"flow_factor_{d}_half_width": 0.1 * 0.8 * leak / LEAK[1][0],
                        f"flow_factor_{d}_count": 4,
                        f"flow_connected_{d}_mean": float(leak > 0),
                        f"flow_connected_{d}_half_width": 0.0, f"flow_connected_{d}_count": 4}
            rows.append(row)
    return pd.DataFrame(rows)


#: Percolation thresholds of the two cells of :func:`leakage_table`: the first sealed inside
#: the swept range along x and y, the second not (above it: no numbers).
THRESHOLDS = pd.DataFrame([
    {"cell": 0, "direction": "x", "area": 0.38, "area_low": 0.33, "area_high": 0.41},
    {"cell": 0, "direction": "y", "area": 0.40, "area_low": 0.35, "area_high": 0.44},
    {"cell": 1, "direction": "x", "area": np.nan, "area_low": 0.45, "area_high": np.nan},
    {"cell": 1, "direction": "y", "area": np.nan, "area_low": 0.45, "area_high": np.nan}])


def test_plot_leakage_draws_each_cell_along_x_and_y_with_its_threshold():
    """Four panels a study: leak rate (the positive levels only, log), flow factor against
    P, flow factor against real area with the thresholds and Dapp's 0.42, share still
    leaking; a curve per cell and direction, y dashed; the legend names each by its study
    and (Sk, Ku)."""
    fig = plot_leakage({"seal": leakage_table()}, {"seal": THRESHOLDS})
    leak, factor, area, connected = fig.axes
    assert [t.get_text() for t in leak.get_legend().get_texts()] == [
        "seal: Sk = 0, Ku = 3", "seal: Sk = -0.8, Ku = 4"]
    for ax in (leak, factor, connected):  # a curve and a band per cell and direction
        assert len(ax.lines) == len(ax.collections) == 4
        assert ax.get_xscale() == "log"
    assert leak.get_yscale() == "log" and area.get_yscale() == "log"
    assert [line.get_linestyle() for line in leak.lines] == ["-", "--", "-", "--"]
    # the sealed cell's leak rate at its three positive levels only, in m^3/s
    np.testing.assert_allclose(leak.lines[0].get_xdata(), [0.1, 0.3, 1.0])
    np.testing.assert_allclose(leak.lines[0].get_ydata(), LEAK[0][:3])
    np.testing.assert_allclose(leak.lines[3].get_ydata(), np.array(LEAK[1]) / 2)
    np.testing.assert_allclose(connected.lines[0].get_ydata(), [100, 100, 100, 0, 0])
    # the flow factor against real area: 4 curves (where > 0), the first cell's two
    # thresholds (x solid, y dotted), none for the cell not sealed, and Dapp et al.'s 0.42
    marks = [line for line in area.lines if len(set(line.get_xdata())) == 1]  # vertical
    curves = [line for line in area.lines if line not in marks]
    assert len(curves) == 4
    np.testing.assert_allclose(curves[0].get_xdata(), [0.1, 0.2, 0.3])
    assert [(m.get_xdata()[0], m.get_linestyle()) for m in marks] == [
        (0.38, "-"), (0.40, ":"), (0.42, "--")]
    assert marks[0].get_color() == curves[0].get_color() == leak.lines[0].get_color()
    (span,) = area.patches  # the x threshold's band of the first cell
    np.testing.assert_allclose(span.get_x(), 0.33)
    np.testing.assert_allclose(span.get_width(), 0.41 - 0.33)
    assert "percolation threshold (y)" in [t.get_text() for t in area.get_legend().get_texts()]
    assert leak.get_xlim() == factor.get_xlim() == connected.get_xlim()  # one P axis
    assert leak.get_title(loc="left").startswith("seal: $\\sigma$ = 5 µm")
    plt.close(fig)
    # along x only: a curve per cell, no y thresholds or their key
    fig = plot_leakage({"seal": leakage_table(("x",))}, {"seal": THRESHOLDS})
    leak, _, area, _ = fig.axes
    assert len(leak.lines) == 2 and len(area.lines) == 2 + 1 + 1 and len(area.patches) == 1
    assert "percolation threshold (y)" not in [
        t.get_text() for t in area.get_legend().get_texts()]
    plt.close(fig)


def test_leakage_pressures_span_the_levels_where_every_cell_is_solved_and_one_leaks():
    table = leakage_table()
    assert leakage_pressures(table) == [1e5, 1e6, 1e7]  # cell 1 leaks up to 10 MPa
    table.loc[(table["cell"] == 1) & (table["nominal_pressure"] == 1e5), "coverage"] = \
        "some surfaces"
    table.loc[table["nominal_pressure"] == 1e7, [c for c in table if c.startswith("leak")
                                                 and c.endswith("_mean")]] = 0.0
    assert leakage_pressures(table) == [3e5, 1e6, 3e6]


def test_load_percolation_reads_the_sidecars_thresholds(tmp_path):
    """The thresholds of each study from its sidecar (checked as the tables are), the
    sidecar's nulls as NaN; a study solved without the flow is refused, naming it."""
    paths = []
    for name, flow in (("seal", {"percolation": [
            {"cell": 0, "direction": "x", "area": 0.42, "area_low": 0.4, "area_high": 0.44,
             "pressure_MPa": 4.6, "pressure_low_MPa": None, "pressure_high_MPa": 4.7}]}),
            ("dry", None)):
        table, moduli = tmp_path / f"{name}.csv", tmp_path / f"{name}.moduli.csv"
        table.write_text("cell\n0\n")
        moduli.write_text("cell\n0\n")
        meta = {"table_sha256": file_sha256(table), "moduli_sha256": file_sha256(moduli)}
        if flow:
            meta["flow"] = flow
        (tmp_path / f"{name}.json").write_text(json.dumps(meta))
        paths += [table, moduli, tmp_path / f"{name}.json", tmp_path / f"{name}.validity.csv"]
    found = load_percolation(paths[:4], ["seal"])
    assert found["seal"]["area"].tolist() == [0.42]
    assert np.isnan(found["seal"]["pressure_low_MPa"].iloc[0])
    with pytest.raises(ValueError, match=r"dry.json: study 'dry' was solved without the flow"):
        load_percolation(paths, ["seal", "dry"])
