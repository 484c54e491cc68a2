"""The guides' commands run as written: every `python3 …` line of docs/guide/python.md's and mitsuba.md's sh
blocks, from a folder that holds the repository's python/, host-adapters/ and scenes/ (so what they write lands
there, not in the repository)."""

import os
import shlex
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def commands(guide: str) -> list[str]:
    out, in_sh = [], False
    for line in (ROOT / "docs" / "guide" / guide).read_text().splitlines():
        if line.startswith("```"):
            in_sh = line == "```sh" and not in_sh
            continue
        if in_sh and line.startswith("python3 "):
            out.append(line)
    return out


class Guides(unittest.TestCase):
    def run_guide(self, guide: str, writes: list[str]):
        cmds = commands(guide)
        self.assertTrue(cmds, f"{guide} has no python3 command")
        with tempfile.TemporaryDirectory(prefix="firemedium-guide-") as d:
            for name in ("python", "host-adapters", "scenes"):
                os.symlink(ROOT / name, Path(d) / name)
            for cmd in cmds:
                args = shlex.split(cmd)
                r = subprocess.run([sys.executable] + args[1:], cwd=d, capture_output=True, text=True)
                self.assertEqual(r.returncode, 0, f"{guide}: {cmd}\n{r.stderr}")
            for name in writes:
                self.assertGreater((Path(d) / name).stat().st_size, 100, name)

    def test_the_python_guide(self):
        self.run_guide("python.md", ["quickstart.pgm"])

    def test_the_mitsuba_guide(self):
        try:
            import mitsuba  # noqa: F401
        except ImportError:
            if os.environ.get("FIREMEDIUM_REQUIRE_MITSUBA"):
                raise
            self.skipTest("Mitsuba 3 is not installed (pip install mitsuba==3.9.1)")
        self.run_guide("mitsuba.md", ["campfire-mitsuba.exr"])


if __name__ == "__main__":
    unittest.main()
