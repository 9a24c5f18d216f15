"""Tests of the influence-coefficient mesh-convergence study (roughcontact.convergence)."""

import math
import re

import numpy as np
import pytest
from matplotlib.image import imread

from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import BlockGeometry, MeshSpec
from roughcontact.elasticity.influence import unit_modulus_influence as build
from roughcontact.reports.convergence import (
    COLUMNS,
    CONTACT_QUANTITIES,
    ENTRY_QUANTITIES,
    HALFSPACE,
    influence_convergence,
    plot_influence_convergence,
    richardson,
)
from roughcontact.study.config import ConvergenceSettings

H = 0.15e-3  # contact element size of the paper's model [m]
PRESSURES = (0.3e6, 1e6)


def thick_block(**kwargs) -> BlockGeometry:
    """12 x 12 contact elements of 0.15 mm on a 2 mm thick block (thick: near-half-space)."""
    return BlockGeometry(size=(12 * H, 12 * H), thickness=2e-3, grid=(12, 12), **kwargs)


@pytest.fixture(scope="module")
def study():
    messages = []
    settings = ConvergenceSettings(presets=("paper", "refined"), surfaces=2,
                                   corr_length=0.5e-3, pressures=PRESSURES)
    table = influence_convergence(thick_block(), settings, progress=messages.append)
    return table, messages


def rows(table, mesh):
    return table[table["mesh"] == mesh].reset_index(drop=True)


def test_tidy_shape_columns_and_units(study):
    table, _ = study
    assert len(table) == 3 * len(PRESSURES)  # paper, refined, half-space x pressures
    assert list(dict.fromkeys(table["mesh"])) == ["paper", "refined", HALFSPACE]
    for column in COLUMNS:
        assert column in table, column
    for q in ENTRY_QUANTITIES + CONTACT_QUANTITIES:
        assert q + "_error" in table, q
    assert table.attrs["units"]["k_P_Pa"] == "Pa"
    assert table.attrs["units"]["peak_memory_GB"] == "GB"
    assert table.attrs["units"]["asperity_deflection_m"] == "m"
    assert set(table["pressure_Pa"]) == set(PRESSURES)
    # the default reference is the last preset when "converged" is absent
    assert (table["reference"] == "refined").all()
    assert "not applied" in table.attrs["richardson"]


def test_cost_columns_are_measured(study):
    table, messages = study
    fe = table[table["kind"] == "fe"].drop_duplicates("mesh")
    assert (fe["dofs"] > 0).all() and (fe["build_s"] > 0).all()
    assert rows(table, "refined")["dofs"][0] > rows(table, "paper")["dofs"][0]
    # a fresh process holds at least the interpreter and numpy/scipy
    assert (fe["peak_memory_GB"] > 0.03).all() and (fe["peak_memory_GB"] < 4).all()
    assert (fe["memory_increase_GB"] >= 0).all()
    assert len(messages) == 3
    assert all("elapsed" in m for m in messages)
    assert messages[0].startswith("paper") and messages[2].startswith(HALFSPACE)


def test_entries_match_an_independent_build(study):
    table, _ = study
    geom = thick_block(mesh="paper")
    ec = build(geom)
    c = 6 * 12 + 6
    paper = rows(table, "paper")
    assert paper["self_compliance"][0] == pytest.approx(ec[c, c] / H, rel=1e-10)
    assert paper["neighbour_1_1"][0] == pytest.approx(ec[c, c + 13] / H, rel=1e-10)
    assert paper["neighbour_2_0"][0] == pytest.approx(ec[c, c + 2] / H, rel=1e-10)
    assert paper["far_offset"][0] == 5  # 10 clipped to the grid (centre at ix = 6 of 12)
    assert paper["far_entry"][0] == pytest.approx(ec[c, c + 5] / H, rel=1e-10)
    hs = halfspace_influence((12, 12), geom.size, 1.0, 0.0)
    love = rows(table, HALFSPACE)
    assert love["self_compliance"][0] == pytest.approx(hs[c, c] / H, rel=1e-12)
    assert love["neighbour_1_0"][0] == pytest.approx(hs[c, c + 1] / H, rel=1e-12)


def test_refined_mesh_is_closer_to_love_than_the_paper_mesh(study):
    table, _ = study
    love = rows(table, HALFSPACE)["self_compliance"][0]
    paper = abs(rows(table, "paper")["self_compliance"][0] / love - 1)
    refined = abs(rows(table, "refined")["self_compliance"][0] / love - 1)
    assert refined < paper
    assert paper > 0.3  # 0.4 mm thick trilinear layers under 0.15 mm elements: far too stiff
    assert refined < 0.05


def test_row_sums_equal_thickness_for_nu_zero(study):
    table, _ = study
    paper = rows(table, "paper")
    assert paper["row_sum_max_error"][0] < 1e-9  # exact for one trilinear element (Eq 38)
    assert rows(table, "refined")["row_sum_max_error"][0] < 0.02  # symmetrized centre values
    assert rows(table, "refined")["row_sum_over_L"][0] == pytest.approx(1.0, abs=2e-3)
    # the half-space has no bottom: its rows do not sum to L
    assert rows(table, HALFSPACE)["row_sum_max_error"][0] > 0.1


