"""The Blender side: the only package that imports bpy.  ``register()``/``unregister()`` add and
remove the properties, presets, operators and panel, in order and in reverse."""
from __future__ import annotations

import importlib

_MODULES = ("props.crowd", "props.rig", "props.skid", "props.figure", "ui.presets", "ops.figure",
            "ops.bake", "ops.layers", "ops.export", "ops.path", "ops.live", "ops.rig",
            "ops.bone_map", "ops.crowd", "ui.panel", "ui.rig", "ui.crowd")


def _modules():
    return [importlib.import_module(f".{name}", __name__) for name in _MODULES]


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
