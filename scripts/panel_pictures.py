"""Pictures of the Turning sidebar, panel by panel, drawn from the panels' own draw code.

    .venv/bin/python scripts/panel_pictures.py --out docs/panels

Registers the add-on on the bpy wheel, builds a scene that gives each panel something to show
(a skier asked to lean more than it can, a baked skier with Live Preview on beside a second one, a snowboarder stopping on a
Ground mesh, a path with obstacles, a crowd, an armature that is not a figure yet), runs every
registered "Turning" panel's ``draw`` into the recording layout of ``scripts/panel_recorder.py``
(``poll`` honoured, sub-panels under their parents) and draws each as a PNG in the look of
Blender's dark sidebar (matplotlib).  Each PNG carries the text it shows (a PNG text chunk,
:data:`CONTENT_KEY`), so tests/test_blender_panel_pictures.py sees a picture that no longer
matches its panel.  Without matplotlib: one line, exit 2.
"""
from __future__ import annotations

import argparse
import math
import os
import re
import struct
import sys
import tempfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "scripts")]
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))

import bpy  # noqa: E402

import panel_recorder as rec  # noqa: E402

CATEGORY = "Turning"
CONTENT_KEY = "Panel content"
FRAMES = (1, 120)
"""The scene's frame range: the baked skier's bake (short, so the pictures take seconds)."""


def picture_name(cls) -> str:
    """``docs/panels/<name>.png`` of a panel: its label in lower case, words joined by '-'."""
    return re.sub(r"[^a-z0-9]+", "-", cls.bl_label.lower()).strip("-")


# -- the scene -------------------------------------------------------------------------------

def add_figure(sport: str, x: float, name: str):
    bpy.context.scene.cursor.location = (x, 0.0, 0.0)
    assert bpy.ops.turning.add_figure(sport=sport) == {"FINISHED"}
    fig = bpy.context.view_layer.objects.active
    fig.name = name
    return fig


def select(active, *others, collection=None, selected=True) -> None:
    """Make ``active`` the active object with ``others`` selected (and itself unless not
    ``selected``); ``collection`` active in the Outliner (else the scene's)."""
    view = bpy.context.view_layer
    for obj in view.objects:
        obj.select_set(False)
    for obj in (active, *others) if selected else others:
        obj.select_set(True)
    view.objects.active = active
    layer = view.layer_collection
    if collection is not None:
        layer = layer.children[collection.name]
    view.active_layer_collection = layer


