"""The user documents (README.md and docs/*.md) and their fenced code blocks.

A block's language is its fence's word (```bash, ```python, ```json, ...). An HTML comment on
the line before the fence says where it runs, when that is not the default:

- ``<!-- run: blender -->``: a Python block for Blender's Python console (or a script in it);
- ``<!-- run: scene -->`` / ``<!-- run: crowd -->``: a JSON block that is a scene or a crowd file;
- ``<!-- file: NAME -->``: a file the page's commands read, written as NAME before they run;
- ``<!-- slow: reason -->``: runs, but only with the ``slow`` tests;
- ``<!-- not-run: reason -->``: not meant to run here (the reason says why).

Without a comment, ``bash`` blocks run their ``python -m blender_turning`` commands and
``python`` blocks run in plain Python.
"""
from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FENCE = re.compile(r"^```(\S*)\s*$")
NOTE = re.compile(r"^<!--\s*([a-z-]+):?\s*(.*?)\s*-->\s*$")


def pages() -> list:
    """README.md and every page of docs/, as paths."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@dataclass(frozen=True)
class Block:
    page: Path
    line: int          # the fence's line, 1-based
    lang: str
    text: str
    note: str = ""     # "run", "file", "slow", "not-run" or ""
    arg: str = ""      # what follows the note

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: Path) -> list:
    """Every fenced block of ``page``, with the note on the line before its fence."""
    lines = page.read_text(encoding="utf-8").split("\n")
    out, i = [], 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        start = i
        j = i + 1
        while j < len(lines) and lines[j].rstrip() != "```":
            j += 1
        if j == len(lines):
            raise AssertionError(f"{page}:{start + 1}: a fence that is never closed")
        note = NOTE.match(lines[start - 1]) if start else None
        out.append(Block(page, start + 1, m.group(1), "\n".join(lines[start + 1:j]) + "\n",
                         *(note.groups() if note else ("", ""))))
        i = j + 1
    return out


def all_blocks() -> list:
    return [b for p in pages() for b in blocks(p)]


def prose(page: Path) -> str:
    """The page without its fenced blocks (links and anchors are read from this)."""
    text = page.read_text(encoding="utf-8").split("\n")
    keep, inside = [], False
    for ln in text:
        if FENCE.match(ln) or (inside and ln.rstrip() == "```"):
            inside = not inside
            continue
        if not inside:
            keep.append(ln)
    return "\n".join(keep)


def commands(block: Block) -> list:
    """The shell commands of a ``bash`` block: continuation lines joined, comments dropped."""
    out, cur = [], ""
    for ln in block.text.split("\n"):
        ln = re.sub(r"(^|\s)#.*$", "", ln).rstrip()
        if ln.endswith("\\"):
            cur += ln[:-1] + " "
            continue
        cur += ln
        if cur.strip():
            out.append(cur.strip())
        cur = ""
    return out


class _Checked(ast.NodeTransformer):
    """Every statement that is a ``bpy.ops`` call becomes ``__finished__(call, "text")``."""

    def visit_Expr(self, node):
        call = node.value
        if isinstance(call, ast.Call) and ast.unparse(call.func).startswith("bpy.ops."):
            node.value = ast.Call(ast.Name("__finished__", ast.Load()),
                                  [call, ast.Constant(ast.unparse(call))], [])
        return node


def checked_ops(source: str) -> ast.Module:
    """``source`` with every statement that calls an operator checked by ``__finished__``
    (an operator that cancels, e.g. a poll that fails or a setting reported bad, does not
    always raise)."""
    return ast.fix_missing_locations(_Checked().visit(ast.parse(source)))
