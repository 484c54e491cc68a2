"""The fire in Blender: `firemedium bake` and the add-on's import, rendered by Cycles on the CPU, against
`firemedium render` of the same scene (tests/data/scenes/campfire-floor.pbrt): the flame's and the floor's mean
luminance, and the flame's chromaticity.

Cycles' film is in the baked grids' units (cd/m² for the emission integrated per metre), so the two renders are
compared as they are; Blender's camera is right-handed and pbrt-v4's left-handed, so Blender's image is mirrored.
"""

import math
import os
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "host-adapters" / "blender"))

try:
    import bpy
    import mathutils
except ImportError:
    if os.environ.get("FIREMEDIUM_REQUIRE_BLENDER"):
        raise
    raise unittest.SkipTest("Blender's Python module is not installed (pip install bpy, 4.5 for Python 3.11)")

import firemedium_blender as addon  # noqa: E402

SPP = 256
# Linear Rec.709 → XYZ.
M = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750], [0.0193339, 0.1191920, 0.9503041]])


def command() -> str:
    exe = os.environ.get("FIREMEDIUM_COMMAND") or str(ROOT / "target" / "release" / "firemedium")
    if not Path(exe).is_file():
        raise unittest.SkipTest(f"{exe} is not built (cargo build --release)")
    os.environ["FIREMEDIUM_COMMAND"] = exe
    return exe


def read_rgb(path: Path) -> np.ndarray:
    """An EXR's RGB, read by Blender's own image loader (top row first)."""
    img = bpy.data.images.load(str(path))
    w, h = img.size
    px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, img.channels)[::-1, :, :3]
    bpy.data.images.remove(img)
    return px


def blackbody_fire(dataset: str) -> None:
    """The dataset's own grids in a volume object whose material is Cycles' Principled Volume as an artist sets it
    up for fire: density and temperature from the grids, blackbody intensity 1 (Cycles' "physically based"
    setting), the temperature input 1 (Cycles multiplies the grid by it: the campfire's grid is in kelvin, a
    Blender smoke simulation's relative to its default 1000 K), everything else its default."""
    vol = bpy.data.volumes.new("blackbody")
    vol.filepath = dataset
    obj = bpy.data.objects.new("blackbody", vol)
    bpy.context.scene.collection.objects.link(obj)
    m = bpy.data.materials.new("blackbody")
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    pv = nt.nodes.new("ShaderNodeVolumePrincipled")
    pv.inputs["Blackbody Intensity"].default_value = 1.0
    pv.inputs["Density Attribute"].default_value = "density"
    pv.inputs["Temperature Attribute"].default_value = "temperature"
    pv.inputs["Temperature"].default_value = 1.0
    nt.links.new(pv.outputs["Volume"], out.inputs["Volume"])
    vol.materials.append(m)