def build_scene() -> dict:
    """Register the add-on in an empty scene and add what the panels show; ``{panel class name:
    how to select for it}`` (panels not named here show the skier; the selections named by a
    sentence draw every panel for the checks, and no picture)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    from blender_turning import blender as addon
    addon.register()
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = FRAMES
    skier = add_figure("SKIER", 0.0, "Skier")
    skier.turning.lean = math.radians(45)      # more than it can make at 10 m/s: Turns says so
    baked = add_figure("SKIER", 4.0, "Baked Skier")
    other = add_figure("SKIER", 8.0, "Second Skier")
    select(baked)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    baked.turning.live = True
    bpy.ops.mesh.primitive_plane_add(size=200.0, location=(0.0, 0.0, -1.0))
    slope = bpy.context.view_layer.objects.active
    slope.name = "Slope"
    bpy.ops.curve.primitive_bezier_curve_add(location=(0.0, 20.0, 0.0))
    course = bpy.context.view_layer.objects.active
    course.name = "Course"
    gates = bpy.data.collections.new("Gates")
    scene.collection.children.link(gates)
    skier.turning.path, skier.turning.obstacles = course, gates
    skier.turning.ground = slope
    boarder = add_figure("SNOWBOARDER", 12.0, "Snowboarder")
    s = boarder.turning
    s.ground, s.terrain.target_speed = slope, 8.0
    s.skid.style, s.skid.use_stop, s.skid.stop_frame = "SKID", True, 100
    leader = add_figure("SKIER", 16.0, "Leader")
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=3) == {"FINISHED"}
    crowd = bpy.context.view_layer.objects.active.users_collection[0]
    for fig in crowd.all_objects:                 # a course each: Crowd lists the planning order
        if fig.type == "ARMATURE":
            fig.turning.path = course
    rig = bpy.data.objects.new("My Rig", bpy.data.armatures.new("My Rig"))
    scene.collection.objects.link(rig)
    select(rig)
    assert bpy.ops.turning.custom_map_from(source="RIGIFY") == {"FINISHED"}
    own = bpy.data.objects.new("Own Rig", skier.data.copy())   # an own rig, made a figure
    scene.collection.objects.link(own)
    select(own)
    assert bpy.ops.turning.make_figure(sport="SNOWBOARDER", bone_map="BUILTIN") == {"FINISHED"}
    return {
        "VIEW3D_PT_turning_bake": lambda: select(baked, other),
        "VIEW3D_PT_turning_speed": lambda: select(boarder),
        "VIEW3D_PT_turning_stance": lambda: select(boarder),
        "VIEW3D_PT_turning_your_rig": lambda: select(rig),
        "VIEW3D_PT_turning_crowd": lambda: select(leader, collection=crowd, selected=False),
        None: lambda: select(skier),
        "an own rig's figure (drawn, not pictured)": lambda: select(own),
        "nothing selected (drawn, not pictured)": lambda: select(None, selected=False),
    }


def draw_every_panel(problems: list) -> dict:
    """``{panel class: the DrawnPanel its picture shows}``: each registered panel of the
    category drawn in the selection made for it, and every panel drawn in every selection
    (problems of any go to ``problems``)."""
    stages = build_scene()
    shown = {}
    for name, stage in stages.items():
        stage()
        for drawn in rec.walk(rec.draw_panels(CATEGORY, bpy.context, problems)):
            key = drawn.cls.__name__
            if key == name or (key not in stages and name is None):
                shown[drawn.cls] = drawn
    problems[:] = dict.fromkeys(problems)         # each once, not once per selection
    return shown


# -- lines: what a panel shows, row by row ---------------------------------------------------

@dataclass
class Line:
    label: str = ""                 # the split's left column
    items: list = field(default_factory=list)      # (Item, active)
    box: int = 0                    # how many boxes it sits in
    kind: str = "items"             # items, gap, box-start, box-end


def lines(layout, active=True, box=0) -> list:
    """The rows a layout shows, top to bottom (a column's children one under another, a row's
    side by side; a boolean array (a vector) one row per component)."""
    active = active and layout.flags["active"] and layout.flags["enabled"]
    out = []
    for child in layout.children:
        if isinstance(child, rec.Layout) and child.kind in ("row", "split"):
            row = Line(box=box, items=flat_items(child, active))
            if child.flags["use_property_split"]:
                row.label = child.args.get("heading", "") or next(
                    (it.label for it, _ in row.items if it.label), "")
            out.append(row)
        elif isinstance(child, rec.Layout):
            inner = box + (child.kind == "box")
            body = lines(child, active, inner)
            out += [Line(box=inner, kind="box-start"), *body, Line(box=inner, kind="box-end")] \
                if child.kind == "box" else body
        elif child.widget == "separator":
            out.append(Line(box=box, kind="gap"))
        elif child.widget == "vector":
            for axis, value in zip("XYZW", child.value.split("\t")):
                part = rec.Item("prop", value=value, widget="number",
                                animatable=child.animatable)
                out.append(Line(f"{child.label} {axis}" if axis == "X" else axis,
                                [(part, active)], box))
        else:
            out.append(Line(child.label, [(child, active)], box))
    return out


def flat_items(layout, active) -> list:
    active = active and layout.flags["active"] and layout.flags["enabled"]
    out = []
    for child in layout.children:
        out += (flat_items(child, active) if isinstance(child, rec.Layout)
                else [(child, active)])
    return out


def describe(drawn) -> str:
    """The text a panel's picture shows, one row a line ('~' marks a greyed-out item)."""
    out = [f"[{drawn.cls.bl_label}]"]
    for ln in lines(drawn.header) + lines(drawn.body):
        if ln.kind != "items":
            out.append(f"({ln.kind})")
            continue
        parts = []
        for it, active in ln.items:
            text = " ".join(t for t in (it.icon if it.icon != "NONE" else "", it.text, it.value)
                            if t)
            parts.append(("~" if not active else "") + (f"!{text}" if it.alert else text))
            parts += [f"  {row}" for row in list_rows(it)]
        out.append(f"{ln.label}: " + " | ".join(parts) if ln.label else " | ".join(parts))
    out += [f"[> {c.cls.bl_label}]" for c in drawn.children]
    return "\n".join(out)


