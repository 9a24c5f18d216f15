"""Tests of the non-dimensional sweep (Eq 23-32 of Kumar et al. 2006).

The scaling claim (sigma and E only rescale the solution) is checked against
independent SI solves: ``contact.sweep`` on a Love half-space matrix built
directly at each modulus E, with gaps in metres.
"""

import logging
from dataclasses import replace

import numpy as np
import pytest
from approach_targets import target_grid

from roughcontact import contact
from roughcontact.contact import SolverOptions, nondim
from roughcontact.contact import cell as cell_module
from roughcontact.contact.curves import PhysicalSweep
from roughcontact.contact.nondim import CellOptions
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import generate_many

SIZE = 1.0e-3  # plan size [m]
GRID = 16
NU = 0.3
LENGTH = 2.0e-3  # reference length L [m]
AREA = (SIZE / GRID) ** 2  # element area [m^2]
QUANTITIES = ("load", "nominal_pressure", "real_area_fraction", "max_pressure",
              "normalized_stiffness", "contact_stiffness", "mean_plane_deflection",
              "approach")


@pytest.fixture(scope="module")
def heights():
    """Four Gaussian surfaces in units of sigma, 16 x 16."""
    spec = SurfaceSpec(grid=GRID, size=SIZE, corr_length=2.5e-4)
    z = generate_many(spec, [11, 12, 13, 14])
    return z / z.std(axis=(1, 2), keepdims=True)


@pytest.fixture(scope="module")
def unit_influence():
    """Love half-space matrix at E = 1 Pa, i.e. E * C [m]."""
    return halfspace_influence((GRID, GRID), (SIZE, SIZE), 1.0, NU)


@pytest.fixture(scope="module")
def cell(heights, unit_influence):
    approaches = target_grid(heights, unit_influence, thickness=LENGTH, target_area=0.6,
                             steps=10)
    nd = nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                           approaches=approaches,
                           options=CellOptions().with_(tol=1e-12, stiffness_tol=1e-12))
    return approaches, nd


def relative_error(a, b):
    return np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300))


@pytest.mark.parametrize("sigma, E", [(1e-6, 1e6), (40e-6, 200e9)])
def test_rescaled_sweep_equals_direct_si_sweep(cell, heights, sigma, E):
    approaches, nd = cell
    assert nd.converged.all() and nd.stiffness_converged.all()
    C = halfspace_influence((GRID, GRID), (SIZE, SIZE), E, NU)  # [m/Pa], built at E
    gaps = sigma * (heights.max(axis=(1, 2), keepdims=True) - heights)  # [m]
    direct = contact.sweep(C, gaps, sigma * approaches, element_area=AREA,
                           options=SolverOptions(tol=1e-12, stiffness_tol=1e-12))
    assert direct.converged.all()
    reference = PhysicalSweep.from_contact_sweep(
        direct, thickness=LENGTH, nominal_area=GRID**2 * AREA, sigma=sigma, E=E)
    scaled = nondim.to_physical(nd, sigma, E, LENGTH, GRID**2 * AREA)
    for name in QUANTITIES:
        assert relative_error(getattr(scaled, name), getattr(reference, name)) < 1e-8, name
    assert relative_error(scaled.asperity_deflection, reference.asperity_deflection) < 1e-8
    # the sweep reaches real contact of interest, so the comparison is not trivial
    assert (scaled.real_area_fraction[:, -1] >= 0.6).all()
    assert (scaled.real_area_fraction[:, 0] < 0.1).all()


def test_paper_form_is_equivalent(cell, heights, unit_influence):
    """Eq 23-26 (p~ = p/E, C~ = C E / sigma) gives P/E = (sigma / L) Phat."""
    approaches, nd = cell
    sigma = 25e-6
    paper = contact.sweep(unit_influence / sigma, nondim.initial_separation(heights), approaches,
                          element_area=1.0 / GRID**2,
                          options=SolverOptions(tol=1e-12, stiffness_tol=1e-12))
    assert relative_error(paper.nominal_pressure, sigma / LENGTH * nd.nominal_pressure) < 1e-8
    assert relative_error(paper.real_area_fraction, nd.real_area_fraction) == 0.0


