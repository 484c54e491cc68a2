"""The campfire in Mitsuba 3: the fire as a `firemedium` medium inside a null-BSDF box on a diffuse floor, before a
wall, beside a copper ball and a small lamp of Mitsuba's own, rendered by `firepath` (Mitsuba's volumetric path
tracing plus the fire's emission and the fire light), written as EXR — the scene below as a Python dict, or any
Mitsuba XML scene that names the plugins (`--xml`, e.g. campfire.xml beside this file).

    python3 host-adapters/mitsuba/examples/campfire.py [--size 256] [--spp 64] [--variant llvm_ad_rgb]
        [--no-fire-light] [--xml SCENE.xml] [-o campfire-mitsuba.exr]

The EXR is Mitsuba's (relative units: multiply Y by 683 × 106.857 for cd/m²).
"""

import argparse
import time
from pathlib import Path

import mitsuba as mi

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--size", type=int, default=256, help="image width and height (the dict scene)")
parser.add_argument("--spp", type=int, default=64, help="samples per pixel (the dict scene)")
parser.add_argument("--variant", default="llvm_ad_rgb", help="a vectorised Mitsuba variant (llvm_ad_spectral, cuda_ad_rgb …)")
parser.add_argument("--no-fire-light", action="store_true", help="leave next-event estimation to the fire out")
parser.add_argument("--xml", help="render this Mitsuba XML scene instead of the dict")
parser.add_argument("-o", "--output", default="campfire-mitsuba.exr")
args = parser.parse_args()

mi.set_variant(args.variant)
import firemedium.mitsuba  # noqa: E402,F401 - registers "firemedium" and "firepath"

T = mi.ScalarTransform4f
dataset = str(Path(__file__).resolve().parents[3] / "scenes" / "campfire" / "campfire.vdb")
start = time.time()
if args.xml:
    scene = mi.load_file(args.xml)
else:
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "firepath", "max_depth": 4, "fire_light": not args.no_fire_light},
        "sensor": {
            "type": "perspective", "fov": 40,
            "to_world": T().look_at(origin=[0, -4.2, 1.6], target=[0, 0, 0.55], up=[0, 0, 1]),
            "film": {"type": "hdrfilm", "width": args.size, "height": args.size},
            "sampler": {"type": "independent", "sample_count": args.spp},
        },
        # Mitsuba's own BSDFs beside the fire: a diffuse floor and a rough copper sphere.
        "floor": {"type": "rectangle", "to_world": T().scale([10, 10, 1]),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.5}}},
        "wall": {"type": "rectangle", "to_world": T().translate([0, 2.0, 2.0]).rotate([1, 0, 0], 90).scale([4, 2, 1]),
                 "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.6}}},
        "ball": {"type": "sphere", "center": [0.95, -0.3, 0.25], "radius": 0.25,
                 "bsdf": {"type": "roughconductor", "material": "Cu", "alpha": 0.2}},
        # Mitsuba's own emitter beside the fire: a dim blue lamp (its shadow rays are attenuated through the fire).
        "lamp": {"type": "sphere", "center": [-1.4, -0.6, 1.8], "radius": 0.1,
                 "emitter": {"type": "area", "radiance": {"type": "rgb", "value": [0.05, 0.08, 0.2]}}},
        # The fire: its medium space is the dataset's ([-0.6, 0.6]² × [0, 1.6] m, z up); the box just above the floor.
        "fire": {"type": "cube", "to_world": T().translate([0, 0, 0.8025]).scale([0.6, 0.6, 0.7975]),
                 "bsdf": {"type": "null"},
                 "interior": {"type": "firemedium", "filename": dataset, "fuel": "propane"}},
    })
loaded = time.time()
image = mi.render(scene)
mi.Bitmap(image).write(args.output)
size = scene.sensors()[0].film().size()
spp = scene.sensors()[0].sampler().sample_count()
print(f"wrote {args.output} ({size[0]}×{size[1]}, {spp} spp, {args.variant}): loaded in {loaded - start:.1f} s, "
      f"rendered in {time.time() - loaded:.1f} s")
