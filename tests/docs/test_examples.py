"""Every code example of the documentation runs (``make test`` collects them here).

Each page's ```python blocks run in order in one namespace, in a temporary working
directory, as a reader would paste them one after the other; a page's examples
fail here as soon as a name they use is renamed or removed. Every ```yaml block is
a configuration (or part of one) and is validated against config/schema.yaml.
Shell commands (```sh) run the workflow for minutes and are not run here: the
workflow tests run the same targets on config/quick.yaml.
"""

import re

import pytest
import yaml
from docs_helpers import DOCS, ROOT

from roughcontact.study.config import schema_errors

PAGES = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts) + [ROOT / "README.md"]
_FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>\w+)[^\n]*\n(?P<body>.*?)^(?P=indent)```",
                    re.DOTALL | re.MULTILINE)


def blocks(page, language):
    """(line number, code) of every fenced block of ``language`` on ``page``, dedented."""
    text = page.read_text(encoding="utf-8")
    out = []
    for match in _FENCE.finditer(text):
        if match["lang"] != language:
            continue
        indent = len(match["indent"])
        code = "\n".join(line[indent:] for line in match["body"].splitlines())
        out.append((text.count("\n", 0, match.start()) + 1, code))
    return out


def _name(page):
    return str(page.relative_to(ROOT))


PYTHON_PAGES = [p for p in PAGES if blocks(p, "python")]
YAML_BLOCKS = [(p, line, code) for p in PAGES for line, code in blocks(p, "yaml")]


def test_the_docs_have_examples():
    assert len(PYTHON_PAGES) >= 3 and len(YAML_BLOCKS) >= 5


@pytest.mark.parametrize("page", PYTHON_PAGES, ids=_name)
def test_python_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__docs__"}
    for line, code in blocks(page, "python"):
        try:
            exec(compile(code, f"{_name(page)}:{line}", "exec"), namespace)
        except Exception as error:
            pytest.fail(f"{_name(page)}, example at line {line}: "
                        f"{type(error).__name__}: {error}")


@pytest.mark.parametrize(("page", "line", "code"), YAML_BLOCKS,
                         ids=[f"{_name(p)}:{line}" for p, line, _ in YAML_BLOCKS])
def test_yaml_examples_are_valid_configurations(page, line, code):
    config = yaml.safe_load(code)
    assert isinstance(config, dict), f"{_name(page)}:{line} is not a mapping"
    assert schema_errors(config) == [], f"{_name(page)}:{line}"
