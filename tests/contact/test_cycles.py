"""Loading, unloading, reloading with the cap's permanent set (roughcontact.contact.cycles),
against closed forms of the model and an independent bounded least-squares solve."""

import logging

import numpy as np
import pytest
from scipy.linalg import cholesky, solve_triangular
from scipy.optimize import lsq_linear

from roughcontact.contact import SolverOptions
from roughcontact.contact.cycles import LoadingPath, cycle_sweep, loop_work
from roughcontact.elasticity.halfspace import PeriodicHalfSpace, halfspace_influence

N, SIZE, E, NU = 24, 1e-3, 2e11, 0.3


def _separations(m: int, n: int = N, seed: int = 1) -> np.ndarray:
    """``m`` Gaussian surfaces of 1 um rms height as separations from their first touch."""
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n)))
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((m, n, n)))
                             * np.exp(-(q / 0.1) ** 2)))
    z *= 1e-6 / z.std(axis=(1, 2), keepdims=True)
    return z.max(axis=(1, 2), keepdims=True) - z


@pytest.fixture(scope="module")
def periodic():
    return PeriodicHalfSpace(grid=(N, N), size=(SIZE, SIZE), E=E, nu=NU)


def test_below_the_first_saturation_unloading_retraces_loading(periodic):
    f = _separations(2)
    path = LoadingPath.cycles(1.0e-6, 8)
    elastic = cycle_sweep(periodic, f, path, hardness=1e15)  # never reached
    assert elastic.converged.all() and np.all(elastic.plastic == 0.0)
    assert np.all(elastic.plastic_volume == 0.0) and np.all(elastic.permanent_set == 0.0)
    up, down = elastic.load[:, :9], elastic.load[:, 8:][:, ::-1]  # the same approaches
    np.testing.assert_allclose(down, up, rtol=1e-7, atol=1e-12 * up.max())
    # and on the way down the tangent stiffness is the loading one's (but at d = 0, the
    # first touch itself, where whether the highest point carries a pressure of round-off
    # size decides whether there is a stiffness at all)
    np.testing.assert_allclose(elastic.contact_stiffness[:, 8:-1][:, ::-1],
                               elastic.contact_stiffness[:, 1:9], rtol=1e-4)


def test_reloading_to_the_peak_gives_back_its_pressures_and_no_new_yield(periodic):
    f = _separations(3)
    path = LoadingPath.cycles(1.5e-6, 10, cycles=2)
    result = cycle_sweep(periodic, f, path, hardness=2e9,
                         options=SolverOptions(return_fields=True))
    assert result.converged.all()
    first_peak, second_peak = 10, 30
    volume = result.plastic_volume[:, 20]
    assert np.all(volume > 0) and np.all(result.plastic_area_fraction[:, first_peak] > 0)
    # the plastic volume never falls, and the second cycle adds nothing (shakedown)
    assert np.all(np.diff(result.plastic_volume, axis=1) >= 0.0)
    assert np.all(result.plastic_volume[:, -1] - volume <= 1e-9 * volume)
    np.testing.assert_allclose(result.pressure[:, second_peak], result.pressure[:, first_peak],
                               rtol=1e-6, atol=1e-8 * 2e9)
    # unloaded, the flattened surface first touches at the permanent set: no load there
    assert np.all(result.load[:, 20] == 0.0) and np.all(result.permanent_set[:, 20] > 0)
    # unloading is elastic and stiffer than loading at the same load (the spots stay
    # larger): compare at the unloading step whose load is nearest half the peak's
    for j in range(3):
        half = result.load[j, first_peak] / 2
        up = np.interp(half, result.load[j, :11], result.contact_stiffness[j, :11])
        down_loads = result.load[j, 10:21][::-1]
        down = np.interp(half, down_loads, result.contact_stiffness[j, 10:21][::-1])
        assert down > up


def test_the_loop_dissipates_the_plastic_work_as_the_steps_shrink(periodic):
    f = _separations(2, seed=4)
    errors = []
    for steps in (10, 20, 40):
        result = cycle_sweep(periodic, f, LoadingPath.cycles(1.5e-6, steps), hardness=2e9,
                             options=SolverOptions(stiffness=False))
        plastic_work = 2e9 * result.plastic_volume[:, -1]  # H V_p, of the stored field
        assert result.plastic_volume[:, -1] == pytest.approx(
            result.plastic.sum(axis=1) * result.element_area, rel=1e-12)
        errors.append(np.abs(loop_work(result) / plastic_work - 1).max())
    # the trapezoids' error falls about four times a halving (second order)
    assert errors[0] < 0.03 and errors[1] < errors[0] / 2.5 and errors[2] < errors[1] / 2.5
    assert errors[2] < 2e-3


