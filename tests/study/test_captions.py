"""The report's captions are written from each study's own settings.

report/figure.rst's captions were fixed text: "left the paper's mesh, right
the converged mesh" for Fig 7 and the mean gap, while config/quick.yaml
draws the refined mesh on the right. They now come from the cells each
figure draws (roughcontact.study.plan.captions, named by the figure registry
roughcontact.study.plan.figures; the figure rule's params.caption), so that each is
true for every shipped config.
"""

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import jinja2
import pytest

from roughcontact.study.config import load_config
from roughcontact.study.contact_records import study_columns
from roughcontact.study.counter_records import (
    NO_COMPLIANCE,
    NO_COUNTER_BODY,
    NO_HEIGHTS,
    CounterBody,
    CounterCompliance,
    CounterHeights,
    counter_name,
)
from roughcontact.study.plan.captions import panels
from roughcontact.study.plan.cells import figure_caption, study_plan
from roughcontact.study.plan.figures import FIGURES, Kind
from roughcontact.study.records import InfluenceModel
from roughcontact.study.settings import Study

REPO = Path(__file__).resolve().parents[2]


def plan_of(name):
    config = load_config(REPO / "config" / f"{name}.yaml")
    return config, study_plan(Study.from_config(config))


def test_every_figure_of_the_schema_has_a_registry_entry_and_a_notebook():
    import yaml

    schema = yaml.safe_load((REPO / "config" / "schema.yaml").read_text())
    assert set(FIGURES) == set(schema["properties"]["figures"]["properties"])
    for name, figure in FIGURES.items():
        assert (REPO / "notebooks" / f"{name}.ipynb").exists(), name
        assert callable(figure.caption) and isinstance(figure.kind, Kind)


@pytest.mark.parametrize(("name", "right", "wrong", "surfaces", "b"), [
    ("quick", "refined", "converged", 4, 0.5),
    ("config", "converged", "refined", 60, 1.0),
])
def test_fig07_and_gaps_captions_name_the_meshes_of_their_config(name, right, wrong, surfaces,
                                                                 b):
    config, plan = plan_of(name)
    assert config["figures"]["fig07"]["meshes"] == ["paper", right]
    for figure in ("fig07", "gaps", "fig12", "fig13"):
        caption = figure_caption(plan, figure)
        assert (f"left the paper's mesh (5 uniform trilinear layers), right the {right} mesh"
                in caption), caption
        assert wrong not in caption
        assert f"{surfaces} surfaces per curve" in caption
        assert f"b {b:g} mm" in caption
    assert "left" not in figure_caption(plan, "fig11")  # one panel, one mesh
    assert f"the {right} mesh" in figure_caption(plan, "hardness")


@pytest.mark.parametrize("name", ["quick", "config", "measured", "two_bodies", "seal"])
def test_every_figure_of_a_shipped_config_has_its_caption(name):
    config, plan = plan_of(name)
    for figure in plan.figures:
        caption = figure_caption(plan, figure)
        assert caption.endswith(".") and "{" not in caption and "nan" not in caption, caption


def test_captions_of_surface_figures_follow_their_settings():
    config, plan = plan_of("quick")  # Fig 4: b 0.5 mm here, 1 mm in the default study
    caption = figure_caption(plan, "fig04")
    assert "sigma 40 um, b 0.5 mm and (Sk, Ku) = (0, 3) and (-0.8, 4)" in caption
    assert "32 x 32 grid over 4.8 mm x 4.8 mm" in figure_caption(plan, "fig01")
    assert "nu = 0 and 0.3" in figure_caption(plan, "table_Eu")
    assert "standard deviation" in figure_caption(plan, "table_Eu")


def test_the_two_bodies_caption_names_each_study_and_its_counter_bodies():
    config, plan = plan_of("two_bodies")
    caption = figure_caption(plan, "two_bodies")
    assert ("pad_on_disc (first body: sigma 5 um, E 2000 MPa, nu 0.25, a 10 mm block on the "
            "refined mesh) against the half-space E 110000 MPa nu 0.26 (sigma 1.5 um) and the "
            "rigid smooth flat") in caption
    assert ("steel_plates (first body: sigma 0.8 um, E 210000 MPa, nu 0.3, a 10 mm block on "
            "the refined mesh) against the block E 210000 MPa nu 0.3 10 mm refined (sigma 0.8 "
            "um) and the rigid smooth flat") in caption
    assert "20 surfaces per curve" in caption


