"""Where surfaces come from besides the ACF: measured height maps and spectra.

A measured surface (a study's ``surface:``) or spectrum (``kind: table`` or
``kind: measured``) is read when the workflow is planned, so that its cells
know the file's content hash (their keys), grid, plan size and statistics.
:class:`MeasurementImport` holds the import options of a measured file and
a type per spectrum kind (:data:`SPECTRA`) its parameters, in SI units,
with their plain ``params()`` (the configuration's units, declared on their fields:
:mod:`roughcontact.study.codec`) as the surface cells of
:mod:`roughcontact.study.records` store them. The readers keep
what they read per file content (modification time and size) for the life
of the process, since a plan reads every file several times.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from roughcontact.errors import MeasurementError
from roughcontact.hashes import file_sha256
from roughcontact.study import codec
from roughcontact.study.codec import Record
from roughcontact.study.provenance import short_hash
from roughcontact.surfaces import measured
from roughcontact.units import MM


@dataclass(frozen=True, kw_only=True)
class MeasurementImport(Record):
    """How a measured height map is imported and prepared (a study's ``surface:``).

    The :class:`~roughcontact.surfaces.measured.ImportOptions` of the file,
    lengths in metres: ``spacing`` (dx, dy) [m] or None (from the file),
    ``crop`` (x0, y0, x1, y1) [m] or None, ``resample_grid`` (nx, ny) or None;
    ``decimate`` a factor or None. Relative file paths are relative to the
    working directory (Snakemake's ``--directory``). Read from a validated
    ``surface:`` entry (lengths in mm; the keys the schema leaves optional may be
    absent: None) or its params, the options as the configuration writes them
    (lengths in mm, None where not given): the form stored with a cell and hashed
    into its key.
    """

    file: str
    format: str
    height_unit: str | None = None
    lateral_unit: str
    spacing: tuple[float, float] | None = codec.si_pair(MM, "spacing_mm", default=None)
    fill_holes: float
    channel: int | str | None = None
    decimal: str
    crop: tuple[float, ...] | None = codec.si_tuple(MM, "crop_mm", default=None)
    form_degree: int
    outliers_sigma: float | None = None
    decimate: int | None = None
    resample_grid: tuple[int, int] | None = codec.grid(default=None)

    def options(self) -> dict:
        """:meth:`params` without the file's name (what a key hashes beside the content)."""
        options = self.params()
        del options["file"]
        return options


# ---------------------------------------------------------------------------
# Reading the files, once per content


def stamp(path) -> tuple | None:
    """Modification time and size of a file: a changed file is read again."""
    try:
        stat = Path(path).stat()
    except OSError:
        return None  # the reader says the file is missing
    return (stat.st_mtime_ns, stat.st_size)


def load_measurement(source: MeasurementImport) -> measured.Measurement:
    """The measurement a :class:`MeasurementImport` describes, imported and prepared in SI
    units (kept per file content)."""
    return _load(source, stamp(source.file))


def measurement_statistics(source: MeasurementImport) -> dict:
    """:func:`roughcontact.surfaces.measured.statistics` of :func:`load_measurement`."""
    return _statistics(source, stamp(source.file))


def measured_psd(source: MeasurementImport) -> tuple[str, tuple]:
    """SHA-256 of the file and the isotropic PSD table of a measurement."""
    return _measured_psd(source, stamp(source.file))


def psd_file(path: str) -> tuple[str, tuple]:
    """SHA-256 and table ((q [1/m], C), ...) of a PSD table file (``q_per_mm,C``)."""
    return _psd_file(path, stamp(path))


@functools.lru_cache(maxsize=16)
def _load(source: MeasurementImport, stamp) -> measured.Measurement:
    return measured.load_measurement(source.file, measured.ImportOptions(
        format=source.format, height_unit=source.height_unit,
        lateral_unit=source.lateral_unit, spacing=source.spacing,
        fill_holes=source.fill_holes, channel=source.channel, decimal=source.decimal,
        crop=source.crop, form_degree=source.form_degree,
        outliers_sigma=source.outliers_sigma, decimate_by=source.decimate,
        resample_grid=None if source.resample_grid is None else list(source.resample_grid),
    ))


@functools.lru_cache(maxsize=16)
def _statistics(source: MeasurementImport, stamp) -> dict:
    return measured.statistics(_load(source, stamp))


@functools.lru_cache(maxsize=16)
def _measured_psd(source: MeasurementImport, stamp) -> tuple[str, tuple]:
    measurement = _load(source, stamp)
    return measurement.sha256, measured.psd_table_from_measurement(measurement)


@functools.lru_cache(maxsize=16)
def _psd_file(path: str, stamp) -> tuple[str, tuple]:
    table = measured.read_psd_table(path)
    return file_sha256(path), table


# ---------------------------------------------------------------------------
# Spectra: ``surfaces.spectrum`` (or a study's ``spectrum``) in place of the ACF


@dataclass(frozen=True)
class SelfAffineSpectrum(Record):
    """An isotropic self-affine PSD: Hurst exponent, roll-off and cut-off wavelengths [m]
    (its entry is its params)."""

    kind: str = codec.constant("self-affine")
    hurst: float
    rolloff: float = codec.si(MM, "rolloff_mm")
    cutoff: float = codec.si(MM, "cutoff_mm")
    #: The :class:`SurfaceSpec` kind, and the ``acf`` of its cells.
    acf: ClassVar[str] = "self-affine"
    file: ClassVar[None] = None

    @classmethod
    def from_entry(cls, entry: dict) -> SelfAffineSpectrum:
        return cls.from_params(entry)

    def tag(self) -> str:
        """``sa-<8 hex>``: the hash of its parameters."""
        return f"sa-{short_hash(self.params(), 8)}"

    def spec_fields(self) -> dict:
        """:class:`SurfaceSpec` fields (SI)."""
        return {"acf": self.acf, "hurst": self.hurst, "rolloff_wavelength": self.rolloff,
                "cutoff_wavelength": self.cutoff}


class _FileSpectrum:
    """A spectrum read from a file: a table (q [1/m], C), checked against the file's
    content the workflow was planned with (``file_sha256``)."""

    acf: ClassVar[str] = "psd"

    def spec_fields(self) -> dict:
        """``acf="psd"`` with the table; raises :class:`MeasurementError` if the file's
        content is no longer the one planned."""
        sha, table = self._read()
        if sha != self.file_sha256:
            raise MeasurementError(
                f"{self.file}: the spectrum's file changed after the workflow was planned "
                f"(sha256 {sha[:12]}, planned {self.file_sha256[:12]}); run again", self.file)
        return {"acf": self.acf, "psd": table}


@dataclass(frozen=True)
class TableSpectrum(_FileSpectrum, Record):
    """An isotropic PSD read from a CSV table (``q_per_mm,C``,
    :func:`roughcontact.surfaces.measured.read_psd_table`) and the file's SHA-256."""

    kind: str = codec.constant("table")
    file: str
    file_sha256: str

    @classmethod
    def from_entry(cls, entry: dict) -> TableSpectrum:
        """Reads the file (relative paths from the working directory) for its hash."""
        path = str(entry["file"])
        return cls(file=path, file_sha256=psd_file(path)[0])

    def tag(self) -> str:
        """``tab-<12 hex>``: the file's SHA-256 as ``sha256sum`` prints it."""
        return f"tab-{self.file_sha256[:12]}"

    def _read(self) -> tuple[str, tuple]:
        return psd_file(self.file)


@dataclass(frozen=True)
class MeasuredSpectrum(_FileSpectrum, Record):
    """The isotropic PSD of a measured height map (its import, without decimation or
    resampling: the measurement's own grid) and the file's SHA-256."""

    kind: str = codec.constant("measured")
    source: MeasurementImport = codec.record(MeasurementImport, flatten=True)
    file_sha256: str

    @property
    def file(self) -> str:
        return self.source.file

    @classmethod
    def from_entry(cls, entry: dict) -> MeasuredSpectrum:
        """Reads the measurement for its hash."""
        source = MeasurementImport.from_params({**entry, "decimate": None,
                                                "resample_grid": None})
        return cls(source=source, file_sha256=load_measurement(source).sha256)

    def tag(self) -> str:
        """``mpsd-<12 hex>-<8 hex>``: the file's SHA-256 and the hash of the import options."""
        options = short_hash({"kind": self.kind, **self.source.options()}, 8)
        return f"mpsd-{self.file_sha256[:12]}-{options}"

    def _read(self) -> tuple[str, tuple]:
        return measured_psd(self.source)


Spectrum = SelfAffineSpectrum | TableSpectrum | MeasuredSpectrum

#: The record type of each ``spectrum: {kind: ...}`` (``acf``: none, the ACF of the
#: ``surfaces`` section).
SPECTRA = {"acf": None, "self-affine": SelfAffineSpectrum, "table": TableSpectrum,
           "measured": MeasuredSpectrum}


def spectrum_from_entry(entry: dict | None) -> Spectrum | None:
    """The spectrum of a validated ``spectrum:`` entry (its file read for the hash), or
    None for ``kind: acf`` or no entry."""
    kind = None if entry is None else SPECTRA[entry["kind"]]
    return None if kind is None else kind.from_entry(entry)


def spectrum_from_params(params: dict | None) -> Spectrum | None:
    """The spectrum of a surface cell's ``spectrum`` params (no file read), or None."""
    return None if params is None else SPECTRA[params["kind"]].from_params(params)