def list_rows(item) -> list:
    return [" / ".join(it.text or it.value for it, _ in flat_items(row, True))
            for row in item.rows]


def png_text(path) -> dict:
    """The text chunks of a PNG file (tEXt, zTXt, iTXt), ``{key: text}``."""
    data, pos, out = Path(path).read_bytes(), 8, {}
    while pos + 8 <= len(data):
        size, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk, pos = data[pos + 8:pos + 8 + size], pos + 12 + size
        key, _, rest = chunk.partition(b"\0")
        if kind == b"tEXt":
            out[key.decode("latin-1")] = rest.decode("latin-1")
        elif kind == b"zTXt":
            out[key.decode("latin-1")] = zlib.decompress(rest[1:]).decode("latin-1")
        elif kind == b"iTXt":
            text = rest[2:].split(b"\0", 2)[2]
            out[key.decode("latin-1")] = (zlib.decompress(text) if rest[0] else text).decode()
    return out


# -- the picture -----------------------------------------------------------------------------

WIDTH, ROW, GAP, PAD = 320, 20, 4, 10          # px: Blender's UI unit is 20 px at scale 1
SPLIT = 0.4                                     # the left column of use_property_split
DECORATOR = 18
COLOURS = {"region": "#282828", "header": "#3d3d3d", "body": "#333333", "text": "#e6e6e6",
           "number": "#545454", "button": "#545454", "dropdown": "#282828", "field": "#1d1d1d",
           "selected": "#4772b3", "box": "#2b2b2b", "outline": "#1c1c1c", "alert": "#b33a3a",
           "alert_text": "#ff7070", "dim": "#8a8a8a"}
#: Blender icons as a glyph of the DejaVu font (an icon not listed is drawn as a small square).
GLYPHS = {"ADD": "+", "REMOVE": "\u2212", "X": "\u2715", "PLAY": "\u25b6", "PAUSE": "\u275a\u275a",
          "INFO": "\u2139", "ERROR": "\u26a0", "TIME": "\u25f7", "REC": "\u25cf",
          "TRASH": "\u2715", "PREVIEW_RANGE": "\u2194", "PRESET": "\u2630", "FILE_TICK": "\u2713",
          "GROUP": "\u229e", "COMMUNITY": "\u229e", "SORTSIZE": "\u2261",
          "CURVE_PATH": "\u223f", "ARMATURE_DATA": "\u2659", "BONE_DATA": "\u2659",
          "OUTLINER_COLLECTION": "\u25a3", "GREASEPENCIL": "\u270e", "NLA": "\u2261",
          "ACTION": "\u25c6"}


def line_height(ln) -> int:
    if ln.kind == "items":
        rows = max((int(it.value or 5) for it, _ in ln.items if it.widget == "list"), default=0)
        return (ROW + GAP) * (rows + 1) if rows else ROW + GAP
    return {"gap": 8, "box-start": 4, "box-end": 6}[ln.kind]


class Canvas:
    """Pixel coordinates on a matplotlib figure (y down)."""

    def __init__(self, height: int, scale: float):
        from matplotlib.figure import Figure
        self.fig = Figure(figsize=(WIDTH / 100, height / 100), dpi=100 * scale)
        self.ax = self.fig.add_axes((0, 0, 1, 1))
        self.ax.set_xlim(0, WIDTH)
        self.ax.set_ylim(height, 0)
        self.ax.axis("off")
        self.fig.patch.set_facecolor(COLOURS["region"])

    def rect(self, x, y, w, h, colour, radius=3.0, edge=None, dashed=False):
        from matplotlib.patches import FancyBboxPatch
        self.ax.add_patch(FancyBboxPatch(
            (x + radius, y + radius), max(w - 2 * radius, 0.1), max(h - 2 * radius, 0.1),
            boxstyle=f"round,pad={radius}", fc=colour, ec=edge or "none", lw=0.8,
            ls="--" if dashed else "-"))

    def text(self, x, y, s, colour=None, ha="left", size=7.2, weight="normal", width=None):
        """Text at (x, y); wider than ``width`` px it ends in an ellipsis, as Blender clips."""
        if width is not None:
            s = fit(s, width, size)
        self.ax.text(x, y, s, color=colour or COLOURS["text"], ha=ha, va="center",
                     fontsize=size, fontweight=weight, family="DejaVu Sans", clip_on=True)


