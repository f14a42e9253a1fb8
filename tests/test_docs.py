"""The user documents hold together: every relative link and anchor in README.md and docs/*.md
resolves, the README stays a front door, no page (nor any other file of the tree) speaks of issue
numbers, every code block says where it runs (tests/test_doc_examples.py runs them), and the
package's code and docstrings fit in 100 columns."""
import os
import re
from pathlib import Path

import pytest

from doc_blocks import ROOT, all_blocks, commands, pages, prose

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
ISSUE = re.compile(r"\bissues? [0-9]+\b|\(issue [0-9]+", re.IGNORECASE)
README_MAX_LINES = 260
NOTES = {"run", "file", "slow", "not-run", ""}
LINE_MAX = 100
"""Columns a line of the package's Python files may take (its code and docstrings read in one
window, side by side with a diff)."""


def anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(page) -> set:
    seen, out = {}, set()
    for ln in prose(page).split("\n"):
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", ln)
        if m:
            a = anchor(m.group(1))
            n = seen.get(a, 0)
            seen[a] = n + 1
            out.add(a if n == 0 else f"{a}-{n}")
    return out


def links():
    for page in pages():
        for ln_no, ln in enumerate(prose(page).split("\n"), 1):
            for target in LINK.findall(ln):
                if not re.match(r"^[a-z]+:", target):       # http:, https:, mailto:
                    yield page, target


@pytest.mark.parametrize("heading, expected", [
    ("8. Follow Path on a Ground mesh (Blender)", "8-follow-path-on-a-ground-mesh-blender"),
    ("Crowds on the command line: `crowd`", "crowds-on-the-command-line-crowd"),
    ("The animator's guide", "the-animators-guide"),
])
def test_anchor_is_githubs(heading, expected):
    assert anchor(heading) == expected


def test_the_pages_are_there():
    names = {p.name for p in pages()}
    assert {"README.md", "getting-started.md", "animator-guide.md", "own-rigs.md", "TERRAIN.md",
            "crowds.md", "cli.md", "render-farms.md", "python-api.md", "physics.md"} <= names


def test_every_relative_link_and_anchor_resolves():
    bad, n = [], 0
    for page, target in links():
        n += 1
        path, _, frag = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            bad.append(f"{page.relative_to(ROOT)}: {target}: no such file")
        elif frag and dest.suffix == ".md" and frag not in anchors(dest):
            bad.append(f"{page.relative_to(ROOT)}: {target}: no heading with that anchor")
    assert n > 50, n                        # the walk sees the links
    assert not bad, "\n".join(bad)


def test_a_broken_link_is_seen(tmp_path):
    page = tmp_path / "p.md"
    page.write_text("# Top\n\nSee [here](#top) and [there](#nowhere).\n")
    assert anchors(page) == {"top"}


def test_the_readme_is_a_front_door():
    n = len((ROOT / "README.md").read_text(encoding="utf-8").split("\n"))
    assert n <= README_MAX_LINES, n


#: The text files of the repository besides the pages: notes, code (its comments, docstrings and
#: tooltips), tests, scripts, scenes, rigs and manifests.
TEXT = {".md", ".py", ".json", ".toml", ".sh", ".js", ".txt", ".cfg"}


def repository_text() -> list:
    """Every text file of the tree (not hidden folders, caches or build output)."""
    out = []
    for dirpath, dirs, files in os.walk(ROOT):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d not in
                         ("__pycache__", "out", "dist", "build") and not d.endswith(".egg-info"))
        out += [Path(dirpath) / f for f in sorted(files) if Path(f).suffix in TEXT]
    return out


def test_no_issue_numbers_in_the_documents():
    bad = [f"{p.relative_to(ROOT)}:{i}: {ln.strip()}"
           for p in pages() for i, ln in enumerate(p.read_text(encoding="utf-8").split("\n"), 1)
           if ISSUE.search(ln)]
    assert not bad, "\n".join(bad)


def test_no_issue_numbers_anywhere_else():
    """Nor in BENCHMARKS.md, TESTING.md, CONTRIBUTING.md, code comments, docstrings, tooltips,
    tests, scripts or scene descriptions: the repository says what is, not which issue asked."""
    files = [p for p in repository_text() if p not in pages()]
    names = {p.relative_to(ROOT).as_posix() for p in files}
    assert {"BENCHMARKS.md", "TESTING.md", "blender_turning/blender/props/figure.py",
            "scripts/mutate.py", "scenes/slalom.json", "tests/test_docs.py"} <= names
    bad = [f"{p.relative_to(ROOT)}:{i}: {ln.strip()}" for p in files
           for i, ln in enumerate(p.read_text(encoding="utf-8", errors="replace").split("\n"), 1)
           if ISSUE.search(ln)]
    assert not bad, "\n".join(bad)


def long_lines(root):
    """``path:line: columns`` of every line of the Python files under ``root`` longer than
    :data:`LINE_MAX`."""
    return [f"{p.relative_to(root)}:{i}: {len(ln)} columns" for p in sorted(root.rglob("*.py"))
            for i, ln in enumerate(p.read_text(encoding="utf-8").split("\n"), 1)
            if len(ln) > LINE_MAX]


def test_the_package_fits_in_100_columns():
    assert len(list((ROOT / "blender_turning").rglob("*.py"))) > 100     # every folder's files
    bad = long_lines(ROOT / "blender_turning")
    assert not bad, "\n".join(bad)


def test_a_long_line_is_seen(tmp_path):
    (tmp_path / "deep").mkdir()
    (tmp_path / "deep" / "wide.py").write_text(f"x = 1\n#{'-' * LINE_MAX}\n{'y' * LINE_MAX}\n")
    assert long_lines(tmp_path) == [f"deep/wide.py:2: {LINE_MAX + 1} columns"]


def test_every_block_says_where_it_runs():
    """A ``bash`` block without a note runs only ``python -m blender_turning`` commands; a block
    that does not run says why."""
    bad = []
    for b in all_blocks():
        if b.note not in NOTES or (b.note in ("not-run", "slow", "file", "run") and not b.arg):
            bad.append(f"{b.where}: note {b.note!r} {b.arg!r}")
        elif b.lang == "bash" and b.note in ("", "slow"):
            bad += [f"{b.where}: {c!r} is not a python -m blender_turning command: mark the "
                    "block <!-- not-run: why -->" for c in commands(b)
                    if not c.startswith("python -m blender_turning ")]
        elif b.note == "run" and b.arg not in ("blender", "scene", "crowd"):
            bad.append(f"{b.where}: run where? {b.arg!r}")
    assert not bad, "\n".join(bad)
