"""The flow a sweep records through its solutions' gaps (roughcontact.transport.probe).

Checked against what the sweep does not compute for it: the gap recomputed here from
the returned pressure fields through the operator (u = C p, g = u + f - d with the
elements in contact closed), solved by an independent five-point finite-volume
system of this file (harmonic faces, scipy's spsolve) on which the probe shares no
code; the flow off changes no other number, bit for bit; the columns survive the
dimensionless form (conductance scaled by sigma^3) and the contact file.
"""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from roughcontact.contact import SolverOptions, sweep
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.probes import Probe, SolvedFields
from roughcontact.elasticity.halfspace import PeriodicHalfSpace
from roughcontact.study.jobs import storage
from roughcontact.transport import ARITHMETIC, FLOW_COLUMNS, NO_FLOW, FlowProbe

N, SIZE, E = 32, 1.0e-3, 1.0e9


def _surfaces(m=3, seed=4):
    rng = np.random.default_rng(seed)
    q = np.fft.fftfreq(N)
    kernel = np.exp(-(np.hypot(*np.meshgrid(q, q)) / 0.08) ** 2)
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((m, N, N))) * kernel))
    z *= 1e-6 / z.std(axis=(1, 2), keepdims=True)
    return z.max(axis=(1, 2), keepdims=True) - z  # initial separations f >= 0


def _reference_conductance(gap, periodic_sides: bool) -> float:
    """K of one gap field (ny, nx), flow along x, pressure 1 at x = 0 and 0 at x = Lx,
    square elements, harmonic faces: a plain five-point system over ALL open elements
    (isolated clusters get a tiny leak to pressure 0 so the matrix is regular; they
    carry no flow from the inlet)."""
    ny, nx = gap.shape
    unit = gap.max()
    k = (gap / unit) ** 3
    index = np.arange(ny * nx).reshape(ny, nx)
    rows, cols, vals = [], [], []
    diag = np.full(ny * nx, 1e-20)
    rhs = np.zeros(ny * nx)

    def face(a, b, ka, kb):
        t = np.where((ka > 0) & (kb > 0), 2 * ka * kb / np.where(ka + kb > 0, ka + kb, 1), 0)
        np.add.at(diag, a, t)
        np.add.at(diag, b, t)
        rows.extend([a, b])
        cols.extend([b, a])
        vals.extend([-t, -t])

    face(index[:, :-1].ravel(), index[:, 1:].ravel(), k[:, :-1].ravel(), k[:, 1:].ravel())
    last = ny if periodic_sides else ny - 1
    lo, hi = np.arange(last), (np.arange(last) + 1) % ny
    face(index[lo].ravel(), index[hi].ravel(), k[lo].ravel(), k[hi].ravel())
    inlet, outlet = index[:, 0], index[:, -1]
    diag[inlet] += 2 * k[:, 0]
    rhs[inlet] += 2 * k[:, 0]
    diag[outlet] += 2 * k[:, -1]
    closed = (k == 0).ravel()
    diag[closed] = 1.0
    matrix = sp.csr_matrix((np.concatenate([diag, *vals]),
                            (np.concatenate([np.arange(ny * nx), *rows]),
                             np.concatenate([np.arange(ny * nx), *cols]))))
    p = spla.spsolve(matrix.tocsc(), rhs)
    q_in = np.sum(2 * k[:, 0] * (1 - p[inlet]))
    return q_in * unit**3 * nx / ny  # K = 12 eta Q Lx / (Ly dp), 12 eta = dp = 1, dx = dy


@pytest.fixture(scope="module")
def solved():
    operator = PeriodicHalfSpace((N, N), (SIZE, SIZE), E=E, nu=0.3)
    gaps = _surfaces()
    loads = np.geomspace(2e5, 2e7, 5)
    grid = InterfaceGrid((SIZE / N, SIZE / N), periodic=True)
    plain = sweep(operator, gaps, mean_pressures=loads, interface=grid,
                  options=SolverOptions(method="pcg", return_fields=True, stiffness=False))
    flowing = sweep(operator, gaps, mean_pressures=loads,
                    interface=InterfaceGrid(grid.spacing, True, probes=(FlowProbe(),)),
                    options=SolverOptions(method="pcg", return_fields=True, stiffness=False))
    return operator, gaps, plain, flowing