def test_errors_are_relative_to_the_reference(study):
    table, _ = study
    ref = rows(table, "refined")
    for q in ENTRY_QUANTITIES + CONTACT_QUANTITIES:
        np.testing.assert_array_equal(ref[q + "_error"], 0.0)
    paper = rows(table, "paper")
    for q in ("self_compliance", "neighbour_1_0", "k_P_Pa", "max_pressure_Pa"):
        np.testing.assert_allclose(paper[q + "_error"], paper[q] / ref[q] - 1, rtol=1e-12)
    assert paper["self_compliance_error"][0] < -0.3


def test_contact_quantities_are_consistent(study):
    table, _ = study
    geom = thick_block()
    assert table["reached"].all()
    assert (table["surfaces"] == 2).all()
    for mesh in ("paper", "refined", HALFSPACE):
        r = rows(table, mesh)
        assert (r["k_P_Pa"] > 0).all()
        assert (np.diff(r["real_area_fraction"]) > 0).all()
        assert (np.diff(r["max_pressure_Pa"]) > 0).all()
        assert (r["max_pressure_Pa"] > r["pressure_Pa"]).all()
        np.testing.assert_allclose(r["asperity_deflection_m"],
                                   r["approach_m"] - r["mean_plane_deflection_m"], rtol=1e-12)
    # nu = 0 and exact row sums L/E: the mean plane moves by P L / E (Eq 36)
    paper = rows(table, "paper")
    np.testing.assert_allclose(paper["mean_plane_deflection_m"],
                               paper["pressure_Pa"] * geom.thickness / geom.E, rtol=1e-6)
    # the stiff paper mesh gives smaller real area and higher peak pressure
    refined = rows(table, "refined")
    assert (paper["real_area_fraction"] < refined["real_area_fraction"]).all()
    assert (paper["max_pressure_Pa"] > refined["max_pressure_Pa"]).all()


def test_plot_writes_a_png(study, tmp_path):
    table, _ = study
    path = tmp_path / "convergence.png"
    plot_influence_convergence(table, path)
    image = imread(path)
    assert image.shape[0] > 600 and image.shape[1] > 1000
    assert image[..., :3].std() > 0.05  # not blank


def test_plot_typesets_its_symbols(study, tmp_path):
    table, _ = study
    fig = plot_influence_convergence(table, tmp_path / "convergence.png")
    stiffness = fig.axes[2]
    assert stiffness.get_ylabel() == "$k_P$ [MPa]"  # was the plain text k_P
    texts = [fig.get_suptitle()] + [t for ax in fig.axes
                                     for t in (ax.get_title(), ax.get_xlabel(), ax.get_ylabel())]
    for text in texts:  # every symbol inside $...$, which mathtext lays out
        plain = re.sub(r"\$[^$]*\$", "", text)
        assert not any(s in plain for s in ("k_P", "p_max", " nu ", "L =", "E C")), text
    label = stiffness.yaxis.label
    assert label._preprocess_math(label.get_text())[1] is True


def test_richardson_recovers_a_power_law_and_refuses_oscillation():
    exact, a, p = 1.25, 0.3, 2.0
    values = [exact + a * h**p for h in (0.4, 0.2, 0.1)]
    value, order = richardson(*values, ratio=2.0)
    assert order == pytest.approx(p, rel=1e-12)
    assert value == pytest.approx(exact, rel=1e-12)
    assert math.isnan(richardson(1.0, 2.0, 1.5, ratio=2.0)[0])  # oscillating
    assert math.isnan(richardson(1.0, 1.5, 1.75, ratio=1.0)[0])  # no refinement


def test_richardson_rows_for_a_refinement_sequence():
    geom = BlockGeometry(size=(6 * H, 6 * H), thickness=6 * H, grid=(6, 6))
    specs = [MeshSpec(element="hex8", refinement=r, layers=None, top_layer=1.0, growth=1.5,
                      coarsen_at=1.0) for r in (1, 2, 4)]
    table = influence_convergence(geom, ConvergenceSettings(presets=tuple(specs), surfaces=0),
                                  halfspace=False, isolate=False)
    assert "applied to hex8 r1" in table.attrs["richardson"]
    extrapolated = table[table["kind"] == "richardson"]
    assert len(extrapolated) == 1
    finest = table[table["refinement"] == 4].iloc[0]
    coarse = table[table["refinement"] == 1].iloc[0]
    medium = table[table["refinement"] == 2].iloc[0]
    for q in ENTRY_QUANTITIES:
        expected, _ = richardson(coarse[q], medium[q], finest[q], 2.0)
        got = extrapolated[q].iloc[0]
        assert (math.isnan(got) and math.isnan(expected)) or got == pytest.approx(expected)
    # the centre value jumps from r = 1 to r = 2 and then falls: not asymptotic
    assert math.isnan(extrapolated["self_compliance"].iloc[0])
    # not isolated: no honest per-build peak memory
    assert table["peak_memory_GB"].isna().all()
    assert table[CONTACT_QUANTITIES[0]].isna().all()


def test_validation():
    def settings(*presets, **fields):
        return ConvergenceSettings(presets=presets, **({"surfaces": 0} | fields))

    with pytest.raises(ValueError, match="mesh"):
        influence_convergence(thick_block(), settings("finest"), isolate=False)
    with pytest.raises(ValueError, match="reference"):
        influence_convergence(thick_block(), settings("paper"), reference="converged",
                              isolate=False)
    with pytest.raises(ValueError, match="distinct"):
        influence_convergence(thick_block(), settings("paper", "paper"), isolate=False)
    with pytest.raises(ValueError, match="pressures"):
        influence_convergence(thick_block(), settings("paper", surfaces=3, pressures=(-1.0,)),
                              isolate=False)
