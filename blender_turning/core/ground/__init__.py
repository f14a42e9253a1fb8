"""The ground under the figure: surfaces (flat, plane, height field), the procedural terrain and a
scene's terrain table."""
