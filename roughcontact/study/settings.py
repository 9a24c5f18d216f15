"""The typed study: one frozen record of a validated configuration.

The configuration's edge: :func:`~roughcontact.study.config.validated` checks a
configuration against ``config/schema.yaml`` and fills every default, and
:meth:`Study.from_config` turns it into a :class:`Study` once, the settings
records of each section in SI units (``surfaces``, ``body``, ``contact``,
``flow``, ``conductance``, ``loading``, ``counterface``, ``audit``, ``reports``) and
the contact studies as configured (:meth:`Study.section`: one :class:`StudySection`, its inheritance
from the accuracy preset and the ``body``, ``surfaces`` and ``contact``
sections applied). Everything after the edge takes the study, or the part of
it it needs, never the configuration's dict::

    study = load_study("config/quick.yaml")
    plan = study_plan(study)          # roughcontact.study.plan.cells
    plan.jobs                         # every contact job, by file key

The values a figure or sweep writes (``moments``, ``b_mm``, ``sigma_um``, ...)
stay as written in its section: the checks name them in the configuration's
units, and the cells convert them (:mod:`roughcontact.study.plan.studies`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from roughcontact.study import codec
from roughcontact.study.codec import Record, in_unit, in_units
from roughcontact.study.conductance_settings import ConductanceSettings, conductance_settings
from roughcontact.study.config import (
    BuildSettings,
    ContactSettings,
    ConvergenceSettings,
    GridConvergenceSettings,
    SpeedReportSettings,
    load_config,
    report_section,
)
from roughcontact.study.contact_records import Accuracy
from roughcontact.study.cycle_records import LoadingSettings, loading_settings
from roughcontact.study.flow_settings import FlowSettings, flow_settings
from roughcontact.study.presets import ACCURACY_PRESETS
from roughcontact.study.probes import study_probes
from roughcontact.study.provenance import config_hash
from roughcontact.study.records import GeneratedCell, Generator, Geometry
from roughcontact.units import GB, MM, MPA

__all__ = ["AuditSettings", "BodySettings", "CounterfaceSettings", "ReportSettings",
           "Study", "StudySection", "SurfaceSettings", "load_study"]


def _frozen(value):
    """A validated section as read-only mappings (lists stay lists: the values as written)."""
    if isinstance(value, dict):
        return MappingProxyType({key: _frozen(item) for key, item in value.items()})
    return value


def thawed(value):
    """A read-only section (:func:`_frozen`) as plain dicts again: a rule's params, a
    notebook's parameters."""
    if isinstance(value, Mapping):
        return {key: thawed(item) for key, item in value.items()}
    if isinstance(value, list):
        return [thawed(item) for item in value]
    return value


@dataclass(frozen=True)
class SurfaceSettings(Record):
    """The ``surfaces`` section: the contact ``grid`` (nx, ny) over the plan ``size``
    (Lx, Ly) [m], the ``acf`` (or, with a ``spectrum`` entry as configured, its kind),
    ``periodic`` or padded filter, the generator ``method`` and the surface ``count``
    per cell."""

    grid: tuple[int, int] = codec.grid()
    size: tuple[float, float] = codec.si_pair(MM, "size_mm")
    acf: str
    spectrum: dict = codec.field(read=thawed)
    periodic: bool
    method: Generator = codec.enum(Generator)
    count: int

    @property
    def size_mm(self) -> tuple[float, float]:
        """The plan size as written [mm]."""
        return tuple(in_units(self.size, MM))

    def cell(self, spectrum, *, skew, kurt, corr_length, count, size=None,
             grid=None) -> GeneratedCell:
        """A generated surface cell of these settings: their ACF (or ``spectrum``'s),
        periodicity, method, grid and plan size (unless given, SI) and these statistics
        (``corr_length`` [m])."""
        return GeneratedCell(
            skew=float(skew), kurt=float(kurt), corr_length=corr_length,
            grid=self.grid if grid is None else grid, size=self.size if size is None else size,
            acf=self.acf if spectrum is None else spectrum.acf, periodic=self.periodic,
            method=self.method, count=int(count), spectrum=spectrum)


@dataclass(frozen=True)
class BodySettings:
    """The ``body`` section: its block as a :class:`~roughcontact.study.records.Geometry`
    on the surfaces' grid and plan size, Young's modulus ``E`` [Pa], the hardness
    values ``hardness_MPa`` as written (None: none), the ``hardness_threshold`` of the
    validity check and the influence builds' :class:`~roughcontact.study.config.
    BuildSettings`."""

    geometry: Geometry
    E: float
    hardness_MPa: float | list | None
    hardness_threshold: float
    build: BuildSettings

    @classmethod
    def from_section(cls, section: Mapping, surfaces: Mapping) -> BodySettings:
        geometry = Geometry.from_params({**section, "grid": surfaces["grid"],
                                         "size_mm": surfaces["size_mm"]})
        return cls(geometry=geometry, E=float(section["E_MPa"]) * MPA,
                   hardness_MPa=thawed(section["hardness_MPa"]),
                   hardness_threshold=float(section["hardness_threshold"]),
                   build=BuildSettings.from_section(section))


