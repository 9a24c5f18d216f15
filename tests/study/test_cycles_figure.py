"""The cycles figure: its registry entry reads the cycles' tables, its caption names the
loading path, the caps and the seal as configured, it is refused with the loading off
(advice that plans when followed), and its code draws a table made here and answers with
the numbers of that table."""

import copy
import json
import re
from pathlib import Path

import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from study_sections import planned, with_sections

from roughcontact.errors import StoredFileError  # noqa: E402
from roughcontact.hashes import file_sha256  # noqa: E402
from roughcontact.reports.cycles_figure import (  # noqa: E402
    cycles_answers,
    leg_segments,
    load_cycles,
    plot_cycles,
)
from roughcontact.reports.plotting import overlapping_labels, tidy_log_ticks  # noqa: E402
from roughcontact.study.config import load_config  # noqa: E402
from roughcontact.study.plan.cells import figure_caption, figure_files, study_plan  # noqa: E402
from roughcontact.study.plan.checks import ConfigProblems  # noqa: E402
from roughcontact.study.plan.figures import FIGURES, Kind  # noqa: E402
from roughcontact.study.settings import Study  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
GASKET = {"sigma_um": 2.0, "b_mm": 0.5, "moments": [[0.0, 3.0], [0.8, 4.0]],
          "pressure_MPa": [2.0, 80.0]}
BASE = {"study_seed": 0,
        "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 2},
        "body": {"thickness_mm": 2.0, "E_MPa": 117000.0, "nu": 0.34, "hardness_MPa": 300.0},
        "contact": {"cap": True, "pressure_levels": 4},
        "loading": {"enabled": True, "cycles": 3, "steps": 5, "unload_to": 0.25},
        "sweeps": {"gasket": GASKET},
        "figures": {"cycles": {"studies": ["gasket"]}}}


def config(**sections) -> dict:
    return with_sections(BASE, **sections)


plan = planned


# ---- the registry and the plan ----------------------------------------------------------

def test_the_registry_entry_reads_the_cycles_tables_and_needs_the_loading():
    entry = FIGURES["cycles"]
    assert entry.kind is Kind.STUDIES and entry.needs == ("loading",)
    assert (REPO / "notebooks" / "cycles.ipynb").exists()
    assert figure_files(plan(config()), "cycles") == [
        "results/aggregates/gasket.cycles.csv", "results/aggregates/gasket.cycles_summary.csv",
        "results/aggregates/gasket.cycles.json"]


def test_the_other_figures_still_read_the_rising_aggregates():
    seal = study_plan(Study.from_config(load_config(REPO / "config" / "seal.yaml")))
    listed = seal.study.entry("leakage")["studies"]
    assert figure_files(seal, "leakage") == [
        f"results/aggregates/{name}.{ext}" for name in listed
        for ext in ("csv", "moduli.csv", "json", "validity.csv")]


def test_the_shipped_config_draws_the_cycles_figure_from_its_cycles_tables():
    raw = load_config(REPO / "config" / "cycles.yaml")
    shipped = study_plan(Study.from_config(raw))
    assert "cycles" in shipped.figures
    assert figure_files(shipped, "cycles")[0] == "results/aggregates/gasket.cycles.csv"
    caption = figure_caption(shipped, "cycles")
    for words in ("back to no load, twice",
                  f"{raw['loading']['steps']} equal load steps per leg",
                  "capped at 450 MPa", "its peak 100 MPa", "1 MPa across it",
                  "(Sk, Ku) = (0, 3), (-0.8, 4), (0.8, 4), (0, 4.5) and (1, 4.5)",
                  "20 surfaces per curve"):
        assert words in caption, words


# ---- the caption ------------------------------------------------------------------------

def test_the_caption_names_the_loading_path_the_cap_and_the_cells():
    caption = figure_caption(plan(config()), "cycles")
    for words in ("down to 0.25 of it, 3 times", "in 5 equal load steps per leg",
                  "capped at 300 MPa", "its peak 80 MPa", "(Sk, Ku) = (0, 3) and (0.8, 4)",
                  "sigma 2 um", "2 surfaces per curve", "first loading is solid",
                  "each unloading dashed", "each reloading dotted",
                  "95 % confidence interval of the mean approach at each step's pressure",
                  "shaken down"):
        assert words in caption, words
    # no flow: the third panel is the permanent set, no leak rate is named
    assert "permanent set (the approach at which the flattened surface" in caption
    assert "leak rate" not in caption
    # unloading to a quarter: the first cycle's work is no closed loop
    assert "first cycle ends above no load" in caption
    closed = figure_caption(plan(config(loading={"unload_to": 0.0})), "cycles")
    assert "first cycle ends above no load" not in closed


