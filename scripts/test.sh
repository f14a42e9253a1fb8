#!/usr/bin/env bash
# The whole test suite in the project's .venv (set up on first use), then the Blender tests again
# on the oldest supported Blender (bpy 4.2 LTS) in .venv-bpy42, set up the same idempotent way.
# Extra args go to pytest (the first run; the 4.2 run takes them when they name blender tests).
# Without args each Blender version also runs the tests marked `installed` against the extension
# built with the README's command and installed into a temporary user configuration
# (scripts/installed.sh: in a venv that cannot import the checkout).  TURNING_SKIP_BPY42=1 skips
# the 4.2 runs.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/env.sh"
cd "$root"
status=0
"$root/.venv/bin/python" -m pytest "$@" || status=$?
installed() {            # $1: the venv's python, $2 its bpy: the marked tests, installed extension
  [ "$nargs" -eq 0 ] || return 0
  echo "test.sh: the built and installed extension on $2" >&2
  bash "$root/scripts/installed.sh" "$1" || status=$?
}
nargs=$#
installed "$root/.venv/bin/python" "bpy 5.0"
[ "${TURNING_SKIP_BPY42:-0}" = 1 ] && exit "$status"

# -- bpy 4.2 LTS (about 350 MB on first use) ------------------------------------------------------
venv="$root/.venv-bpy42"
reqs="bpy==4.2.23 numpy==1.26.4 pytest==9.2.0 hypothesis==6.170.15"
want="$(printf '%s\n' "$reqs" | cat - "$root/pyproject.toml" | sha256sum | cut -d' ' -f1)"
if [ ! -x "$venv/bin/python" ]; then
  py="${PYTHON:-}"
  if [ -z "$py" ]; then
    for cand in python3.11 python3; do command -v "$cand" >/dev/null 2>&1 && { py="$cand"; break; }; done
  fi
  echo "test.sh: creating $venv (first run downloads bpy 4.2, about 350 MB)" >&2
  "$py" -m venv "$venv"
fi
if [ "$(cat "$venv/.installed" 2>/dev/null)" != "$want" ]; then
  # shellcheck disable=SC2086
  "$venv/bin/python" -m pip install -q --disable-pip-version-check $reqs
  "$venv/bin/python" -m pip install -q --disable-pip-version-check --no-deps -e "$root"
  echo "$want" > "$venv/.installed"
fi
blender_args=()
for a in "$@"; do case "$a" in *test_blender_*) blender_args+=("$a");; esac; done
[ "${#blender_args[@]}" -gt 0 ] || blender_args=("$root"/tests/test_blender_*.py)
echo "test.sh: Blender tests on bpy 4.2 LTS" >&2
"$venv/bin/python" -m pytest -p no:cacheprovider -m blender "${blender_args[@]}" || status=$?
installed "$venv/bin/python" "bpy 4.2 LTS"
exit "$status"