@dataclass(frozen=True)
class CounterfaceSettings:
    """The ``counterface`` section: the counter ``surface`` (``"smooth"`` or its entry)
    and ``body`` (``"rigid"`` or its entry) of every study that names none, as
    configured, and the ``rigid_share`` below which a counter body is treated as
    rigid."""

    surface: str | Mapping
    body: str | Mapping
    rigid_share: float


@dataclass(frozen=True)
class AuditSettings:
    """The ``audit`` section: ``verify`` a seeded sample of ``verify_sample`` stored
    batches (drawn with ``verify_seed``), and fail the run on a flagged cell
    (``strict``)."""

    verify: bool
    verify_sample: int
    strict: bool
    verify_seed: int


@dataclass(frozen=True)
class ReportSettings:
    """The ``reports`` section: the settings of the mesh-convergence report, the
    speed-against-error report and the grid-convergence study (each its schema defaults
    where not configured: a report is also made on demand, by its target), the names of
    those ``configured`` (made by the default target: the mesh-convergence report) and
    each section as configured or defaulted (``sections``: a rule's params)."""

    influence_convergence: ConvergenceSettings
    speed_vs_error: SpeedReportSettings
    grid_convergence: GridConvergenceSettings
    configured: frozenset
    sections: Mapping

    @property
    def convergence_presets(self) -> list[str]:
        """Mesh presets of the influence-convergence report ([] when not configured)."""
        if "influence_convergence" not in self.configured:
            return []
        return list(self.influence_convergence.presets)


@dataclass(frozen=True)
class StudySection:
    """A contact figure or sweep as configured, every axis present: its own values over
    the accuracy preset's (mesh, surface count) over the ``body``'s (meshes, nu, E_MPa,
    hardness_MPa), the ``surfaces``' (count, spectrum) and the ``contact`` section's
    (cap, cap_meshes); values in the configuration's units, as written (a list axis a
    list). ``name`` the figure or sweep, ``source`` the one whose cells it has
    (``from:`` followed), ``where`` its configuration path (``sweeps.pad``) and ``own``
    the keys its entry writes itself."""

    name: str
    source: str
    where: str
    own: frozenset
    meshes: object
    count: int
    nu: object
    E_MPa: object
    spectrum: Mapping
    hardness_MPa: object
    cap: object
    cap_meshes: object
    pressure_MPa: object = None
    moments: object = None
    b_mm: object = None
    size_mm: object = None
    sigma_um: object = None
    surface: Mapping | None = None
    compare_synthetic: bool = False
    thickness_mm: object = None
    counterface: object = None

    @property
    def measured(self) -> bool:
        """The study is on a measured surface (``surface:``)."""
        return self.surface is not None