def fit(text: str, width: float, size: float) -> str:
    """``text`` cut to ``width`` px (the font at ``size`` pt, 100 px an inch) with an ellipsis."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextPath
    font = FontProperties(family="DejaVu Sans")

    def wide(t):
        return TextPath((0, 0), t, size=size * 100 / 72, prop=font).get_extents().width

    cut = text
    while cut and wide(cut if cut == text else cut + "\u2026") > width:
        cut = cut[:-1]
    return cut if cut == text else cut.rstrip() + "\u2026"


def icon(c, x, y, name, colour):
    """Draw icon ``name`` centred at (x, y); its width."""
    if name == "NONE":
        return 0
    glyph = GLYPHS.get(name)
    if glyph is None:
        c.rect(x - 4, y - 4, 8, 8, "none", radius=1.5, edge=colour)
    else:
        c.text(x, y, glyph, colour, ha="center", size=7.5)
    return 14


def widget(c, it, x, y, w, active):
    """One item in the box (x, y, w, ROW)."""
    ink = COLOURS["text"] if active else COLOURS["dim"]
    if it.alert:
        ink = COLOURS["alert_text"]
    mid = y + ROW / 2
    kind = it.widget
    if kind == "label":
        dx = icon(c, x + 7, mid, it.icon, ink)
        c.text(x + 2 + dx, mid, it.text, ink, width=w - 4 - dx)
    elif kind == "check":
        on = it.value == "on"
        c.rect(x + 2, mid - 6, 12, 12, COLOURS["selected"] if on else COLOURS["number"], 2)
        if on:
            c.text(x + 8, mid, "\u2713", "white" if active else COLOURS["dim"], "center", 7)
        c.text(x + 19, mid, it.text, ink, width=w - 21)
    elif kind in ("number", "button", "toggle"):
        on = kind == "toggle" and it.value == "on"
        fill = COLOURS["alert"] if it.alert else COLOURS["selected" if on else kind
                                                           if kind != "toggle" else "button"]
        c.rect(x, y, w, ROW, fill)
        if kind == "number" and it.text:
            c.text(x + 6, mid, it.text, ink, width=w / 2)
            c.text(x + w - 6, mid, it.value, ink, "right")
            return
        label = it.value if kind == "number" else it.text
        glyph = GLYPHS.get(it.icon, "")
        if it.icon != "NONE" and not glyph:
            icon(c, x + 10, mid, it.icon, ink)
        c.text(x + w / 2, mid, "  ".join(t for t in (glyph, label) if t), ink, "center",
               width=w - 8)
    elif kind in ("enum", "dropdown", "field", "search"):
        fill = COLOURS["dropdown"] if kind in ("enum", "dropdown") else COLOURS["field"]
        c.rect(x, y, w, ROW, COLOURS["alert"] if it.alert else fill, edge=COLOURS["outline"])
        dx = icon(c, x + 9, mid, it.icon, ink)
        shown = it.value if kind in ("enum", "field", "search") else it.text
        if kind in ("field", "search") and it.text:
            shown = f"{it.text}: {shown}"
        c.text(x + 5 + dx, mid, shown, ink, width=w - 10 - dx - 12 * (kind in ("enum", "dropdown")))
        if kind in ("enum", "dropdown"):
            c.text(x + w - 8, mid - 1, "\u2304", ink, "center")
    elif kind == "missing":
        c.text(x + 2, mid, it.text, COLOURS["alert_text"])
    else:                                       # a layout function the pictures do not draw
        c.rect(x, y, w, ROW, "none", edge=COLOURS["dim"], dashed=True)
        c.text(x + w / 2, mid, it.text, COLOURS["dim"], "center")


def draw_line(c, ln, y):
    x0 = PAD + 6 * ln.box
    width = WIDTH - 2 * PAD - 12 * ln.box
    split = ln.label or any(it.split for it, _ in ln.items)
    deco = any(it.animatable for it, _ in ln.items)
    if split or deco:
        width -= DECORATOR
    if deco:                                    # the keyframe dot of an animatable setting
        from matplotlib.patches import Circle
        c.ax.add_patch(Circle(
            (WIDTH - PAD - 12 * ln.box - DECORATOR / 2, y + ROW / 2), 2.2,
            fc="none", ec=COLOURS["dim"], lw=0.8))
    if split:
        left = width * SPLIT
        active = any(a for _, a in ln.items)
        c.text(x0 + left - 6, y + ROW / 2, ln.label,
               COLOURS["text"] if active else COLOURS["dim"], "right", width=left - 8)
        x0, width = x0 + left, width - left
    narrow = [it.widget in ("button", "dropdown", "toggle", "check") and not it.text
              for it, _ in ln.items]
    fixed = 24 * sum(narrow)
    free = (width - fixed - 1 * (len(ln.items) - 1)) / max(len(ln.items) - sum(narrow), 1)
    x = x0
    for (it, active), small in zip(ln.items, narrow):
        w = 24 if small else free
        if it.widget == "list":
            draw_list(c, it, x, y, w)
        else:
            widget(c, it, x, y, w, active)
        x += w + 1


def draw_list(c, it, x, y, w):
    rows = int(it.value or 5)
    c.rect(x, y, w, rows * (ROW + GAP) + GAP, COLOURS["box"], edge=COLOURS["outline"])
    for i, row in enumerate(it.rows[:rows]):
        ln = Line(items=flat_items(row, True))
        yy = y + GAP + i * (ROW + GAP)
        xx, ww = x + 4, (w - 8) / max(len(ln.items), 1)
        for item, active in ln.items:
            widget(c, item, xx, yy, ww - 2, active)
            xx += ww


def render(drawn, path: Path, scale: float = 1.5) -> None:
    """The panel as Blender's sidebar shows it, open, with its sub-panels closed below."""
    body = lines(drawn.body)
    header_h = ROW + 6
    height = int(PAD + header_h + 6 + sum(line_height(ln) for ln in body) + 6
                 + (header_h + 2) * len(drawn.children) + PAD)
    c = Canvas(height, scale)
    c.rect(PAD / 2, PAD / 2, WIDTH - PAD, height - PAD, COLOURS["body"], 4)
    c.rect(PAD / 2, PAD / 2, WIDTH - PAD, header_h, COLOURS["header"], 4)
    c.text(PAD + 4, PAD / 2 + header_h / 2, "\u25be", size=8)
    head = [it.text for ln in lines(drawn.header) for it, _ in ln.items if it.text]
    c.text(PAD + 16, PAD / 2 + header_h / 2, " ".join([drawn.cls.bl_label, *head]),
           weight="bold", size=7.6)
    y = PAD / 2 + header_h + 6
    open_boxes = []
    for ln in body:
        if ln.kind == "box-start":
            open_boxes.append(y)
        elif ln.kind == "box-end":
            top = open_boxes.pop()
            x = PAD + 6 * (ln.box - 1) - 2
            c.rect(x, top, WIDTH - 2 * x, y - top + 2, "none", edge=COLOURS["outline"])
        elif ln.kind == "items":
            draw_line(c, ln, y)
        y += line_height(ln)
    y += 4
    for child in drawn.children:
        c.rect(PAD, y, WIDTH - 2 * PAD, header_h, COLOURS["header"], 3)
        c.text(PAD + 6, y + header_h / 2, "\u25b8", size=8)
        c.text(PAD + 18, y + header_h / 2, child.cls.bl_label, size=7.4)
        y += header_h + 2
    c.fig.savefig(path, facecolor=COLOURS["region"], metadata={CONTENT_KEY: describe(drawn)},
                  pil_kwargs={"optimize": True})


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "panels",
                    help="folder for <panel>.png (default docs/panels)")
    args = ap.parse_args(argv)
    try:
        import matplotlib
        matplotlib.use("Agg")
    except ImportError:
        print("panel_pictures: matplotlib is needed (pip install blender-turning[plots])")
        return 2
    problems = []
    shown = draw_every_panel(problems)
    args.out.mkdir(parents=True, exist_ok=True)
    for cls, drawn in shown.items():
        path = args.out / f"{picture_name(cls)}.png"
        render(drawn, path)
        print(f"panel_pictures: {path} ({path.stat().st_size // 1024} kB)")
    for p in problems:
        print(f"panel_pictures: {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
