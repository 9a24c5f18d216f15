"""A seal pressed once leaks less at the same load: the flow through the gap of the
flattened surface on unloading (roughcontact.contact.cycles with the flow probe)."""

import numpy as np

from roughcontact.contact.cycles import LoadingPath, cycle_sweep
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.elasticity.halfspace import PeriodicHalfSpace
from roughcontact.transport import FlowProbe, column_name
from roughcontact.transport.probe import CONDUCTANCE

N, SIZE = 32, 1e-3


def test_after_one_loading_the_gap_carries_less_flow_at_the_same_load():
    rng = np.random.default_rng(9)
    q = np.hypot(*np.meshgrid(np.fft.fftfreq(N), np.fft.fftfreq(N)))
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((2, N, N)))
                             * np.exp(-(q / 0.12) ** 2)))
    z *= 1e-6 / z.std(axis=(1, 2), keepdims=True)
    f = z.max(axis=(1, 2), keepdims=True) - z
    operator = PeriodicHalfSpace(grid=(N, N), size=(SIZE, SIZE), E=2e11, nu=0.3)
    grid = InterfaceGrid((SIZE / N, SIZE / N), periodic=True, probes=(FlowProbe(("x",)),))
    steps = 8
    path = LoadingPath.cycles(0.9 * 1.6e-6, steps, control="approach")
    result = cycle_sweep(operator, f, path, hardness=1.5e9, interface=grid)
    assert result.converged.all() and np.all(result.plastic_volume[:, -1] > 0)
    conductance = result.probe_columns[column_name(CONDUCTANCE, "x")]
    # the flow conductance at the loading leg's load halfway up, and on unloading at the
    # same load (interpolated in the load along the unloading leg): less, the spots
    # flattened into a closer gap
    for j in range(2):
        half = result.load[j, steps // 2]
        down = slice(steps, 2 * steps + 1)
        loads, flows = result.load[j, down][::-1], conductance[j, down][::-1]
        keep = loads > 0
        unloaded = np.interp(half, loads[keep], flows[keep])
        assert 0 < unloaded < conductance[j, steps // 2]
    # and the probe saw the flattened surface: with no yield its columns retrace
    elastic = cycle_sweep(operator, f, path, hardness=1e15, interface=grid)
    np.testing.assert_allclose(
        elastic.probe_columns[column_name(CONDUCTANCE, "x")][:, :steps + 1],
        elastic.probe_columns[column_name(CONDUCTANCE, "x")][:, steps:][:, ::-1],
        rtol=1e-5)
