"""Extension entry point (Blender 4.2+): the repository root is the extension's root, so this
package is ``bl_ext.<repository>.blender_turning``; everything is in the inner package."""


def register():
    from .blender_turning import blender
    blender.register()


def unregister():
    from .blender_turning import blender
    blender.unregister()


def __getattr__(name):
    # The glTF exporter looks for this on every enabled add-on's module
    # (blender_turning/blender/anim/export_gltf.py).
    if name in ("glTF2ExportUserExtension", "glTF2_pre_export_callback",
                "glTF2_post_export_callback"):
        from .blender_turning.blender.anim import export_gltf
        return getattr(export_gltf, name)
    raise AttributeError(name)
