"""Draw the add-on's sidebar panels without a window: a recording stand-in for ``UILayout``.

The bpy wheel has no window manager, so no ``UILayout`` exists to draw into.  :class:`Layout`
takes its place: each call a panel's ``draw`` makes (``row``, ``prop``, ``operator`` ...) is
checked against ``UILayout``'s own RNA description (the function exists, its keywords and
required arguments, the icon is one of Blender's) and recorded with what Blender would show:
the property's name and current value read through the RNA, the operator's label, the menu's.
What Blender would refuse or draw as an error (a property the data has not, an operator or menu
that is not registered, an operator property that does not exist) goes to :attr:`Layout.problems`.

:func:`draw_panels` walks the registered panels of a sidebar category as Blender does: ``poll``
honoured, sub-panels under their parents, ``draw_header`` where present.  Used by
``scripts/panel_pictures.py`` (the pictures of docs/animator-guide.md) and its test.
"""
from __future__ import annotations

import types
from dataclasses import dataclass, field

import bpy

FUNCTIONS = bpy.types.UILayout.bl_rna.functions
FLAGS = ("active", "enabled", "alert", "use_property_split", "use_property_decorate",
         "alignment", "scale_x", "scale_y", "ui_units_x", "ui_units_y", "emboss",
         "operator_context", "active_default", "activate_init")
"""``UILayout``'s settable attributes (its RNA properties)."""
ICONS = frozenset(FUNCTIONS["label"].parameters["icon"].enum_items.keys())


@dataclass
class Item:
    """One button or label as Blender would show it."""

    kind: str                   # prop, operator, menu, label, separator, list, or the function
    text: str = ""              # the text on the button (or beside a checkbox)
    label: str = ""             # the split's left label (``use_property_split``)
    value: str = ""             # a field's value as shown
    widget: str = "label"       # number, check, toggle, enum, field, button, dropdown, label ...
    icon: str = "NONE"
    alert: bool = False
    split: bool = False         # drawn in the right column of ``use_property_split``
    animatable: bool = False    # a keyframe dot beside it (``use_property_decorate``)
    rows: list = field(default_factory=list)   # a list's rows, each a Layout


