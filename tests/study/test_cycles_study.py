"""Loading, unloading, reloading in a study (the ``loading`` section): planned only for
capped cells, off by default; each cell's cycle job on its contact job's files, its file
checked on every read; the aggregation per step and per cycle in SI units.

Referees: the path's pressure levels written here from the configuration's numbers; the
surfaces' cycle solved again here in SI units (the heights times sigma, the compliance
E C / E, the cap and the loads in Pa: none of the job's scaling); the bands by
scipy.stats.t; the energy identity of the cap model (the loop's area is the plastic work)."""

import types

import h5py
import numpy as np
import pandas as pd
import pytest
import scipy.stats
from study_sections import planned, with_sections

from roughcontact.contact import SolverOptions
from roughcontact.contact.cycles import LoadingPath, cycle_sweep
from roughcontact.errors import StoredFileError
from roughcontact.study import layout
from roughcontact.study.config import validated
from roughcontact.study.cycle_records import NO_LOADING, CycleJob
from roughcontact.study.jobs.cycle_aggregation import aggregate_cycles
from roughcontact.study.jobs.cycle_storage import read_cycle
from roughcontact.study.jobs.cycles import solve_cycle_job
from roughcontact.study.jobs.influence import build_influence, build_pair
from roughcontact.study.jobs.storage import read_influence, read_surfaces
from roughcontact.study.jobs.surfaces import build_surface_cell
from roughcontact.study.plan import resources
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.settings import Study
from roughcontact.units import MPA, UM

SIGMA_UM, P_MAX_MPA, H_MPA = 1.0, 40.0, 300.0
STUDY = {"sigma_um": SIGMA_UM, "b_mm": 0.5, "pressure_MPa": [2.0, P_MAX_MPA]}
BASE = {"study_seed": 3,
        "surfaces": {"grid": [10, 10], "size_mm": [1.5, 1.5], "count": 3},
        "body": {"thickness_mm": 2.0, "E_MPa": 117000.0, "nu": 0.3, "hardness_MPa": H_MPA},
        "contact": {"cap": True},
        "loading": {"enabled": True, "cycles": 2, "steps": 4},
        "figures": {}, "reports": {},
        "sweeps": {"gasket": STUDY}}


def config(**sections):
    return validated(with_sections(BASE, **sections))


def plan(**sections):
    return planned(with_sections(BASE, **sections))


def test_off_by_default_nothing_is_planned():
    study = Study.from_config(config(loading=None))
    assert study.loading == NO_LOADING and not study.loading.enabled
    planned = study_plan(study)
    assert planned.cycles == {} and planned.cycle_studies == ()


def test_with_cap_both_only_the_capped_cells_are_swept():
    planned = plan(contact={"cap": "both"})
    cells = planned.cells["gasket"]
    assert len(cells) == 2  # the elastic cell and the capped one
    (cycle,) = planned.cycles.values()
    capped = next(cell for cell in cells if cell.hardness is not None)
    assert cycle.contact.key == capped.job.key and planned.cycle_studies == ("gasket",)
    # its peak: the highest level in P L / (E sigma), written from the config's numbers
    assert cycle.peak == pytest.approx(P_MAX_MPA * 2.0e-3 / (117000.0 * SIGMA_UM * 1e-6),
                                       rel=1e-6)
    assert cycle.files() == capped.job.files() and cycle.paths() == capped.job.paths()
    assert CycleJob.from_params(cycle.params()) == cycle
    # its cost: the path's steps at a share of its contact job's
    assert resources.job_runtime(planned, "cycle", {"cycle": cycle.key}) >= 1
    assert resources.job_memory_mb(planned, "cycle", {"cycle": cycle.key}) == \
        resources.job_memory_mb(planned, "contact", {"job": cycle.contact.key})


def test_another_path_is_another_file():
    one = next(iter(plan().cycles.values()))
    other = next(iter(plan(loading={"unload_to": 0.25}).cycles.values()))
    more = next(iter(plan(loading={"cycles": 3}).cycles.values()))
    assert len({one.key, other.key, more.key}) == 3
    assert one.contact.key == other.contact.key == more.contact.key


