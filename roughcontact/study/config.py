"""The configuration's edge: validated sections to typed settings in SI units.

``config/schema.yaml`` carries every default (``default:`` entries, applied
when the configuration is validated: by the Snakefile, or by
:func:`validated` for library users and tests). The dataclasses below take a
validated section and convert its units once (``*_mm`` -> m, ``*_um`` -> m,
``*_MPa`` -> Pa, ``*_gb`` -> bytes); nothing past this module converts units
of configuration values or repeats a default. :func:`from_unit` and
:func:`in_unit` are the two directions of that conversion, for the records
of :mod:`roughcontact.study.records` and their plain ``params()``.
"""

from __future__ import annotations

import copy
import difflib
import functools
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.transport.probe import NO_FLOW, FlowProbe, probe_from_params
from roughcontact.units import GB, MM, MPA, UM

if TYPE_CHECKING:
    from roughcontact.elasticity.influence import MeshSpec

#: The schema of every configuration (with its defaults).
SCHEMA = Path(__file__).resolve().parents[2] / "config" / "schema.yaml"


def in_unit(value: float, unit: float) -> float:
    """``value`` [SI] in ``unit`` (e.g. :data:`~roughcontact.units.MM`), to 12 significant digits.

    The form of a value for people and files (parameters, keys, labels,
    table columns): a value read from the configuration comes back as it was
    written, free of the rounding of the conversion.
    """
    return float(f"{value / unit:.12g}")


def as_pair(value) -> tuple:
    """``(a, b)`` of a pair, or ``(value, value)`` of a scalar (the configuration allows both)."""
    if isinstance(value, list | tuple):
        return (value[0], value[1])
    return (value, value)


def from_unit(values, unit: float = MM) -> tuple[float, ...] | None:
    """Values written in ``unit`` (the configuration's) as a tuple in SI units (None stays
    None)."""
    return None if values is None else tuple(float(v) * unit for v in values)


def unit_slips(key: str, value: float, slips, fits) -> list[str]:
    """The advice for a value of ``key`` that is almost surely a unit slip: for each
    ``(unit, factor)`` of ``slips`` (the unit it may have been typed in, and the factor
    to the key's unit) whose converted value ``fits``, ``typed in <unit>? then write
    <key>: <value>``."""
    return [f"typed in {unit}? then write {key}: {value * factor:.6g}"
            for unit, factor in slips if fits(value * factor)]


def in_units(values, unit: float = MM) -> list[float] | None:
    """SI values as a list in ``unit`` (:func:`in_unit`; None stays None)."""
    return None if values is None else [in_unit(v, unit) for v in values]


def grid_pair(value) -> tuple[int, int]:
    """A grid (nx, ny) of a pair or of a scalar (square)."""
    return tuple(int(v) for v in as_pair(value))


class ConfigError(ValueError):
    """A configuration the schema refuses: one line per offending key (its path in
    the configuration, the value and what was expected)."""


