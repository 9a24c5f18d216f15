"""The conductance a sweep records (roughcontact.transport.conduction.probe).

Referees that share no code with the probe's influence: Barber's (2003) identity
``C = 2 k K / E*`` against the sweep's own tangent stiffness column (the elastic
half-space's Love element integral, the contact stage's CG; the probe's dense thermal
kernel is its own quarter-plane integral), here with a rigid counter face and a
perfectly conducting one, so ``E* = E / (1 - nu^2)`` of the one elastic body and ``k``
of the one conducting body; the closed form ``k A / L`` of a block's full contact; the
dimensionless sweep's columns against its SI form. (Both CGs are the contact stage's
free-set CG: the identity checks the operators and the contact sets, not the CG.)
"""

import json

import numpy as np
import pytest

from roughcontact.contact import SolverOptions, aggregate, sweep
from roughcontact.contact import cell as cell_module
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.nondim import CellOptions, to_physical
from roughcontact.contact.probes import Probe, SolvedFields
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import BlockGeometry, MeshSpec
from roughcontact.study import probes as study_probes
from roughcontact.study.jobs import storage
from roughcontact.transport.conduction import (
    BlockBody,
    ConductanceProbe,
    HalfSpaceBody,
    conductance_probe_from_params,
)

N, SIZE, E, NU = 12, 1.0e-3, 2.0e8, 0.3
SPACING = (SIZE / N, SIZE / N)
K, RHO = 45.0, 1.7e-8


def _heights(m=3, seed=7):
    """Smooth random heights (m, N, N), zero mean, unit standard deviation."""
    rng = np.random.default_rng(seed)
    q = np.fft.fftfreq(N)
    kernel = np.exp(-(np.hypot(*np.meshgrid(q, q)) / 0.15) ** 2)
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((m, N, N))) * kernel))
    z -= z.mean(axis=(1, 2), keepdims=True)
    return z / z.std(axis=(1, 2), keepdims=True)


def _barber(stiffness):
    """``2 k K / E*`` [W/K] of the tangent stiffness ``K`` [N/m] (module docstring)."""
    return 2.0 * K * stiffness / (E / (1.0 - NU**2))


@pytest.fixture(scope="module")
def solved():
    """An SI sweep of 3 surfaces over a free half-space, the probe on its dense kernel."""
    heights = 1e-6 * _heights()
    gaps = heights.max(axis=(1, 2), keepdims=True) - heights
    probe = ConductanceProbe(HalfSpaceBody(dense=True), conductivity=K, resistivity=RHO,
                             tol=1e-11)
    result = sweep(halfspace_influence((N, N), (SIZE, SIZE), E, NU), gaps,
                   np.linspace(0.2e-6, 3.0e-6, 5), element_area=SPACING[0] ** 2,
                   interface=InterfaceGrid(SPACING, probes=(probe,)),
                   options=SolverOptions(return_fields=True, stiffness_tol=1e-11))
    return probe, result


def test_the_half_space_conductance_is_barbers_stiffness(solved):
    probe, result = solved
    columns = result.probe_columns
    assert list(columns) == ["thermal_conductance", "thermal_conductance_per_area",
                             "conduction_bulk_share", "constriction_conductance_per_area",
                             "electrical_resistance", "conduction_converged"]
    stiffness = result.contact_stiffness
    assert np.all(stiffness > 0) and columns["conduction_converged"].all()
    np.testing.assert_allclose(columns["thermal_conductance"], _barber(stiffness), rtol=1e-8)
    np.testing.assert_allclose(columns["thermal_conductance_per_area"],
                               _barber(stiffness) / SIZE**2, rtol=1e-8)
    # the same spots carry current: rho_e / (C / k)
    np.testing.assert_allclose(columns["electrical_resistance"], RHO * K / _barber(stiffness),
                               rtol=1e-8)
    np.testing.assert_array_equal(columns["conduction_bulk_share"], 0.0)
    # a half-space has no bulk: all of it is the spots' constriction
    np.testing.assert_allclose(columns["constriction_conductance_per_area"],
                               columns["thermal_conductance_per_area"], rtol=1e-12)
    # the conductance grows with the load
    assert np.all(np.diff(columns["thermal_conductance"], axis=1) > 0)
    # the default (zero-padded FFT) form of the free half-space gives the same numbers
    fft = ConductanceProbe(HalfSpaceBody(), conductivity=K, tol=1e-11)
    fields = SolvedFields(result.pressure, np.zeros_like(result.pressure),
                          np.zeros(result.pressure.shape[:2]), SPACING, False)
    np.testing.assert_allclose(fft.measure(fields)["thermal_conductance"],
                               columns["thermal_conductance"], rtol=1e-8)


