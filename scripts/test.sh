#!/usr/bin/env bash
# The whole test suite in the project's .venv (set up on first use).  Extra args go to pytest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/env.sh"
cd "$root"
exec "$root/.venv/bin/python" -m pytest "$@"
