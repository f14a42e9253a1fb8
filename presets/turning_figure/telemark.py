import bpy
settings = bpy.context.object.turning

settings.sport = 'TELEMARK'
settings.mass = 75.0
settings.com_height = 0.925
settings.inertia = 9.4
settings.speed = 8.0
settings.curvature_max = 0.125
settings.curvature_rate_max = 0.5
settings.fall_angle = 0.9599310885968813
settings.plan_curvature_rate = 0.3