def test_no_contact_records_zero_conductance_and_an_infinite_resistance():
    probe = ConductanceProbe(HalfSpaceBody(periodic=True), conductivity=K, resistivity=RHO)
    pressure = np.zeros((2, N, N))
    pressure[1] = 1.0  # full contact of a periodic half-space: no resistance left
    measured = probe.measure(SolvedFields(pressure, pressure, np.zeros(2), SPACING, True))
    assert measured["thermal_conductance"][0] == 0.0
    assert measured["thermal_conductance"][1] == np.inf
    assert measured["electrical_resistance"].tolist() == [np.inf, 0.0]
    assert measured["conduction_bulk_share"].tolist() == [0.0, 0.0]
    assert measured["conduction_converged"].all()
    assert not any(np.isnan(values).any() for values in measured.values())


def test_full_contact_of_a_block_is_k_a_over_l():
    geometry = BlockGeometry(size=(1.2e-3, 1.0e-3), thickness=0.6e-3, grid=(6, 5),
                             mesh="paper")
    probe = ConductanceProbe(BlockBody(geometry), conductivity=K, resistivity=RHO, tol=1e-12)
    spacing = (0.2e-3, 0.2e-3)
    full = np.ones((1, 5, 6))
    measured = probe.measure(SolvedFields(full, full, np.zeros(1), spacing, False))
    area = 1.2e-3 * 1.0e-3
    assert measured["thermal_conductance"][0] == pytest.approx(K * area / 0.6e-3, rel=1e-9)
    assert measured["thermal_conductance_per_area"][0] == pytest.approx(K / 0.6e-3, rel=1e-9)
    assert measured["electrical_resistance"][0] == pytest.approx(RHO * 0.6e-3 / area,
                                                                 rel=1e-9)
    assert measured["conduction_bulk_share"][0] == pytest.approx(1.0, rel=1e-9)
    # a spot: less conductance, the bulk a part of its resistance
    spot = np.zeros((1, 5, 6))
    spot[0, 2, 2:4] = 1.0
    part = probe.measure(SolvedFields(spot, spot, np.zeros(1), spacing, False))
    assert 0 < part["thermal_conductance"][0] < measured["thermal_conductance"][0]
    assert 0 < part["conduction_bulk_share"][0] < 1
    # the constriction alone: the spot's resistance less full contact's (the bulk's)
    constriction = 1.0 / (area * (1.0 / part["thermal_conductance"][0]
                                  - 1.0 / measured["thermal_conductance"][0]))
    assert part["constriction_conductance_per_area"][0] == pytest.approx(constriction,
                                                                          rel=1e-8)


def test_a_block_of_another_grid_is_refused_and_the_advice_works():
    geometry = BlockGeometry(size=(1.2e-3, 1.0e-3), thickness=0.6e-3, grid=(6, 5))
    fields = SolvedFields(np.ones((1, 10, 12)), np.zeros((1, 10, 12)), np.zeros(1),
                          (1e-4, 1e-4), False)
    with pytest.raises(ValueError, match=r"body.geometry has grid \(6, 5\).*sweep's grid"):
        ConductanceProbe(BlockBody(geometry), conductivity=K).measure(fields)
    followed = BlockGeometry(size=(1.2e-3, 1.0e-3), thickness=0.6e-3, grid=(12, 10))
    measured = ConductanceProbe(BlockBody(followed), conductivity=K).measure(fields)
    assert measured["conduction_bulk_share"][0] == pytest.approx(1.0, rel=1e-8)


@pytest.fixture(scope="module")
def cell_sweep():
    """A dimensionless cell sweep of the probe on a free half-space (dense kernel)."""
    geometry = type("Block", (), {"thickness": 5e-3, "element_area": SPACING[0] ** 2,
                                  "size": (SIZE, SIZE), "grid": (N, N)})()
    probe = ConductanceProbe(HalfSpaceBody(dense=True), conductivity=K, tol=1e-11)
    options = CellOptions().with_(method="pivot", stiffness_tol=1e-11,
                                  interface=InterfaceGrid(SPACING, probes=(probe,)))
    return cell_module.sweep_cell(halfspace_influence((N, N), (SIZE, SIZE), 1.0, NU),
                                  _heights(seed=11), geometry, 0.5, 8, options=options)


def test_the_conductance_does_not_scale_with_sigma(cell_sweep):
    nd = cell_sweep
    for sigma in (1e-6, 4e-6):
        physical = to_physical(nd, sigma, E)
        for name in nd.probe_columns:
            np.testing.assert_array_equal(physical.probe_columns[name], nd.probe_columns[name])
        touching = physical.contact_stiffness > 0
        assert touching.sum() > 10
        np.testing.assert_allclose(physical.probe_columns["thermal_conductance"][touching],
                                   _barber(physical.contact_stiffness[touching]), rtol=1e-8)
    units = to_physical(nd, 1e-6, E).to_frame().attrs["units"]
    assert units["thermal_conductance"] == "W/K" and units["conduction_converged"] == "bool"


