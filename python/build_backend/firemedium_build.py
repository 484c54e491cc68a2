"""The package's build backend: setuptools', after building the plugin with cargo and copying it into the package.

`pip install ./python` (from a checkout of the repository) runs `cargo build --release -p firemedium-plugin` in
the repository and ships its library as `firemedium/lib/`, so `import firemedium` finds the plugin with no
environment variable. A wheel so built is the platform's (it holds a native library). `FIREMEDIUM_PLUGIN` still
names another plugin at run time.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import build_meta as _setuptools
from setuptools.build_meta import *  # noqa: F401,F403  (every hook not overridden below)

HERE = Path(__file__).resolve().parents[1]
ROOT = HERE.parent


def _library_name() -> str:
    if sys.platform == "darwin":
        return "libfiremedium_plugin.dylib"
    if sys.platform == "win32":
        return "firemedium_plugin.dll"
    return "libfiremedium_plugin.so"


def _build_plugin() -> None:
    """Builds the plugin with cargo (release) and copies it into the package's lib/ folder."""
    if not (ROOT / "Cargo.toml").is_file():
        raise RuntimeError(
            f"firemedium: building the package needs the repository around {HERE} (its Cargo workspace builds the "
            "plugin): pip install ./python from a checkout"
        )
    cargo = os.environ.get("CARGO") or shutil.which("cargo")
    if not cargo:
        raise RuntimeError("firemedium: building the package needs cargo (https://rustup.rs) to build the plugin")
    target = Path(os.environ.get("CARGO_TARGET_DIR") or ROOT / "target")
    subprocess.run([cargo, "build", "--release", "-p", "firemedium-plugin"], cwd=ROOT, check=True,
                   stdout=sys.stderr)
    built = target / "release" / _library_name()
    if not built.is_file():
        raise RuntimeError(f"firemedium: cargo built no {built}")
    lib = HERE / "firemedium" / "lib"
    lib.mkdir(exist_ok=True)
    shutil.copy2(built, lib / _library_name())


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    _build_plugin()
    return _setuptools.build_wheel(wheel_directory, config_settings, metadata_directory)


def build_editable(wheel_directory, config_settings=None, metadata_directory=None):
    _build_plugin()
    return _setuptools.build_editable(wheel_directory, config_settings, metadata_directory)