def cycles_scene(dataset: str, out: Path, size: tuple[int, int] = (32, 32), spp: int = SPP,
                 fire: str = "baked") -> None:
    """The campfire over a grey floor in Cycles, as tests/data/scenes/campfire-floor.pbrt: `fire` "baked" (the
    add-on's import) or "blackbody" (Cycles' Principled Volume on the dataset's grids)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    addon.render_settings(scene, samples=spp)
    scene.cycles.seed = 3
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.cycles.pixel_filter_type = "BOX"  # one pixel wide, as the reference's
    scene.cycles.filter_width = 1.0
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    if fire == "baked":
        # (As the reference scene: its emission and absorption × 15.)
        addon.import_fire(dataset, {"fuel": "propane", "firescale": 15, "smokescale": 15},
                          directory=str(Path(out).parent))
    else:
        blackbody_fire(dataset)
    bpy.ops.mesh.primitive_plane_add(size=20)
    floor = bpy.context.active_object
    m = bpy.data.materials.new("floor")
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.remove(nt.nodes["Principled BSDF"])
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    nt.links.new(d.outputs["BSDF"], nt.nodes["Material Output"].inputs["Surface"])
    floor.data.materials.append(m)
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    # pbrt-v4's fov spans the film's shorter side (the fit first: the angle sets the lens for the fitted side).
    cam.data.sensor_fit = "VERTICAL" if size[0] > size[1] else "HORIZONTAL"
    cam.data.angle = math.radians(40)
    scene.collection.objects.link(cam)
    scene.camera = cam
    eye, target = mathutils.Vector((0, -4.2, 1.6)), mathutils.Vector((0, 0, 0.55))
    cam.location = eye
    cam.rotation_euler = (target - eye).to_track_quat("-Z", "Y").to_euler()
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.filepath = str(out)
    bpy.ops.render.render(write_still=True)


class Cycles(unittest.TestCase):
    def test_the_baked_fire_in_cycles_is_firemedium_renders(self):
        exe = command()
        with tempfile.TemporaryDirectory(prefix="firemedium-blender-") as d:
            d = Path(d)
            subprocess.run([exe, "render", str(ROOT / "tests/data/scenes/campfire-floor.pbrt"), "-o", str(d / "ref.exr"),
                            "--quiet"], check=True)
            cycles_scene(str(ROOT / "scenes/campfire/campfire.vdb"), d / "cycles.exr")
            ref = read_rgb(d / "ref.exr")
            img = read_rgb(d / "cycles.exr")[:, ::-1]
        y_ref, y = ref @ M[1], img @ M[1]
        flame = y_ref > 0.05 * y_ref.max()
        floor = np.zeros_like(flame)
        floor[-8:, :] = True
        floor &= ~flame

        def xy(rgb):
            X = rgb.sum(axis=0) @ M.T
            return X[:2] / X.sum()

        r_flame = y[flame].mean() / y_ref[flame].mean()
        r_floor = y[floor].mean() / y_ref[floor].mean()
        dxy = np.abs(xy(img[flame]) - xy(ref[flame])).max()
        print(f"cycles: flame {y[flame].mean():.1f} against {y_ref[flame].mean():.1f} cd/m² ({r_flame:.4f}); floor "
              f"{y[floor].mean():.3f} against {y_ref[floor].mean():.3f} ({r_floor:.4f}); flame xy {xy(img[flame]).round(4)}"
              f" against {xy(ref[flame]).round(4)}")
        self.assertLess(abs(r_flame - 1.0), 0.05)
        self.assertLess(abs(r_floor - 1.0), 0.10)
        self.assertLess(dxy, 0.01)


class Rebake(unittest.TestCase):
    def test_an_edited_parameter_rebakes_the_fire(self):
        command()
        bpy.ops.wm.read_factory_settings(use_empty=True)
        addon.register()
        try:
            with tempfile.TemporaryDirectory(prefix="firemedium-blender-") as d:
                baked = str(Path(d) / "fire-firemedium.vdb")
                addon.bake(str(ROOT / "scenes/campfire/campfire.vdb"), baked, {"fuel": "propane"})
                obj = addon.import_fire(str(ROOT / "scenes/campfire/campfire.vdb"), {"fuel": "propane"}, baked=baked)
                before = Path(baked).read_bytes()
                self.assertEqual(dict(obj["firemedium_params"]), {"fuel": "propane"})
                # Half the soot: the file is baked again, and Blender reads the same three grids from it.
                obj["firemedium_params"]["sootscale"] = 0.5
                bpy.context.view_layer.objects.active = obj
                self.assertEqual(bpy.ops.firemedium.rebake(), {"FINISHED"})
                after = Path(baked).read_bytes()
                self.assertNotEqual(before, after)
                grids = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.grids
                self.assertEqual(sorted(g.name for g in grids), ["emission", "sigma_a", "sigma_s"])
                # A bad parameter is the command's message, and the operator cancels.
                obj["firemedium_params"]["fule"] = "propane"
                with self.assertRaises(RuntimeError) as e:
                    addon.rebake(obj)
                self.assertIn("fule", str(e.exception))
        finally:
            addon.unregister()



class Sequence(unittest.TestCase):
    def test_a_simulations_frames_play_as_a_volume_sequence_with_their_velocity(self):
        # Two frames of a Mantaflow cache (its velocity grid included), named as a sequence: the add-on bakes both,
        # loads them as a volume sequence that plays frame f of the files at the scene's frame f, and names the
        # baked velocity as the volume's velocity grid for Cycles' motion blur.
        command()
        bpy.ops.wm.read_factory_settings(use_empty=True)
        with tempfile.TemporaryDirectory(prefix="firemedium-blender-") as d:
            d = Path(d)
            for f, src in [(7, "mantaflow_fire_f030.vdb"), (8, "mantaflow_fire_f060.vdb")]:
                (d / f"fire_{f:04d}.vdb").write_bytes((ROOT / "tests/data/valid/vdb" / src).read_bytes())
            self.assertEqual(addon.sequence_pattern(str(d / "fire_0007.vdb")), str(d / "fire_####.vdb"))
            obj = addon.import_fire(str(d / "fire_####.vdb"), {"source": "blender"}, baked=None, frames=(7, 8))
            vol = obj.data
            self.assertTrue(vol.is_sequence)
            self.assertEqual((vol.frame_start, vol.frame_duration), (7, 2))
            self.assertEqual(vol.velocity_grid, "velocity")
            seen = {}
            for frame in (7, 8):
                bpy.context.scene.frame_set(frame)
                grids = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.grids
                seen[frame] = Path(grids.frame_filepath).name
                self.assertEqual(sorted(g.name for g in grids), ["emission", "sigma_a", "sigma_s", "velocity"])
            self.assertTrue(seen[7].endswith("-0007.vdb") and seen[8].endswith("-0008.vdb"), seen)


if __name__ == "__main__":
    unittest.main()
