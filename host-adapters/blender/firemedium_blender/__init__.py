"""firemedium for Blender: import a fire as a volume object whose Cycles material reads the fire's own coefficients.

The operator "Import firemedium fire" (File ▸ Import, or ``bpy.ops.firemedium.import_fire``) runs
``firemedium bake`` on a dataset (OpenVDB, NanoVDB, ...) with the fire's parameters, loads the baked grids —
``sigma_a``, ``sigma_s`` and ``emission``: linear Rec.709, per metre, emission in cd/m² per metre — as a volume
object, and gives it a material whose Volume Coefficients node takes the three grids directly (Blender 4.5+), so
Cycles renders the fire's physics (soot spectra, absolute Planck emission, the CIE observer) instead of a
blackbody ramp. A simulation's frames bake into a volume sequence, and a velocity in the dataset becomes the
volume's velocity grid for motion blur. A panel on the object (Properties ▸ Object ▸ firemedium fire) shows the fire's parameters and
re-bakes after one changes (``bpy.ops.firemedium.rebake``).

Where the bake goes: beside the saved ``.blend`` (``//firemedium/``, a path relative to it, which Blender remaps
when the file is saved elsewhere), else beside the dataset, or in a folder you choose — never Blender's temporary
folder, which Blender deletes when it quits. The add-on writes only its own bake files (``NAME-firemedium.vdb``)
and ``firemedium bake`` replaces only files it wrote.

Units: a Cycles render of the fire is in the same absolute units as ``firemedium render``'s EXR (Y in cd/m²).
The import sets the scene's view exposure from the baked fire's luminance as ``firemedium bake`` measures it
(the 99th percentile of its lines of sight from the side, two stops above mid-grey, as firemedium's AgX preview
does), so the fire reads at once.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
from pathlib import Path

import bpy
from bpy.props import BoolProperty, FloatProperty, IntProperty, StringProperty

bl_info = {
    "name": "firemedium",
    "author": "firemedium",
    "version": (0, 1, 0),
    "blender": (4, 5, 0),
    # (Blender 4.2+ installs the same module as an extension: blender_manifest.toml beside this file.)
    "location": "File > Import > firemedium fire",
    "description": "Physically based fire (Pegoraro & Parker 2006) baked to Cycles' Volume Coefficients",
    "category": "Import-Export",
}

GRIDS = ("sigma_a", "sigma_s", "emission")


def firemedium_command() -> str:
    """The `firemedium` command: FIREMEDIUM_COMMAND, else the one on the PATH."""
    exe = os.environ.get("FIREMEDIUM_COMMAND") or shutil.which("firemedium")
    if not exe:
        raise RuntimeError("firemedium: no firemedium command (install it with tools/install.sh, or set FIREMEDIUM_COMMAND)")
    return exe


# What the add-on's bake files end with: it writes and re-bakes no other file.
BAKE_SUFFIX = "-firemedium"


def bake(dataset: str, output: str, params: dict[str, object],
         frames: tuple[int, int] | None = None) -> list[dict]:
    """Runs `firemedium bake` (`frames`: a sequence, the names holding ####) and returns its JSON reports, one per
    frame (the file, the fire's luminance seen from its side, the exposure that shows it). The dataset is passed
    after `--` (a name starting with '-' is a file, not an option) and every parameter as one `--param=NAME=VALUE`
    word. Raises RuntimeError with the command's one-line message."""
    args = [firemedium_command(), "bake", "--json", "-o", output]
    if frames is not None:
        args.append(f"--frames={frames[0]}-{frames[1]}")
    for k, v in params.items():
        args.append(f"--param={k}={str(v).lower() if isinstance(v, bool) else v}")
    args += ["--", dataset]
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr.strip())
    return [json.loads(line) for line in r.stdout.splitlines() if line.strip()]


def bake_path(dataset: str, directory: str | None = None, sequence: bool = False) -> str:
    """Where the add-on bakes `dataset`, as Blender stores it: in `directory` (a folder, `//` relative to the
    .blend allowed) when given; else `//firemedium/` beside the saved .blend; else beside the dataset. The file is
    the dataset's name with -firemedium (and -#### for a sequence). Never Blender's temporary folder, which it
    deletes on quitting."""
    stem = Path(dataset).stem.replace("#", "").rstrip("_-.") or "fire"
    name = stem + BAKE_SUFFIX + ("-####" if sequence else "") + ".vdb"
    if directory:
        folder = directory
    elif bpy.data.filepath:
        folder = "//firemedium"
    else:
        folder = os.path.dirname(os.path.abspath(dataset))
    temp = Path(bpy.app.tempdir).resolve() if bpy.app.tempdir else None
    if temp is not None and Path(bpy.path.abspath(folder)).resolve().is_relative_to(temp):
        raise RuntimeError(f"{folder}: inside Blender's temporary folder, which Blender deletes on quitting; "
                           "choose another folder")
    return folder.rstrip("/\\") + "/" + name


def is_own_bake(path: str) -> bool:
    """Whether `path` is a name the add-on bakes into (NAME-firemedium.vdb, NAME-firemedium-####.vdb)."""
    stem = Path(path).name
    return stem.endswith(BAKE_SUFFIX + ".vdb") or stem.endswith(BAKE_SUFFIX + "-####.vdb")


def fire_material(name: str, g: float = 0.0) -> bpy.types.Material:
    """A volume material: Attribute nodes for the three grids into Volume Coefficients (Henyey–Greenstein g)."""
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    coef = nt.nodes.new("ShaderNodeVolumeCoefficients")
    coef.inputs["Anisotropy"].default_value = g
    sockets = {"sigma_a": "Absorption Coefficients", "sigma_s": "Scatter Coefficients", "emission": "Emission Coefficients"}
    for i, (grid, socket) in enumerate(sockets.items()):
        a = nt.nodes.new("ShaderNodeAttribute")
        a.attribute_type = "GEOMETRY"
        a.attribute_name = grid
        a.location = (-400, 200 - 200 * i)
        nt.links.new(a.outputs["Vector"], coef.inputs[socket])
    nt.links.new(coef.outputs["Volume"], out.inputs["Volume"])
    coef.location = (-150, 0)
    return m


def frame_name(pattern: str, frame: int) -> str:
    """`pattern` with its #### (the frame number, zero-padded to the run of #) filled in."""
    start = pattern.find("#")
    if start < 0:
        return pattern
    end = start
    while end < len(pattern) and pattern[end] == "#":
        end += 1
    return pattern[:start] + str(frame).zfill(end - start) + pattern[end:]


def sequence_pattern(path: str) -> str:
    """A frame file's name with its frame number as #### (`fire_0042.vdb` → `fire_####.vdb`); unchanged without one."""
    p = Path(path)
    stem = p.stem
    digits = len(stem) - len(stem.rstrip("0123456789"))
    if digits == 0:
        return path
    return str(p.with_name(stem[:-digits] + "#" * digits + p.suffix))


def import_fire(dataset: str, params: dict[str, object] | None = None, baked: str | None = None,
                name: str = "fire", frames: tuple[int, int] | None = None, directory: str | None = None,
                exposure: bool = True) -> bpy.types.Object:
    """Bakes `dataset` (unless `baked` names grids already baked) into `bake_path(dataset, directory)` and links
    a volume object using them, selected and active; with `exposure`, sets the scene's view exposure to show the
    fire (the bake's measure of its luminance) and the view transform to AgX.

    `frames` (first, last): a simulation's frames, the dataset's and the baked names holding #### — baked one by one
    and loaded as a volume sequence playing frame f of the scene from frame f of the files. A velocity in the
    dataset is baked beside the coefficients and named as the volume's velocity grid (Cycles' motion blur)."""
    params = dict(params or {})
    reports: list[dict] = []
    if baked is None:
        baked = bake_path(dataset, directory, frames is not None)
        target = bpy.path.abspath(baked)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        reports = bake(dataset, target, params, frames)
    vol = bpy.data.volumes.new(name)
    if frames is not None:
        first, last = frames
        vol.filepath = frame_name(baked, first)
        vol.is_sequence = True
        # Blender plays file number (scene frame − start + 1 + offset): files numbered as the scene's frames.
        vol.frame_start = first
        vol.frame_offset = first - 1
        vol.frame_duration = last - first + 1
    else:
        vol.filepath = baked
    vol.grids.load()
    if any(g.name == "velocity" for g in vol.grids):
        vol.velocity_grid = "velocity"
        vol.velocity_unit = "SECOND"
    obj = bpy.data.objects.new(name, vol)
    bpy.context.scene.collection.objects.link(obj)
    vol.materials.append(fire_material(name + " material"))
    # Selected and active, as an imported object is.
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    stops = [r["exposure"] for r in reports if r.get("exposure") is not None]
    if exposure and stops:
        view = bpy.context.scene.view_settings
        view.view_transform = "AgX"
        # The brightest frame's: the sequence never clips harder than its brightest frame.
        view.exposure = min(stops)
    # What re-baking needs, on the object: the dataset, the baked file and the fire's parameters (edited in the
    # panel, or as the object's custom properties).
    obj["firemedium_dataset"] = dataset
    obj["firemedium_baked"] = baked
    obj["firemedium_params"] = {k: v for k, v in params.items()}
    if frames is not None:
        obj["firemedium_frames"] = list(frames)
    return obj


def rebake(obj: bpy.types.Object) -> str:
    """Bakes `obj`'s dataset again with its (edited) parameters into its bake file, and reloads the grids. Only a
    file the add-on names as its own (NAME-firemedium.vdb) is written — a .blend's saved properties cannot make it
    write anywhere else — and `firemedium bake` itself replaces only files it wrote."""
    if "firemedium_dataset" not in obj:
        raise RuntimeError(f"{obj.name} is not a firemedium fire (import one with File > Import > firemedium fire)")
    baked = str(obj["firemedium_baked"])
    if not is_own_bake(baked):
        raise RuntimeError(f"{baked}: not a firemedium bake file (NAME{BAKE_SUFFIX}.vdb); re-import the fire")
    params = {k: v for k, v in obj["firemedium_params"].items()}
    frames = tuple(obj["firemedium_frames"]) if "firemedium_frames" in obj else None
    reports = bake(str(obj["firemedium_dataset"]), bpy.path.abspath(baked), params, frames)
    obj.data.grids.unload()
    obj.data.filepath = frame_name(baked, frames[0]) if frames else baked
    obj.data.update_tag()
    return "\n".join(json.dumps(r) for r in reports)


def exposure_for(luminance_cd_m2: float) -> float:
    """The view exposure (stops) that shows a luminance as mid-grey."""
    return -math.log2(max(luminance_cd_m2, 1e-9) / 0.18)


def render_settings(scene: bpy.types.Scene, samples: int = 64) -> None:
    """Cycles on the CPU with a volume step of the voxel and bounces enough for a fire over surfaces."""
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.volume_step_rate = 1.0
    scene.cycles.volume_bounces = 1
    scene.cycles.max_bounces = 4
    scene.view_settings.view_transform = "AgX"


class FIREMEDIUM_OT_import(bpy.types.Operator):
    """Import a fire dataset as a firemedium volume (bakes it with the firemedium command)"""

    bl_idname = "firemedium.import_fire"
    bl_label = "Import firemedium fire"
    bl_options = {"REGISTER", "UNDO"}

    filepath: StringProperty(subtype="FILE_PATH")
    fuel: StringProperty(name="Fuel", default="propane")
    temperaturescale: FloatProperty(name="Temperature scale", default=0.0, min=0.0,
                                    description="Kelvin per unit of the temperature grid; 0: found from the data")
    sootscale: FloatProperty(name="Soot scale", default=0.0, min=0.0,
                             description="Soot volume fraction per unit density; 0: found from the data")
    sequence: BoolProperty(name="Sequence", default=False,
                           description="The file is one frame of a simulation: bake frames First to Last")
    frame_first: IntProperty(name="First", default=1)
    frame_last: IntProperty(name="Last", default=1)
    directory_bake: StringProperty(name="Bake folder", subtype="DIR_PATH", default="",
                                   description="Where the baked grids go (default: //firemedium beside the saved "
                                               ".blend, else beside the dataset)")

    def execute(self, context):
        # Unset scales are the fire's own choices (a simulator's density and temperature read from the data).
        params = {"fuel": self.fuel}
        if self.temperaturescale > 0.0:
            params["temperaturescale"] = self.temperaturescale
        if self.sootscale > 0.0:
            params["sootscale"] = self.sootscale
        try:
            if self.sequence:
                if self.frame_last < self.frame_first:
                    raise RuntimeError(f"frames {self.frame_first}-{self.frame_last}: the last is before the first")
                pattern = sequence_pattern(self.filepath)
                if pattern == self.filepath:
                    raise RuntimeError(f"{self.filepath}: no frame number at the end of its name (fire_0001.vdb)")
                import_fire(pattern, params, frames=(self.frame_first, self.frame_last),
                            directory=self.directory_bake or None)
            else:
                import_fire(self.filepath, params, directory=self.directory_bake or None)
        except RuntimeError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


class FIREMEDIUM_OT_rebake(bpy.types.Operator):
    """Bake the active firemedium fire again with its parameters"""

    bl_idname = "firemedium.rebake"
    bl_label = "Re-bake firemedium fire"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.object is not None and "firemedium_dataset" in context.object

    def execute(self, context):
        try:
            rebake(context.object)
        except RuntimeError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}


class FIREMEDIUM_PT_fire(bpy.types.Panel):
    """The fire's main parameters, and the button that re-bakes it (Properties ▸ Object)."""

    bl_label = "firemedium fire"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "object"

    @classmethod
    def poll(cls, context):
        return context.object is not None and "firemedium_dataset" in context.object

    def draw(self, context):
        obj = context.object
        self.layout.label(text=str(obj["firemedium_dataset"]))
        params = obj["firemedium_params"]
        for key in params.keys():
            self.layout.prop(params, f'["{key}"]', text=key)
        self.layout.operator(FIREMEDIUM_OT_rebake.bl_idname)


def menu(self, context):
    self.layout.operator(FIREMEDIUM_OT_import.bl_idname, text="firemedium fire (.vdb)")


CLASSES = (FIREMEDIUM_OT_import, FIREMEDIUM_OT_rebake, FIREMEDIUM_PT_fire)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.TOPBAR_MT_file_import.append(menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu)
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
