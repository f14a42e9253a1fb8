"""``python -m blender_turning``: see :mod:`blender_turning.cli`."""
import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