def config_path(path) -> str:
    """A key's place in the configuration in plain words: ``sweeps.rough.moments[0]``."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else f".{part}" if text else str(part)
    return text or "the configuration"


def _listed(values, last: str = "or") -> str:
    words = [json.dumps(v) if not isinstance(v, str) else f"'{v}'" for v in values]
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} {last} {words[-1]}"


def _described(schema: dict, key: str) -> str:
    """`` (its description)`` of a key the schema describes, else ''."""
    text = (schema.get("properties", {}).get(key) or {}).get("description")
    return f" ({' '.join(text.split())})" if text else ""


def _alternatives(error) -> str | None:
    """An ``anyOf`` of required keys (a study: from, or sigma_um and pressure_MPa, or
    surface and pressure_MPa): the keys missing from the alternative begun, else all."""
    branches = [b.get("required") for b in error.validator_value]
    if not isinstance(error.instance, dict) or not all(branches):
        return None
    given = set(error.instance)
    begun = [b for b in branches if given & set(b)]
    if begun:
        missing = min(([k for k in b if k not in given] for b in begun), key=len)
        schema = error.schema
        return "; ".join(f"'{key}' is missing{_described(schema, key)}" for key in missing)
    options = "; ".join(f"'{b[0]}'" if len(b) == 1 else _listed(b, "with") for b in branches)
    return f"needs one of: {options}"


def _unknown_keys(error) -> str:
    known = list(error.schema.get("properties", {}))
    unknown = [k for k in error.instance if k not in known]
    hints = []
    for key in unknown:
        close = difflib.get_close_matches(str(key), known, n=1)
        hints.append(f"'{key}'" + (f" (did you mean '{close[0]}'?)" if close else ""))
    return (f"unknown key{'s' if len(unknown) > 1 else ''} {', '.join(hints)}; the keys here "
            f"are {_listed(known, 'and')}" if known else f"unknown key {', '.join(hints)}")


_TYPES = {"number": "a number", "integer": "a whole number", "string": "text",
          "boolean": "true or false", "array": "a list", "object": "a section of keys",
          "null": "null"}
_BOUNDS = {"minimum": "at least", "maximum": "at most", "exclusiveMinimum": "above",
           "exclusiveMaximum": "below"}


def _unquoted(value, kinds) -> str:
    """The advice for a number written in quotes (text) where a number is expected."""
    if not isinstance(value, str) or not {"number", "integer"} & set(kinds):
        return ""
    try:
        number = float(value)
    except ValueError:
        return ""
    if not math.isfinite(number) or ("number" not in kinds and not number.is_integer()):
        return ""
    return f" (text: write {value.strip()} without quotes)"


def _plain(error) -> str:
    """One schema violation in plain words (the value found and what is expected)."""
    value, rule, kind = error.instance, error.validator_value, error.validator
    if "message" in error.schema and kind in ("not", "const", "required"):
        return " ".join(error.schema["message"].split())
    if kind == "required":
        key = error.message.split("'")[1]
        return f"'{key}' is missing{_described(error.schema, key)}"
    if kind == "additionalProperties":
        return _unknown_keys(error)
    if kind == "enum":
        return f"{json.dumps(value)} is not one of {_listed(rule)}"
    if kind == "type":
        kinds = [rule] if isinstance(rule, str) else rule
        wanted = " or ".join(_TYPES.get(t, t) for t in kinds)
        return f"{json.dumps(value)} is not {wanted}{_unquoted(value, kinds)}"
    if kind in _BOUNDS:
        return f"{json.dumps(value)} is out of range: it must be {_BOUNDS[kind]} {rule:g}"
    if kind in ("minItems", "maxItems"):
        bound = "at least" if kind == "minItems" else "at most"
        items = f"{len(value)} item{'' if len(value) == 1 else 's'}"
        return f"{json.dumps(value)} has {items}, {bound} {rule} expected"
    if kind == "anyOf" and (text := _alternatives(error)):
        return text
    if kind in ("oneOf", "anyOf") and error.context:
        # of the branches, the error of a value of the right type says most
        specific = _specific(error.context)
        if specific:
            from jsonschema.exceptions import best_match

            return _plain(best_match(specific))
        kinds = [e.validator_value for e in error.context]
        wanted = " or ".join(_TYPES.get(k, str(k)) for k in kinds)
        return f"{json.dumps(value)} is not {wanted}{_unquoted(value, kinds)}"
    return error.message


def _specific(branches) -> list:
    """The errors of a ``oneOf``'s (``anyOf``'s) branches that the value's type matched:
    all but a branch's refusal of the value's type itself. An error deeper in the value
    (``{surface: {sigma_um: "1.5"}}``: a key of the entry branch) is specific, whatever
    its kind."""
    return [e for e in branches if e.validator != "type" or e.path]


def schema_errors(config: dict) -> list[str]:
    """``key.path: message`` in plain words of every schema violation of ``config``
    (none: []).

    jsonschema is imported here, not with the module: a job that only reads its
    typed settings does not pay for it.
    """
    import jsonschema

    schema = load_schema()
    validator = jsonschema.validators.validator_for(schema)(schema)
    lines = []
    for error in sorted(validator.iter_errors(config), key=lambda e: list(map(str, e.path))):
        # of a oneOf's branches, the one for a value of the right type gives the place
        deepest = error
        while deepest.validator in ("oneOf", "anyOf") and deepest.context:
            specific = _specific(deepest.context)
            if not specific:
                break
            deepest = jsonschema.exceptions.best_match(specific)
        lines.append(f"{config_path(deepest.absolute_path)}: {_plain(error)}")
    return lines


def apply_schema(config: dict) -> dict:
    """Validate ``config`` in place against the schema and fill in every default.

    Raises :class:`ConfigError` with one line per offending key (not the
    schema's text).
    """
    problems = schema_errors(config)
    if problems:
        raise ConfigError("Invalid configuration (no job was started):\n  "
                          + "\n  ".join(problems)
                          + "\nKeys, units and defaults: config/schema.yaml; a complete "
                            "example: config/config.yaml.")
    _fill_defaults(config)
    return config


@functools.lru_cache(maxsize=1)
def load_schema() -> dict:
    """The schema (:data:`SCHEMA`), parsed once per process (with libyaml's parser where
    PyYAML has it): the workflow validates several configurations when it is planned,
    and pure-Python YAML takes 0.2 s for this file. Read-only: do not change it."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    return yaml.load(SCHEMA.read_text(), Loader=loader)


def _fill_defaults(config: dict) -> None:
    """Set every default of the schema that ``config`` (valid) leaves out, in place.

    The recipe of jsonschema's FAQ that ``snakemake.utils.validate`` applies (a
    validator whose ``properties`` rule sets each property's ``default`` before
    validating it), run on the schema parsed once (:func:`load_schema`) instead
    of a parse of the file per call; tests compare the two on every config.
    """
    from jsonschema import validators

    schema = load_schema()
    base = validators.validator_for(schema)
    check_properties = base.VALIDATORS["properties"]

    def set_defaults(validator, properties, instance, subschema):
        for name, property_schema in properties.items():
            if "default" in property_schema:
                instance.setdefault(name, copy.deepcopy(property_schema["default"]))
        yield from check_properties(validator, properties, instance, subschema)

    validators.extend(base, {"properties": set_defaults})(schema).validate(config)


def validated(config: dict) -> dict:
    """A copy of ``config`` validated against the schema, with every default applied.

    Raises :class:`ConfigError` naming each offending key.
    """
    return apply_schema(copy.deepcopy(config))


def report_section(reports: dict, name: str) -> dict:
    """The validated ``reports: <name>`` section of a configuration's ``reports``, or its
    schema defaults when it is not configured (another report may need it: the speed
    report reads the mesh-convergence table)."""
    section = reports.get(name)  # optional: a report not configured
    if section is not None:
        return section
    return apply_schema({"reports": {name: {}}})["reports"][name]


def load_config(path: str | os.PathLike) -> dict:
    """Read a YAML configuration and return it :func:`validated`."""
    import yaml

    return validated(yaml.safe_load(Path(path).read_text()))


@dataclass(frozen=True)
class ContactSettings:
    """The contact solver of every contact job (config section ``contact``).

    ``method``, ``tol`` (dimensionless KKT residual) and ``precision`` of
    :func:`roughcontact.contact.nondim.solve_cell`; ``steps`` approaches per
    sweep; ``pressure_levels`` nominal pressures per aggregated cell; ``flow`` the
    flow each sweep records (config section ``flow``,
    :mod:`roughcontact.study.flow_settings`; :data:`NO_FLOW`: none), its one probe
    (:attr:`probes`).
    """

    method: str
    tol: float
    precision: str
    steps: int
    pressure_levels: int
    flow: FlowProbe = NO_FLOW

    @classmethod
    def from_section(cls, section: dict) -> ContactSettings:
        """The settings of a ``contact`` section, or of a contact job's :meth:`params`
        (which hold the flow probe's under ``flow`` where the flow is on)."""
        return cls(method=str(section["method"]), tol=float(section["tol"]),
                   precision=str(section["precision"]), steps=int(section["steps"]),
                   pressure_levels=int(section["pressure_levels"]),
                   flow=probe_from_params(section.get("flow")))

    def params(self) -> dict:
        """The settings as the ``contact`` section writes them (a contact job's params),
        with the flow probe's settings where the flow is on (none where it is off: a
        study without flow keeps its jobs' parameters)."""
        params = {"method": self.method, "tol": self.tol, "precision": self.precision,
                  "steps": self.steps, "pressure_levels": self.pressure_levels}
        for probe in self.probes:
            params[probe.kind] = probe.params()
        return params

    @property
    def probes(self) -> tuple:
        """The probes every contact job's sweep records
        (:mod:`roughcontact.contact.probes`): the flow probe where the flow is on, none
        where it is off."""
        return (self.flow,) if self.flow.directions else ()


@dataclass(frozen=True)
class BuildSettings:
    """How influence models are built (config section ``body``): the sparse
    ``solver`` and the largest estimated peak memory ``max_bytes`` [bytes]."""

    solver: str
    max_bytes: float

    @classmethod
    def from_section(cls, body: dict) -> BuildSettings:
        return cls(solver=str(body["solver"]), max_bytes=float(body["max_memory_gb"]) * GB)


@dataclass(frozen=True)
class ConvergenceSettings:
    """The mesh-convergence report (``reports.influence_convergence``), SI units.

    ``presets`` compared (mesh preset names; a library user may also give
    :class:`~roughcontact.elasticity.influence.MeshSpec` objects), coarse to
    fine; ``surfaces`` Gaussian surfaces (0: no contact part) of height
    standard deviation ``sigma`` [m] and 10 % correlation length
    ``corr_length`` [m], read at the nominal ``pressures`` [Pa]. The defaults
    are the schema's (``config/schema.yaml``; a test holds them equal), for
    library users: the workflow builds the record :meth:`from_section`.
    """

    presets: tuple[str | MeshSpec, ...] = ("paper", "graded", "refined", "converged")
    surfaces: int = 3
    sigma: float = 24.5e-6
    corr_length: float = 1e-3
    pressures: tuple[float, ...] = (0.3e6, 1e6, 2e6)

    @classmethod
    def from_section(cls, section: dict) -> ConvergenceSettings:
        return cls(presets=tuple(section["presets"]), surfaces=int(section["surfaces"]),
                   sigma=float(section["sigma_um"]) * UM,
                   corr_length=float(section["b_mm"]) * MM,
                   pressures=tuple(float(p) * MPA for p in section["pressures_MPa"]))


@dataclass(frozen=True)
class SpeedReportSettings:
    """The speed-against-error report (``reports.speed_vs_error``), SI units.

    ``surfaces`` per solver-study cell, the ``grids`` of the grid study,
    ``count_surfaces`` and ``counts`` of the surface-count study, the
    tolerances ``tol_kP`` and ``tol_area`` (relative) of the recommendation,
    read at the nominal ``pressures`` [Pa]. The record
    :func:`roughcontact.reports.speed.speed_vs_error_report` takes whole. The
    defaults are the schema's (``config/schema.yaml``; a test holds them
    equal), for library users: the workflow builds the record
    :meth:`from_section`.
    """

    surfaces: int = 4
    grids: tuple[int, ...] = (30, 60, 120)
    count_surfaces: int = 120
    counts: tuple[int, ...] = (5, 10, 20, 40, 60, 120)
    tol_kP: float = 0.02
    tol_area: float = 0.05
    pressures: tuple[float, ...] = (0.3e6, 1e6, 3e6)

    @classmethod
    def from_section(cls, section: dict) -> SpeedReportSettings:
        return cls(surfaces=int(section["surfaces"]), grids=tuple(int(g) for g in section["grids"]),
                   count_surfaces=int(section["count_surfaces"]),
                   counts=tuple(int(c) for c in section["counts"]),
                   tol_kP=float(section["tol_kP"]), tol_area=float(section["tol_area"]),
                   pressures=tuple(float(p) * MPA for p in section["pressures_MPa"]))


#: Pilot sweep on the coarsest grid: approaches as fractions of the mean initial gap.
PILOT_FRACTIONS = np.geomspace(0.1, 0.95, 24)


@dataclass(frozen=True)
class GridConvergenceSettings:
    """The grid-convergence study (``reports.grid_convergence``), SI units.

    ``grids`` (elements per side, ascending), ``surfaces`` seeds, square
    ``size`` [m]; the self-affine spectrum (``hurst``, ``rolloff_wavelength``,
    ``cutoff_wavelength`` [m]) and ``generator`` (``"paper"``: a Gaussian
    process); each surface scaled to ``rms_gradient`` h'_rms [-]; the body's
    ``E`` [Pa] and ``nu``; the ``reduced_pressures`` ``p0 / (E* h'_rms)`` [-]
    read per grid; ``kappa_area`` the (lowest, highest) real area fraction of
    the fit of kappa; ``steps`` approaches per sweep, contact ``tol``; and
    ``converged_within``, the relative distance to the extrapolated value at
    which an aggregate counts as converged.
    """

    grids: tuple[int, ...]
    surfaces: int
    size: float
    hurst: float
    rolloff_wavelength: float
    cutoff_wavelength: float
    generator: str
    rms_gradient: float
    E: float
    nu: float
    reduced_pressures: tuple[float, ...]
    kappa_area: tuple[float, float]
    steps: int
    tol: float
    converged_within: float

    @classmethod
    def from_section(cls, section: dict) -> GridConvergenceSettings:
        return cls(grids=tuple(sorted(int(g) for g in section["grids"])),
                   surfaces=int(section["surfaces"]), size=float(section["size_mm"]) * MM,
                   hurst=float(section["hurst"]),
                   rolloff_wavelength=float(section["rolloff_mm"]) * MM,
                   cutoff_wavelength=float(section["cutoff_mm"]) * MM,
                   generator=str(section["generator"]),
                   rms_gradient=float(section["rms_gradient"]),
                   E=float(section["E_MPa"]) * MPA, nu=float(section["nu"]),
                   reduced_pressures=tuple(sorted(float(p)
                                                  for p in section["reduced_pressures"])),
                   kappa_area=(float(section["kappa_area"][0]),
                               float(section["kappa_area"][1])),
                   steps=int(section["steps"]), tol=float(section["tol"]),
                   converged_within=float(section["converged_within"]))

    @property
    def contact_modulus(self) -> float:
        """``E* = E / (1 - nu^2)`` [Pa] (rigid flat on an elastic body)."""
        return self.E / (1.0 - self.nu**2)

    @property
    def pressure_scale(self) -> float:
        """``E* h'_rms`` [Pa]: nominal pressure = reduced pressure x this."""
        return self.contact_modulus * self.rms_gradient

    def spec(self, grid: int | None = None) -> SurfaceSpec:
        """The surfaces' :class:`SurfaceSpec` (``sigma`` 1: the scale is ``rms_gradient``)."""
        return SurfaceSpec(grid=grid or self.grids[0], size=self.size, acf="self-affine",
                           hurst=self.hurst, rolloff_wavelength=self.rolloff_wavelength,
                           cutoff_wavelength=self.cutoff_wavelength)