def test_stiffness_matches_finite_difference(cell):
    """dPhat/ddhat is the slope of Phat(dhat) where the contact set stays put."""
    approaches, nd = cell
    slope = np.diff(nd.nominal_pressure, axis=1) / np.diff(approaches)
    # secant between steps lies between the tangents at its ends (load convex in d)
    assert (slope >= nd.normalized_stiffness[:, :-1] * (1 - 1e-9)).all()
    assert (slope <= nd.normalized_stiffness[:, 1:] * (1 + 1e-9)).all()


def test_block_matrix_stiffness_tends_to_E():
    """nu = 0 block with rows summing to L: full contact gives k_P = E (Eq 33, 38)."""
    geom = BlockGeometry(size=(1.8e-3, 1.8e-3), thickness=2e-3, grid=(12, 12), nu=0.0)
    chat = unit_modulus_influence(geom)
    rng = np.random.default_rng(3)
    h = rng.standard_normal((2, 12, 12))
    nd = nondim.solve_cell(chat, h, thickness=2e-3, element_area=1.5e-4**2,
                           approaches=[0.5, 10.0, 1e3, 1e5])
    assert nd.converged.all()
    assert nd.real_area_fraction[:, -1] == pytest.approx(1.0)
    physical = nondim.to_physical(nd, sigma=30e-6, E=5.11e8)
    assert physical.normalized_stiffness[:, -1] == pytest.approx(5.11e8, rel=1e-5)
    assert physical.nominal_area == pytest.approx(1.8e-3**2)


def test_cell_grid_reaches_its_pressure_on_every_surface_without_a_trial_solve():
    """cell.approach_grid ends at bulk_factor P_end + max(h), enough for P_end (nu = 0 block)."""
    geom = BlockGeometry(size=(1.8e-3, 1.8e-3), thickness=2e-3, grid=(12, 12), nu=0.0)
    h = np.random.default_rng(4).standard_normal((3, 12, 12))
    grid = cell_module.approach_grid(h, 2.0, 8)
    assert grid[-1] == pytest.approx(cell_module.BULK_FACTOR * 2.0 + h.max(), rel=1e-12)
    ratio = cell_module.APPROACH_RANGE ** (1 / 7)
    assert grid[1:] / grid[:-1] == pytest.approx(np.full(7, ratio))
    nd = nondim.solve_cell(unit_modulus_influence(geom), h, thickness=2e-3,
                           element_area=1.5e-4**2, approaches=grid)
    assert nd.converged.all()
    assert (nd.nominal_pressure[:, -1] >= 2.0).all()
    assert (nd.nominal_pressure[:, 0] < 2.0).all()


def test_unconverged_steps_are_flagged_not_hidden(heights, unit_influence, caplog):
    approaches = np.linspace(0.5, 3.0, 4)
    with caplog.at_level(logging.WARNING):
        # pivoting, the solver of last resort, limited to one pivot: the sweep's
        # retries (cold) cannot settle every step either
        nd = nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                               approaches=approaches,
                               options=CellOptions().with_(method="exact", max_iter=1))
    assert (~nd.converged).any()
    assert (nd.residual[~nd.converged] > nd.tol).all()
    assert np.isfinite(nd.nominal_pressure).all()
    assert any("flagged converged=False" in r.message for r in caplog.records)
    physical = nondim.to_physical(nd, 1e-6, 1e9)
    assert np.array_equal(physical.converged, nd.converged)


def test_progress_reports_every_step_of_every_batch(heights, unit_influence):
    reports = []
    nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                      approaches=[0.5, 1.0, 1.5],
                      options=CellOptions().with_(batch_size=3, progress=reports.append))
    assert [(r.surfaces_done, r.step) for r in reports] == [
        (3, 1), (3, 2), (3, 3), (4, 1), (4, 2), (4, 3)]
    assert all(r.surfaces_total == 4 and r.steps_total == 3 for r in reports)
    assert all(r.iterations > 0 and r.elapsed >= 0 for r in reports)