def test_the_columns_are_the_flow_through_the_solutions_gaps(solved):
    operator, gaps, _, flowing = solved
    flow = flowing.probe_columns
    m, k = flowing.approach.shape
    checked = 0
    for j in range(m):
        for step in range(k):
            p = flowing.pressure[j, step]
            u = (operator @ p.ravel()).reshape(N, N)
            gap = np.where(p > 0, 0.0, np.maximum(u + gaps[j] - flowing.approach[j, step], 0))
            if not flow["flow_connected_x"][j, step]:
                assert flow["flow_conductance_x"][j, step] == 0.0
                continue
            expected = _reference_conductance(gap, periodic_sides=True)
            np.testing.assert_allclose(flow["flow_conductance_x"][j, step], expected,
                                       rtol=1e-8)
            np.testing.assert_allclose(flow["flow_factor_x"][j, step],
                                       expected / gap.mean() ** 3, rtol=1e-8)
            separation = np.mean(gaps[j]) - flowing.approach[j, step]  # mean(f) - d
            if separation > 0:
                np.testing.assert_allclose(flow["pressure_flow_factor_x"][j, step],
                                           expected / separation**3, rtol=1e-6)
            checked += 1
    assert checked >= 5  # leaking steps were compared (the sweep also reaches sealing)
    assert not flow["flow_connected_x"][:, -1].any()  # 2e7 Pa: sealed on every surface


def test_flow_off_records_nothing_and_flow_on_changes_no_other_number(solved):
    _, _, plain, flowing = solved
    assert len(plain.probe_columns) == 0 and plain.probe_columns.probes == ()
    assert list(flowing.probe_columns) == list(FLOW_COLUMNS)
    assert flowing.probe_columns.probes == (FlowProbe(),)
    for name in ("approach", "nominal_pressure", "real_area_fraction", "mean_gap",
                 "spot_count", "residual", "pressure"):
        np.testing.assert_array_equal(getattr(plain, name), getattr(flowing, name))


def test_the_conductance_falls_as_the_load_grows(solved):
    """Rayleigh's monotonicity: a gap closing everywhere passes less (the gap of a
    frictionless contact under a growing load closes everywhere, checked here)."""
    operator, gaps, _, flowing = solved
    p = flowing.pressure
    u = np.einsum("ij,mkj->mki", operator.dense() if hasattr(operator, "dense") else
                  np.column_stack([operator @ e for e in np.eye(N * N)]),
                  p.reshape(*p.shape[:2], -1)).reshape(p.shape)
    gap = np.maximum(u + gaps[:, None] - flowing.approach[..., None, None], 0.0)
    assert (np.diff(gap, axis=1) <= 1e-9 * gap.max()).all()  # to the solver's tolerance
    for name in ("flow_conductance_x", "flow_conductance_y"):
        assert (np.diff(flowing.probe_columns[name], axis=1) <= 0.0).all()


def test_one_direction_and_the_arithmetic_rule(solved):
    operator, gaps, _, flowing = solved
    probe = FlowProbe(directions=("y",), face_rule=ARITHMETIC)
    assert probe.names == ("flow_conductance_y", "flow_factor_y", "pressure_flow_factor_y",
                           "flow_connected_y", "flow_balance_y")
    again = sweep(operator, gaps[:1], mean_pressures=np.geomspace(2e5, 2e7, 5),
                  interface=InterfaceGrid((SIZE / N, SIZE / N), True, probes=(probe,)),
                  options=SolverOptions(method="pcg", stiffness=False))
    assert "flow_conductance_x" not in again.probe_columns
    assert list(again.probe_columns) == list(probe.names)
    # the arithmetic mean of two conductances is at least their harmonic mean: the
    # arithmetic rule passes at least as much, and the connectivity is the rule's own
    harmonic = sweep(operator, gaps[:1], mean_pressures=np.geomspace(2e5, 2e7, 5),
                     interface=InterfaceGrid((SIZE / N, SIZE / N), True,
                                             probes=(FlowProbe(directions=("y",)),)),
                     options=SolverOptions(method="pcg", stiffness=False))
    arithmetic, harmonic = again.probe_columns, harmonic.probe_columns
    assert (arithmetic["flow_conductance_y"]
            >= harmonic["flow_conductance_y"] * (1 - 1e-12)).all()
    np.testing.assert_array_equal(arithmetic["flow_connected_y"], harmonic["flow_connected_y"])