class Layout:
    """Records what a ``draw`` function puts into a ``UILayout``."""

    def __init__(self, kind="column", parent=None, problems=None, where="", **kw):
        d = self.__dict__
        d["kind"], d["children"], d["args"] = kind, [], kw
        d["problems"] = problems if problems is not None else []
        d["where"] = where
        inherit = ("alert", "use_property_split", "use_property_decorate")
        d["flags"] = {"active": True, "enabled": True, "alert": False,
                      "use_property_split": False, "use_property_decorate": False}
        if parent is not None:
            d["flags"].update({k: parent.flags[k] for k in inherit})

    def __setattr__(self, name, value):
        if name not in FLAGS:
            raise AttributeError(f"UILayout has no attribute {name!r}")
        self.flags[name] = value

    def __getattr__(self, name):
        if name in FLAGS:
            return self.flags.get(name)
        if name not in FUNCTIONS:
            raise AttributeError(f"UILayout has no function {name!r}")
        return types.MethodType(lambda self, *a, **kw: self._call(name, a, kw), self)

    # -- the calls ---------------------------------------------------------------------------

    def _problem(self, text: str) -> None:
        self.problems.append(f"{self.where}: {text}")

    def _arguments(self, name: str, args, kw) -> dict | None:
        """The call's arguments by name, checked as Blender checks them (``TypeError``)."""
        params = [p for p in FUNCTIONS[name].parameters if not p.is_output]
        if len(args) > len(params):
            raise TypeError(f"UILayout.{name}() takes at most {len(params)} arguments")
        given = dict(zip((p.identifier for p in params), args))
        for key, val in kw.items():
            if key not in {p.identifier for p in params} or key in given:
                raise TypeError(f"UILayout.{name}(): unexpected keyword {key!r}")
            given[key] = val
        missing = [p.identifier for p in params if p.is_required and p.identifier not in given]
        if missing:
            raise TypeError(f"UILayout.{name}(): missing {missing}")
        if given.get("icon", "NONE") not in ICONS:
            raise TypeError(f"UILayout.{name}(): icon {given['icon']!r} is not one of Blender's")
        return given

    def _call(self, name, args, kw):
        a = self._arguments(name, args, kw)
        if name in ("row", "column", "box", "split", "column_flow", "grid_flow"):
            sub = Layout(name, self, self.problems, self.where, **a)
            self.children.append(sub)
            return sub
        handler = getattr(self, f"_{name}", None)
        if handler is None:             # a function the pictures do not draw: shown as its name
            item = Item(name, text=name, widget="placeholder")
            out = None
        else:
            item, out = handler(a)
        if item is not None:
            item.alert = self.flags["alert"]
            self.children.append(item)
        return out

    def _split_label(self, text: str) -> tuple[str, str]:
        """(left label, text on the button) of a property under ``use_property_split``."""
        return (text, "") if self.flags["use_property_split"] else ("", text)

    def _prop(self, a):
        data, name = a["data"], a["property"]
        rna = _property(data, name)
        if rna is None:
            self._problem(f"prop({type(data).__name__}, {name!r}): no such property")
            return Item("prop", text=f"property not found: {name}", widget="missing"), None
        text = a.get("text", rna.name)
        value = getattr(data, name)
        item = Item("prop", icon=a.get("icon", "NONE"), split=self.flags["use_property_split"],
                    animatable=self.flags["use_property_decorate"] and rna.is_animatable)
        if rna.type == "BOOLEAN" and not getattr(rna, "is_array", False):
            item.text, item.value = text, "on" if value else "off"
            item.widget = "toggle" if a.get("toggle") else "check"
            return item, None
        item.label, item.text = self._split_label(text)
        item.value, item.widget = show_value(data, rna, value)
        return item, None

    def _prop_search(self, a):
        item, _ = self._prop({k: a[k] for k in ("data", "property", "text") if k in a})
        if _property(a["search_data"], a["search_property"]) is None:
            self._problem(f"prop_search(..., {a['search_property']!r}): no such collection")
        item.widget = "search" if item.widget != "missing" else item.widget
        return item, None

    def _operator(self, a, kind="operator"):
        idname = a["operator"]
        rna = operator_rna(idname)
        if rna is None:
            self._problem(f"{kind}({idname!r}): no such operator")
            return Item(kind, text=idname, widget="missing"), OperatorProperties(None, idname, self)
        item = Item(kind, text=a.get("text", rna.name), icon=a.get("icon", "NONE"),
                    widget="button" if kind == "operator" else "dropdown")
        if kind == "operator_menu_enum":
            prop = rna.properties.get(a["property"])
            if prop is None or prop.type != "ENUM":
                self._problem(f"operator_menu_enum({idname!r}, {a['property']!r}): the "
                              "operator has no such enum")
        return item, OperatorProperties(rna, idname, self)

    def _operator_menu_enum(self, a):
        return self._operator(a, "operator_menu_enum")

    def _menu(self, a):
        menu = getattr(bpy.types, a["menu"], None)
        if menu is None:
            self._problem(f"menu({a['menu']!r}): no such menu")
        text = a.get("text", getattr(menu, "bl_label", a["menu"]))
        return Item("menu", text=text, icon=a.get("icon", "NONE"), widget="dropdown"), None

    def _label(self, a):
        return Item("label", text=a.get("text", ""), icon=a.get("icon", "NONE")), None

    def _separator(self, a):
        return Item("separator", widget="separator"), None

    def _template_list(self, a):
        ul = getattr(bpy.types, a["listtype_name"], None)
        data, prop = a["dataptr"], a["propname"]
        if ul is None:
            self._problem(f"template_list({a['listtype_name']!r}): no such UIList")
        for obj, name in ((data, prop), (a["active_dataptr"], a["active_propname"])):
            if _property(obj, name) is None:
                self._problem(f"template_list(..., {name!r}): no such property")
        item = Item("list", widget="list", value=str(a.get("rows", 5)))
        if ul is None or _property(data, prop) is None:
            return item, None
        for index, entry in enumerate(getattr(data, prop)):
            row = Layout("row", self, self.problems, f"{self.where} > {ul.__name__}")
            ul.draw_item(stand_in(ul, row), bpy.context, row, data, entry, 0,
                         a["active_dataptr"], a["active_propname"], index)
            item.rows.append(row)
        return item, None


