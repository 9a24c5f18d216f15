"""Measured height maps: the entry point, and their statistics.

A measured surface (from a profilometer, an optical instrument or an AFM)
enters the study in place of a generated one. :func:`load_measurement`
reads it as its :class:`ImportOptions` say (:mod:`roughcontact.surfaces.readers`:
npy, text grids, xyz point lists and the instruments' own formats through
SurfaceTopography; heights and lateral lengths converted to SI at import),
prepares it for the contact study (:mod:`roughcontact.surfaces.preparation`:
crop, fill holes, remove the form, outliers, decimate or resample) and returns
a :class:`Measurement`.

Its statistics (:func:`statistics`) are those of the generator's targets:
sigma, skewness and kurtosis (Eq 2-5 of Kumar et al. 2006,
:func:`roughcontact.surfaces.statistics.height_stats`), the 10 % decay lags
of the autocorrelation function (Eq 1,
:func:`roughcontact.surfaces.statistics.correlation_length`, non-periodic
estimate; NaN, with a warning, where it does not fall to 10 % within half the
window) and the Johnson law with the same moments
(:func:`roughcontact.surfaces.johnson.fit`); with ``spectral=True`` also the
rms slope and the rms curvature
(:func:`roughcontact.surfaces.statistics.spectral_moments`, finite
differences) and the isotropic power spectral density (SurfaceTopography).
Arrays are ``(ny, nx)``, row-major over y then x, as everywhere in the
package.

An isotropic PSD can also stand in for the autocorrelation of generated
surfaces (``SurfaceSpec(acf="psd")``): :func:`psd_table_from_measurement`
takes it from a measurement, :func:`read_psd_table` from a CSV table.
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from roughcontact.errors import MeasurementError
from roughcontact.hashes import file_sha256
from roughcontact.surfaces import johnson
from roughcontact.surfaces.preparation import decimate, prepare, remove_polynomial
from roughcontact.surfaces.readers import HEIGHT_UNITS, read_heights, resolve_format, unit_scale
from roughcontact.surfaces.spec import check_psd_table
from roughcontact.surfaces.statistics import correlation_length, height_stats, spectral_moments
from roughcontact.units import MM

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Measurement:
    """A measured surface, imported and prepared for the contact study.

    Attributes
    ----------
    heights : ndarray (ny, nx)
        Heights [m]: holes filled, form removed, resampled (zero mean).
    spacing : (dx, dy)
        Grid spacing [m].
    source : str
        The file it was read from.
    sha256 : str
        SHA-256 of the file's bytes.
    options : dict
        The import and preparation options as given.
    filled : int
        Number of missing points filled by interpolation.
    plane : (a, b, c)
        The removed plane ``a + b x + c y``: offset [m], slopes [1].
    preparation : dict
        What was done, for the provenance: the reader and channel, the units
        and pixel size from the file, the crop window in points, the points
        the instrument masked (``masked_points`` in the window used,
        ``file_masked_points`` in the whole file), the missing, filled and
        outlier points, the form's polynomial coefficients, the resampling.
    """

    heights: np.ndarray
    spacing: tuple[float, float]
    source: str
    sha256: str
    options: dict = field(default_factory=dict)
    filled: int = 0
    plane: tuple[float, float, float] = (0.0, 0.0, 0.0)
    preparation: dict = field(default_factory=dict)

    @property
    def grid(self) -> tuple[int, int]:
        """Points ``(nx, ny)``."""
        return (self.heights.shape[1], self.heights.shape[0])

    @property
    def size(self) -> tuple[float, float]:
        """Side lengths ``(Lx, Ly) = (nx dx, ny dy)`` [m], as for generated surfaces."""
        return (self.grid[0] * self.spacing[0], self.grid[1] * self.spacing[1])

    @property
    def filled_fraction(self) -> float:
        """Fraction of the points that were filled."""
        return self.filled / self.heights.size




@dataclass(frozen=True)
class ImportOptions:
    """How a measured height map is read and prepared (:func:`load_measurement`).

    Attributes
    ----------
    format : {"auto", "instrument", "npy", "text", "xyz"}
        See :mod:`roughcontact.surfaces.readers`; ``auto`` chooses by the file.
    height_unit : {"nm", "um", "mm", "m"}, optional
        Unit of the heights, where the file does not say (npy, text, xyz and
        instrument files without units); refused where it contradicts the file.
    lateral_unit : {"um", "mm", "m"}
        Unit of the x, y coordinates of an ``xyz`` file.
    spacing : (dx, dy) [m], optional
        Grid spacing, where the file does not say (npy and text grids);
        refused for ``xyz`` files and where it contradicts an instrument file.
    fill_holes : float
        Largest fraction of missing or masked points to fill (:func:`preparation.fill_missing`).
    channel : int or str, optional
        Data channel of an instrument file (default: the file's default).
    decimal : {"auto", ".", ","}
        Decimal mark of a text grid.
    crop : (x0, y0, Lx, Ly) [m], optional
        Window from the first point (:func:`preparation.crop_window`), before anything else.
    form_degree : int
        1: the least-squares plane is removed; k >= 2: then the polynomial of
        total degree k (:func:`preparation.remove_polynomial`).
    outliers_sigma : float, optional
        Points farther than this many sigma from the mean plane are filled as
        holes (counted in ``preparation``), and the form removed again.
    decimate_by : int, optional
        Means of k x k blocks (:func:`preparation.decimate`).
    resample_grid : (nx, ny), optional
        Linear interpolation onto this grid over the same plan size (:func:`preparation.resample`).

    The defaults read the file as it says and remove the mean plane only.
    A study builds these options from a ``surface:`` entry
    (:class:`roughcontact.study.sources.MeasurementImport`).
    """

    format: str = "auto"
    height_unit: str | None = None
    lateral_unit: str = "mm"
    spacing: tuple[float, float] | None = None
    fill_holes: float = 0.0
    channel: int | str | None = None
    decimal: str = "auto"
    crop: tuple[float, float, float, float] | None = None
    form_degree: int = 1
    outliers_sigma: float | None = None
    decimate_by: int | None = None
    resample_grid: tuple[int, int] | None = None

    def check(self) -> None:
        """ValueError for an option out of its range (before the file is read)."""
        if self.height_unit is not None:
            unit_scale(self.height_unit, HEIGHT_UNITS, "height_unit")
        if not 0.0 <= float(self.fill_holes) < 1.0:
            raise ValueError(f"fill_holes must be a fraction in [0, 1); got {self.fill_holes!r}")
        degree = self.form_degree
        if int(degree) != degree or not 1 <= degree <= 6:
            raise ValueError(f"form_degree must be an integer from 1 (plane) to 6; got "
                             f"{degree!r}")
        if self.decimate_by is not None and self.resample_grid is not None:
            raise ValueError("give decimate or resample_grid, not both")

    def given_spacing(self) -> tuple[float, float] | None:
        """``spacing`` (dx, dy) [m] checked positive and finite, or None (from the file)."""
        return None if self.spacing is None else _pair_m(self.spacing, "spacing")

    def record(self) -> dict:
        """The options as given, plain values for the provenance (:attr:`Measurement.options`)."""
        spacing, crop, grid = self.given_spacing(), self.crop, self.resample_grid
        return {"format": self.format, "height_unit": self.height_unit,
                "lateral_unit": self.lateral_unit,
                "spacing": None if spacing is None else list(spacing),
                "fill_holes": float(self.fill_holes), "channel": self.channel,
                "decimal": self.decimal,
                "crop": None if crop is None else [float(v) for v in crop],
                "form_degree": int(self.form_degree), "outliers_sigma": self.outliers_sigma,
                "decimate": self.decimate_by,
                "resample_grid": None if grid is None else list(grid)}


def _pair_m(value, what: str) -> tuple[float, float]:
    pair = tuple(float(v) for v in np.broadcast_to(np.asarray(value, float), (2,)))
    if not all(math.isfinite(v) and v > 0 for v in pair):
        raise ValueError(f"{what} must be positive and finite [m]; got {value!r}")
    return pair


#: The default import: the file read as it says, the mean plane removed.
DEFAULT_IMPORT = ImportOptions()


def load_measurement(path: str | os.PathLike,
                     options: ImportOptions = DEFAULT_IMPORT) -> Measurement:
    """Import a measured height map and prepare it for the study, in SI units.

    Parameters
    ----------
    path : path-like
        The file.
    options : ImportOptions
        How it is read (format, units, spacing, channel, decimal mark) and
        prepared (crop, holes, form, outliers, decimation or resampling); the
        default reads the file as it says and removes the mean plane, e.g.
        ``load_measurement("map.npy", ImportOptions(height_unit="um",
        spacing=(1e-6, 1e-6)))`` for a bare array.

    Raises
    ------
    MeasurementError
        For a file that cannot be used, naming the file and the line, the
        missing fraction, the non-uniform axis or the format.
    ValueError
        For inconsistent options (unknown unit or format, a unit or spacing
        missing, or contradicting the file).
    """
    path = Path(path)
    kind = resolve_format(path, options.format)
    options.check()
    if not path.is_file():
        raise MeasurementError(f"{path}: no such file", path)
    raw, spacing, absent, said = read_heights(path, kind, height_unit=options.height_unit,
                                              lateral_unit=options.lateral_unit,
                                              spacing=options.given_spacing(),
                                              channel=options.channel, decimal=options.decimal)
    heights, spacing, filled, plane, steps = prepare(
        raw, spacing, source=path, absent=absent, crop=options.crop,
        fill_holes=options.fill_holes, form_degree=options.form_degree,
        outliers_sigma=options.outliers_sigma, decimate_by=options.decimate_by,
        resample_grid=options.resample_grid)
    if "masked_points" in said:  # the instrument's mask: counted in the window used
        said = {**said, "file_masked_points": said["masked_points"],
                "masked_points": steps["missing_points"]}
    return Measurement(heights, (float(spacing[0]), float(spacing[1])), str(path),
                       file_sha256(path), options.record(), filled, plane, {**said, **steps})


def statistics(measurement: Measurement, spectral: bool = False) -> dict:
    """Height statistics of a measurement and the Johnson law of its moments.

    Returns plain values: ``sigma`` [m], ``skew``, ``kurt`` (Pearson), ``mean``
    [m] (zero after detrending), ``corr_length_x``, ``corr_length_y`` [m]
    (lags of 10 % ACF decay, non-periodic estimate; NaN, with a warning that
    names the direction, where the ACF stays above 10 % over half the
    window), ``grid`` [nx, ny], ``size`` [Lx, Ly] [m],
    ``spacing`` [dx, dy] [m], ``filled_points``, ``filled_fraction``, the
    removed plane (``plane_offset`` [m], ``plane_slope_x``, ``plane_slope_y``),
    and ``johnson_family`` with ``johnson_params`` ``[gamma, delta, xi, lam]``
    of the law fitted to (Sk, Ku) for heights in units of sigma (zero mean,
    unit standard deviation).

    With ``spectral``, on the prepared heights (not periodic,
    :func:`spectral_statistics`): ``rms_slope`` [1] (the rms gradient
    h'_rms), ``rms_curvature`` [1/m] (h''_rms, half the rms Laplacian) and
    the isotropic power spectral density ``psd_q`` [1/m] (wavevectors) and
    ``psd_C`` [m^4].
    """
    z = measurement.heights
    moments = height_stats(z)
    bx, by = correlation_length(z, measurement.spacing, periodic=False)
    for name, value, side in (("x", bx, measurement.size[0]), ("y", by, measurement.size[1])):
        if not math.isfinite(value):
            log.warning(
                "%s: the %s autocorrelation does not fall to 10 %% within half the window "
                "(%.4g mm): corr_length_%s is NaN. %s", measurement.source, name,
                side / 2e-3, name, form_advice(measurement))
    curve = johnson.fit(moments["skew"], moments["kurt"])
    stats = {
        "sigma": moments["sigma"],
        "skew": moments["skew"],
        "kurt": moments["kurt"],
        "mean": moments["mean"],
        "corr_length_x": float(bx),
        "corr_length_y": float(by),
        "grid": list(measurement.grid),
        "size": list(measurement.size),
        "spacing": list(measurement.spacing),
        "filled_points": int(measurement.filled),
        "filled_fraction": float(measurement.filled_fraction),
        "plane_offset": measurement.plane[0],
        "plane_slope_x": measurement.plane[1],
        "plane_slope_y": measurement.plane[2],
        "johnson_family": curve.family,
        "johnson_params": [curve.gamma, curve.delta, curve.xi, curve.lam],
    }
    if spectral:
        stats.update(spectral_statistics(measurement))
    return stats


#: Largest map :func:`finite_form_degree` searches point by point.
FORM_SEARCH_POINTS = 1_000_000


def finite_form_degree(measurement: Measurement) -> tuple[int, tuple[float, float]] | None:
    """The smallest ``form_degree`` above the measurement's (up to 6) whose heights
    have finite correlation lengths, with them (bx, by) [m]; None if none has.

    The polynomial of that degree is removed from the prepared heights: the
    same heights as an import with that degree (least squares onto nested
    polynomial spaces), but for the points an outlier step removes and the
    interpolation of a resampled grid. Maps of more than
    :data:`FORM_SEARCH_POINTS` points are searched on means of k x k blocks
    (the least-squares fit of degree 6 holds 28 numbers per point).
    """
    heights, spacing = measurement.heights, measurement.spacing
    block = max(1, math.ceil(math.sqrt(heights.size / FORM_SEARCH_POINTS)))
    if block > 1:
        heights, spacing = decimate(heights, block), (spacing[0] * block, spacing[1] * block)
    for degree in range(int(measurement.options["form_degree"]) + 1, 7):
        residual, _ = remove_polynomial(heights, spacing, degree)
        lags = correlation_length(residual, spacing, periodic=False)
        if all(math.isfinite(b) for b in lags):
            return degree, (float(lags[0]), float(lags[1]))
    return None


def form_advice(measurement: Measurement) -> str:
    """What gives a measurement whose autocorrelation does not fall to 10 % within half
    the window finite correlation lengths (:func:`finite_form_degree`), as a sentence."""
    found = finite_form_degree(measurement)
    if found is not None:
        degree, (bx, by) = found
        return (f"A form or waviness is left: surface.form_degree: {degree} removes it "
                f"(then b = {bx / 1e-3:.3g} x {by / 1e-3:.3g} mm)")
    return ("No form_degree up to 6 brings it within the window: the surface is "
            "correlated over more than half the measured length; measure (or crop, "
            "surface.crop_mm) a window several correlation lengths wide")


def spectral_statistics(measurement: Measurement) -> dict:
    """``rms_slope``, ``rms_curvature``, ``psd_q`` and ``psd_C`` of :func:`statistics`.

    The rms gradient and the rms curvature (half the rms Laplacian) are
    :func:`~roughcontact.surfaces.statistics.spectral_moments` of the
    non-periodic heights by finite differences (SurfaceTopography's
    ``rms_gradient`` and ``rms_curvature_from_area``: the same stencils on
    the same points); the PSD is SurfaceTopography's
    ``power_spectrum_from_area``.
    """
    # SurfaceTopography takes 1-3 s to import: only the jobs that store these pay it
    from SurfaceTopography import Topography

    slopes = spectral_moments(measurement.heights, measurement.size, derivative="difference",
                              periodic=False)
    topography = Topography(np.ascontiguousarray(measurement.heights.T), measurement.size,
                            periodic=False, unit="m")
    q, C = (np.ma.filled(np.ma.asarray(v, dtype=float), np.nan)
            for v in topography.power_spectrum_from_area())
    keep = np.isfinite(q) & np.isfinite(C) & (q > 0)
    return {
        "rms_slope": slopes.rms_gradient,
        "rms_curvature": slopes.rms_curvature,
        "psd_q": [float(v) for v in q[keep]],
        "psd_C": [float(v) for v in C[keep]],
    }


#: Columns of a PSD table file (:func:`read_psd_table`).
PSD_COLUMNS = ("q_per_mm", "C")


def psd_table_from_measurement(measurement: Measurement) -> tuple[tuple[float, float], ...]:
    """The isotropic PSD of a measurement as a ``SurfaceSpec(acf="psd")`` table.

    ``psd_q`` [1/m] and ``psd_C`` [m^4] of :func:`spectral_statistics`
    (SurfaceTopography's ``power_spectrum_from_area`` on the prepared,
    non-periodic heights), without the bins whose q or C is not finite or not
    positive, sorted by q (a repeated q keeps its first bin). Returns
    ``((q, C), ...)`` checked by
    :func:`roughcontact.surfaces.spec.check_psd_table`.
    """
    spectral = spectral_statistics(measurement)
    q = np.asarray(spectral["psd_q"], dtype=float)
    c = np.asarray(spectral["psd_C"], dtype=float)
    keep = np.isfinite(q) & np.isfinite(c) & (q > 0) & (c > 0)
    q, c = q[keep], c[keep]
    q, first = np.unique(q, return_index=True)
    return check_psd_table(np.column_stack([q, c[first]]),
                           f"{measurement.source}: the measured PSD")


def read_psd_table(path: str | os.PathLike) -> tuple[tuple[float, float], ...]:
    """An isotropic PSD table from a CSV file with columns ``q_per_mm,C``.

    ``q_per_mm`` is the wavenumber magnitude ``q = 2 pi / wavelength`` [1/mm]
    (so a 1 mm wavelength is 6.283), positive and strictly increasing; ``C``
    the isotropic 2-D PSD ``C(q) >= 0`` in any unit (only its shape matters).
    Read with pandas (a header line, comma separators; other columns are
    refused). Returns ``((q [1/m], C), ...)`` for ``SurfaceSpec(acf="psd")``.

    Raises
    ------
    MeasurementError
        When the file is missing, cannot be parsed, has other columns or
        non-numeric values, or its table is not a valid PSD
        (:func:`roughcontact.surfaces.spec.check_psd_table`).
    """
    import pandas as pd

    path = Path(path)
    if not path.is_file():
        raise MeasurementError(f"{path}: no such file (a PSD table with columns "
                               f"{','.join(PSD_COLUMNS)})", path)
    try:
        frame = pd.read_csv(path, comment="#", skipinitialspace=True)
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError) as err:
        raise MeasurementError(f"{path}: not a CSV table ({err}); write a header line "
                               f"{','.join(PSD_COLUMNS)} and one row per wavenumber", path
                               ) from None
    columns = [str(c).strip() for c in frame.columns]
    if columns != list(PSD_COLUMNS):
        raise MeasurementError(
            f"{path}: columns {columns}; expected exactly {list(PSD_COLUMNS)}: q = 2 pi / "
            "wavelength in 1/mm, and the isotropic PSD C(q) in any unit", path)
    values = frame.apply(pd.to_numeric, errors="coerce")
    bad = values.isna().any(axis=1).to_numpy().nonzero()[0]
    if bad.size:
        row = int(bad[0])
        raise MeasurementError(f"{path}: row {row + 1} of the table, "
                               f"{frame.iloc[row].tolist()}, is not two numbers (q_per_mm, C)",
                               path)
    table = values.to_numpy(dtype=float) * np.array([1.0 / MM, 1.0])
    try:
        return check_psd_table(table, f"{path} (q in 1/m)")
    except ValueError as err:
        raise MeasurementError(str(err), path) from None


__all__ = [
    "PSD_COLUMNS",
    "DEFAULT_IMPORT",
    "ImportOptions",
    "Measurement",
    "finite_form_degree",
    "form_advice",
    "load_measurement",
    "psd_table_from_measurement",
    "read_psd_table",
    "spectral_statistics",
    "statistics",
]
