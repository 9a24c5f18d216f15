"""The configuration's edge: validated sections to typed settings in SI units.

``config/schema.yaml`` carries every default (``default:`` entries, applied
when the configuration is validated: by the Snakefile, or by
:func:`validated` for library users and tests). The dataclasses below take a
validated section and convert its units once (``*_mm`` -> m, ``*_um`` -> m,
``*_MPa`` -> Pa, ``*_gb`` -> bytes), each declared once on its field
(:mod:`roughcontact.study.codec`, whose :func:`~roughcontact.study.codec.from_unit`
and :func:`~roughcontact.study.codec.in_unit` are the two directions of that
conversion, for these settings and for the records of
:mod:`roughcontact.study.records` and their plain ``params()``); nothing past this
module converts units of configuration values or repeats a default.
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

from roughcontact.study import codec
from roughcontact.study.codec import Record
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.transport.conduction.probe import (
    NO_CONDUCTION,
    ConductionMaterials,
    materials_from_params,
)
from roughcontact.transport.probe import NO_FLOW, FlowProbe, probe_from_params
from roughcontact.units import GB, MM, MPA, UM

if TYPE_CHECKING:
    from roughcontact.elasticity.influence import MeshSpec

#: The schema of every configuration (with its defaults).
SCHEMA = Path(__file__).resolve().parents[2] / "config" / "schema.yaml"


def unit_slips(key: str, value: float, slips, fits) -> list[str]:
    """The advice for a value of ``key`` that is almost surely a unit slip: for each
    ``(unit, factor)`` of ``slips`` (the unit it may have been typed in, and the factor
    to the key's unit) whose converted value ``fits``, ``typed in <unit>? then write
    <key>: <value>``."""
    return [f"typed in {unit}? then write {key}: {value * factor:.6g}"
            for unit, factor in slips if fits(value * factor)]


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


def _yaml_number(text: str):
    """The number YAML 1.1 reads ``text`` as (PyYAML's loaders, Snakemake's among them),
    or None where it reads text (``1e-3``, ``1.0e5``: an exponent needs a point in the
    mantissa and a sign)."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        number = yaml.load(f"value: {text}", Loader=loader)["value"]
    except yaml.YAMLError:
        return None
    return number if isinstance(number, int | float) and not isinstance(number, bool) else None


def yaml_number_forms(number: float, integer: bool = False) -> list[str]:
    """Ways to write ``number`` that YAML 1.1 reads as that number: the plain decimal
    (``0.001``, ``100000.0``) and the exponent form with a point and a sign (``1.0e-3``,
    ``1.0e+5``); each read back by YAML here, so every form offered works."""
    if integer:
        forms = [str(int(number))]
    else:
        mantissa, exponent = f"{number:.15e}".split("e")
        mantissa = mantissa.rstrip("0")
        mantissa += "0" if mantissa.endswith(".") else ""
        plain = repr(float(number))
        forms = ([plain] if "e" not in plain else []) + (
            [f"{mantissa}e{int(exponent):+d}"] if int(exponent) else [])
    return [form for form in dict.fromkeys(forms) if _yaml_number(form) == number]


def _unquoted(value, kinds) -> str:
    """The advice for a number that YAML read as text where a number is expected: one
    written in quotes, or in a form YAML 1.1 reads as text (``1e-3``), with forms that
    YAML reads as the number."""
    if not isinstance(value, str) or not {"number", "integer"} & set(kinds):
        return ""
    try:
        number = float(value)
    except ValueError:
        return ""
    integer = "number" not in kinds
    if not math.isfinite(number) or (integer and not number.is_integer()):
        return ""
    text = value.strip()
    if _yaml_number(text) is not None:
        return f" (text: write {text} without quotes)"
    forms = yaml_number_forms(number, integer)
    return f" (YAML reads {text} as text, quoted or not: write {' or '.join(forms)})"


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


def _branch_errors(error) -> list:
    """The errors of ``error`` to report, each at its deepest place: of a ``oneOf``'s
    (``anyOf``'s) branches, every error of the branch the value's type matched best (a
    block entry with a bad ``nu`` and a bad ``E_MPa``: both, in one round), not only the
    first."""
    from jsonschema.exceptions import best_match

    if error.validator not in ("oneOf", "anyOf") or not error.context:
        return [error]
    specific = _specific(error.context)
    if not specific:
        return [error]
    branch = best_match(specific).relative_schema_path[0]
    same = [e for e in specific if e.relative_schema_path[0] == branch]
    return [deeper for e in same for deeper in _branch_errors(e)]


def schema_errors(config: dict) -> list[str]:
    """``key.path: message`` in plain words of every schema violation of ``config``
    (none: []), every bad value of an entry at once.

    jsonschema is imported here, not with the module: a job that only reads its
    typed settings does not pay for it.
    """
    import jsonschema

    schema = load_schema()
    validator = jsonschema.validators.validator_for(schema)(schema)
    lines = []
    for error in sorted(validator.iter_errors(config), key=lambda e: list(map(str, e.path))):
        # of a oneOf's branches, the one for a value of the right type gives the places
        found = _branch_errors(error)
        if len(found) == 1:  # the oneOf's own words (its message, its alternatives)
            lines.append(f"{config_path(found[0].absolute_path)}: {_plain(error)}")
        else:
            lines += [f"{config_path(e.absolute_path)}: {_plain(e)}" for e in found]
    return list(dict.fromkeys(lines))


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
class ContactSettings(Record):
    """The contact solver of every contact job (config section ``contact``).

    ``method``, ``tol`` (dimensionless KKT residual) and ``precision`` of
    :func:`roughcontact.contact.nondim.solve_cell`; ``steps`` approaches per
    sweep; ``pressure_levels`` nominal pressures per aggregated cell; ``flow`` the
    flow each sweep records (config section ``flow``,
    :mod:`roughcontact.study.flow_settings`; :data:`NO_FLOW`: none), its one probe
    (:attr:`probes`). Its params are a contact job's (the ``contact`` section's keys),
    with the flow probe's settings under ``flow`` where the flow is on (none where it
    is off: a study without flow keeps its jobs' parameters).
    """

    method: str
    tol: float
    precision: str
    steps: int
    pressure_levels: int
    flow: FlowProbe = codec.record(probe_from_params, omit=lambda probe: not probe.directions,
                                   default=NO_FLOW)
    conductance: ConductionMaterials = codec.record(
        materials_from_params, omit=lambda materials: not materials.enabled,
        default=NO_CONDUCTION)

    def probes(self, geometry) -> tuple:
        """The probes the sweep of a contact job on ``geometry``
        (:class:`~roughcontact.study.records.Geometry`) records
        (:mod:`roughcontact.contact.probes`): the flow probe where the flow is on, the
        conductance through the geometry's body
        (:meth:`~roughcontact.study.records.Geometry.thermal_body`) where the
        ``conductance`` section is on; none where both are off."""
        flow = (self.flow,) if self.flow.directions else ()
        materials = self.conductance
        conduction = ((materials.probe(geometry.thermal_body(materials.body)),)
                      if materials.enabled else ())
        return flow + conduction


@dataclass(frozen=True)
class BuildSettings(Record):
    """How influence models are built (config section ``body``): the sparse
    ``solver`` and the largest estimated peak memory ``max_bytes`` [bytes]."""

    solver: str
    max_bytes: float = codec.si(GB, "max_memory_gb")


@dataclass(frozen=True)
class ConvergenceSettings(Record):
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
    sigma: float = codec.si(UM, "sigma_um", default=24.5e-6)
    corr_length: float = codec.si(MM, "b_mm", default=1e-3)
    pressures: tuple[float, ...] = codec.si_tuple(MPA, "pressures_MPa",
                                                  default=(0.3e6, 1e6, 2e6))


@dataclass(frozen=True)
class SpeedReportSettings(Record):
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
    pressures: tuple[float, ...] = codec.si_tuple(MPA, "pressures_MPa",
                                                  default=(0.3e6, 1e6, 3e6))


#: Pilot sweep on the coarsest grid: approaches as fractions of the mean initial gap.
PILOT_FRACTIONS = np.geomspace(0.1, 0.95, 24)


def _ascending(cast):
    """Values read in ascending order, each ``cast``."""
    return lambda values: tuple(sorted(cast(v) for v in values))


@dataclass(frozen=True)
class GridConvergenceSettings(Record):
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

    grids: tuple[int, ...] = codec.field(read=_ascending(int))
    surfaces: int
    size: float = codec.si(MM, "size_mm")
    hurst: float
    rolloff_wavelength: float = codec.si(MM, "rolloff_mm")
    cutoff_wavelength: float = codec.si(MM, "cutoff_mm")
    generator: str
    rms_gradient: float
    E: float = codec.si(MPA, "E_MPa")
    nu: float
    reduced_pressures: tuple[float, ...] = codec.field(read=_ascending(float))
    kappa_area: tuple[float, float]
    steps: int
    tol: float
    converged_within: float

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