def solve_study(raw: dict, root) -> types.SimpleNamespace:
    """Every file the cycle jobs of the configuration ``raw`` read, built by their jobs in
    a results tree ``root`` of its own; the cycle jobs solved and aggregated."""
    study = Study.from_config(raw)
    planned = study_plan(study)
    seed = raw["study_seed"]
    for key, cell in planned.surfaces.items():
        build_surface_cell(cell.params(), seed, root / layout.surfaces(key))
    for key, geometry in planned.geometries.items():
        build_influence(geometry.params(), root / layout.influence(key),
                        solver=raw["body"]["solver"], max_memory_gb=raw["body"]["max_memory_gb"])
    for key, pair in planned.pairs.items():
        build_pair(pair.params(), root / layout.influence(pair.first.key),
                   root / layout.influence(pair.second.key), root / layout.pair(key))
    outs = {}
    for cycle in planned.cycles.values():
        outs[cycle.key] = root / cycle.output
        solve_cycle_job(cycle.params(), {k: str(root / v) for k, v in cycle.paths().items()},
                        outs[cycle.key], planned.contact.params())
    cells = [cell for cell in planned.cells["gasket"] if study.loading.applies(cell)]
    outputs = types.SimpleNamespace(**{name: root / path for name, path in zip(
        ("table", "summary", "meta"), layout.cycle_aggregates("gasket"), strict=True)})
    aggregate_cycles(cells, study.loading, outs, outputs)
    return types.SimpleNamespace(cycles=list(planned.cycles.values()), cells=cells, outs=outs,
                                 table=pd.read_csv(outputs.table),
                                 summary=pd.read_csv(outputs.summary), study=study)


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """The cycle job of the capped cell, solved and aggregated in a results tree of its
    own."""
    root = tmp_path_factory.mktemp("cycles")
    out = solve_study(config(), root)
    (out.cycle,) = out.cycles
    out.out = out.outs[out.cycle.key]
    out.paths = {name: root / path for name, path in out.cycle.paths().items()}
    return out


def test_the_table_follows_the_configured_path_in_mpa(solved):
    table = solved.table
    up = np.linspace(0.0, P_MAX_MPA, 5)
    expected = np.concatenate([up, up[::-1][1:], up[1:], up[::-1][1:]])
    np.testing.assert_allclose(table["nominal_pressure_MPa"], expected, rtol=1e-6, atol=1e-12)
    assert table["leg"].tolist() == (["loading"] * 5 + ["unloading"] * 4 + ["reloading"] * 4
                                     + ["unloading"] * 4)
    assert table["cycle"].tolist() == [1] * 9 + [2] * 8
    assert (table["approach_count"] == 3).all()


def test_the_cycle_in_si_units_solved_again_gives_the_table(solved):
    """The job's dimensionless cycle, taken to SI units by the aggregation, against the
    same surfaces' cycle solved here in SI units."""
    surfaces = read_surfaces(solved.paths["surfaces"])
    unit, _ = read_influence(solved.paths["influence"])
    E, sigma = 117000.0 * MPA, SIGMA_UM * UM
    heights = surfaces["heights"].reshape(3, -1) * sigma
    gaps = heights.max(axis=1, keepdims=True) - heights
    area = 1.5e-3 * 1.5e-3
    path = LoadingPath(tuple(np.asarray(solved.cycle.path().values) * E * sigma / 2.0e-3),
                       "mean_pressure")
    si = cycle_sweep(np.asarray(unit) / E, gaps, path, H_MPA * MPA, element_area=area / 100,
                     options=SolverOptions(method="pivot", tol=1e-10))
    table = solved.table
    np.testing.assert_allclose(table["approach_mean"], si.approach.mean(axis=0), rtol=1e-6,
                               atol=1e-6 * sigma)
    np.testing.assert_allclose(table["permanent_set_mean"], si.permanent_set.mean(axis=0),
                               rtol=1e-6, atol=1e-6 * sigma)
    np.testing.assert_allclose(table["plastic_depth_mean"],
                               si.plastic_volume.mean(axis=0) / area, rtol=1e-6,
                               atol=1e-9 * sigma)
    np.testing.assert_allclose(table["normalized_stiffness_mean"][1:],
                               si.contact_stiffness.mean(axis=0)[1:] / area, rtol=1e-5)
    # the bands: Student-t 95 % of the three surfaces
    t = scipy.stats.t.ppf(0.975, 2)
    np.testing.assert_allclose(table["approach_half_width"],
                               t * si.approach.std(axis=0, ddof=1) / np.sqrt(3), rtol=1e-5,
                               atol=1e-6 * sigma)


