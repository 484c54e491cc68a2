#!/usr/bin/env bash
# Packages the Blender add-on (host-adapters/blender/firemedium_blender) two ways:
#   target/firemedium_blender.zip    a legacy add-on (Edit > Preferences > Add-ons > Install from Disk), its folder inside
#   target/firemedium-extension.zip  a Blender 4.2+ extension (Get Extensions > Install from Disk): blender_manifest.toml
#                                    and the module at the zip's root
# A folder given as the only argument takes both instead of target/.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-target}"
mkdir -p "$out"
python3 - "$out" <<'PY'
import sys, zipfile, pathlib
src = pathlib.Path("host-adapters/blender/firemedium_blender")
out = pathlib.Path(sys.argv[1])
files = sorted(src.rglob("*.py"))
with zipfile.ZipFile(out / "firemedium_blender.zip", "w", zipfile.ZIP_DEFLATED) as z:
    for f in files:
        z.write(f, f.relative_to(src.parent))
with zipfile.ZipFile(out / "firemedium-extension.zip", "w", zipfile.ZIP_DEFLATED) as z:
    z.write(src / "blender_manifest.toml", "blender_manifest.toml")
    for f in files:
        z.write(f, f.relative_to(src))
print(f"wrote {out / 'firemedium_blender.zip'} and {out / 'firemedium-extension.zip'}")
PY
