import bpy
settings = bpy.context.object.turning

settings.sport = 'SKIER'
settings.mass = 75.0
settings.com_height = 1.0
settings.inertia = 12.0
settings.speed = 10.0
settings.curvature_max = 0.16666666666666666
settings.curvature_rate_max = 0.67
settings.fall_angle = 1.0471975511965976
settings.plan_curvature_rate = 0.2
