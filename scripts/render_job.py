"""Headless job: build a scene from a TOML config, bake the figures, save a .blend, render.

    blender -b --python scripts/render_job.py -- --config scripts/configs/demo.toml
    python scripts/render_job.py --config scripts/configs/demo.toml      # on the bpy wheel

The entry point only: the job is :mod:`blender_turning.blender.render.job` (its text has the
config, the output and the farm use; ``--help`` lists the flags).
"""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:                      # inside a Blender binary: find the package
    sys.path.insert(0, str(ROOT))
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-job-"))

from blender_turning.blender.render.job import main  # noqa: E402

if __name__ == "__main__":
    code = main()
    if code:
        sys.exit(code)
