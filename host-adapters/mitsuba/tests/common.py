"""What the Mitsuba adapter's tests share: Mitsuba in a vectorised variant (llvm_ad_rgb, or
FIREMEDIUM_MITSUBA_VARIANT; or a skip saying why), the repository and the built `firemedium` command."""

import os
import unittest
from pathlib import Path


def mitsuba_or_skip(variant: str | None = None):
    try:
        import mitsuba as mi
    except ImportError:
        if os.environ.get("FIREMEDIUM_REQUIRE_MITSUBA"):
            raise
        raise unittest.SkipTest("Mitsuba 3 is not installed (pip install mitsuba==3.9.1)")
    mi.set_variant(variant or os.environ.get("FIREMEDIUM_MITSUBA_VARIANT") or "llvm_ad_rgb")
    return mi


def repository() -> Path:
    return Path(__file__).resolve().parents[3]


def command() -> str:
    """The `firemedium` command: FIREMEDIUM_COMMAND, else the release build's."""
    exe = os.environ.get("FIREMEDIUM_COMMAND") or str(repository() / "target" / "release" / "firemedium")
    if not Path(exe).is_file():
        raise unittest.SkipTest(f"{exe} is not built (cargo build --release)")
    return exe
