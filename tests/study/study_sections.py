"""A test's configuration: its base with some sections changed, and the plan of one."""

import copy

from roughcontact.study.config import validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.settings import Study


def with_sections(base: dict, **sections) -> dict:
    """A copy of the configuration ``base`` with each of ``sections`` updated by its
    values (None: the section removed)."""
    raw = copy.deepcopy(base)
    for section, values in sections.items():
        if values is None:
            raw.pop(section, None)
        else:
            raw.setdefault(section, {}).update(values)
    return raw


def planned(raw: dict):
    """The plan of the configuration ``raw`` (validated, defaults filled in; ``raw``
    itself unchanged)."""
    return study_plan(Study.from_config(validated(copy.deepcopy(raw))))
