#!/usr/bin/env bash
# Sets up the project-local virtual environment .venv once: Python 3.11, the pinned
# requirements.txt and this package (editable).  Re-running is quick: it reinstalls only when
# requirements.txt or pyproject.toml changed.  Source it or run it; it prints nothing when ready.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$root/.venv"
py="${PYTHON:-}"
if [ -z "$py" ]; then
  for cand in python3.11 python3; do command -v "$cand" >/dev/null 2>&1 && { py="$cand"; break; }; done
fi
[ -n "$py" ] || { echo "env.sh: no python3.11 or python3 on PATH" >&2; exit 2; }
want="$(cat "$root/requirements.txt" "$root/pyproject.toml" | sha256sum | cut -d' ' -f1)"
if [ ! -x "$venv/bin/python" ]; then
  echo "env.sh: creating $venv (first run downloads about 400 MB: bpy, numpy, matplotlib)" >&2
  "$py" -m venv "$venv"
fi
if [ "$(cat "$venv/.installed" 2>/dev/null)" != "$want" ]; then
  "$venv/bin/python" -m pip install -q --disable-pip-version-check -r "$root/requirements.txt"
  "$venv/bin/python" -m pip install -q --disable-pip-version-check --no-deps -e "$root"
  echo "$want" > "$venv/.installed"
fi
