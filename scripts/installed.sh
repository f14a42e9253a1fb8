#!/usr/bin/env bash
# The Blender tests marked `installed` against the extension built with the README's command and
# installed into a temporary user configuration (tests/installed_addon.py), run by the Python of
# a venv with bpy ($1, e.g. .venv/bin/python); further args go to pytest (default: every
# tests/test_blender_*.py).  The run cannot import the checkout, as a user's Blender cannot: it
# is in a venv of its own that sees the packages of $1's venv through a .pth naming its
# site-packages (whose own .pth files, the checkout's editable install, Python then never reads),
# with python -P (the working directory off sys.path); worker processes start with the same
# interpreter.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
py="$1"
shift
[ "$#" -gt 0 ] || set -- "$root"/tests/test_blender_*.py
view="$(mktemp -d "${TMPDIR:-/tmp}/turning-installed-venv.XXXXXX")"
trap 'rm -rf "$view"' EXIT
"$py" -m venv --without-pip "$view"
purelib='import sysconfig; print(sysconfig.get_path("purelib"))'
"$py" -c "$purelib" > "$("$view/bin/python" -c "$purelib")/venv.pth"
cd "$root"
TURNING_INSTALLED=1 "$view/bin/python" -P -m pytest -p no:cacheprovider -q -m installed "$@"