def test_gaps_of_rounding_size_are_closed():
    """A chain of elements with p = 0 and a gap of 1e-12 of the largest, through a
    field otherwise in contact but for two open pools at inlet and outlet: closed by
    default (no percolation through rounding), open with closed_below=0."""
    gap = np.zeros((1, 6, 12))
    pressure = np.ones_like(gap)
    gap[0, :, :2] = gap[0, :, -2:] = 1e-6  # pools at inlet and outlet
    pressure[0, :, :2] = pressure[0, :, -2:] = 0.0
    gap[0, 3, 2:-2] = 1e-18  # the chain
    pressure[0, 3, 2:-2] = 0.0
    fields = SolvedFields(pressure, gap, np.array([1e-6]), (1e-5, 1e-5), False)
    columns = FlowProbe(directions=("x",)).measure(fields)
    assert not columns["flow_connected_x"][0] and columns["flow_conductance_x"][0] == 0.0
    opened = FlowProbe(directions=("x",), closed_below=0.0).measure(fields)
    # connected, through a chain that passes nothing but rounding: the inlet flow is read
    # off a pressure drop of 1 - p ~ 1e-16 at the pools (K ~ 1e-15 of the pools' 1e-18)
    assert opened["flow_connected_x"][0] and opened["flow_conductance_x"][0] < 1e-30


def test_the_default_band_solver_gives_superlus_conductance(solved):
    from roughcontact.transport import DIRECT

    operator, gaps, _, flowing = solved
    for sides in ("sealed", "periodic"):
        banded = FlowProbe(sides=sides)
        lu = FlowProbe(sides=sides, solver=DIRECT)
        g = np.maximum(gaps - 0.8 * gaps.mean(), 0.0)
        p = np.where(g == 0.0, 1.0, 0.0)
        fields = SolvedFields(p, g, g.mean(axis=(1, 2)), (1e-5, 1e-5), False)
        a, b = banded.measure(fields), lu.measure(fields)
        for name in a:
            if name.startswith("flow_balance"):  # rounding-size: each below 1e-10
                assert (a[name] < 1e-10).all() and (b[name] < 1e-10).all()
            else:
                np.testing.assert_allclose(a[name], b[name], rtol=1e-10)


def test_the_flow_probe_is_a_probe_and_names_its_columns():
    probe = FlowProbe()
    assert isinstance(probe, Probe) and probe.kind == "flow"
    assert [column.name for column in probe.columns] == list(FLOW_COLUMNS) == [
        f"{quantity}_{d}" for d in "xy" for quantity in
        ("flow_conductance", "flow_factor", "pressure_flow_factor", "flow_connected",
         "flow_balance")]
    # the conductance is a gap cubed: m^3, sigma^3 in the dimensionless form
    assert {column.name: (column.unit, column.length_power, column.dtype)
            for column in probe.columns if column.name.endswith("_x")} == {
        "flow_conductance_x": ("m^3", 3, float), "flow_factor_x": ("1", 0, float),
        "pressure_flow_factor_x": ("1", 0, float), "flow_connected_x": ("1", 0, bool),
        "flow_balance_x": ("1", 0, float)}
    # x before y whatever order the directions are given in
    assert FlowProbe(directions=("y", "x")).names == FLOW_COLUMNS
    assert NO_FLOW.columns == () and NO_FLOW.measure(None) == {}


@pytest.mark.parametrize("bad", [{"directions": ("z",)}, {"directions": ("x", "x")},
                                 {"sides": "open"}, {"face_rule": "harmonic"}])
