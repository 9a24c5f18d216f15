"""What a sweep measures beyond pressure and load is a probe (roughcontact.contact.probes).

A probe of this file, :class:`GapCubed`, records the mean gap cubed (a length cubed,
``length_power`` 3), the nominal separation (a length) and whether a surface touches
(yes/no). Checked against what the sweep does not compute for it: the gaps
recomputed here from the returned pressure fields through the influence matrix
(``g = C p + f - d``); the dimensionless form scaled by sigma^3, sigma and 1; the
aggregate's mean of the column interpolated here by hand (a power law between the
steps, Eq 36's reading), in the column's unit; the rest of the sweep unchanged, bit
for bit, by the probe.
"""

from dataclasses import dataclass

import numpy as np
import pytest

from roughcontact.contact import SolverOptions, aggregate, sweep
from roughcontact.contact import cell as cell_module
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.nondim import CellOptions, to_physical
from roughcontact.contact.probes import Column, Probe, ProbeColumns, SolvedFields, measure
from roughcontact.elasticity.halfspace import halfspace_influence

N, SIZE, E = 10, 1.0e-3, 2.0e8
SPACING = (SIZE / N, SIZE / N)


@dataclass(frozen=True)
class GapCubed:
    """A probe of the test: ``mean(g)^3`` [m^3], the nominal separation [m] and whether
    any element is in contact (bool)."""

    kind = "gap_cubed"  # not annotated: class attributes, not fields
    columns = (Column("mean_gap_cubed", "m^3", "mean(g)^3, the mean gap cubed", length_power=3),
               Column("separation", "m", "h = mean(f) - d", length_power=1),
               Column("touching", "1", "share of surfaces in contact", dtype=bool))

    def params(self) -> dict:
        return {"statistic": "mean"}

    def measure(self, fields: SolvedFields) -> dict:
        return {"touching": (np.asarray(fields.pressure) > 0).any(axis=(-2, -1)),
                "separation": np.asarray(fields.separation),
                "mean_gap_cubed": np.asarray(fields.gap).mean(axis=(-2, -1)) ** 3}


def _separations(m=3, seed=7):
    """Initial separations f >= 0 [m] of ``m`` smooth random surfaces (m, N, N)."""
    rng = np.random.default_rng(seed)
    q = np.fft.fftfreq(N)
    kernel = np.exp(-(np.hypot(*np.meshgrid(q, q)) / 0.15) ** 2)
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((m, N, N))) * kernel))
    z *= 1e-6 / z.std(axis=(1, 2), keepdims=True)
    return z.max(axis=(1, 2), keepdims=True) - z


@pytest.fixture(scope="module")
def matrix():
    return halfspace_influence((N, N), (SIZE, SIZE), E, 0.3)


@pytest.mark.parametrize("method", ["cg", "pivot"])  # pivot records one surface at a time
def test_a_sweep_records_the_probe_at_every_step(matrix, method):
    gaps = _separations()
    approaches = np.linspace(0.3e-6, 2.0e-6, 5)
    plain = sweep(matrix, gaps, approaches, element_area=SPACING[0] ** 2,
                  interface=InterfaceGrid(SPACING),
                  options=SolverOptions(method=method, return_fields=True, stiffness=False))
    probed = sweep(matrix, gaps, approaches, element_area=SPACING[0] ** 2,
                   interface=InterfaceGrid(SPACING, probes=(GapCubed(),)),
                   options=SolverOptions(method=method, return_fields=True, stiffness=False))
    columns = probed.probe_columns
    assert list(columns) == ["mean_gap_cubed", "separation", "touching"]
    assert columns["touching"].dtype == bool and columns["separation"].shape == (3, 5)
    for j in range(3):
        for step, d in enumerate(approaches):
            p = probed.pressure[j, step]
            gap = (matrix @ p.ravel()).reshape(N, N) + gaps[j] - d
            np.testing.assert_allclose(columns["mean_gap_cubed"][j, step], gap.mean() ** 3,
                                       rtol=1e-9)
            np.testing.assert_allclose(columns["separation"][j, step], gaps[j].mean() - d,
                                       rtol=1e-9)
            assert columns["touching"][j, step] == (p > 0).any()
    assert columns["touching"][:, -1].all() and columns["mean_gap_cubed"][:, -1].min() > 0
    # without the probe: no probe column, and every other number the same, bit for bit
    assert len(plain.probe_columns) == 0 and plain.probe_columns.probes == ()
    for name in ("load", "real_area_fraction", "mean_gap", "spot_count", "residual",
                 "pressure"):
        np.testing.assert_array_equal(getattr(plain, name), getattr(probed, name))


@pytest.fixture(scope="module")
def cell_sweep():
    """A dimensionless cell sweep with the probe, in batches of 2 of its 3 surfaces."""
    heights = _separations(seed=11)
    heights = -(heights - heights.mean(axis=(1, 2), keepdims=True)) / heights.std()
    geometry = type("Block", (), {"thickness": 5e-3, "element_area": SPACING[0] ** 2,
                                  "size": (SIZE, SIZE), "grid": (N, N)})()
    unit = halfspace_influence((N, N), (SIZE, SIZE), 1.0, 0.3)
    options = CellOptions().with_(method="pivot", batch_size=2,
                                  interface=InterfaceGrid(SPACING, probes=(GapCubed(),)))
    return cell_module.sweep_cell(unit, heights, geometry, 0.5, 12, options=options)


