"""The documentation site builds with warnings as errors, and its internal links, anchors
and images resolve (``make docs-check`` runs the same checks on docs/_build/html).

The build takes about half a minute; it needs the ``docs`` extra (Sphinx), which
``make test`` installs, and is skipped without it.
"""

import re
import subprocess
import sys
from html.parser import HTMLParser

import pytest
import yaml
from docs_helpers import DOCS, ROOT, SCHEMA, description, docs_module, is_overlay, schema_properties

pytest.importorskip("sphinx")
pytest.importorskip("myst_parser")

check_links = docs_module("check_links.py")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built as ``make docs`` builds it (-W: a warning fails), into a temporary
    folder."""
    out = tmp_path_factory.mktemp("site")
    run = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(out / "doctrees"), str(DOCS), str(out / "html")],
        cwd=ROOT, capture_output=True, text=True)
    return run, out / "html"


def test_site_builds_without_warnings(site):
    run, html = site
    assert run.returncode == 0, run.stderr[-5000:]
    assert (html / "index.html").exists()


def test_no_broken_internal_links_or_images(site):
    _, html = site
    pages = list(html.rglob("*.html"))
    assert len(pages) > 30
    assert check_links.broken_references(html) == []


class _Text(HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.parts = []

    def handle_data(self, data):
        self.parts.append(data)


def test_configuration_reference_shows_every_description(site):
    """Every described key of the schema with its description, in the built page."""
    _, html = site
    parser = _Text()
    parser.feed((html / "reference" / "configuration.html").read_text(encoding="utf-8"))
    text = " ".join("".join(parser.parts).split())
    schema = yaml.safe_load(SCHEMA.read_text())
    wanted = {" ".join((description(schema, sub) or "").replace("`", "").split())
              for _, _, sub in schema_properties(schema) if not is_overlay(sub)} - {""}
    missing = [d for d in wanted if d not in text]
    assert len(wanted) > 90
    assert not missing, "\n".join(missing)
    for key in ("surfaces.grid", "contact.pressure_levels", "<study>.moments",
                "<measured_surface>.fill_holes", "<spectrum>.hurst"):
        assert re.search(re.escape(key), text), key


def test_link_checker_finds_broken_references(tmp_path):
    """The checker itself: a missing page, a missing anchor, a missing image and an
    unresolved cross-reference are reported; an external link, a good anchor and a
    resolved cross-reference are not."""
    (tmp_path / "a.html").write_text(
        '<p id="here"></p><a href="b.html">b</a><a href="a.html#here">ok</a>'
        '<a href="a.html#gone">x</a><img src="_images/fig.png">'
        '<a href="https://example.org/x.html">ext</a>'
        '<a href="a.html#here"><code class="xref py"><span>pkg.found</span></code></a>'
        '<code class="xref py py-func"><span>pkg.lost()</span></code>')
    problems = check_links.broken_references(tmp_path)
    assert len(problems) == 4
    assert any("unresolved cross-reference pkg.lost()" in p for p in problems)
    assert any("b.html: no such file" in p for p in problems)
    assert any("'gone'" in p for p in problems)
    assert any("fig.png" in p for p in problems)
