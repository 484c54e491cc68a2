#!/usr/bin/env bash
# Zips the Blender add-on (host-adapters/blender/firemedium_blender) for Blender's add-on installer
# (Edit > Preferences > Add-ons > Install from Disk): target/firemedium_blender.zip, or the path given.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target/firemedium_blender.zip}"
mkdir -p "$(dirname "$out")"
python3 - "$out" <<'PY'
import sys, zipfile, pathlib
src = pathlib.Path("host-adapters/blender/firemedium_blender")
with zipfile.ZipFile(sys.argv[1], "w", zipfile.ZIP_DEFLATED) as z:
    for f in sorted(src.rglob("*.py")):
        z.write(f, f.relative_to(src.parent))
print(f"wrote {sys.argv[1]}")
PY