def test_the_dimensionless_form_scales_each_column_by_its_length_power(cell_sweep):
    nd = cell_sweep
    assert nd.probe_columns.probes == (GapCubed(),)  # joined over the batches of 2 and 1
    assert nd.probe_columns["mean_gap_cubed"].shape == nd.approach.shape == (3, 12)
    # the mean gap the interface records, in units of sigma, cubed
    np.testing.assert_allclose(nd.probe_columns["mean_gap_cubed"], nd.mean_gap ** 3,
                               rtol=1e-12)
    sigma = 3e-6
    physical = to_physical(nd, sigma, E)
    si = physical.probe_columns
    np.testing.assert_array_equal(si["mean_gap_cubed"],
                                  sigma**3 * nd.probe_columns["mean_gap_cubed"])
    np.testing.assert_array_equal(si["separation"], sigma * nd.probe_columns["separation"])
    np.testing.assert_array_equal(si["touching"], nd.probe_columns["touching"])
    assert si["touching"].dtype == bool
    np.testing.assert_allclose(si["mean_gap_cubed"], physical.mean_gap ** 3, rtol=1e-12)
    units = physical.to_frame().attrs["units"]
    assert (units["mean_gap_cubed"], units["separation"], units["touching"]) == (
        "m^3", "m", "bool")


def test_the_aggregate_averages_a_probe_column_in_its_unit(cell_sweep):
    physical = to_physical(cell_sweep, 3e-6, E)
    levels = aggregate.pressure_axis(*aggregate.covered_range(physical), 5)
    table = aggregate.aggregate_cell(physical, levels)
    assert table.attrs["units"]["mean_gap_cubed_mean"] == "m^3"
    assert table.attrs["units"]["separation_half_width"] == "m"
    assert table.attrs["units"]["touching_mean"] == "1"
    # the probe's columns come last, in its order
    quantities = [name[:-5] for name in table.columns if name.endswith("_mean")]
    assert quantities[-3:] == ["mean_gap_cubed", "separation", "touching"]
    # each surface's power law between its converged steps, by hand, then the mean
    by_hand = []
    for j in range(physical.approach.shape[0]):
        P = physical.nominal_pressure[j]
        usable = physical.converged[j] & (P > 0)
        y = physical.probe_columns["mean_gap_cubed"][j, usable]
        by_hand.append(np.exp(np.interp(np.log(levels), np.log(P[usable]), np.log(y))))
    np.testing.assert_allclose(table["mean_gap_cubed_mean"], np.mean(by_hand, axis=0),
                               rtol=1e-12)
    assert (table["mean_gap_cubed_count"] == 3).all()
    assert table["touching_mean"].between(0.0, 1.0).all()


def test_probe_columns_hold_exactly_their_probes_columns():
    values = {"mean_gap_cubed": np.zeros((2, 3)), "separation": np.zeros((2, 3)),
              "touching": np.zeros((2, 3), dtype=bool)}
    columns = ProbeColumns((GapCubed(),), dict(reversed(values.items())))
    assert list(columns) == ["mean_gap_cubed", "separation", "touching"]  # the probe's order
    assert [column.length_power for column in columns.specs] == [3, 1, 0]
    with pytest.raises(TypeError):
        columns.values["separation"] = np.ones((2, 3))  # read-only
    with pytest.raises(ValueError, match="touching"):
        ProbeColumns((GapCubed(),), {k: v for k, v in values.items() if k != "touching"})
    with pytest.raises(ValueError, match="distinct"):
        InterfaceGrid(SPACING, probes=(GapCubed(), GapCubed()))
    assert isinstance(GapCubed(), Probe)
    allocated = ProbeColumns.allocated((GapCubed(),), (2, 3))
    assert allocated["touching"].dtype == bool and allocated["separation"].dtype == float


def test_measure_asks_every_probe_for_its_columns_in_order():
    gap = np.arange(2 * N * N, dtype=float).reshape(2, N, N)
    fields = SolvedFields(np.zeros_like(gap), gap, np.array([1.0, 2.0]), SPACING, False)
    measured = measure((GapCubed(),), fields)
    assert list(measured) == ["mean_gap_cubed", "separation", "touching"]
    np.testing.assert_array_equal(measured["mean_gap_cubed"], gap.mean(axis=(1, 2)) ** 3)
    assert measure((), fields) == {}


@pytest.mark.parametrize(("bad", "match"), [
    ({"dtype": int}, "dtype"), ({"dtype": bool, "length_power": 1}, "yes/no"),
    ({"length_power": 1.5}, "length_power"), ({"name": "a b"}, "identifier")])
def test_a_bad_column_is_refused(bad, match):
    with pytest.raises(ValueError, match=match):
        Column(**{"name": "c", "unit": "1", "meaning": "c", **bad})