def test_batches_and_matrix_free_operator_agree(cell, heights, unit_influence):
    approaches, nd = cell

    class MatrixFree:
        shape = unit_influence.shape

        def diagonal(self):
            return np.diag(unit_influence).copy()

        def matvec(self, p):
            return unit_influence @ p

    other = nondim.solve_cell(MatrixFree(), heights, thickness=LENGTH, element_area=AREA,
                              approaches=approaches,
                              options=CellOptions().with_(tol=1e-12, stiffness_tol=1e-12,
                                                          batch_size=3))
    for name in ("nominal_pressure", "real_area_fraction", "normalized_stiffness",
                 "mean_plane_deflection", "max_pressure"):
        assert relative_error(getattr(other, name), getattr(nd, name)) < 1e-9, name


def test_frame_has_units(cell):
    _, nd = cell
    frame = nondim.to_physical(nd, 1e-6, 1e9).to_frame()
    assert len(frame) == nd.approach.size
    assert frame.attrs["units"]["nominal_pressure"] == "Pa"
    assert np.allclose(frame["asperity_deflection"],
                       frame["approach"] - frame["mean_plane_deflection"],
                       atol=1e-12 * frame["approach"].max())


@pytest.mark.parametrize(
    "change, message",
    [
        (dict(heights=1e-6), "units of sigma"),
        (dict(approaches=[1.0, 0.5]), "increase"),
        (dict(approaches=[-1.0, 0.5]), "non-negative"),
        (dict(thickness=0.0), "thickness"),
        (dict(batch_size=0), "batch_size"),
    ],
)
def test_bad_input_is_rejected(heights, unit_influence, change, message):
    kwargs = dict(heights=heights, approaches=[0.5, 1.0], thickness=LENGTH)
    if "heights" in change:
        change = dict(heights=heights * change["heights"])
    options = {"batch_size": change.pop("batch_size")} if "batch_size" in change else {}
    kwargs.update(change)
    with pytest.raises(ValueError, match=message):
        nondim.solve_cell(unit_influence, element_area=AREA, **kwargs,
                          options=CellOptions().with_(**options))


def test_to_physical_rejects_other_geometry(cell):
    _, nd = cell
    with pytest.raises(ValueError, match="thickness"):
        nondim.to_physical(nd, 1e-6, 1e9, thickness=2 * LENGTH)
    with pytest.raises(ValueError, match="area"):
        nondim.to_physical(nd, 1e-6, 1e9, area=2 * SIZE**2)
    with pytest.raises(ValueError, match="sigma"):
        nondim.to_physical(replace(nd), -1.0, 1e9)


def test_a_fallbacks_steps_are_named_in_the_cell_and_its_contact_file(heights, unit_influence,
                                                                       tmp_path, caplog):
    """cg stopped after one iteration: pivoting answers every step; the cell's sweep and
    its contact file name it per step, and a file without fallbacks stores nothing more."""
    from roughcontact.study.jobs import storage

    approaches = np.linspace(0.5, 1.5, 3)
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        nd = nondim.solve_cell(unit_influence, heights[:2], thickness=LENGTH,
                               element_area=AREA, approaches=approaches,
                               options=CellOptions().with_(method="cg", max_iter=1,
                                                           stiffness=False))
    assert nd.method == "cg" and nd.converged.all() and (nd.solved_by == "exact").all()
    assert sum("fallback exact answered" in r.getMessage() for r in caplog.records) == 6
    storage.write_contact(tmp_path / "c.h5", nd, {"job": "{}"})
    back, _ = storage.read_contact(tmp_path / "c.h5")
    np.testing.assert_array_equal(back.solved_by, nd.solved_by)
    plain = nondim.solve_cell(unit_influence, heights[:2], thickness=LENGTH,
                              element_area=AREA, approaches=approaches,
                              options=CellOptions().with_(method="cg", stiffness=False))
    assert (plain.solved_by == "cg").all()
    storage.write_contact(tmp_path / "p.h5", plain, {"job": "{}"})
    with storage.open_h5(tmp_path / "p.h5") as f:
        assert "solved_by" not in f
    assert (storage.read_contact(tmp_path / "p.h5")[0].solved_by == "cg").all()
