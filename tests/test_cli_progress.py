"""The progress bar of the long commands: drawn on stderr when it is a terminal,
nothing in a pipeline, and the results the same either way."""
import io
import json
import re
import sys

import pytest

from blender_turning.cli import main
from blender_turning.cli.progress import Progress


class Terminal(io.StringIO):
    """A stderr that says it is a terminal."""

    def isatty(self):
        return True


def scene(tmp_path, **extra):
    doc = {"name": "short road", "figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}},
           "path": {"polyline": [[0, 0], [25, 0]]}, "clearance": 0.3,
           "obstacles": [{"type": "circle", "center": [14, 1.6], "radius": 0.4}],
           "planner": {"stages": 4, "choices": 3}, **extra}
    p = tmp_path / "scene.json"
    p.write_text(json.dumps(doc))
    return p


def follow(tmp_path, monkeypatch, stderr, name, tqdm=False, **extra):
    out = tmp_path / name
    monkeypatch.setattr("sys.stderr", stderr)
    if not tqdm:                                      # the plain counter (without the extra)
        monkeypatch.setitem(sys.modules, "tqdm", None)
    assert main(["follow", str(scene(tmp_path, **extra)), "--out", str(out)]) == 0
    monkeypatch.undo()
    return out.read_text()


def lines(text):
    """The bar's successive states: (percent, course s planned)."""
    return [(int(p), float(t)) for p, t in
            re.findall(r"\rfollow: (\d+)%, ([\d.]+) s of course planned, \d+ s, ", text)]


def test_follow_draws_path_share_and_course_time_on_a_terminal(tmp_path, monkeypatch):
    term = Terminal()
    csv_tty = follow(tmp_path, monkeypatch, term, "tty.csv")
    states = lines(term.getvalue())
    assert len(states) > 5                            # one per replanning, and the end
    pct, t = zip(*states)
    assert list(pct) == sorted(pct) and pct[0] == 0 and pct[-1] == 100 and 0 < pct[-2] < 100
    assert list(t) == sorted(t) and t[0] == 0.0 and t[-1] > 2.0
    assert "about" in term.getvalue() and term.getvalue().endswith("\n")
    # A pipeline gets nothing, and the plan is the same.
    pipe = io.StringIO()
    csv_pipe = follow(tmp_path, monkeypatch, pipe, "pipe.csv")
    assert pipe.getvalue() == "" and csv_pipe == csv_tty


def test_follow_with_a_duration_counts_its_share_of_the_duration(tmp_path, monkeypatch):
    term = Terminal()
    follow(tmp_path, monkeypatch, term, "d.csv", duration=2.0)
    states = lines(term.getvalue())
    # Before each replanning: t / duration (t printed to 0.1 s: the percent to within 2).
    assert len(states) > 3
    assert all(abs(p - 100 * t / 2.0) <= 2.5 for p, t in states[:-1]), states
    assert states[-1][0] == 100


def test_follow_bar_drawn_by_tqdm_when_installed(tmp_path, monkeypatch):
    pytest.importorskip("tqdm")
    term = Terminal()
    follow(tmp_path, monkeypatch, term, "q.csv", tqdm=True)
    text = term.getvalue()
    assert re.search(r"\rfollow: +100%\|.*100/100 .*s of course planned\]\n$", text), text[-200:]


def test_progress_writer_counts_and_stays_quiet_off_a_terminal(monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    term = Terminal()
    with Progress(4, "figure", "crowd", stream=term) as bar:
        bar.update(1)
        bar.update(3, note="x")
    text = term.getvalue()
    assert re.search(r"\rcrowd: 1/4 figures, \d+ s, about \d+ s left", text)
    assert "\rcrowd: 3/4 figures, x, " in text and text.endswith("\n")
    quiet = io.StringIO()
    with Progress(4, "figure", "crowd", stream=quiet) as bar:
        bar.update(2, note="x")
    assert quiet.getvalue() == ""
