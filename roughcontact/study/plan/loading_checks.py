"""Plan-time checks of the ``loading`` section: a loading path needs capped cells.

The permanent set of :mod:`roughcontact.contact.cycles` is the cap's: an elastic cell
unloads along its loading curve, so its loop has no area and nothing is learnt from
it. A configuration that turns the loading path on without a capped cell is refused,
naming the keys that cap its cells; a figure of the loops that lists a study with no
capped cell likewise.
"""

from __future__ import annotations

from collections.abc import Mapping

from roughcontact.study.settings import Study

__all__ = ["check_loading", "cycle_studies"]


def cycle_studies(study: Study, cells: Mapping[str, tuple]) -> tuple[str, ...]:
    """The studies among ``cells`` (study name -> its study cells) with a cell swept
    along the loading path (none with the section off), in their order."""
    return tuple(name for name, study_cells in cells.items()
                 if any(study.loading.applies(cell) for cell in study_cells))


def check_loading(study: Study, cells: Mapping[str, tuple], listing: Mapping) -> list[str]:
    """The problems of a configuration whose ``loading`` is on: no capped cell at all,
    or a figure of the loops (``listing``: figure name -> the studies it lists) listing
    a study without one."""
    if not study.loading.enabled:
        return []
    swept = set(cycle_studies(study, cells))
    advice = ("cap its cells: contact.cap: true (or both, beside the elastic ones) with "
              "body.hardness_MPa: [<H in MPa>] (or the study's own hardness_MPa)")
    if not swept:
        return [f"loading.enabled: true, but no cell of the config is capped, and the "
                f"loading path keeps the permanent set of the pressure cap (an elastic "
                f"cell unloads along its loading curve); {advice}, or set "
                f"loading.enabled: false"]
    return [f"figures.{figure}.studies: {listed!r} has no capped cell, so no loop to draw; "
            f"{advice}, or remove it from the list"
            for figure, studies in listing.items() for listed in studies
            if study.source_name(listed) not in swept and listed not in swept]