def test_the_caption_names_the_seal_where_the_flow_is_on():
    raw = config(flow={"enabled": True, "pressure_drop_MPa": 2.0, "seal_width_mm": 50.0,
                       "seal_length_mm": 3.0, "viscosity_Pa_s": 0.002},
                 loading={"cycles": 1, "unload_to": 0.0})
    caption = figure_caption(plan(raw), "cycles")
    for words in ("back to no load, once", "viscosity 0.002 Pa s through a seal 50 mm wide "
                  "and 3 mm long with 2 MPa across it", "pressure drop of 2 MPa exceeds",
                  "faces_open", "leak rate along x at half the peak on loading and on "
                  "unloading"):
        assert words in caption, words
    assert "shaken down" not in caption  # one cycle: no second to shake down in


# ---- refused with the loading off ------------------------------------------------------

@pytest.mark.parametrize("changed, words, advice", [
    ({"loading": {"enabled": False}},
     ("figures.cycles.studies: 'gasket' is solved without the loading",
      "set loading.enabled: true"), ("loading", "enabled", True)),
    ({"contact": {"cap": False}},
     ("loading.enabled: true, but no cell of the config is capped", "contact.cap: true",
      "body.hardness_MPa"), ("contact", "cap", True)),
], ids=["loading off", "no capped cell"])
def test_the_figure_is_refused_without_loops_and_the_advice_plans(changed, words, advice):
    raw = config(**changed)
    with pytest.raises(ConfigProblems) as caught:
        plan(raw)
    for part in words:
        assert part in str(caught.value)
    followed = copy.deepcopy(raw)
    section, key, value = advice
    followed[section][key] = value  # the advice (body.hardness_MPa is set)
    planned = plan(followed)
    assert "cycles" in planned.figures and planned.cycle_studies == ("gasket",)


# ---- the figure's code on a table made here --------------------------------------------

STEPS = 4  # per leg
PEAK = 40e6  # Pa
SURFACES = 4


def _path() -> list[tuple[int, str, float]]:
    """(cycle, leg, P [Pa]) of two cycles of :data:`STEPS` steps per leg from no load."""
    up = [PEAK * k / STEPS for k in range(STEPS + 1)]
    down = up[-2::-1]
    rows = [(1, "loading", p) for p in up] + [(1, "unloading", p) for p in down]
    return rows + [(2, "reloading", p) for p in up[1:]] + [(2, "unloading", p) for p in down]


def steps_table(flow: bool) -> pd.DataFrame:
    """Two cells' rows per step: approach and k_P made up from P, the permanent set
    growing on loading, the leak rate (along x, with ``flow``) falling with P; the faces
    open below 5 MPa."""
    rows = []
    for cell, (skew, kurt) in enumerate(((0.0, 3.0), (0.8, 4.0))):
        for step, (cycle, leg, p) in enumerate(_path()):
            approach = (cell + 1) * 1e-6 * (1 + (p / PEAK) ** 0.5 + (leg != "loading"))
            row = {"step": step, "cycle": cycle, "leg": leg, "nominal_pressure": p,
                   "nominal_pressure_MPa": p / 1e6, "approach_mean": approach,
                   "approach_half_width": 0.1e-6, "approach_count": SURFACES,
                   "normalized_stiffness_mean": 1e12 * (10 + p / 1e6),
                   "normalized_stiffness_half_width": 1e12, "normalized_stiffness_count": SURFACES,
                   "permanent_set_mean": 1e-6 * (cell + 1) * min(step, STEPS) / STEPS,
                   "permanent_set_half_width": 0.05e-6, "permanent_set_count": SURFACES,
                   "cell": cell, "label": f"Sk {skew:g}, Ku {kurt:g}", "skew": skew,
                   "kurt": kurt, "sigma_um": 2.0, "cap_MPa": 300.0}
            if flow:
                leak = (cell + 1) * 1e-7 / (1 + p / 1e6) / (1 + (leg != "loading"))
                row |= {"leak_rate_x_mean": leak, "leak_rate_x_half_width": 0.1 * leak,
                        "leak_rate_x_count": SURFACES, "faces_open": p < 5e6}
            rows.append(row)
    return pd.DataFrame(rows)