def test_the_summary_per_cycle_obeys_the_cap_model(solved):
    first, second = solved.summary.iloc[0], solved.summary.iloc[1]
    assert first["residual_approach_mean"] > 0  # a permanent set once unloaded
    # the loop's area is the plastic work H dV_p (second order in the step: 4 steps a leg)
    assert first["dissipated_energy_mean"] == pytest.approx(first["plastic_work_mean"],
                                                            rel=0.15)
    assert first["unloading_stiffness_ratio_mean"] > 1.0  # the spots stay larger
    # the second cycle adds (almost) nothing: its loop is a thousand times smaller
    assert abs(second["dissipated_energy_mean"]) < 1e-3 * first["dissipated_energy_mean"]
    assert second["residual_approach_mean"] == pytest.approx(first["residual_approach_mean"],
                                                             rel=1e-3)
    # the same load on the rise and the fall: the spots stay larger on unloading
    assert first["fall_real_area_fraction_mean"] > first["rise_real_area_fraction_mean"]
    assert first["half_peak_MPa"] == pytest.approx(P_MAX_MPA / 2, rel=1e-6)


def test_a_file_of_another_path_or_damaged_is_refused(solved, tmp_path):
    read_cycle(solved.out, job=solved.cycle.params())
    other = CycleJob(**{**solved.cycle.__dict__, "unload_to": 0.5})
    with pytest.raises(StoredFileError, match="unload_to"):
        read_cycle(solved.out, job=other.params())
    damaged = tmp_path / "damaged.h5"
    damaged.write_bytes(solved.out.read_bytes())
    with h5py.File(damaged, "r+") as f:
        f["approach"][0, 3] *= 1.001
    with pytest.raises(StoredFileError, match="no longer match the hash"):
        read_cycle(damaged, job=solved.cycle.params())


@pytest.mark.parametrize("changed", [
    {"body": {"operator": "halfspace"}},
    {"body": {"operator": "hybrid", "mesh": "refined"}},
    {"sweeps": {"gasket": {**STUDY, "counterface": {
        "surface": {"sigma_um": 0.5, "b_mm": 0.5},
        "body": {"kind": "halfspace", "E_MPa": 110000.0, "nu": 0.26}}}}},
], ids=["half-space", "matrix-free block", "rough elastic counter body"])
def test_every_body_the_study_models_cycles_alike(changed, tmp_path):
    """The study's other bodies: the cycle job on each, the cap model's marks kept (a
    permanent set; the loop's area near the plastic work; the second cycle elastic)."""
    out = solve_study(config(loading={"cycles": 2, "steps": 4}, **changed), tmp_path)
    first, second = out.summary.iloc[0], out.summary.iloc[1]
    assert first["residual_approach_mean"] > 0
    assert first["dissipated_energy_mean"] == pytest.approx(first["plastic_work_mean"],
                                                            rel=0.2)
    assert first["unloading_stiffness_ratio_mean"] > 1.0
    assert abs(second["dissipated_energy_mean"]) < 1e-3 * first["dissipated_energy_mean"]
    assert (out.table["approach_count"] == 3).all()
