"""Check the built HTML site for broken internal links and missing files.

Usage: ``python docs/check_links.py docs/_build/html`` (``make docs-check``). Every
``href`` of an ``<a>`` or ``<link>`` and every ``src`` of an ``<img>`` or ``<script>``
that points into the site (no scheme such as ``https:`` or ``mailto:``) must name a
file that exists; a ``#fragment`` must be the ``id`` (or the ``name``) of an element
of that page. External links are not followed (no network). A cross-reference to
the API written in a page (``{func}`roughcontact...```) that Sphinx could not resolve
is left as code without a link: those are reported too, except in the generated API
pages, where the words of a parameter's type (``ndarray``) are such references by
design. Exit status 1 and one line per broken reference when any is found.
"""

from __future__ import annotations

import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

#: (tag, attribute) pairs that reference another file of the site.
REFERENCES = {("a", "href"), ("link", "href"), ("img", "src"), ("script", "src")}
#: Folders of generated pages whose unresolved type references are expected.
GENERATED = ("reference/_api/",)


class _Page(HTMLParser):
    """The ids and the references of one HTML page."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.ids: set[str] = set()
        self.references: list[tuple[str, str]] = []
        self.unresolved: list[str] = []
        self._open: list[str] = []  # tags from the nearest <a> or <code class="xref"> on
        self._xref: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "a":
            self._open.append("a")
        elif tag == "code" and "xref" in (attrs.get("class") or "").split():
            # an unresolved cross-reference: code.xref outside any link
            self._xref = [] if "a" not in self._open else None
            self._open.append("code")
        for key in ("id", "name"):
            if attrs.get(key):
                self.ids.add(attrs[key])
        for element, attribute in REFERENCES:
            if tag == element and attrs.get(attribute):
                self.references.append((tag, attrs[attribute]))

    def handle_endtag(self, tag):
        if tag in ("a", "code") and tag in self._open:
            while self._open and self._open.pop() != tag:
                pass
            if tag == "code" and self._xref is not None:
                self.unresolved.append("".join(self._xref))
                self._xref = None

    def handle_data(self, data):
        if self._xref is not None:
            self._xref.append(data)


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def broken_references(site: str | Path) -> list[str]:
    """``page: <tag> reference: why`` for every internal reference of ``site`` (the
    HTML output folder) that does not resolve; [] when all do."""
    site = Path(site).resolve()
    pages = {path: _parse(path) for path in sorted(site.rglob("*.html"))}
    if not pages:
        return [f"{site}: no HTML pages (build the site first: make docs)"]
    problems = []
    for path, page in pages.items():
        if not path.relative_to(site).as_posix().startswith(GENERATED):
            problems += [f"{path.relative_to(site)}: unresolved cross-reference {name}"
                         for name in page.unresolved]
        for tag, reference in page.references:
            parts = urlsplit(reference)
            if parts.scheme or parts.netloc:
                continue  # external: not followed
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            where = f"{path.relative_to(site)}: <{tag}> {reference}"
            if not target.is_relative_to(site):
                problems.append(f"{where}: points outside the site")
            elif target.is_dir():
                if not (target / "index.html").exists():
                    problems.append(f"{where}: folder without index.html")
            elif not target.exists():
                problems.append(f"{where}: no such file")
            elif parts.fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else _parse(target).ids
                if unquote(parts.fragment) not in ids:
                    problems.append(f"{where}: no element with id {parts.fragment!r}")
    return problems


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    site = Path(args[0] if args else "docs/_build/html")
    problems = broken_references(site)
    for line in problems:
        print(line)
    pages = len(list(site.rglob("*.html")))
    print(f"{pages} pages checked, {len(problems)} broken internal references")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