class OperatorProperties:
    """What ``layout.operator()`` returns: setting a property the operator has not is a problem
    (Blender raises ``AttributeError``), as is an enum value it does not list."""

    def __init__(self, rna, idname, layout):
        self.__dict__.update(rna=rna, idname=idname, layout=layout)

    def __setattr__(self, name, value):
        if self.rna is None:                    # the operator itself is missing: said already
            return
        prop = self.rna.properties.get(name)
        if prop is None:
            self.layout._problem(f"operator({self.idname!r}).{name}: no such property")
        elif prop.type == "ENUM" and len(prop.enum_items) and value not in prop.enum_items:
            self.layout._problem(f"operator({self.idname!r}).{name} = {value!r}: not one of "
                                 f"{list(prop.enum_items.keys())}")


def _property(data, name: str):
    if data is None:
        return None
    return data.bl_rna.properties.get(name)


def operator_rna(idname: str):
    """The operator's RNA type (its label and properties), ``None`` when none is registered."""
    module, _, name = idname.partition(".")
    try:
        return getattr(getattr(bpy.ops, module), name).get_rna_type()
    except (AttributeError, KeyError):
        return None


def show_value(data, rna, value) -> tuple[str, str]:
    """``(text, widget)`` of a property's current value as a field shows it."""
    if rna.type == "ENUM":
        items = rna.enum_items if len(rna.enum_items) else None
        if items is None:           # items from a function: ask the data for the name
            name = bpy.types.UILayout.enum_item_name(data, rna.identifier, value)
        else:
            name = items[value].name if value in items else str(value)
        return name, "enum"
    if rna.type == "POINTER":
        return (getattr(value, "name", "") if value is not None else ""), "field"
    if rna.type == "STRING":
        return value, "field"
    if rna.type in ("FLOAT", "INT"):
        if getattr(rna, "is_array", False):         # one row per component
            return "\t".join(number(rna, v) for v in value), "vector"
        return number(rna, value), "number"
    return str(value), "field"


def number(rna, value) -> str:
    """A number as Blender's field shows it: with its unit (metric, degrees), else to the
    property's precision."""
    if rna.type == "INT":
        return str(int(value))
    units = bpy.utils.units
    if rna.unit != "NONE" and hasattr(units.categories, rna.unit):
        return units.to_string(units.systems.METRIC, getattr(units.categories, rna.unit),
                               float(value), precision=max(rna.precision, 2)).strip()
    return f"{value:.{max(rna.precision, 1)}f}"


def stand_in(cls, layout):
    """A stand-in ``self`` for a registered UI class's methods: its class attributes and
    methods, and ``layout`` (a bpy struct cannot be made without a window)."""

    class StandIn:
        def __getattr__(self, name):
            attr = getattr(cls, name)
            return types.MethodType(attr, self) if isinstance(attr, types.FunctionType) else attr

    obj = StandIn()
    obj.layout = layout
    return obj


@dataclass
class DrawnPanel:
    """One panel as drawn: its class, header and body, and its sub-panels that poll true."""

    cls: type
    header: Layout
    body: Layout
    children: list


def panels(category: str) -> list:
    """The registered sidebar panels of ``category``, in the order Blender lists them."""
    found = [c for c in bpy.types.Panel.__subclasses__()
             if c.is_registered and getattr(c, "bl_category", None) == category
             and c.bl_region_type == "UI"]
    return sorted(found, key=lambda c: getattr(c, "bl_order", 0))


def draw_panels(category: str, context, problems: list) -> list:
    """Every panel of ``category`` whose ``poll`` (and whose parents') is true in ``context``,
    drawn into recorders: a tree of :class:`DrawnPanel` from the top-level panels down."""
    every = panels(category)

    def draw(cls):
        if hasattr(cls, "poll") and not cls.poll(context):
            return None
        where = cls.bl_label
        header = Layout("row", problems=problems, where=f"{where} (header)")
        body = Layout("column", problems=problems, where=where)
        for name in ("draw_header_preset", "draw_header"):
            if hasattr(cls, name):
                getattr(cls, name)(stand_in(cls, header), context)
        cls.draw(stand_in(cls, body), context)
        subs = [draw(c) for c in every if getattr(c, "bl_parent_id", "") == cls.__name__]
        return DrawnPanel(cls, header, body, [s for s in subs if s is not None])

    tops = [draw(c) for c in every if not getattr(c, "bl_parent_id", "")]
    return [t for t in tops if t is not None]


def walk(drawn: list):
    """Each :class:`DrawnPanel` of a tree, parents first."""
    for p in drawn:
        yield p
        yield from walk(p.children)
