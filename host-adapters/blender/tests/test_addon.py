"""The add-on as an artist meets it, headless: the bake lands beside the saved .blend (a `//` path) or beside the
dataset, never in Blender's temporary folder, and the fire survives saving, quitting and reopening the file; the
imported object is selected and active, and the view's exposure shows the fire; a .blend's saved properties cannot
make a re-bake write anything but the add-on's own bake file; the extension package installs through Blender's
own extension installer."""

import os
import shutil
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "host-adapters" / "blender"))

try:
    import bpy
except ImportError:
    if os.environ.get("FIREMEDIUM_REQUIRE_BLENDER"):
        raise
    raise unittest.SkipTest("Blender's Python module is not installed (pip install bpy, 4.5 for Python 3.11)")

import firemedium_blender as addon  # noqa: E402

CAMPFIRE = ROOT / "scenes" / "campfire" / "campfire.vdb"


def command() -> str:
    exe = os.environ.get("FIREMEDIUM_COMMAND") or str(ROOT / "target" / "release" / "firemedium")
    if not Path(exe).is_file():
        raise unittest.SkipTest(f"{exe} is not built (cargo build --release)")
    os.environ["FIREMEDIUM_COMMAND"] = exe
    return exe


class Addon(unittest.TestCase):
    def setUp(self):
        command()
        self.cwd = os.getcwd()
        self.dir = Path(tempfile.mkdtemp(prefix="firemedium-addon-"))
        bpy.ops.wm.read_factory_settings(use_empty=True)

    def tearDown(self):
        os.chdir(self.cwd)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        shutil.rmtree(self.dir, ignore_errors=True)

    def test_a_saved_blend_keeps_its_fire_after_quitting_and_reopening(self):
        blend = self.dir / "shot" / "shot.blend"
        blend.parent.mkdir()
        bpy.ops.wm.save_as_mainfile(filepath=str(blend))
        fire = addon.import_fire(str(CAMPFIRE), {"fuel": "propane"})
        # Baked beside the .blend, as a path relative to it; not in Blender's temporary folder.
        self.assertEqual(fire.data.filepath, "//firemedium/campfire-firemedium.vdb")
        baked = blend.parent / "firemedium" / "campfire-firemedium.vdb"
        self.assertTrue(baked.is_file())
        self.assertFalse(Path(bpy.path.abspath(fire.data.filepath)).resolve().is_relative_to(
            Path(bpy.app.tempdir).resolve()))
        # Selected and active; the exposure shows the fire (the bake's measure: its brightest lines of sight, in
        # cd/m², at 2 in AgX).
        self.assertTrue(fire.select_get())
        self.assertIs(bpy.context.view_layer.objects.active, fire)
        view = bpy.context.scene.view_settings
        self.assertEqual(view.view_transform, "AgX")
        self.assertLess(view.exposure, -5.0)
        self.assertGreater(view.exposure, -10.0)
        bpy.ops.wm.save_mainfile()
        # Quit (Blender deletes its temporary folder) and reopen.
        temp = Path(bpy.app.tempdir)
        bpy.ops.wm.read_factory_settings(use_empty=True)
        shutil.rmtree(temp, ignore_errors=True)
        bpy.ops.wm.open_mainfile(filepath=str(blend))
        fire = bpy.data.objects["fire"]
        fire.data.grids.load()
        self.assertEqual(sorted(g.name for g in fire.data.grids), ["emission", "sigma_a", "sigma_s"])
        self.assertTrue(fire.data.grids.is_loaded)
        # Saved elsewhere, the relative path follows (Blender remaps it).
        moved = self.dir / "elsewhere" / "moved.blend"
        moved.parent.mkdir()
        bpy.ops.wm.save_as_mainfile(filepath=str(moved), relative_remap=True)
        bpy.ops.wm.open_mainfile(filepath=str(moved))
        fire = bpy.data.objects["fire"]
        self.assertTrue(Path(bpy.path.abspath(fire.data.filepath)).resolve() == baked.resolve())
        fire.data.grids.load()
        self.assertTrue(fire.data.grids.is_loaded)

    def test_an_unsaved_blend_bakes_beside_the_dataset_or_where_asked(self):
        data = self.dir / "data"
        data.mkdir()
        shutil.copy(CAMPFIRE, data / "camp.vdb")
        fire = addon.import_fire(str(data / "camp.vdb"))
        self.assertEqual(Path(fire.data.filepath), data.resolve() / "camp-firemedium.vdb")
        chosen = self.dir / "bakes"
        fire2 = addon.import_fire(str(data / "camp.vdb"), name="fire2", directory=str(chosen))
        self.assertTrue((chosen / "camp-firemedium.vdb").is_file())
        self.assertTrue(fire2.select_get() and not fire.select_get())
        # Blender's temporary folder is refused.
        with self.assertRaisesRegex(RuntimeError, "temporary folder"):
            addon.import_fire(str(data / "camp.vdb"), name="fire3", directory=bpy.app.tempdir)
        # Saved now, reopened: the absolute path still holds.
        blend = self.dir / "later.blend"
        bpy.ops.wm.save_as_mainfile(filepath=str(blend))
        bpy.ops.wm.open_mainfile(filepath=str(blend))
        bpy.data.objects["fire"].data.grids.load()
        self.assertTrue(bpy.data.objects["fire"].data.grids.is_loaded)

    def test_saved_properties_cannot_make_a_rebake_write_elsewhere(self):
        data = self.dir / "data"
        data.mkdir()
        shutil.copy(CAMPFIRE, data / "camp.vdb")
        victim = self.dir / "notes.txt"
        victim.write_text("the user's own file")
        fire = addon.import_fire(str(data / "camp.vdb"))
        # A shared .blend's properties pointing the bake at another file: refused by the add-on...
        fire["firemedium_baked"] = str(victim)
        with self.assertRaisesRegex(RuntimeError, "not a firemedium bake file"):
            addon.rebake(fire)
        # ...and a file named like a bake that firemedium did not write: refused by `firemedium bake` itself.
        fake = self.dir / "decoy-firemedium.vdb"
        fake.write_text("not a VDB")
        fire["firemedium_baked"] = str(fake)
        with self.assertRaisesRegex(RuntimeError, "not a file firemedium bake wrote"):
            addon.rebake(fire)
        self.assertEqual(victim.read_text(), "the user's own file")
        self.assertEqual(fake.read_text(), "not a VDB")
        # A dataset whose name starts with '-' is a file, not an option.
        dash = data / "-camp.vdb"
        shutil.copy(CAMPFIRE, dash)
        os.chdir(data)
        odd = addon.import_fire("-camp.vdb", name="dash")
        self.assertTrue(Path(odd.data.filepath).name == "-camp-firemedium.vdb")
        # The legitimate re-bake of its own file works.
        fire["firemedium_baked"] = str(data.resolve() / "camp-firemedium.vdb")
        fire["firemedium_params"]["fuel"] = "acetylene"
        addon.rebake(fire)

    def test_the_extension_package_installs_through_blenders_installer(self):
        out = self.dir / "pkg"
        r = subprocess.run(["bash", str(ROOT / "tools" / "blender-addon.sh"), str(out)], capture_output=True,
                           text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        ext = out / "firemedium-extension.zip"
        self.assertTrue(ext.is_file() and (out / "firemedium_blender.zip").is_file())
        repos = list(bpy.context.preferences.extensions.repos)
        repo = next((r for r in repos if r.module == "user_default"), None)
        self.assertIsNotNone(repo, [r.module for r in repos])
        result = bpy.ops.extensions.package_install_files(filepath=str(ext), repo="user_default",
                                                          enable_on_install=True)
        self.assertEqual(result, {"FINISHED"})
        try:
            module = "bl_ext.user_default.firemedium"
            self.assertIn(module, sys.modules)
            self.assertTrue(hasattr(bpy.ops.firemedium, "import_fire"))
        finally:
            bpy.ops.extensions.package_uninstall(repo_index=repos.index(repo), pkg_id="firemedium")


if __name__ == "__main__":
    unittest.main()