#: Each cell's numbers per cycle in the table per cycle: (residual [m], its half width,
#: stiffness ratio, dissipated [J/m^2], plastic work [J/m^2], shaken down, leak on the
#: rise [m^3/s], leak on the fall) by (cell, cycle).
SUMMARY = {(0, 1): (1.5e-6, 0.12e-6, 1.7, 50.0, 45.0, 0.0, 2.0e-8, 5.0e-9),
           (0, 2): (1.5e-6, 0.12e-6, 1.0, 1e-6, 1.1e-6, 0.75, 5.0e-9, 5.0e-9),
           (1, 1): (3.25e-6, 0.2e-6, 2.1, 120.0, 110.0, 0.0, 4.0e-8, 7.0e-9),
           (1, 2): (3.25e-6, 0.2e-6, 1.0, 3e-6, 3.2e-6, 0.25, 7.0e-9, 7.0e-9)}


def summary_table(flow: bool) -> pd.DataFrame:
    rows = []
    for (cell, cycle), (res, res_pm, ratio, energy, work, shaken, rise, fall) in SUMMARY.items():
        row = {"cycle": cycle, "peak_pressure_MPa": PEAK / 1e6, "half_peak_MPa": PEAK / 2e6,
               "cell": cell, "skew": (0.0, 0.8)[cell], "kurt": (3.0, 4.0)[cell],
               "label": f"Sk {(0, 0.8)[cell]:g}, Ku {(3, 4)[cell]:g}"}
        for name, value in (("residual_approach", res), ("unloading_stiffness_ratio", ratio),
                            ("dissipated_energy", energy), ("plastic_work", work),
                            ("shaken_down", shaken)):
            row |= {f"{name}_mean": value, f"{name}_count": SURFACES,
                    f"{name}_half_width": res_pm if name == "residual_approach" else 0.1 * value}
        if flow:
            for side, value in (("rise", rise), ("fall", fall)):
                row |= {f"{side}_leak_rate_x_mean": value,
                        f"{side}_leak_rate_x_half_width": 0.2 * value,
                        f"{side}_leak_rate_x_count": SURFACES}
        rows.append(row)
    return pd.DataFrame(rows)


def write_cycles(tmp_path, name: str, flow: bool) -> list:
    """A study's three cycle files with the sidecar's SHA-256 of both tables."""
    table, summary = tmp_path / f"{name}.cycles.csv", tmp_path / f"{name}.cycles_summary.csv"
    steps_table(flow).to_csv(table, index=False)
    summary_table(flow).to_csv(summary, index=False)
    sidecar = tmp_path / f"{name}.cycles.json"
    sidecar.write_text(json.dumps({"table_sha256": file_sha256(table),
                                   "summary_sha256": file_sha256(summary)}))
    return [table, summary, sidecar]


def test_the_legs_are_cut_and_each_starts_where_the_one_before_ended():
    rows = steps_table(flow=False).query("cell == 0")
    segments = leg_segments(rows)
    assert [leg for leg, _ in segments] == ["loading", "unloading", "reloading", "unloading"]
    firsts = [int(seg["step"].iloc[0]) for _, seg in segments]
    lasts = [int(seg["step"].iloc[-1]) for _, seg in segments]
    assert firsts == [0, STEPS, 2 * STEPS, 3 * STEPS]
    assert lasts == [STEPS, 2 * STEPS, 3 * STEPS, 4 * STEPS]
    unjoined = [int(seg["step"].iloc[0]) for _, seg in leg_segments(rows, joined=False)]
    assert unjoined == [0, STEPS + 1, 2 * STEPS + 1, 3 * STEPS + 1]


def _lines(ax, color=None):
    return [line for line in ax.get_lines() if len(line.get_xdata()) > 1
            and (color is None or line.get_color() == color)]


