import bpy
settings = bpy.context.object.turning

settings.sport = 'SNOWBOARDER'
settings.mass = 70.0
settings.com_height = 0.95
settings.inertia = 10.0
settings.speed = 8.0
settings.curvature_max = 0.2
settings.curvature_rate_max = 0.8
settings.fall_angle = 1.0471975511965976
settings.plan_curvature_rate = 0.3
