"""The Blender side: the only package that imports bpy.  ``register()``/``unregister()`` add and
remove the properties, presets, operators and panel, in order and in reverse."""
from __future__ import annotations

import importlib

_MODULES = ("props_crowd", "props_rig", "props_skid", "props", "presets", "ops_figure", "ops_bake",
            "ops_layers", "ops_path", "ops_live", "ops_rig", "ops_bone_map", "ops_crowd", "panel",
            "panel_rig", "panel_crowd")


def _modules():
    return [importlib.import_module(f".{name}", __name__) for name in _MODULES]


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