def test_a_bad_probe_is_refused_naming_the_setting(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        FlowProbe(**bad)


def test_the_dimensionless_form_scales_the_conductance_by_sigma_cubed(tmp_path):
    from roughcontact.contact import cell as cell_module
    from roughcontact.contact.nondim import CellOptions, to_physical
    from roughcontact.elasticity.halfspace import halfspace_influence

    heights = _surfaces(m=2, seed=9)[:, :16, :16]
    heights = (heights - heights.mean(axis=(1, 2), keepdims=True)) / heights.std()
    geometry = type("Block", (), {"thickness": 10e-3, "element_area": (1e-4) ** 2,
                                  "size": (1.6e-3, 1.6e-3), "grid": (16, 16)})()
    unit = halfspace_influence((16, 16), (1.6e-3, 1.6e-3), 1.0, 0.0)
    grid = InterfaceGrid((1e-4, 1e-4), probes=(FlowProbe(),))
    options = CellOptions().with_(method="pivot", interface=grid)
    nd = cell_module.sweep_cell(unit, heights, geometry, 0.05, 8, options=options)
    sigma = 2e-6
    physical = to_physical(nd, sigma, 1e8)
    si, scaled = physical.probe_columns, nd.probe_columns
    np.testing.assert_allclose(si["flow_conductance_x"], scaled["flow_conductance_x"] * sigma**3,
                               rtol=1e-15)
    np.testing.assert_array_equal(si["flow_factor_x"], scaled["flow_factor_x"])
    np.testing.assert_array_equal(si["flow_connected_y"], scaled["flow_connected_y"])
    assert si["flow_connected_y"].dtype == bool
    # and through a contact file, bit for bit, the probe made again from its settings
    path = tmp_path / "contact.h5"
    storage.write_contact(path, nd, {"job": "{}"})
    back, attrs = storage.read_contact(path)
    assert attrs["flow"] == ('{"balance_tol":1e-06,"closed_below":1e-07,"directions":["x","y"],'
                             '"face_rule":"harmonic","sides":"grid"}')
    assert back.probe_columns.probes == (FlowProbe(),)
    assert list(back.probe_columns) == list(FLOW_COLUMNS)
    for name in FLOW_COLUMNS:
        np.testing.assert_array_equal(back.probe_columns[name], scaled[name])


@pytest.mark.parametrize("sides", ["periodic", "sealed"])
def test_a_sweep_to_sealing_has_no_negative_conductance_and_records_the_balance(sides):
    """Twelve loads up to sealing on every surface: every connected step's conductance
    positive and finite, its balance recorded and within the tolerance (none flagged:
    2e-12 to 8e-9 measured on such sweeps); a sealed step's conductance and balance 0."""
    operator = PeriodicHalfSpace((N, N), (SIZE, SIZE), E=E, nu=0.3)
    result = sweep(operator, _surfaces(seed=8), mean_pressures=np.geomspace(1e6, 3e7, 12),
                   interface=InterfaceGrid((SIZE / N, SIZE / N), True,
                                           probes=(FlowProbe(sides=sides),)),
                   options=SolverOptions(method="pcg", stiffness=False))
    flow = result.probe_columns
    for d in "xy":
        connected = flow[f"flow_connected_{d}"]
        conductance, balance = flow[f"flow_conductance_{d}"], flow[f"flow_balance_{d}"]
        assert connected.any() and not connected[:, -1].any()  # reaches sealing
        assert (conductance[connected] > 0.0).all() and np.isfinite(conductance).all()
        assert (balance[connected] <= FlowProbe().balance_tol).all()
        assert (balance[connected] > 0.0).any()  # computed, not a placeholder
        assert (conductance[~connected] == 0.0).all() and (balance[~connected] == 0.0).all()
        # the last connected step of each surface passes orders of magnitude less than
        # its first: the sweep went close to sealing
        last = [row[c][-1] for row, c in zip(conductance, connected, strict=True) if c.any()]
        assert min(last) < 1e-3 * conductance[:, 0].max()
