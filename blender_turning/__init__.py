"""blender_turning: physically based turning (van de Panne, Fiume, Vranesic 1993) for Blender."""
__version__ = "0.1.0"

# The built-in sports register their records (core/sports.py) when their modules are imported:
# importing the mapping package here makes them known to every part of the package (the core's
# readers included) however it is entered.  docs/registry.md: adding a sport.
from . import mapping as _sports  # noqa: E402,F401