@dataclass(frozen=True)
class Study:
    """One validated configuration as typed settings (module docstring).

    ``seed`` the study seed of every generated surface; ``plausibility_check``
    refuses values that are almost surely a unit slip; ``job_memory_gb`` the memory
    one job may use as configured (None: this machine's); ``blas_threads`` of every
    job; the sections' settings; ``accuracy`` the accuracy preset named (its measured
    errors recorded with every cell) and ``preset`` its settings (None: none);
    ``figures`` and ``sweeps`` the validated entries as configured (read-only);
    ``config_hash`` the configuration's hash, recorded with every output.
    """

    seed: int
    plausibility_check: bool
    job_memory_gb: float | None
    blas_threads: int
    surfaces: SurfaceSettings
    body: BodySettings
    counterface: CounterfaceSettings
    contact: ContactSettings
    cap: object
    cap_meshes: object
    flow: FlowSettings
    conductance: ConductanceSettings
    loading: LoadingSettings
    accuracy: Accuracy
    preset: Mapping | None
    audit: AuditSettings
    reports: ReportSettings
    figures: Mapping
    sweeps: Mapping
    config_hash: str

    @classmethod
    def from_config(cls, config: dict) -> Study:
        """The study of a validated ``config``
        (:func:`~roughcontact.study.config.validated`: every default filled in)."""
        preset = config.get("accuracy")  # optional: no preset unless named
        preset = None if preset is None else MappingProxyType(dict(ACCURACY_PRESETS[preset]))
        conductance = conductance_settings(config["conductance"])
        contact = dataclasses.replace(ContactSettings.from_section(config["contact"]),
                                      flow=flow_settings(config["flow"]).probe,
                                      conductance=conductance.materials)
        if preset is not None:
            contact = dataclasses.replace(contact, method=str(preset["method"]),
                                          tol=float(preset["tol"]),
                                          precision=str(preset["precision"]))
        return cls(
            seed=int(config["study_seed"]), plausibility_check=bool(config["plausibility_check"]),
            job_memory_gb=config.get("job_memory_gb"),  # null: this machine's
            blas_threads=int(config["blas_threads"]),
            surfaces=SurfaceSettings.from_section(config["surfaces"]),
            body=BodySettings.from_section(config["body"], config["surfaces"]),
            counterface=CounterfaceSettings(
                _frozen(config["counterface"]["surface"]), _frozen(config["counterface"]["body"]),
                float(config["counterface"]["rigid_share"])),
            contact=contact, cap=thawed(config["contact"]["cap"]),
            cap_meshes=thawed(config["contact"]["cap_meshes"]),
            flow=flow_settings(config["flow"]), conductance=conductance,
            loading=loading_settings(config["loading"]),
            accuracy=_accuracy(config.get("accuracy"), preset), preset=preset,
            audit=_audit(config["audit"], config["study_seed"]),
            reports=_reports(config["reports"]),
            figures=_frozen(config["figures"]), sweeps=_frozen(config["sweeps"]),
            config_hash=config_hash(config))

    @property
    def probes(self) -> tuple:
        """The study-side records of the probes it turns on, in the order the contact
        jobs record them (:func:`~roughcontact.study.probes.study_probes`)."""
        return study_probes(self.flow, self.conductance)

    @property
    def max_memory_bytes(self) -> float | None:
        """The memory one job may use [bytes] as configured (None: this machine's)."""
        return None if self.job_memory_gb is None else float(self.job_memory_gb) * GB

    def entry(self, name: str) -> dict:
        """The figure's or sweep's own entry as configured (a copy)."""
        return thawed(self.sweeps[name] if name in self.sweeps else self.figures[name])

    def source_name(self, name: str) -> str:
        """The figure or sweep whose cells ``name`` uses (itself unless ``from:``)."""
        seen = [name]
        source = self.entry(name).get("from")
        while source is not None:
            if source in seen or (source not in self.figures and source not in self.sweeps):
                raise ValueError(f"{seen[0]}: 'from: {source}' must name another figure or "
                                 f"sweep without a cycle (followed {' -> '.join(seen)})")
            seen.append(source)
            source = self.entry(source).get("from")
        return seen[-1]

    def source(self, name: str) -> dict:
        """A figure's (or sweep's) cell description as configured, following ``from:``."""
        return self.entry(self.source_name(name))

    def path(self, name: str) -> str:
        """The configuration path of a figure or sweep: ``figures.<name>`` or
        ``sweeps.<name>``."""
        return f"{'sweeps' if name in self.sweeps else 'figures'}.{name}"

    def section(self, name: str) -> StudySection:
        """The cell description of a contact figure or sweep (:class:`StudySection`)."""
        body, preset, source = self.body.geometry, self.preset, self.source_name(name)
        inherited = {
            "meshes": body.mesh if preset is None else preset["mesh"],
            "count": self.surfaces.count if preset is None else preset["surfaces"],
            "nu": body.nu, "E_MPa": in_unit(self.body.E, MPA),
            "spectrum": self.surfaces.spectrum, "hardness_MPa": self.body.hardness_MPa,
            "cap": self.cap, "cap_meshes": self.cap_meshes,
        }
        own = self.entry(source)
        own.pop("from", None)
        return StudySection(name=name, source=source, where=self.path(source),
                            own=frozenset(own), **{**inherited, **own})


def _accuracy(name: str | None, preset: Mapping | None) -> Accuracy:
    """The preset's name and measured expected errors, recorded with every cell."""
    if preset is None:
        return Accuracy()
    errors = tuple((k, v) for k, v in preset.items()
                   if k.endswith("_error") or k.startswith(("grid_change_", "sampling_")))
    return Accuracy(name, errors)


def _audit(section: dict, study_seed: int) -> AuditSettings:
    """The ``audit`` section; ``verify_seed`` by default the ``study_seed`` (another key's
    value, which the schema cannot write as a default)."""
    seed = section.get("verify_seed")  # optional: the study_seed
    return AuditSettings(verify=bool(section["verify"]), strict=bool(section["strict"]),
                         verify_sample=int(section["verify_sample"]),
                         verify_seed=int(study_seed if seed is None else seed))


def _reports(reports: dict) -> ReportSettings:
    """The ``reports`` section's settings records (schema defaults where not configured)."""
    sections = {name: report_section(reports, name)
                for name in ("influence_convergence", "speed_vs_error", "grid_convergence")}
    return ReportSettings(
        influence_convergence=ConvergenceSettings.from_section(sections["influence_convergence"]),
        speed_vs_error=SpeedReportSettings.from_section(sections["speed_vs_error"]),
        grid_convergence=GridConvergenceSettings.from_section(sections["grid_convergence"]),
        configured=frozenset(reports), sections=_frozen(sections))


def load_study(path) -> Study:
    """The :class:`Study` of a YAML configuration file (validated, defaults filled)."""
    return Study.from_config(load_config(path))
