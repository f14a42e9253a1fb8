import bpy
settings = bpy.context.object.turning

settings.sport = 'CYCLIST'
settings.mass = 85.0
settings.com_height = 1.0
settings.inertia = 15.0
settings.speed = 6.0
settings.curvature_max = 0.5
settings.curvature_rate_max = 2.0
settings.fall_angle = 0.8726646259971648
settings.plan_curvature_rate = 0.5