def _referee(matrix, f, path, hardness):
    """The same model by bounded least squares (scipy's lsq_linear) and its own yield:
    min 1/2 p.Cp - p.(d - f - w) over 0 <= p <= H is ||R^T p - R^-1 (d - f - w)||^2
    with C = R R^T."""
    lower = cholesky(matrix, lower=True)
    plastic, pressures, volumes = np.zeros_like(f), [], []
    for d in path.values:
        target = solve_triangular(lower, d - f - plastic, lower=True)
        fit = lsq_linear(lower.T, target, bounds=(0.0, hardness), method="bvls", tol=1e-14)
        p = fit.x
        gap = matrix @ p + f + plastic - d
        plastic = plastic + np.where(fit.active_mask == 1, np.maximum(-gap, 0.0), 0.0)
        pressures.append(p)
        volumes.append(plastic.sum())
    return np.array(pressures), np.array(volumes)


def test_a_dense_half_space_against_bounded_least_squares_including_unloading():
    n, size = 10, 1e-3
    matrix = halfspace_influence((n, n), (size, size), E, NU)  # [m/Pa], dense, free
    y, x = (np.mgrid[:n, :n] + 0.5) / n
    heights = 1e-6 * (np.cos(2 * np.pi * x) * np.cos(2 * np.pi * y) + 0.3 * np.sin(
        4 * np.pi * x))
    f = (heights.max() - heights).ravel()
    path = LoadingPath.cycles(1.2e-6, 6, unload_to=0.3e-6, cycles=2)
    hardness = 1.5e9
    result = cycle_sweep(matrix, f[None], path, hardness, element_area=(size / n) ** 2,
                         options=SolverOptions(return_fields=True, tol=1e-12))
    pressures, volumes = _referee(matrix, f, path, hardness)
    assert result.converged.all() and volumes[-1] > 0
    np.testing.assert_allclose(result.pressure[0], pressures, rtol=1e-6,
                               atol=1e-7 * hardness)
    np.testing.assert_allclose(result.plastic_volume[0] / (size / n) ** 2, volumes,
                               rtol=1e-6, atol=1e-9 * volumes[-1])


def test_under_load_control_the_same_state_at_the_same_load(periodic):
    f = _separations(1, seed=2)
    by_approach = cycle_sweep(periodic, f, LoadingPath.cycles(1.5e-6, 12), hardness=2e9)
    peak = float(by_approach.nominal_pressure[0, 12])
    by_load = cycle_sweep(periodic, f, LoadingPath.cycles(peak, 12, control="mean_pressure"),
                          hardness=2e9)
    assert by_load.converged[0, 1:].all()
    # the peak: the same approach and permanent set as under displacement control
    assert by_load.approach[0, 12] == pytest.approx(by_approach.approach[0, 12], rel=1e-6)
    assert by_load.plastic_volume[0, 12] == pytest.approx(by_approach.plastic_volume[0, 12],
                                                          rel=1e-6)


def test_bad_paths_are_refused_and_an_unconverged_surface_is_flagged_onwards(periodic,
                                                                             caplog):
    with pytest.raises(ValueError, match="control must be one of"):
        LoadingPath((1.0,), control="force")
    with pytest.raises(ValueError, match="values must be finite non-negative"):
        LoadingPath((1e-6, -1e-6))
    with pytest.raises(ValueError, match="need 0 <= unload_to < peak"):
        LoadingPath.cycles(1e-6, 4, unload_to=2e-6)
    with pytest.raises(ValueError, match="hardness must be a finite positive cap"):
        cycle_sweep(periodic, _separations(1), LoadingPath((1e-6,)), hardness=np.inf)
    options = SolverOptions(method="cg", max_iter=2, retries=False)
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = cycle_sweep(periodic, _separations(1), LoadingPath.cycles(1.5e-6, 3),
                             hardness=2e9, options=options)
    first = int(np.argmin(result.converged[0]))
    assert not result.converged[0, first:].any()
    assert np.isnan(result.load[0, first:]).all()
    assert "did not converge for surfaces [0]" in caplog.text


def test_the_summary_of_each_cycle(periodic):
    from roughcontact.contact.cycles import cycle_summary

    f = _separations(2)
    result = cycle_sweep(periodic, f, LoadingPath.cycles(1.5e-6, 20, cycles=2), hardness=2e9)
    summary = cycle_summary(result)
    assert summary["peak_load"].shape == (2, 2)
    first, second = (slice(None), 0), (slice(None), 1)
    # the first cycle dissipates its plastic work (trapezoids, 20 steps a leg: < 1 %),
    # the second neither yields nor dissipates: shaken down, unloading retraces loading
    np.testing.assert_allclose(summary["dissipated"][first], summary["plastic_work"][first],
                               rtol=0.01)
    assert np.all(summary["plastic_work"][second] <= 1e-9 * summary["plastic_work"][first])
    assert np.all(np.abs(summary["dissipated"][second]) < 1e-6 * summary["dissipated"][first])
    assert summary["shaken_down"].tolist() == [[False, True], [False, True]]
    assert np.all(summary["unloading_stiffness_ratio"][first] > 1.0)
    np.testing.assert_allclose(summary["unloading_stiffness_ratio"][second], 1.0, rtol=1e-3)
    # the residual approach of the unloaded surface: the flattened surface's first touch
    np.testing.assert_allclose(summary["permanent_set"][first],
                               (f.reshape(2, -1) + result.plastic).min(axis=1), rtol=1e-12)


