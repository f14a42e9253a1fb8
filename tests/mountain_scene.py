"""The Blender tests' mountain: a factory scene with the add-on registered, its frame range set to
``seconds`` at ``fps``, and the rolling ``ski_slope`` (seed 3, 1 m cells) as a Ground mesh named
"Mountain".  A module fixture yields from :func:`mountain_scene`: ``(scene, mountain object)``."""


def mountain_scene(seconds: float, fps: int, length: float = 160.0, width: float = 160.0):
    import bpy

    from blender_turning import blender as addon
    from blender_turning.blender.scene.ground import mesh_from_height_field
    from blender_turning.core.ground.terrain_gen import ski_slope

    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    sc = bpy.context.scene
    sc.render.fps, sc.frame_start, sc.frame_end = fps, 1, 1 + int(seconds * fps)
    mountain = ski_slope(length=length, width=width, cell=1.0, seed=3)
    obj = bpy.data.objects.new("Mountain", mesh_from_height_field(bpy, mountain, "Mountain"))
    sc.collection.objects.link(obj)
    yield sc, obj
    addon.unregister()