def test_the_leakage_caption_names_the_configured_seal_and_its_cells():
    config = load_config(REPO / "config" / "seal.yaml")
    config["flow"] |= {"viscosity_Pa_s": 0.0035, "pressure_drop_MPa": 2.5,
                       "directions": ["x"], "face_rule": "arithmetic"}
    caption = figure_caption(study_plan(Study.from_config(config)), "leakage")
    assert ("a fluid of viscosity 0.0035 Pa s through a seal 100 mm wide and 2 mm long with "
            "2.5 MPa across it (steady Reynolds equation, local cubic law, arithmetic face "
            "rule, grid sides; along x)") in caption
    assert ("seal (sigma 5 um, b 0.5 mm, E 511 MPa, nu 0, a 10 mm block on the refined mesh; "
            "(Sk, Ku) = (0, 3), (-0.8, 4), (0.8, 4), (0, 4.5) and (1, 4.5))") in caption
    assert "20 surfaces per curve, 24 steps each, 16 pressure levels" in caption
    assert "dashed" not in caption.split("Dapp")[0] and "dotted" not in caption
    # the levels 0.2 * 100^(k/15) MPa (16, log-spaced) below the 2.5 MPa drop: k = 0..8
    opened = ", ".join(f"{0.2 * 10 ** (2 * k / 15):.3g}" for k in range(8))
    assert (f"the pressure drop of 2.5 MPa exceeds the nominal contact pressure, so the "
            f"fluid would lift the faces apart (seal at {opened} and 2.33 MPa;") in caption
    assert "Hollow markers: a level resting on fewer surfaces than the cell has" in caption
    assert "sealing pressure along x" in caption
    shipped = figure_caption(plan_of("seal")[1], "leakage")
    assert "viscosity 0.001 Pa s" in shipped and "with 1 MPa across it" in shipped
    assert "along x and y, y dashed" in shipped and "along y dotted" in shipped


def test_counter_columns_name_each_counter_body_and_the_flat_beside_them():
    """The ``counter`` column the figures and captions read: written by the counter body
    (its body, and its surface in brackets, Sk and Ku unless Gaussian), the rigid smooth
    flat's too in a study of counter bodies, none in a study without."""
    cell = plan_of("quick")[1].cells["fig07"][0]
    heights = CounterHeights(dataclasses.replace(cell.surface, skew=-0.5, kurt=4.0))
    rough_rigid = CounterBody(heights=heights, sigma=2e-6, compliance=NO_COMPLIANCE)
    halfspace = dataclasses.replace(cell.geometry, nu=0.3, operator=InfluenceModel.HALFSPACE)
    smooth_halfspace = CounterBody(heights=NO_HEIGHTS, compliance=CounterCompliance(halfspace),
                                   E=1e6)
    cells = [dataclasses.replace(cell, counterface=counter)
             for counter in (rough_rigid, smooth_halfspace, NO_COUNTER_BODY)]
    rows = study_columns(cells)
    assert [row["counter"] for row in rows] == [
        "rigid (sigma 2 um, Sk -0.5, Ku 4)", "half-space E 1 MPa nu 0.3 (smooth)",
        "rigid smooth flat"]
    assert [counter_name(row) for row in rows] == [row["counter"] for row in rows]
    assert "counter" not in cells[2].columns()  # the flat names itself only beside others
    assert study_columns(cells[2:]) == [cell.columns()]  # a study without: its columns
    assert counter_name(study_columns(cells[2:])[0]) == "rigid smooth flat"


def test_panels():
    assert panels(["refined"]) == "one panel, the refined mesh"
    assert panels(["paper", "graded", "converged"]) == (
        "from left to right the paper's mesh (5 uniform trilinear layers), the graded mesh "
        "and the converged mesh")


def test_the_report_template_shows_the_caption_of_the_job():
    """report/figure.rst (rendered by Snakemake's report with the job's params)."""
    template = jinja2.Template((REPO / "report" / "figure.rst").read_text())
    job = SimpleNamespace(params=SimpleNamespace(caption="Fig 7: right the refined mesh."),
                          wildcards=SimpleNamespace(fig="fig07"),
                          output=SimpleNamespace(answers="results/figures/fig07.answers.rst"))
    text = template.render(snakemake=job)
    assert text.startswith("Fig 7: right the refined mesh.")
    assert "results/figures/fig07.ipynb" in text
    assert ".. include:: results/figures/fig07.answers.rst" in text


def test_the_report_caption_includes_the_numbers_the_notebook_found(tmp_path, monkeypatch):
    """The include resolves against the working directory (Snakemake renders captions
    there) and an empty answers file leaves the plan's caption alone."""
    from docutils.core import publish_parts

    template = jinja2.Template((REPO / "report" / "figure.rst").read_text())
    monkeypatch.chdir(tmp_path)
    (tmp_path / "found.rst").write_text("Sealing pressure: 4.57 MPa (95 %: 3.88-4.72).\n")
    (tmp_path / "empty.rst").write_text("")
    for answers, expected in (("found.rst", "4.57 MPa (95 %: 3.88-4.72)"), ("empty.rst", None)):
        job = SimpleNamespace(params=SimpleNamespace(caption="The caption."),
                              wildcards=SimpleNamespace(fig="leakage"),
                              output=SimpleNamespace(answers=answers))
        html = publish_parts(template.render(snakemake=job), writer="html")["body"]
        assert "The caption." in html and "leakage.ipynb" in html
        assert (expected in html) if expected else ("MPa" not in html)