def _operators():
    """The bodies a cycle runs on: a dense and an FFT half-space, the finite block (its
    dense finite-element matrix) and a pair of bodies (C1 + C2)."""
    from roughcontact.contact.counterface import equivalent_operator, scaled
    from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
    from roughcontact.elasticity.operators import halfspace_operator

    n, size = 12, 1e-3
    area = (size / n) ** 2
    dense = halfspace_influence((n, n), (size, size), E, NU)
    block = BlockGeometry(size=(size, size), thickness=1e-3, grid=(n, n), mesh="paper",
                          E=E, nu=NU)
    return area, {
        "dense half-space": dense,
        "FFT half-space": scaled(halfspace_operator((n, n), (size, size), NU), 1 / E,
                                 element_area=area),
        "block": unit_modulus_influence(block) / E,
        "pair": equivalent_operator(dense, 0.5 * dense, element_area=area),
    }


@pytest.mark.parametrize("body", ["dense half-space", "FFT half-space", "block", "pair"])
def test_every_solver_path_gives_the_same_cycle_on_every_body(body):
    area, operators = _operators()
    f = _separations(2, n=12, seed=2)
    path = LoadingPath.cycles(1.0e-6, 6, cycles=2)
    runs = {method: cycle_sweep(operators[body], f, path, 5e8, element_area=area,
                                options=SolverOptions(method=method, tol=1e-11))
            for method in ("steepest", "cg", "exact", "pivot")}
    reference = runs["pivot"]
    assert reference.converged.all() and np.all(reference.plastic_volume[:, -1] > 0)
    for method, run in runs.items():
        assert run.converged.all(), method
        np.testing.assert_allclose(run.plastic_volume, reference.plastic_volume, rtol=1e-6,
                                   atol=1e-9 * reference.plastic_volume.max(), err_msg=method)
        np.testing.assert_allclose(run.load, reference.load, rtol=1e-6,
                                   atol=1e-9 * reference.load.max(), err_msg=method)


def test_a_dimensionless_cycle_is_the_si_cycle_of_every_sigma_and_E():
    from roughcontact.contact import cycle_to_physical
    from roughcontact.contact.nondim import dimensionless_operator, initial_separation

    n, size, thickness = 12, 1e-3, 2e-3
    unit = halfspace_influence((n, n), (size, size), 1.0, NU)  # E C [m]
    heights = _separations(2, n=12, seed=6) / 1e-6  # unit rms: heights in sigma
    heights = heights.max(axis=(1, 2), keepdims=True) - heights
    gaps = initial_separation(heights)
    path = LoadingPath.cycles(2.0, 6, unload_to=0.5, cycles=2)  # d / sigma
    nondim_cap = 0.02  # H L / (E sigma)
    nd = cycle_sweep(dimensionless_operator(unit, thickness), gaps, path, nondim_cap,
                     element_area=1.0 / n**2, options=SolverOptions(tol=1e-12))
    for sigma, modulus in ((1e-6, 2e11), (5e-6, 5e8)):
        si = cycle_to_physical(nd, sigma, modulus, thickness, size * size)
        # the same problem in SI units, solved on its own
        direct = cycle_sweep(unit / modulus, sigma * gaps,
                             LoadingPath(tuple(sigma * np.asarray(path.values))),
                             nondim_cap * modulus * sigma / thickness,
                             element_area=(size / n) ** 2, options=SolverOptions(tol=1e-12))
        for name in ("approach", "load", "nominal_pressure", "plastic_volume",
                     "permanent_set"):
            expected = getattr(direct, name)
            np.testing.assert_allclose(getattr(si, name), expected, rtol=1e-8,
                                       atol=1e-10 * np.nanmax(np.abs(expected)), err_msg=name)
        # the tangent on the free set (0 < p < H): where an element sits at the cap to
        # rounding, which side it falls on is the rounding's, so compare the typical step
        stiff = direct.contact_stiffness > 0
        ratio = si.contact_stiffness[stiff] / direct.contact_stiffness[stiff]
        assert np.median(np.abs(ratio - 1)) < 1e-6
        assert si.hardness == pytest.approx(direct.hardness, rel=1e-12)
        assert np.all(si.plastic_volume[:, -1] > 0)
