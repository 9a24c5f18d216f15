"""The study's conductance across the spots: its settings, checks and table columns.

The configuration's ``conductance`` section (off by default) gives every contact job
a :class:`~roughcontact.transport.conduction.probe.ConductanceProbe` through its
geometry's body (:meth:`~roughcontact.study.records.Geometry.thermal_body`: the
block, isothermal base and insulated sides, whatever its elastic model; or, with
``body: halfspace``, a free half-space), with the body's thermal conductivity and/or
electrical resistivity: the job's sweep records the spots' thermal conductance ``C`` [W/K],
``h_c = C / A_n`` [W/(m^2 K)], the bulk's share of the resistance and the
electrical contact resistance [Ohm] at every step. The counter body is a perfect
conductor (an isothermal face): on two like half-spaces, give the series
conductivity ``k1 k2 / (k1 + k2)``. The aggregation averages the columns per cell
like every other probe column (95 % bands) and adds, from :class:`ConductanceSettings`
(the conductance's study-side record,
:class:`~roughcontact.study.probes.StudyProbe`), the constriction's share
``1 - R_bulk C`` beside the bulk's.

The counter body's material, the gas in the gap (``h_gap = k_gas / (g + M)``) and a
matrix-free thermal block beyond 64 x 64 are not modelled: a configuration that
needs them is refused or warned about when the plan is made.

Off, the section changes nothing: the jobs' parameters, files and tables are those
of a configuration without it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import ClassVar

from roughcontact.study.config import unit_slips
from roughcontact.transport.conduction.bodies import DENSE_LIMIT
from roughcontact.transport.conduction.probe import (
    BULK_SHARE,
    NO_CONDUCTION,
    BlockBody,
    ConductanceProbe,
    ConductionMaterials,
    materials_from_params,
)

__all__ = ["CONDUCTANCE_OFF", "CONSTRICTION_SHARE",
           "ConductanceSettings", "check_conductance", "conductance_settings"]

log = logging.getLogger(__name__)

#: The table column (with a conductivity) of the constriction's share of the resistance.
CONSTRICTION_SHARE = "conduction_constriction_share"
#: ``10^-8`` Ohm m per micro-ohm centimetre (the configuration's resistivity unit).
UOHM_CM = 1e-8

#: Plausible ranges of the materials' values (outside: almost surely a unit slip), the
#: narrower range of the values a contact's body has, and the units each is likely
#: typed in by mistake with their factors to the key's unit.
PLAUSIBLE = {
    # polymers 0.1-0.5, steels 15-60, copper 400, diamond 2000
    "conductivity_W_mK": ((0.1, 3000.0), (1.0, 500.0),
                          (("W/(mm K)", 1e3), ("W/(cm K)", 1e2))),
    # silver 1.6, copper 1.7, steels 10-70, nichrome 110, graphite ~1000, carbon brushes
    # up to 1e5
    "resistivity_uohm_cm": ((1.5, 1e7), (1.5, 1e5),
                            (("Ohm m", 1e8), ("Ohm cm", 1e6), ("Ohm mm", 1e5))),
}


@dataclass(frozen=True)
class ConductanceSettings:
    """The ``conductance`` section as the study uses it: the contact jobs' ``materials``
    (each job's probe through its own body, :meth:`job_probe`). Where it is on, the
    conductance's study-side probe record
    (:class:`~roughcontact.study.probes.StudyProbe`, of ``kind`` "conductance"): the
    constriction's share in each cell's table; nothing in the sidecar but its
    settings."""

    kind: ClassVar[str] = ConductanceProbe.kind

    materials: ConductionMaterials

    @property
    def enabled(self) -> bool:
        return self.materials.enabled

    def job_probe(self, geometry) -> ConductanceProbe:
        """The probe a contact job on ``geometry`` records
        (:class:`~roughcontact.study.records.Geometry`)."""
        return self.materials.probe(geometry.thermal_body(self.materials.body))

    def written(self) -> dict:
        """The materials' values in the configuration's units, by key (none off, and
        none for a material not given)."""
        materials = self.materials
        out = {}
        for prefix in ("", "counter_"):
            conductivity = getattr(materials, f"{prefix}conductivity")
            resistivity = getattr(materials, f"{prefix}resistivity")
            if conductivity is not None:
                out[f"{prefix}conductivity_W_mK"] = conductivity
            if resistivity is not None:
                out[f"{prefix}resistivity_uohm_cm"] = resistivity / UOHM_CM
        return out

    def material_text(self, prefix: str = "") -> str:
        """The body's materials in words (a caption's; with ``prefix="counter_"`` the
        counter body's, empty where it is a perfect conductor)."""
        w = self.written()
        parts = ([f"thermal conductivity {w[prefix + 'conductivity_W_mK']:g} W/(m K)"]
                 if prefix + "conductivity_W_mK" in w else [])
        parts += ([f"electrical resistivity {w[prefix + 'resistivity_uohm_cm']:g} uOhm cm"]
                  if prefix + "resistivity_uohm_cm" in w else [])
        return " and ".join(parts)

    def counter_text(self) -> str:
        """The counter face in words: a perfect conductor, or a half-space of its
        materials (the sidecar's, a caption's)."""
        counter = self.material_text("counter_")
        return (f"a half-space of {counter} in series" if counter
                else "a perfect conductor (isothermal face)")

    def table_columns(self, rows) -> tuple[dict, dict]:
        """The constriction's share of a cell's aggregated ``rows`` (a table with the
        bulk share's ``_mean``, ``_half_width`` and ``_count``): ``1 - R_bulk C``, its
        band the bulk share's; none without a conductivity."""
        if self.materials.conductivity is None:
            return {}, {}
        columns = {f"{CONSTRICTION_SHARE}_mean": 1.0 - rows[f"{BULK_SHARE}_mean"],
                   f"{CONSTRICTION_SHARE}_half_width": rows[f"{BULK_SHARE}_half_width"],
                   f"{CONSTRICTION_SHARE}_count": rows[f"{BULK_SHARE}_count"]}
        return columns, {f"{CONSTRICTION_SHARE}_mean": "1",
                         f"{CONSTRICTION_SHARE}_half_width": "1",
                         f"{CONSTRICTION_SHARE}_count": "1"}

    def cell_rows(self, sweep, labels: dict) -> list[dict]:
        """No rows of the sidecar per cell."""
        return []

    def sidecar(self, rows: list[dict]) -> dict:
        """The sidecar's entry: the materials in SI units, the counter body's model."""
        return {**self.params(), "counter_body": self.counter_text()}

    @classmethod
    def from_params(cls, params: dict) -> ConductanceSettings:
        """The settings of their :meth:`params` (the aggregate rule's; empty: off)."""
        return cls(materials_from_params(params))

    def params(self) -> dict:
        """The materials in SI units (the aggregate rule's params; empty off)."""
        return self.materials.params()


#: The conductance off: nothing recorded.
CONDUCTANCE_OFF = ConductanceSettings(NO_CONDUCTION)


def conductance_settings(section) -> ConductanceSettings:
    """The :class:`ConductanceSettings` of a validated configuration's ``conductance``
    section."""
    if not section["enabled"]:
        return CONDUCTANCE_OFF
    conductivity = section.get("conductivity_W_mK")  # optional: no thermal columns
    resistivity = section.get("resistivity_uohm_cm")  # optional: no electrical column
    if conductivity is None and resistivity is None:
        raise ValueError(
            "conductance: enabled without conductivity_W_mK or resistivity_uohm_cm; give "
            "the body's thermal conductivity [W/(m K)] (steel 50), its electrical "
            "resistivity [uOhm cm] (steel 15), or both, or set conductance.enabled: false")
    counter_resistivity = section.get("counter_resistivity_uohm_cm")  # optional: perfect
    return ConductanceSettings(ConductionMaterials(
        conductivity=conductivity,
        resistivity=None if resistivity is None else resistivity * UOHM_CM,
        tol=float(section["tol"]), body=str(section["body"]),
        counter_conductivity=section.get("counter_conductivity_W_mK"),  # optional: perfect
        counter_resistivity=None if counter_resistivity is None
        else counter_resistivity * UOHM_CM))


def _slip(key: str, value: float) -> str | None:
    """The message for a value of ``conductance.<key>`` outside its plausible range, or
    None (a counter body's material as the body's)."""
    (low, high), (usual_low, usual_high), slips = PLAUSIBLE[key.removeprefix("counter_")]
    if low <= value <= high:
        return None
    guesses = unit_slips(f"conductance.{key}", value, slips,
                         lambda v: usual_low <= v <= usual_high)
    unit = "W/(m K)" if key.endswith("conductivity_W_mK") else "uOhm cm"
    return (f"conductance.{key}: {value:g} is outside the plausible {low:g}-{high:g} {unit}"
            + (f" ({'; '.join(guesses)})" if guesses else "")
            + " (plausibility_check: false accepts it)")


def check_conductance(conductance: ConductanceSettings, plausibility_check: bool,
                      geometries: dict, compliant_counters=()) -> list[str]:
    """The problems of the ``conductance`` settings: values that are almost surely a
    unit slip (with ``plausibility_check``). Blocks (``geometries``: a contact
    geometry's place in words -> its :class:`~roughcontact.study.records.Geometry`)
    beyond :data:`~roughcontact.transport.conduction.bodies.DENSE_LIMIT` elements are
    logged: their thermal influence is the matrix-free hybrid. The
    ``compliant_counters`` (their names) are warned about: a block's own bulk is not
    counted, or the counter is a perfect conductor."""
    if not conductance.enabled:
        return []
    for where, geometry in geometries.items():
        nx, ny = geometry.grid
        body = geometry.thermal_body(conductance.materials.body)
        if nx * ny > DENSE_LIMIT and isinstance(body, BlockBody):
            log.info("conductance: %s (%d x %d elements) gets the matrix-free thermal "
                     "block (Love's half-space and a coarse block's correction): h_c "
                     "within 0.2-1.6 %% of the dense block's on clustered spots, up to 7 %% "
                     "on scattered ones (docs/performance/conductance.md)", where, nx, ny)
    counter = conductance.material_text("counter_")
    for name in sorted(compliant_counters):
        if counter:
            log.warning("conductance: the counter body %s conducts as a half-space of "
                        "%s: a counter block's own bulk resistance is not counted", name,
                        counter)
        else:
            log.warning("conductance: the counter body %s is taken as a perfect conductor "
                        "(isothermal face): its own resistance is not counted, so h_c is "
                        "that of the first body alone; give its material "
                        "(conductance.counter_conductivity_W_mK, "
                        "counter_resistivity_uohm_cm)", name)
    problems = []
    if plausibility_check:
        problems += [message for key, value in conductance.written().items()
                     if (message := _slip(key, float(value))) is not None]
    return problems
