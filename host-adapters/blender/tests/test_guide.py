"""The Blender guide (docs/guide/blender.md) as an artist follows it, headless: its shell commands run as written
(in a folder holding the repository's scenes, tools and build, with the build's `firemedium` on the PATH), the
add-on installed from the zip they make and enabled as Blender's installer does, its Import operator, and the
guide's script."""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
GUIDE = ROOT / "docs" / "guide" / "blender.md"

try:
    import bpy
except ImportError:
    if os.environ.get("FIREMEDIUM_REQUIRE_BLENDER"):
        raise
    raise unittest.SkipTest("Blender's Python module is not installed (pip install bpy, 4.5 for Python 3.11)")


def blocks(lang: str) -> list[str]:
    """The guide's fenced code blocks in `lang`."""
    return re.findall(rf"```{lang}\n(.*?)```", GUIDE.read_text(encoding="utf-8"), re.S)


class Guide(unittest.TestCase):
    def test_the_guides_steps_run_as_written(self):
        release = ROOT / "target" / "release"
        if not (release / "firemedium").is_file():
            raise unittest.SkipTest("target/release/firemedium is not built (cargo build --release)")
        saved = (os.getcwd(), dict(os.environ), list(sys.path), sys.modules.pop("firemedium_blender", None))
        with tempfile.TemporaryDirectory(prefix="firemedium-guide-") as d:
            d = Path(d)
            for name in ("target", "scenes", "tools", "host-adapters"):
                (d / name).symlink_to(ROOT / name)
            # Two frames of a simulation (Mantaflow's cache) for the import with Sequence ticked; the guide's commands
            # copy the campfire its script imports.
            for f, src in ((1, "mantaflow_fire_f030.vdb"), (2, "mantaflow_fire_f060.vdb")):
                shutil.copy(ROOT / "tests" / "data" / "valid" / "vdb" / src, d / f"fire_{f:04d}.vdb")
            os.environ.pop("FIREMEDIUM_COMMAND", None)
            os.environ["PATH"] = f"{release}{os.pathsep}{os.environ['PATH']}"
            commands = [line for b in blocks("sh") for line in b.strip().splitlines()]
            self.assertGreaterEqual(len(commands), 2, commands)
            for line in commands:
                r = subprocess.run(line, shell=True, cwd=d, capture_output=True, text=True)
                self.assertEqual(r.returncode, 0, f"{line}: {r.stderr}")
            self.assertTrue((d / "campfire-cycles.vdb").is_file())
            zip_file = ROOT / "target" / "firemedium_blender.zip"
            self.assertTrue(zip_file.is_file() and (ROOT / "target" / "firemedium-extension.zip").is_file())
            bpy.ops.wm.read_factory_settings(use_empty=True)
            # The guide's script installs the add-on through Blender's installer: the installed copy, not the
            # repository's that other tests import.
            sys.path[:] = [p for p in sys.path if not p.startswith(str(ROOT / "host-adapters"))]
            try:
                os.chdir(d)
                scripts = blocks("python")
                self.assertEqual(len(scripts), 1)
                # As typed in Blender's Python console: its own imports, nothing given.
                exec(scripts[0], {"__name__": "__main__"})
                installed = Path(sys.modules["firemedium_blender"].__file__)
                self.assertTrue(installed.is_relative_to(Path(bpy.utils.user_resource("SCRIPTS"))), installed)
                fire = bpy.context.view_layer.objects.active
                self.assertEqual(fire.name, "fire")
                fire.data.grids.load()
                self.assertEqual(sorted(g.name for g in fire.data.grids), ["emission", "sigma_a", "sigma_s"])
                # Unsaved: baked beside the dataset, not in Blender's temporary folder; the view exposed for it.
                self.assertEqual(Path(fire.data.filepath).name, "campfire-firemedium.vdb")
                self.assertFalse(Path(fire.data.filepath).resolve().is_relative_to(Path(bpy.app.tempdir).resolve()))
                scene = bpy.context.scene
                self.assertEqual(scene.render.engine, "CYCLES")
                self.assertLess(scene.view_settings.exposure, -5.0)
                # File ▸ Import ▸ firemedium fire (.vdb), with the fuel, and with Sequence ticked, frames 1 to 2.
                self.assertEqual(bpy.ops.firemedium.import_fire(filepath=str(d / "campfire.vdb"), fuel="propane"),
                                 {"FINISHED"})
                self.assertEqual(bpy.ops.firemedium.import_fire(filepath=str(d / "fire_0001.vdb"), fuel="propane",
                                                                sequence=True, frame_first=1, frame_last=2),
                                 {"FINISHED"})
                sequences = [o for o in bpy.data.objects if o.type == "VOLUME" and o.data.is_sequence]
                self.assertEqual(len(sequences), 1)
                for o in sequences:
                    self.assertEqual((o.data.frame_start, o.data.frame_duration), (1, 2))
                    self.assertEqual(o.data.velocity_grid, "velocity")
            finally:
                # (Preferences ▸ Add-ons ▸ Remove, which needs a window to redraw: its two steps.)
                import addon_utils

                addon_utils.disable("firemedium_blender", default_set=True)
                shutil.rmtree(Path(bpy.utils.user_resource("SCRIPTS")) / "addons" / "firemedium_blender",
                              ignore_errors=True)
                os.chdir(saved[0])
                os.environ.clear()
                os.environ.update(saved[1])
                sys.path[:] = saved[2]
                sys.modules.pop("firemedium_blender", None)
                if saved[3] is not None:
                    sys.modules["firemedium_blender"] = saved[3]


if __name__ == "__main__":
    unittest.main()
