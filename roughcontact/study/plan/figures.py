"""The figure registry: what each figure draws, from which study, with which caption.

A figure is a notebook ``notebooks/<name>.ipynb`` (papermill parameters, drawn
by the ``figure`` rule) and one entry of :data:`FIGURES`: its :class:`Kind` (the
surfaces alone, a contact study's cells, or the studies it lists), its report
caption (:mod:`roughcontact.study.plan.captions`), the surface cells it draws
(``surfaces``), the other figures whose settings it draws with, and whether it
needs the flow through the gap. The plan (:func:`roughcontact.study.plan.cells.study_plan`)
and the workflow read everything about a figure from here; its configuration keys
and their defaults are in ``config/schema.yaml`` (``figures.<name>``).

Adding a figure: the notebook, its schema entry (with defaults) and one entry
here, in drawing order.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from types import MappingProxyType

from roughcontact.study import layout
from roughcontact.study.codec import as_pair, from_unit
from roughcontact.study.plan import captions
from roughcontact.study.sources import spectrum_from_entry

__all__ = ["FIGURES", "Figure", "Kind"]


class Kind(Enum):
    """What a figure is drawn from: ``SURFACES`` (generated surfaces, or nothing at all),
    ``CONTACT`` (a contact study: its own cells, or ``from:`` another's), ``STUDIES``
    (the aggregates of the contact studies it lists under ``studies:``)."""

    SURFACES = "surfaces"
    CONTACT = "contact"
    STUDIES = "studies"


def _no_surfaces(study, name: str, cells) -> list:
    return []


def _fig03_surfaces(study, name: str, cells) -> list:
    """Fig 3: one Gaussian cell per correlation length."""
    figure, surfaces = study.entry(name), study.surfaces
    spectrum = spectrum_from_entry(surfaces.spectrum)
    return [surfaces.cell(spectrum, skew=0.0, kurt=3.0, corr_length=from_unit(as_pair(b)),
                          count=figure["count"])
            for b in figure["b_mm"]]


def _fig04_surfaces(study, name: str, cells) -> list:
    """Figs 4 and 5: one cell per (Sk, Ku) pair of Fig 4."""
    figure, surfaces = study.entry("fig04"), study.surfaces
    spectrum = spectrum_from_entry(surfaces.spectrum)
    return [surfaces.cell(spectrum, skew=skew, kurt=kurt,
                          corr_length=from_unit(as_pair(figure["b_mm"])), count=surfaces.count)
            for skew, kurt in figure["moments"]]


def _study_surfaces(study, name: str, cells) -> list:
    """Fig 10: the surfaces of each of its study cells (the cumulative height
    distributions of the Fig 9 surfaces)."""
    return [cell.surface for cell in cells[name]]


def _listed_study_surfaces(study, name: str, cells) -> list:
    """The conductance figure: the surfaces of the cells of the studies it lists, once
    each (their slopes, for the correlations)."""
    return list({cell.surface.key: cell.surface for listed in study.entry(name)["studies"]
                 for cell in cells[listed]}.values())


def _unique_study_surfaces(study, name: str, cells) -> list:
    """The measured figure: the measured surface and its twin, once each."""
    return list({cell.surface.key: cell.surface for cell in cells[name]}.values())


@dataclass(frozen=True)
class Figure:
    """One figure of :data:`FIGURES` (module docstring).

    ``kind`` what it is drawn from; ``caption(plan, name)`` its report caption;
    ``surfaces(study, name, cells)`` the surface cells it draws, in its order (``cells``
    the study cells by study name); ``generated``: those surfaces are its own to
    generate (a study's are its jobs'); ``drawn_with`` the other figures whose settings
    it draws with (notebook parameters: Fig 5 draws Fig 4's heights in Fig 4's sigma);
    ``needs``: the study probes (kinds, :data:`~roughcontact.study.probes.STUDY_PROBE_KINDS`)
    whose columns of its studies' aggregates it draws, or ``"loading"`` for the loops of
    the ``loading`` section; ``files(study)`` the files it reads of each study it draws
    (its notebook's ``aggregate_files``, in the study's order): the rising sweep's
    aggregates (:func:`~roughcontact.study.layout.aggregates`) or the cycles' tables
    (:func:`~roughcontact.study.layout.cycle_aggregates`).
    """

    kind: Kind
    caption: Callable
    surfaces: Callable = _no_surfaces
    generated: bool = False
    drawn_with: tuple[str, ...] = ()
    needs: tuple[str, ...] = ()
    files: Callable[[str], list[str]] = layout.aggregates


def _contact(caption: Callable, surfaces: Callable = _no_surfaces) -> Figure:
    return Figure(Kind.CONTACT, caption, surfaces)


#: Every figure, in drawing order ("measured": a measured surface against its synthetic
#: twin, usually ``from:`` a sweep; "fig11_resolved": Fig 11 on a grid that resolves the
#: ACF, config/fig11_resolved.yaml; "gaps": the mean gap and the spots of a study's
#: cells, usually ``from:`` fig07; "two_bodies": each counter body of the listed studies
#: beside the rigid flat; "leakage": the flow through the contact gap of the listed
#: studies; "conductance": the thermal contact conductance of the listed studies;
#: "cycles": the loops of loading, unloading and reloading of the listed studies' capped
#: cells, from their cycles' tables).
FIGURES = MappingProxyType({
    "fig01": Figure(Kind.SURFACES, captions.fig01),
    "fig02": Figure(Kind.SURFACES, captions.fig02),
    "fig03": Figure(Kind.SURFACES, captions.fig03, _fig03_surfaces, generated=True),
    "fig04": Figure(Kind.SURFACES, captions.fig04, _fig04_surfaces, generated=True),
    "fig05": Figure(Kind.SURFACES, captions.fig05, _fig04_surfaces, generated=True,
                    drawn_with=("fig04",)),
    "fig07": _contact(captions.fig07),
    "fig09": _contact(captions.fig09),
    "fig10": _contact(captions.fig10, _study_surfaces),
    "fig11": _contact(captions.fig11),
    "fig12": _contact(captions.fig12),
    "fig13": _contact(captions.fig13),
    "fig14": _contact(captions.fig14),
    "table_Eu": _contact(captions.table_eu),
    "hardness": _contact(captions.hardness),
    "measured": _contact(captions.measured, _unique_study_surfaces),
    "fig11_resolved": _contact(captions.fig11_resolved),
    "gaps": _contact(captions.gaps),
    "two_bodies": Figure(Kind.STUDIES, captions.two_bodies),
    "leakage": Figure(Kind.STUDIES, captions.leakage, needs=("flow",)),
    "conductance": Figure(Kind.STUDIES, captions.conductance, _listed_study_surfaces,
                          needs=("conductance",)),
    "cycles": Figure(Kind.STUDIES, captions.cycles, needs=("loading",),
                     files=layout.cycle_aggregates),
})
