"""Tabulated isotropic spectra (``SurfaceSpec(acf="psd", psd=...)``) and PSD tables.

The references are independent: the self-affine law of ``self_affine_psd``
(closed form), numpy FFTs of the generated surfaces, and log-log
interpolation written out by hand at chosen points.
"""

from __future__ import annotations

import hashlib
import logging
import math

import numpy as np
import pytest

from roughcontact.errors import MeasurementError
from roughcontact.surfaces import measured, spec, spectra, synthetic
from roughcontact.surfaces.measured import ImportOptions
from roughcontact.surfaces.spec import SurfaceSpec

MM = 1e-3
SIZE = 9 * MM
GRID = 128
ROLLOFF = 1.5 * MM
CUTOFF = 0.3 * MM
HURST = 0.8
Q_LOWEST = 2 * math.pi / SIZE
Q_R = 2 * math.pi / ROLLOFF
Q_S = 2 * math.pi / CUTOFF


@pytest.fixture(autouse=True)
def _quiet(caplog):
    caplog.set_level(logging.ERROR)


def self_affine_spec(**kw):
    return SurfaceSpec(grid=GRID, size=SIZE, acf="self-affine", hurst=HURST,
                                 rolloff_wavelength=ROLLOFF, cutoff_wavelength=CUTOFF, **kw)


def sampled_table(q):
    return tuple(zip(q, spectra.self_affine_psd(q, HURST, ROLLOFF, CUTOFF), strict=True))


def psd_spec(table, **kw):
    base = dict(grid=GRID, size=SIZE, acf="psd", psd=table)
    return SurfaceSpec(**(base | kw))


def grid_wavenumber(n=GRID, size=SIZE):
    q = 2 * math.pi * np.fft.fftfreq(n, size / n)
    return np.hypot(q[None, :], q[:, None])


def ring_power(surfaces):
    """Mean |FFT2|^2 over surfaces in rings of integer radial index (numpy only)."""
    n = surfaces.shape[-1]
    power = np.mean(np.abs(np.fft.fft2(surfaces)) ** 2, axis=0)
    k = np.hypot(np.fft.fftfreq(n, 1 / n)[None, :], np.fft.fftfreq(n, 1 / n)[:, None])
    ring = np.rint(k).astype(int).ravel()
    counts = np.bincount(ring)
    return np.bincount(ring, power.ravel()) / np.maximum(counts, 1)


def test_table_with_the_kinks_as_rows_is_the_self_affine_kernel():
    # log-log interpolation is exact on a power law and on a plateau, so rows at
    # the roll-off and the cut-off give the self-affine transfer to rounding
    q = np.unique(np.concatenate([np.geomspace(Q_LOWEST, Q_S, 7), [Q_R]]))
    transfer = spectra.filter_kernel(psd_spec(sampled_table(q))).transfer
    reference = spectra.filter_kernel(self_affine_spec()).transfer
    assert np.max(np.abs(transfer - reference)) < 1e-12 * reference.max()


def test_densely_sampled_self_affine_table_reproduces_its_kernel_and_surfaces():
    # 100 log-spaced rows up to the cut-off, none at the roll-off: only the segment
    # across the roll-off kink is approximate (measured 0.8 % of the largest transfer)
    table = sampled_table(np.geomspace(Q_LOWEST, Q_S, 100))
    spec, reference = psd_spec(table), self_affine_spec()
    transfer = spectra.filter_kernel(spec).transfer
    expected = spectra.filter_kernel(reference).transfer
    assert np.max(np.abs(transfer - expected)) < 0.015 * expected.max()
    seeds = range(4)
    power = ring_power(synthetic.generate_many(spec, seeds, method="paper"))
    power_ref = ring_power(synthetic.generate_many(reference, seeds, method="paper"))
    band = power_ref > 1e-6 * power_ref.max()
    # same noise, same rings: the realised radial PSDs agree within 3 % ring by ring
    assert np.max(np.abs(power[band] / power_ref[band] - 1)) < 0.03
    assert spec.corr_length == pytest.approx((SIZE, SIZE))  # 2 pi / q_1


def test_no_power_above_the_last_row_and_a_plateau_below_the_first():
    q_first, q_last = 6 * Q_LOWEST, 40 * Q_LOWEST
    table = ((q_first, 2.0), (q_last, 0.5))
    spec = psd_spec(table, skew=0.5, kurt=4.0)
    q = grid_wavenumber()
    transfer = spectra.filter_kernel(spec).transfer
    below, above = (q > 0) & (q < q_first), q > q_last * (1 + 1e-9)
    assert np.ptp(transfer[below]) < 1e-12 * transfer.max()  # flat: C = 2 below q_1
    assert np.all(transfer[above] == 0.0)
    # a non-Gaussian surface of the linear filter: none of its power above q_last
    z = synthetic.generate_many(spec, range(3), method="paper")
    power = np.abs(np.fft.fft2(z)) ** 2
    assert power[:, above].sum() < 1e-24 * power.sum()
    assert power[:, (q > q_first) & (q < q_last)].sum() > 0.5 * power.sum()


def test_interpolation_is_log_log_with_linear_segments_at_zeros():
    table = spec.check_psd_table(((1.0, 4.0), (4.0, 1.0), (8.0, 0.0), (16.0, 2.0)))
    q = np.array([0.5, 1.0, 2.0, 4.0, 6.0, 12.0, 16.0, 16.5])
    c = spectra.tabulated_psd(q, table)
    # plateau; rows; log-log midpoint of (1, 4)-(4, 1) is (2, 2); linear in C next to
    # the zero: halfway between 4 and 8 is 0.5, between 8 and 16 is 1; cut-off above
    assert c == pytest.approx([4.0, 4.0, 2.0, 1.0, 0.5, 1.0, 2.0, 0.0], rel=1e-12)
    # a power law between rows is exact anywhere in the segment
    law = spec.check_psd_table(((10.0, 10.0**-3), (1000.0, 1000.0**-3)))
    x = np.geomspace(10.0, 1000.0, 17)
    assert spectra.tabulated_psd(x, law) == pytest.approx(x**-3, rel=1e-10)


