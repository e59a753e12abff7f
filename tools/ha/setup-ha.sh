#!/usr/bin/env bash
# Installs Home Assistant core from PyPI into a venv of its own, for the real-Home-Assistant test
# (host/tests/ha_real/). Cached: a second run finds the venv complete and costs nothing.
#
#   tools/ha/setup-ha.sh            prints the venv's folder (installs first when needed)
#
# Home Assistant 2025.x needs Python 3.13; where only 3.11/3.12 is found, 2024.3 (the last release
# that runs on 3.11) is installed instead. HUBWIRE_HA_PYTHON names an interpreter to use.
set -euo pipefail

find_python() {
    local p
    for p in "${HUBWIRE_HA_PYTHON:-}" python3.13 /root/.pyenv/versions/3.13*/bin/python3 \
             "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.13*/bin/python3 python3.12 python3.11 python3; do
        [ -n "$p" ] || continue
        command -v "$p" >/dev/null 2>&1 || continue
        if "$p" -c 'import sys, ssl, sqlite3, venv; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
            echo "$(command -v "$p")"; return 0
        fi
    done
    return 1
}

PY=$(find_python) || { echo "setup-ha: no Python 3.11+ with ssl, sqlite3 and venv found" >&2; exit 1; }
MINOR=$("$PY" -c 'import sys; print(sys.version_info[1])')
if [ "$MINOR" -ge 13 ]; then
    HA_VERSION=${HUBWIRE_HA_VERSION:-2025.4.4}
    PINS=""
else
    HA_VERSION=${HUBWIRE_HA_VERSION:-2024.3.3}
    # its dependencies are not all pinned: josepy 2 dropped what its acme imports
    PINS="josepy<2"
fi
DIR=${HUBWIRE_HA_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/hubwire/ha-$HA_VERSION-py3.$MINOR}

if [ ! -f "$DIR/.complete" ]; then
    echo "setup-ha: installing Home Assistant $HA_VERSION into $DIR (once; takes minutes)" >&2
    rm -rf "$DIR"
    "$PY" -m venv "$DIR"
    "$DIR/bin/python" -m pip install -q --upgrade pip >&2
    "$DIR/bin/python" -m pip install -q "homeassistant==$HA_VERSION" >&2
    # the packages of the integrations the test loads (and what they depend on), installed here
    # rather than by Home Assistant at its first start; versions as the manifests pin them
    "$DIR/bin/python" - >"$DIR/requirements-ha.txt" <<'PY'
import json, pathlib, homeassistant.components as c
root, todo, seen, reqs = pathlib.Path(c.__path__[0]), ["mqtt", "frontend", "config", "api", "onboarding", "backup"], set(), set()
while todo:
    name = todo.pop()
    if name in seen or not (root / name / "manifest.json").exists():
        continue
    seen.add(name)
    m = json.loads((root / name / "manifest.json").read_text())
    reqs.update(m.get("requirements", []))
    todo += m.get("dependencies", []) + m.get("after_dependencies", [])
print("\n".join(sorted(reqs)))
PY
    "$DIR/bin/python" -m pip install -q -r "$DIR/requirements-ha.txt" $PINS >&2
    touch "$DIR/.complete"
fi
echo "$DIR"
