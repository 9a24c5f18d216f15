"""Results outside physical plausibility are flagged in the tables, the log and the audit.

The measured patch of the issue, resampled to 64 x 64 under a 10 mm block,
gave 4 of 4096 elements in contact and a peak pressure of 12.5 GPa on
E = 511 MPa (24 E): its rows are flagged. The same chain, small: a 16 x 16
patch with one tall asperity on a 10 mm paper block (no longer planned: the
jobs are run directly), through the aggregation and the audit.
"""

import json
import logging

import numpy as np
import pandas as pd
import pytest
from scipy import ndimage

from roughcontact.contact.plausibility import (
    MAX_PRESSURE_OVER_E_STAR,
    MIN_CONTACT_ELEMENTS,
    implausible,
    plausibility_flags,
)
from roughcontact.reports.audit import audit_cell
from roughcontact.study.config import ContactSettings, validated
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.jobs.aggregation import aggregate_study
from roughcontact.study.jobs.contact import solve_contact_job
from roughcontact.study.jobs.influence import build_influence
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.records import Geometry, MeasuredCell
from roughcontact.study.sources import MeasurementImport

E = 511e6


def table(pressure, area, peak):
    return pd.DataFrame({"nominal_pressure": pressure, "real_area_fraction_mean": area,
                         "real_area_fraction_count": [1] * len(pressure),
                         "max_pressure_mean": peak})


def test_the_resample_grid_case_is_flagged():
    # 4 of 4096 elements at p_max = 12.5 GPa on E = 511 MPa (nu 0: E* = E)
    frame = table([1e6, 5e6], [2 / 4096, 4 / 4096], [3e9, 12.5e9])
    flags = plausibility_flags(frame, 4096, E, 0.0)
    assert flags[0] == "4 of 4096 elements in contact at the highest pressure"
    assert flags[1] == "p_max 24.5 E*; 4 of 4096 elements in contact at the highest pressure"
    reasons = implausible(frame, 4096, E, 0.0)
    assert "24.5 E*" in reasons[0] and "from P = 5 MPa" in reasons[0]
    assert "4 of 4096" in reasons[1] and f"fewer than {MIN_CONTACT_ELEMENTS}" in reasons[1]


def test_the_papers_own_extremes_are_plausible():
    # the default study's largest peak (3.2 E*, paper mesh) and its fewest contact
    # elements at a cell's highest pressure (23 of 3600)
    frame = table([1e4, 1e5], [2 / 3600, 23 / 3600], [0.5 * E, 3.2 * E])
    assert list(plausibility_flags(frame, 3600, E, 0.0)) == ["ok", "ok"]
    assert implausible(frame, 3600, E, 0.0) == []
    # the limit is in E* = E / (1 - nu^2): at nu = 0.3, 10 E / 0.91
    at_limit = table([1e5], [0.1], [MAX_PRESSURE_OVER_E_STAR * E / (1 - 0.09) * 1.01])
    assert plausibility_flags(at_limit, 100, E, 0.3)[0].startswith("p_max 10.1 E*")


def spiky_patch(root, n=16, spike=60.0):
    """A rough n x n map [um] of 0.126 x 0.0944 mm with one tall asperity, as a measured cell."""
    rng = np.random.default_rng(4)
    z = ndimage.gaussian_filter(rng.standard_normal((n, n)), 1.0, mode="wrap")
    z /= z.std()
    z[n // 2, n // 2] += spike
    np.save(root / "patch.npy", z)
    source = MeasurementImport.from_params({
        "file": str(root / "patch.npy"), "format": "npy", "height_unit": "um",
        "lateral_unit": "mm", "spacing_mm": [0.126 / n, 0.0944 / n], "fill_holes": 0,
        "decimal": "auto", "form_degree": 1})
    return MeasuredCell.from_source(source)


def test_a_one_element_contact_is_flagged_in_the_table_the_log_and_the_audit(tmp_path, caplog):
    surface = spiky_patch(tmp_path)
    geometry = Geometry(nu=0.0, size=surface.size, thickness=10e-3, grid=surface.grid,
                        base="clamped", mesh="paper")
    cell = StudyCell(surface, geometry, sigma=surface.sigma, E=E, pressure_range=(1e5, 5e7))
    results = tmp_path / "results"
    paths = {d: results / d / f"{key}.h5" for d, key in
             (("surfaces", surface.key), ("influence", geometry.key),
              ("contact", cell.contact_key))}
    for path in paths.values():
        path.parent.mkdir(parents=True, exist_ok=True)
    build_surface_cell(surface.params(), 0, paths["surfaces"])
    build_influence(geometry.params(), paths["influence"], solver="auto", max_memory_gb=4)
    settings = ContactSettings.from_section(validated({"study_seed": 0})["contact"])
    solve_contact_job(cell.job.params(), {"surfaces": paths["surfaces"],
                                          "influence": paths["influence"]},
                      paths["contact"], settings.params())
    with caplog.at_level(logging.WARNING):
        frame = aggregate_study([cell], {cell.contact_key: paths["contact"]}, 8,
                                tmp_path / "t.csv", tmp_path / "m.csv", tmp_path / "t.json")
    stored = pd.read_csv(tmp_path / "t.csv")
    valued = stored[stored["real_area_fraction_count"] > 0]
    # one element carries the load: p_max = P n at the top, 16^2 * 50 MPa = 25 E
    assert (valued["real_area_fraction_mean"] * 256).round().eq(1).all()
    assert valued["max_pressure_mean"].iloc[-1] == pytest.approx(256 * 5e7, rel=1e-6)
    assert stored["plausibility"].str.contains("1 of 256 elements in contact").all()
    assert stored["plausibility"].iloc[-1].startswith("p_max 25 E*")
    assert (frame["plausibility"] == stored["plausibility"]).all()
    meta = json.loads((tmp_path / "t.json").read_text())
    assert meta["units"]["plausibility"] == "-"
    (summary,) = meta["mean_plane_modulus"]
    assert len(summary["implausible"]) == 2
    assert "outside physical plausibility" in caplog.text and "25 E*" in caplog.text
    row = audit_cell("s", 0, cell.params(), tmp_path, 8)
    assert "implausible: peak pressure up to 25 E*" in row["flags"]
    assert "implausible: 1 of 256 elements in contact" in row["flags"]
    assert row["contact_elements_at_P_max"] == pytest.approx(1.0)