@pytest.mark.parametrize("table, words", [
    (None, r" must be a table of \(q, C\) rows.*got None"),
    ([1.0, 2.0, 3.0], r"table of \(q, C\) rows"),
    ([(1.0, 2.0, 3.0), (2.0, 1.0, 0.0)], r"table of \(q, C\) rows"),
    ([(1.0, 2.0)], "at least 2 rows"),
    ([(1.0, 2.0), (2.0, float("nan"))], r"row 2 .* not finite"),
    ([(0.0, 2.0), (2.0, 1.0)], "row 1 has q = 0 1/m; wavenumbers must be positive"),
    ([(1.0, 2.0), (3.0, 1.0), (3.0, 0.5)], "q must increase strictly.*row 3.*Sort the table"),
    ([(2.0, 2.0), (1.0, 1.0)], "q must increase strictly"),
    ([(1.0, 2.0), (2.0, -1.0)], r"row 2 has C = -1; a power spectral density is >= 0"),
    ([(1.0, 0.0), (2.0, 0.0)], "every C is zero"),
])
def test_bad_tables_are_refused_naming_the_field(table, words):
    with pytest.raises(ValueError, match=rf"SurfaceSpec\.psd.*{words}"):
        psd_spec(table)


def test_psd_spec_round_trips_is_hashable_and_periodic_only():
    table = [[Q_LOWEST, 1.0], [Q_S, 1e-3]]  # lists, as as_dict writes them
    spec = psd_spec(table, skew=0.3, kurt=3.5)
    assert spec.psd == ((Q_LOWEST, 1.0), (Q_S, 1e-3))
    assert SurfaceSpec(**spec.as_dict()) == spec
    assert hash(spec) == hash(SurfaceSpec(**spec.as_dict()))
    with pytest.raises(ValueError, match="periodic"):
        psd_spec(table, periodic=False)
    with pytest.raises(ValueError, match=r"SurfaceSpec.psd applies to acf='psd' only"):
        SurfaceSpec(grid=GRID, size=SIZE, corr_length=MM, psd=table)
    with pytest.raises(ValueError, match="autocorrelation.*PSD"):
        spectra.autocorrelation(spec, 0.0, 0.0)


def test_a_table_whose_power_the_grid_cannot_carry_is_refused():
    # power only at wavelengths longer than the surface
    with pytest.raises(ValueError, match=r"psd has power only up to .* Enlarge the surface"):
        psd_spec(((0.1 * Q_LOWEST, 1.0), (0.5 * Q_LOWEST, 1.0)))
    # power only in a narrow band between two grid wavenumbers
    spec = psd_spec(((1.2 * Q_LOWEST, 0.0), (1.3 * Q_LOWEST, 1.0), (1.35 * Q_LOWEST, 0.0)))
    with pytest.raises(ValueError, match="no power on any wavenumber"):
        spectra.filter_kernel(spec)


def test_read_psd_table_converts_per_mm_and_refuses_bad_files(tmp_path):
    path = tmp_path / "psd.csv"
    path.write_text("q_per_mm,C\n0.5,1.0\n2,0.25\n# a comment\n8,0\n")
    assert measured.read_psd_table(path) == ((500.0, 1.0), (2000.0, 0.25), (8000.0, 0.0))
    cases = {
        "wavelength_mm,C\n1,1\n2,2\n": r"columns \['wavelength_mm', 'C'\]; expected exactly "
                                       r"\['q_per_mm', 'C'\]",
        "q_per_mm,C\n1,1\n2,abc\n": r"row 2 of the table.*not two numbers",
        "q_per_mm,C\n2,1\n1,2\n": "q must increase strictly",
    }
    for text, message in cases.items():
        path.write_text(text)
        with pytest.raises(MeasurementError, match=message):
            measured.read_psd_table(path)
    with pytest.raises(MeasurementError, match="no such file"):
        measured.read_psd_table(tmp_path / "missing.csv")


def test_measured_psd_table_follows_the_measured_surface(tmp_path):
    # a self-affine "measurement" with a roll-off at a third of its width: the table
    # from its isotropic PSD has the same band slope, and positive, increasing rows
    spec = SurfaceSpec(grid=96, size=9.6 * MM, acf="self-affine", hurst=0.5,
                                 rolloff_wavelength=3.2 * MM, cutoff_wavelength=0.4 * MM,
                                 sigma=1e-6)
    np.save(tmp_path / "map.npy", synthetic.generate(spec, 3, method="paper"))
    measurement = measured.load_measurement(
        tmp_path / "map.npy", ImportOptions(height_unit="m", spacing=(0.1 * MM, 0.1 * MM)))
    table = np.array(measured.psd_table_from_measurement(measurement))
    assert np.all(table > 0) and np.all(np.diff(table[:, 0]) > 0)
    q, c = table.T
    band = (q > 1.5 * 2 * math.pi / (3.2 * MM)) & (q < 0.7 * 2 * math.pi / (0.4 * MM))
    slope = np.polyfit(np.log(q[band]), np.log(c[band]), 1)[0]
    assert slope == pytest.approx(-3.0, abs=0.4)  # -2 (1 + H), one windowed map
    assert hashlib.sha256((tmp_path / "map.npy").read_bytes()).hexdigest() == \
        measurement.sha256
    assert SurfaceSpec(grid=96, size=9.6 * MM, acf="psd", psd=tuple(table)).psd[0][0] \
        == q[0]