def test_the_figure_draws_the_table_with_its_leg_styles(tmp_path):
    studies = load_cycles(write_cycles(tmp_path, "gasket", flow=True), ["gasket"])
    fig = plot_cycles(studies)
    loops, stiffness, leak = fig.axes
    table = steps_table(flow=True)
    first = loops.get_lines()[0]  # cell 0's first loading: P against the approach
    loading = table.query("cell == 0 and leg == 'loading'")
    assert np.allclose(first.get_xdata(), loading["approach_mean"] / 1e-6)
    assert np.allclose(first.get_ydata(), loading["nominal_pressure"] / 1e6)
    assert first.get_linestyle() == "-" and first.get_label() == "gasket: Sk = 0, Ku = 3"
    color = first.get_color()
    assert [line.get_linestyle() for line in _lines(loops, color)] == ["-", "--", ":", "--"]
    stiff = _lines(stiffness, color)[0]
    assert np.allclose(stiff.get_ydata(), loading["normalized_stiffness_mean"] / 1e12)
    assert leak.get_yscale() == "log"
    crosses = [line for line in leak.get_lines() if line.get_marker() == "x"
               and len(line.get_xdata())]
    opened = table.query("faces_open")
    assert sum(len(line.get_xdata()) for line in crosses) == len(opened)
    tidy_log_ticks(fig)  # as save_figure does
    assert overlapping_labels(fig) == []
    plt.close(fig)


def test_without_the_flow_the_third_panel_is_the_permanent_set(tmp_path):
    studies = load_cycles(write_cycles(tmp_path, "dry", flow=False), ["dry"])
    fig = plot_cycles(studies)
    right = fig.axes[2]
    assert right.get_xlabel() == "load step" and right.get_yscale() == "linear"
    first = _lines(right)[0]
    rows = steps_table(flow=False).query("cell == 0 and leg == 'loading'")
    assert np.allclose(first.get_ydata(), rows["permanent_set_mean"] / 1e-6)
    assert "leak rate" not in cycles_answers(studies)
    plt.close(fig)


def _number(text: str, before: str, after: str = "") -> float:
    found = re.search(re.escape(before) + r"\s*([-+0-9.e]+)" + re.escape(after), text)
    assert found, (before, text)
    return float(found.group(1))


def test_the_answers_give_the_numbers_of_the_table(tmp_path):
    studies = load_cycles(write_cycles(tmp_path, "gasket", flow=True), ["gasket"])
    answers = cycles_answers(studies)
    paragraphs = answers.strip().split("\n\n")
    assert len(paragraphs) == 2
    for cell, text in enumerate(paragraphs):
        res, res_pm, ratio, energy, work, _, rise, fall = SUMMARY[(cell, 1)]
        shaken = SUMMARY[(cell, 2)][5]
        assert text.startswith(f"gasket: Sk = {(0, 0.8)[cell]:g}, Ku = {(3, 4)[cell]:g}:")
        assert _number(text, "after cycle 1") == pytest.approx(res * 1e6, rel=5e-3)
        assert _number(text, f"after cycle 1 {_number(text, 'after cycle 1'):g} ±") == \
            pytest.approx(res_pm * 1e6, rel=5e-2)
        assert _number(text, "(20 MPa)") == pytest.approx(ratio, rel=5e-3)
        assert _number(text, "energy dissipated per cycle") == pytest.approx(energy, rel=5e-3)
        assert _number(text, "(plastic work") == pytest.approx(work, rel=5e-3)
        assert _number(text, "shaken down in cycle 2:") == pytest.approx(100 * shaken, abs=0.5)
        assert _number(text, "at half the peak") == pytest.approx(rise, rel=5e-3)
        assert _number(text, "m³/s on loading,") == pytest.approx(fall, rel=5e-3)
        assert _number(text, "(unloading over loading") == pytest.approx(fall / rise, rel=5e-3)


def test_an_edited_table_is_refused(tmp_path):
    paths = write_cycles(tmp_path, "gasket", flow=False)
    with open(paths[1], "a") as stream:
        stream.write("\n")
    with pytest.raises(StoredFileError, match="does not match the SHA-256"):
        load_cycles(paths, ["gasket"])
    with pytest.raises(ValueError, match="expected 3 each"):
        load_cycles(paths[:2], ["gasket"])
