"""Two bodies in series: the counter body's material, a half-space after the first body
(roughcontact.transport.conduction.bodies.SeriesBody through the probe)."""

import numpy as np
import pytest

from roughcontact.contact.probes import SolvedFields
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.transport.conduction import (
    BlockBody,
    ConductanceProbe,
    HalfSpaceBody,
    SeriesBody,
    body_from_params,
    conductance_probe_from_params,
    halfspace_thermal_influence,
)
from roughcontact.transport.conduction.block import unit_conductivity_influence

K1, K2 = 50.0, 16.0
RHO1, RHO2 = 1.5e-7, 1.7e-8


def _fields(mask, spacing):
    pressure = mask.astype(float)[None]
    return SolvedFields(pressure, pressure, np.zeros(1), spacing, False)


def test_two_half_spaces_are_holms_spot_with_both_resistances():
    n, side = 48, 1.0e-3  # a spot of radius 16 elements
    dx = side / n
    y, x = (np.mgrid[:n, :n] - (n - 1) / 2) * dx
    radius = 16 * dx
    spot = np.hypot(x, y) < radius
    fields = _fields(spot, (dx, dx))
    series = ConductanceProbe(HalfSpaceBody(), conductivity=K1, counter_conductivity=K2,
                              tol=1e-12).measure(fields)["thermal_conductance"][0]
    # Holm (1967): R = (1/k1 + 1/k2) / (4 a) for an isothermal circular spot; the
    # staircase's own area gives the radius (first order in dx/a: -0.3 % at 16)
    a = np.sqrt(spot.sum() * dx * dx / np.pi)
    assert series == pytest.approx(4 * a / (1 / K1 + 1 / K2), rel=0.01)
    # and exactly one half-space of the series conductivity, another path through the code
    single = ConductanceProbe(HalfSpaceBody(), conductivity=K1 * K2 / (K1 + K2),
                              tol=1e-12).measure(fields)["thermal_conductance"][0]
    assert series == pytest.approx(single, rel=1e-9)


def test_a_block_and_a_counter_half_space_against_a_direct_solve():
    geometry = BlockGeometry(size=(1.6e-3, 1.2e-3), thickness=0.8e-3, grid=(16, 12),
                             mesh="paper")
    spacing = (1e-4, 1e-4)
    rng = np.random.default_rng(7)
    spot = rng.random((12, 16)) < 0.15
    probe = ConductanceProbe(BlockBody(geometry), conductivity=K1, resistivity=RHO1,
                             counter_conductivity=K2, counter_resistivity=RHO2, tol=1e-12)
    measured = probe.measure(_fields(spot, spacing))
    # the referee: each body's matrix from its own constructor, summed and solved by numpy
    r1 = unit_conductivity_influence(geometry)  # k1 R1 [m]
    r2 = halfspace_thermal_influence((16, 12), (1.6e-3, 1.2e-3))  # k2 R2 [m]
    flat = np.flatnonzero(spot)
    dA, area = 1e-8, 1.6e-3 * 1.2e-3
    thermal = (r1 / K1 + r2 / K2)[np.ix_(flat, flat)]
    expected = dA * np.linalg.solve(thermal, np.ones(flat.size)).sum()
    assert measured["thermal_conductance"][0] == pytest.approx(expected, rel=1e-9)
    electrical = (r1 * RHO1 + r2 * RHO2)[np.ix_(flat, flat)]
    resistance = 1 / (dA * np.linalg.solve(electrical, np.ones(flat.size)).sum())
    assert measured["electrical_resistance"][0] == pytest.approx(resistance, rel=1e-9)
    # the bulk is the first block's alone (a half-space has none): L / (k1 A_n)
    assert measured["conduction_bulk_share"][0] == pytest.approx(
        0.8e-3 / (K1 * area) * expected, rel=1e-9)
    assert measured["conduction_converged"].all()


def test_the_series_is_stored_and_read_back_and_its_materials_checked():
    probe = ConductanceProbe(HalfSpaceBody(), conductivity=K1, counter_conductivity=K2)
    assert conductance_probe_from_params(probe.params()) == probe
    assert probe.params()["counter_conductivity"] == K2
    assert "counter_conductivity" not in ConductanceProbe(HalfSpaceBody(),
                                                          conductivity=K1).params()
    body = probe.thermal_body
    assert isinstance(body, SeriesBody) and body.ratio == pytest.approx(K1 / K2)
    assert body_from_params(body.params()) == body
    with pytest.raises(ValueError, match="counter_resistivity needs the body's own "
                                         "resistivity"):
        ConductanceProbe(HalfSpaceBody(), conductivity=K1, counter_resistivity=RHO2)
    with pytest.raises(ValueError, match="body.ratio must be a finite positive number"):
        SeriesBody(HalfSpaceBody(), HalfSpaceBody(), 0.0)
