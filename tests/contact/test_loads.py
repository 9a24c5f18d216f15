"""Load control (mean pressure given) against displacement control at the same mean pressure."""

import logging

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import SpectralHalfSpace

E, NU = 1.0e9, 0.3
SIZE = (1.2e-3, 1.0e-3)


def rough_gaps(count, shape, seed, sigma=1e-6):
    """Smooth random surfaces' initial separations ``max z - z`` [m], (count, ny, nx)."""
    ny, nx = shape
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.rfftfreq(nx) * nx, np.fft.fftfreq(ny) * ny))
    z = np.fft.irfft2(np.fft.rfft2(rng.standard_normal((count, ny, nx))) / (1 + q**2),
                      s=shape)
    z *= sigma / z.std(axis=(1, 2), keepdims=True)
    return z.max(axis=(1, 2), keepdims=True) - z


CASES = {
    "pcg-halfspace": (lambda: operators.halfspace_operator((24, 20), SIZE, NU), "pcg"),
    "pcg-spectral": (lambda: SpectralHalfSpace((24, 20), SIZE, E, NU), "pcg"),
    "cg-spectral": (lambda: SpectralHalfSpace((24, 20), SIZE, E, NU), "cg"),
    "pivot-dense": (lambda: operators.halfspace_operator((24, 20), SIZE, NU).to_dense(), "pivot"),
}


def _same(loaded, displaced, tol):
    np.testing.assert_array_equal(loaded.contact_set, displaced.contact_set)
    assert np.abs(loaded.pressure - displaced.pressure).max() <= tol * displaced.max_pressure
    assert loaded.approach == pytest.approx(displaced.approach, rel=tol)


@pytest.mark.parametrize("case", list(CASES))
def test_load_controlled_solve_equals_displacement_controlled(case):
    build, method = CASES[case]
    op = build()
    area = (SIZE[0] / 24) * (SIZE[1] / 20)
    gap = rough_gaps(1, (20, 24), seed=11)[0]
    for fraction in (0.2, 0.6):
        d = fraction * gap.mean()
        displaced = contact.solve(op, gap, d, element_area=area,
                                  options=SolverOptions(method=method, tol=1e-11))
        loaded = contact.solve(op, gap, mean_pressure=displaced.nominal_pressure, element_area=area,
                               options=SolverOptions(method=method, tol=1e-11))
        assert loaded.converged and loaded.method == method
        assert 0.005 < displaced.real_area_fraction < 0.9
        assert loaded.nominal_pressure == pytest.approx(displaced.nominal_pressure, rel=1e-9)
        _same(loaded, displaced, 1e-6)


@pytest.mark.parametrize("case", ["pcg-halfspace", "pivot-dense"])
def test_load_controlled_sweep_equals_displacement_controlled(case):
    build, method = CASES[case]
    op = build()
    area = (SIZE[0] / 24) * (SIZE[1] / 20)
    gaps = rough_gaps(2, (20, 24), seed=12)
    approaches = np.array([0.1, 0.3, 0.5]) * gaps.mean()
    displaced = contact.sweep(op, gaps, approaches, element_area=area,
                              options=SolverOptions(method=method, tol=1e-11, return_fields=True))
    loaded = contact.sweep(op, gaps, mean_pressures=displaced.nominal_pressure, element_area=area,
                           options=SolverOptions(method=method, tol=1e-11, return_fields=True))
    assert loaded.converged.all() and loaded.method == method
    np.testing.assert_array_equal(loaded.pressure > 0, displaced.pressure > 0)
    assert np.abs(loaded.pressure - displaced.pressure).max() <= 1e-6 * displaced.pressure.max()
    np.testing.assert_allclose(loaded.approach, displaced.approach, rtol=1e-6)
    np.testing.assert_allclose(loaded.contact_stiffness, displaced.contact_stiffness, rtol=1e-5)


def test_zero_load_touches_and_exactly_one_control_is_required():
    op = operators.halfspace_operator((8, 8), SIZE, NU)
    gap = rough_gaps(1, (8, 8), seed=13)[0]
    for method in ("pcg", "cg"):
        idle = contact.solve(op, gap, mean_pressure=0.0, options=SolverOptions(method=method))
        assert idle.converged and idle.load == 0.0 and idle.approach == gap.min()
    with pytest.raises(ValueError, match="exactly one of approach"):
        contact.solve(op, gap)
    with pytest.raises(ValueError, match="exactly one of approach"):
        contact.solve(op, gap, 1e-7, mean_pressure=1e3)
    with pytest.raises(ValueError, match="exactly one of approaches"):
        contact.sweep(op, gap[None], [1e-7], mean_pressures=[1e3])
    with pytest.raises(ValueError, match="mean_pressure must be finite and non-negative"):
        contact.solve(op, gap, mean_pressure=-1.0)


# --- issue 42: load control that stalled, and flags that cried wolf ------------------


