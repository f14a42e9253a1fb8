"""blender_turning: physically based turning (van de Panne, Fiume, Vranesic 1993) for Blender."""
__version__ = "0.1.0"
