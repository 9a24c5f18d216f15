"""The band Cholesky solver of the flow gives the direct solver's conductance."""

import numpy as np
import pytest

from roughcontact.transport import DIRECT, PERIODIC, SEALED, BandedCholesky, FlowSetup, solve_flow


@pytest.mark.parametrize("sides", [SEALED, PERIODIC])
@pytest.mark.parametrize("direction", ["x", "y"])
def test_banded_cholesky_matches_superlu(sides, direction):
    rng = np.random.default_rng(3)
    gap = np.maximum(rng.normal(size=(3, 24, 30)) + 0.8, 0.0) * 1e-6  # ~20 % in contact
    results = [solve_flow(gap, FlowSetup((1e-5, 2e-5), direction, sides, solver=solver))
               for solver in (DIRECT, BandedCholesky(max_bandwidth=1000))]
    direct, banded = results
    assert np.array_equal(direct.connected, banded.connected)
    assert direct.connected.any()
    np.testing.assert_allclose(banded.conductance, direct.conductance, rtol=1e-10, atol=0.0)


def test_banded_cholesky_falls_back_beyond_its_bandwidth():
    gap = np.full((8, 8), 1e-6)
    banded = solve_flow(gap, FlowSetup((1e-5, 1e-5), "x", PERIODIC,
                                       solver=BandedCholesky(max_bandwidth=4)))
    np.testing.assert_allclose(banded.conductance, 1e-18, rtol=1e-12)