@pytest.fixture(scope="module")
def paper_block():
    """The 32 x 32 paper-mesh block of issue 42 (4.8 mm wide, 10 mm thick, E 511 MPa,
    nu 0; condition number 6e7) and one of the rough surfaces (sigma 0.5 um, b 0.5 mm,
    seed 2) on which pcg's load control cycled at 0.1 MPa."""
    from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
    from roughcontact.elasticity.protocol import DenseInfluence
    from roughcontact.surfaces import synthetic
    from roughcontact.surfaces.spec import SurfaceSpec

    geom = BlockGeometry(size=(4.8e-3, 4.8e-3), grid=(32, 32), thickness=10e-3, mesh="paper",
                         nu=0.0)
    op = DenseInfluence(unit_modulus_influence(geom) / geom.E, geom.element_area, geom.grid)
    spec = SurfaceSpec(grid=32, size=4.8e-3, corr_length=0.5e-3, sigma=0.5e-6,
                       acf="exponential")
    heights = synthetic.generate_many(spec, range(3), method="paper")[2]
    return op, heights.max() - heights


@pytest.mark.parametrize("precision", ["double", "mixed"])
def test_pcg_load_control_on_an_ill_conditioned_block_is_right_or_flagged(paper_block,
                                                                          precision, caplog):
    # On 16554c5 pcg's load control cycled here from its first iteration (KKT residual
    # 0.43-0.66; 20000 iterations did not help) and the sweep returned a real area of
    # 0.52 against pivot's 0.02, flagged, and started its next step from it. Now the
    # stalled solve stops after its window and is solved again by pivoting; every step
    # is right.
    op, gap = paper_block
    loads = np.geomspace(0.1e6, 10e6, 12)
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = contact.sweep(op, gap[None], mean_pressures=loads,
                               options=SolverOptions(method="pcg", precision=precision, tol=1e-10,
                                                     stiffness=False))
    assert result.converged.all()
    np.testing.assert_allclose(result.nominal_pressure[0], loads, rtol=1e-8)
    # the referee: pivoting at the approaches found gives the same contact and loads
    exact = contact.sweep(op, gap[None], result.approach[0],
                          options=SolverOptions(method="pivot", tol=1e-12, stiffness=False))
    np.testing.assert_array_equal(result.real_area_fraction, exact.real_area_fraction)
    np.testing.assert_allclose(exact.nominal_pressure[0], loads, rtol=1e-6)
    assert not any("did not converge" in r.getMessage() for r in caplog.records)


def test_pcg_load_control_stall_is_cut_short(paper_block):
    # Without the retries the stalled solve is returned flagged after its stall window
    # (the residual not halved in max(1000, 4 sqrt(n)) iterations), not after 20000.
    from roughcontact.contact import pcg

    op, gap = paper_block
    stalled = contact.solve(op, gap, mean_pressure=0.1e6,
                            options=SolverOptions(method="pcg", tol=1e-10, retries=False))
    assert not stalled.converged and stalled.residual > 0.1
    assert stalled.iterations == pcg.stall_window(gap.size)
    retried = contact.solve(op, gap, mean_pressure=0.1e6,
                            options=SolverOptions(method="pcg", tol=1e-10))
    exact = contact.solve(op, gap, mean_pressure=0.1e6,
                          options=SolverOptions(method="exact", tol=1e-12))
    assert retried.converged
    np.testing.assert_array_equal(retried.contact_set, exact.contact_set)
    assert retried.approach == pytest.approx(exact.approach, rel=1e-8)


def _natural_residual(op, gap, approach, pressure):
    """The KKT residual of Eq 27 recomputed from the operator's products (not the
    solver's): ``max |min(C_ii p, g)| / max |d - f|``, ``g = C p + f - d``."""
    p = pressure.reshape(-1)
    g = np.asarray(op.matvec(p), dtype=float) + gap.reshape(-1) - approach
    natural = np.minimum(op.diagonal() * p, g)
    return float(np.abs(natural).max() / np.abs(approach - gap).max())


@pytest.mark.parametrize("seed", [1, 2])
def test_cg_load_control_flags_mean_what_they_say(seed):
    # On 16554c5 cg's outer solve on the approach used tol for both the KKT residual
    # and the load, and flagged good solutions (KKT met, load missed by 3e-10 to 2e-9),
    # and near full contact of these zero-mean operators it stopped at d = mean f with
    # the load 3-33 % off. Now: every step converged, to both tolerances, by an
    # independent measure.
    op = SpectralHalfSpace((32, 32), (1e-3, 1e-3), E, NU)
    gaps = rough_gaps(4, (32, 32), seed)
    loads = np.geomspace(1e5, 3e7, 8)
    result = contact.sweep(op, gaps, mean_pressures=loads,
                           options=SolverOptions(method="cg", tol=1e-10, return_fields=True,
                                                 stiffness=False))
    assert result.converged.all()
    for j, k in np.ndindex(result.approach.shape):
        pressure = result.pressure[j, k]
        assert abs(pressure.mean() - loads[k]) <= 1e-8 * loads[k]
        assert _natural_residual(op, gaps[j], result.approach[j, k], pressure) <= 1.01e-10
    assert (result.real_area_fraction[:, -1] > 0.99).all()  # near full contact
