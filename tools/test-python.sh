#!/usr/bin/env bash
# The Python package's, the Mitsuba 3 adapter's and the Blender add-on's tests, against the plugin and the command
# the release build made (run `cargo build --release` or the test suite first): numpy, mitsuba==3.9.1 and Blender's
# Python module (bpy 4.5, for Python 3.11) come from PyPI when missing, the package is installed from ./python as
# a user installs it, and the guides' examples run as written. About two minutes on 2 cores (small Mitsuba and
# Cycles renders, the examples), plus the downloads once (bpy is about 350 MB).
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import numpy' 2>/dev/null || python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore numpy
python3 -c 'import mitsuba, sys; sys.exit(mitsuba.__version__ != "3.9.1")' 2>/dev/null \
    || python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore "mitsuba==3.9.1"
# Mitsuba's vectorised llvm_* variants (the adapter's) need an LLVM Dr.Jit can compile with for these CPUs:
# Debian's libllvm19 (the system's LLVM 14/15 fail to select `fminimum`).
llvm=/usr/lib/x86_64-linux-gnu/libLLVM-19.so
if [[ ! -f "$llvm" ]]; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q libllvm19 > /dev/null 2>&1 || { apt-get update -q > /dev/null && apt-get install -y -q libllvm19 > /dev/null; }
fi
export DRJIT_LIBLLVM_PATH="$llvm"
python3 -c 'import bpy, sys; sys.exit(bpy.app.version < (4, 5, 0))' 2>/dev/null \
    || python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore "bpy>=4.5,<5"
python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore --force-reinstall --no-deps ./python
# pip alone gives a working package: a fresh venv (numpy from the outer site-packages), no FIREMEDIUM_* variable,
# no firemedium on the PATH — the plugin pip built into the package is found.
venv="$(mktemp -d /tmp/firemedium-venv.XXXXXX)"
python3 -m venv --system-site-packages "$venv"
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check --no-deps ./python
(cd / && env -u FIREMEDIUM_PLUGIN -u FIREMEDIUM_PLUGIN_PATH PATH=/usr/bin:/bin "$venv/bin/python" -c '
import sys, firemedium as fm
p = fm.plugin().path
assert str(p).startswith(sys.prefix), p
print("pip-installed package: plugin", p, "ABI", fm.plugin().abi_version)')
rm -rf "$venv"
lib=libfiremedium_plugin.so
plugin="target/release/$lib"
[[ -f "$plugin" ]] || plugin="target/release/deps/$lib"
export FIREMEDIUM_PLUGIN="$PWD/$plugin" FIREMEDIUM_COMMAND="$PWD/target/release/firemedium"
export FIREMEDIUM_REQUIRE_MITSUBA=1 FIREMEDIUM_REQUIRE_BLENDER=1
for f in "$FIREMEDIUM_PLUGIN" "$FIREMEDIUM_COMMAND"; do
    [[ -f "$f" ]] || { echo "test-python: $f is missing (cargo build --release)" >&2; exit 1; }
done
(cd python/tests && python3 -m unittest -v 2>&1)
(cd host-adapters/mitsuba/tests && python3 -m unittest -v 2>&1)
# The spectral variant (one variant per process): the emitting fires again, binned over Mitsuba's wavelengths.
(cd host-adapters/mitsuba/tests && FIREMEDIUM_MITSUBA_VARIANT=llvm_ad_spectral python3 -m unittest -v test_emitting test_refused 2>&1)
# (Blender's module prints its memory bookkeeping at exit; the result is unittest's.)
(cd host-adapters/blender/tests && python3 -m unittest -v 2>&1 | grep -v '^Fra:\|leak detector\|Not freed')
