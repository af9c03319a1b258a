"""The documents' links: every relative Markdown link in README.md and docs/ resolves to a file of the
repository, every `docs/...` path they name exists, and README's documentation list names exactly
the pages in docs/ and docs/studies/."""
import re
from pathlib import Path

import pytest

from conftest import REPO

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
# A repository path written out in the text, e.g. `docs/studies/validation.md` or
# docs/figures/quiescent/none_psi_pdf.png; templates such as docs/figures/<study>/ are not paths.
DOCS_PATH = re.compile(r"(?<![\w/.-])(docs/[\w./-]*\w\.(?:md|png|csv|tsv|nml))(?![\w<{*])")
README_ENTRY = re.compile(r"^- `(docs/[^`]+\.md)` — ", re.M)


def documents():
    return [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]


def broken_links(path, text):
    """The relative link targets of one Markdown text that name no file (anchors ignored)."""
    broken = []
    for target in LINK.findall(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue
        file_part = target.split("#", 1)[0]
        if not (path.parent / file_part).exists():
            broken.append(target)
    return broken


def missing_paths(text):
    """The docs/... paths named in a text that do not exist in the repository."""
    return [name for name in DOCS_PATH.findall(text) if not (REPO / name).exists()]


def test_checkers_catch_a_broken_link_and_a_missing_path():
    page = REPO / "docs" / "page.md"
    text = ("[fine](theory.md) [anchor](theory.md#fluid) [web](https://example.org) "
            "[gone](studies/no-such-page.md) ![figure](figures/no-such.png) docs/no-such.md")
    assert broken_links(page, text) == ["studies/no-such-page.md", "figures/no-such.png"]
    assert missing_paths(text) == ["docs/no-such.md"]


@pytest.mark.parametrize("path", documents(), ids=lambda p: str(p.relative_to(REPO)))
def test_relative_links_resolve(path):
    assert broken_links(path, path.read_text(encoding="utf-8")) == []


@pytest.mark.parametrize("path", documents(), ids=lambda p: str(p.relative_to(REPO)))
def test_named_docs_paths_exist(path):
    assert missing_paths(path.read_text(encoding="utf-8")) == []


def test_readme_lists_every_page():
    listed = README_ENTRY.findall((REPO / "README.md").read_text(encoding="utf-8"))
    pages = sorted(str(p.relative_to(REPO))
                   for p in [*(REPO / "docs").glob("*.md"), *(REPO / "docs" / "studies").glob("*.md")])
    assert sorted(listed) == pages
    assert len(listed) == len(set(listed))