def test_the_columns_go_through_storage_and_the_aggregate(cell_sweep, tmp_path, monkeypatch):
    """Stored and read back (the probe made again from its settings, registered here the
    way the study's registry will), then aggregated in their units."""
    kinds = {**study_probes.PROBE_KINDS, "conductance": conductance_probe_from_params}
    monkeypatch.setattr(study_probes, "PROBE_KINDS", kinds)
    path = tmp_path / "contact.h5"
    storage.write_contact(path, cell_sweep, {"job": "{}"})
    back, attrs = storage.read_contact(path)
    assert json.loads(attrs["conductance"])["body"] == {"body": "halfspace", "dense": True,
                                                        "periodic": False}
    assert back.probe_columns.probes == cell_sweep.probe_columns.probes
    for name, values in cell_sweep.probe_columns.items():
        np.testing.assert_array_equal(back.probe_columns[name], values)
    physical = to_physical(back, 2e-6, E)
    levels = aggregate.pressure_axis(*aggregate.covered_range(physical), 4)
    table = aggregate.aggregate_cell(physical, levels)
    assert table.attrs["units"]["thermal_conductance_mean"] == "W/K"
    assert table.attrs["units"]["thermal_conductance_per_area_mean"] == "W/(m^2 K)"
    assert (table["conduction_converged_mean"] == 1.0).all()
    by_hand = []  # each surface's power law in P between its steps, then the mean
    for j in range(physical.approach.shape[0]):
        P = physical.nominal_pressure[j]
        usable = physical.converged[j] & (P > 0)
        y = physical.probe_columns["thermal_conductance"][j, usable]
        by_hand.append(np.exp(np.interp(np.log(levels), np.log(P[usable]), np.log(y))))
    np.testing.assert_allclose(table["thermal_conductance_mean"], np.mean(by_hand, axis=0),
                               rtol=1e-12)


@pytest.mark.parametrize("probe", [
    ConductanceProbe(HalfSpaceBody(periodic=True), conductivity=K),
    ConductanceProbe(HalfSpaceBody(dense=True), resistivity=RHO, tol=1e-8),
    ConductanceProbe(BlockBody(BlockGeometry(size=(1e-3, 2e-3), thickness=3e-3, grid=(4, 8),
                                             mesh="refined"), solver="superlu"),
                     conductivity=K, resistivity=RHO),
    ConductanceProbe(BlockBody(BlockGeometry(grid=(4, 4), mesh=MeshSpec(layers=3))),
                     conductivity=K)])
def test_params_round_trip(probe):
    assert isinstance(probe, Probe)
    params = json.loads(json.dumps(probe.params()))
    assert params["conductivity"] == probe.conductivity
    back = conductance_probe_from_params(params)
    assert back == probe and back.params() == probe.params()
    assert [column.name for column in back.columns] == [column.name for column in probe.columns]


@pytest.mark.parametrize(("settings", "match"), [
    ({"conductivity": -1.0}, r"conductivity must be a finite positive number \[W/\(m K\)\]"),
    ({"resistivity": float("nan")}, r"resistivity must be a finite positive number"),
    ({}, "conductivity or resistivity must be given"),
    ({"conductivity": K, "tol": 2.0}, r"tol must be in \(0, 1\)")])
def test_bad_settings_are_refused_naming_the_field(settings, match):
    with pytest.raises(ValueError, match=match):
        ConductanceProbe(HalfSpaceBody(), **settings)


def test_bad_bodies_are_refused_naming_the_field():
    with pytest.raises(ValueError, match="body.dense is for a free half-space"):
        HalfSpaceBody(periodic=True, dense=True)
    with pytest.raises(ValueError, match="body must be a HalfSpaceBody or a BlockBody"):
        ConductanceProbe("halfspace", conductivity=K)
    with pytest.raises(ValueError,
                       match=r"body.body must be one of \('halfspace', 'block', 'series'\)"):
        conductance_probe_from_params({"body": {"body": "sphere"}, "conductivity": K,
                                       "tol": 1e-10})


def test_the_direct_solve_on_a_dense_block_agrees_with_cg_and_hands_over_what_it_cannot():
    from roughcontact.contact.checks import as_operator
    from roughcontact.contact.products import Products
    from roughcontact.contact.stiffness import free_set_cg
    from roughcontact.transport.conduction import direct_totals
    from roughcontact.transport.conduction.block import unit_conductivity_influence

    geometry = BlockGeometry(size=(1.2e-3, 1.0e-3), thickness=0.6e-3, grid=(12, 10),
                             mesh="paper")
    matrix = unit_conductivity_influence(geometry)
    rng = np.random.default_rng(4)
    sets = rng.random((5, 120)) < np.array([0.02, 0.1, 0.3, 0.6, 0.95])[:, None]
    totals, settled = direct_totals(matrix, sets, 1e-12)
    assert settled.all()
    cg = free_set_cg(Products(as_operator(matrix, 1e-8)), sets, np.zeros(sets.shape), 1e-12,
                     2000)
    assert cg.converged.all()
    np.testing.assert_allclose(totals, cg.total, rtol=1e-9)
    # a matrix that is not positive definite on a set: not settled, left to CG
    indefinite = np.array([[1.0, 2.0], [2.0, 1.0]])
    totals, settled = direct_totals(indefinite, np.array([[True, True], [True, False]]), 1e-10)
    assert settled.tolist() == [False, True] and totals[1] == pytest.approx(1.0)
