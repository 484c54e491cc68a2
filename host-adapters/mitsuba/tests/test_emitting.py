"""An emitting fire lighting a floor renders in Mitsuba (through the adapter and `firepath`) as `firemedium render`
renders the same scene written for pbrt-v4 (tests/data/scenes/campfire-floor.pbrt): the flame's luminance and the
floor's, in absolute units.

Mitsuba's spectral film is relative (a constant spectrum of 1 W·m⁻²·sr⁻¹·nm⁻¹ gives Y = 1); firemedium's is in
cd/m², so Mitsuba's Y is multiplied by 683 lm/W × ∫ȳ dλ (106.857 nm). Mitsuba's camera is right-handed and
pbrt-v4's left-handed: the Mitsuba camera is mirrored in x so the two images line up pixel for pixel; both films
use a box pixel filter (pbrt-v4's default Gaussian spreads the flame's light over its neighbours: 3 % on the floor's
rows).
"""

import math
import os
import subprocess
import tempfile
import unittest
from pathlib import Path

import numpy as np

from common import command, mitsuba_or_skip, repository

mi = mitsuba_or_skip()
import firemedium.mitsuba  # noqa: E402,F401 - registers the plugins

T = mi.ScalarTransform4f
RES = 32
SPP = 128
K = 683.0 * 106.856895
def mitsuba_scene(dataset: str, fire_light: bool = True, spp: int = SPP, **fire) -> dict:
    return {
        "type": "scene",
        # max_depth 2 is pbrt-v4's maxdepth 2 here: the floor lit by the fire, nothing further.
        "integrator": {"type": "firepath", "max_depth": 2, "fire_light": fire_light},
        "sensor": {
            "type": "perspective", "fov": 40, "fov_axis": "smaller",
            "to_world": T().look_at(origin=[0, -4.2, 1.6], target=[0, 0, 0.55], up=[0, 0, 1]) @ T().scale([-1, 1, 1]),
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "floor": {"type": "rectangle", "to_world": T().scale([10, 10, 1]),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.5}}},
        "fire": {"type": "cube", "to_world": T().translate([0, 0, 0.8025]).scale([0.6, 0.6, 0.7975]),
                 "bsdf": {"type": "null"},
                 "interior": {"type": "firemedium", "filename": dataset, "fuel": "propane",
                              "firescale": 15, "smokescale": 15, **fire}},
    }


def luminance(a) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)[..., :3]
    return a[..., 0] * 0.2126 + a[..., 1] * 0.7152 + a[..., 2] * 0.0722


class EmittingFire(unittest.TestCase):
    SCENE = "campfire-floor.pbrt"
    FIRE: dict = {}

    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.TemporaryDirectory(prefix="firemedium-mitsuba-")
        d = Path(cls.dir.name)
        cls.dataset = str(repository() / "scenes" / "campfire" / "campfire.vdb")
        scene = repository() / "tests" / "data" / "scenes" / cls.SCENE
        subprocess.run([command(), "render", str(scene), "-o", str(d / "ref.exr"), "--quiet"], check=True)
        cls.ref = luminance(mi.Bitmap(str(d / "ref.exr")))

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def test_the_flame_and_the_floor_it_lights_match_firemedium_render(self):
        # Two independent halves of the samples: their mean is the render, their difference its noise.
        halves = [luminance(mi.render(mi.load_dict(mitsuba_scene(self.dataset, spp=SPP // 2, **self.FIRE)), seed=s)) * K
                  for s in (5, 6)]
        img = (halves[0] + halves[1]) / 2
        ref = self.ref
        flame = ref > 0.05 * ref.max()
        floor = np.zeros_like(flame)
        floor[-8:, :] = True
        floor &= ~flame
        r_flame = img[flame].mean() / ref[flame].mean()
        r_floor = img[floor].mean() / ref[floor].mean()
        # The same image within noise: the squared differences to the reference against the render's own variance
        # (of a mean of two halves: ((a − b) / 2)², pixel by pixel) — about 1 when they differ by noise alone.
        noise = ((halves[0] - halves[1]) / 2) ** 2
        chi = np.sum((img - ref) ** 2) / np.sum(noise)
        print(f"{self.SCENE}: flame {img[flame].mean():.1f} cd/m² against {ref[flame].mean():.1f} ({r_flame:.4f}); "
              f"floor {img[floor].mean():.3f} against {ref[floor].mean():.3f} ({r_floor:.4f}); squared difference "
              f"{chi:.2f}× the render's variance; correlation {np.corrcoef(img.ravel(), ref.ravel())[0, 1]:.4f}")
        # The flame's mean within 1 % and the floor's within 2 %, each plus three of its standard errors (the
        # pixels' variance from the halves).
        sigma = math.sqrt(noise[flame].sum()) / flame.sum() / ref[flame].mean()
        sigma_floor = math.sqrt(noise[floor].sum()) / floor.sum() / ref[floor].mean()
        print(f"  the flame's ratio {r_flame:.4f} ± {sigma:.4f}, the floor's {r_floor:.4f} ± {sigma_floor:.4f} (one "
              f"standard error; {flame.sum()} and {floor.sum()} pixels)")
        self.assertLess(abs(r_flame - 1.0), 0.01 + 3.0 * sigma)
        self.assertLess(abs(r_floor - 1.0), 0.02 + 3.0 * sigma_floor)
        self.assertLess(sigma, 0.05)
        self.assertLess(sigma_floor, 0.035)
        self.assertLess(chi, 2.0)



class ScatteringEmittingFire(EmittingFire):
    """The same fire, its smoke scattering (albedo ≈ 0.2, g 0.6): the fire's own light scattered in its smoke and
    the floor's light through it, Mitsuba's Henyey–Greenstein taking the fire's g."""

    SCENE = "campfire-floor-scattering.pbrt"
    FIRE = {"look": "campfire"}

    def test_the_fire_gives_mitsuba_its_g(self):
        medium = mi.load_dict({"type": "firemedium", "filename": self.dataset, **self.FIRE})
        self.assertAlmostEqual(float(mi.traverse(medium.phase_function())["g"][0]), 0.6, places=6)
        # The same g given as Mitsuba's phase function is the fire's; another is refused, naming both.
        mi.load_dict({"type": "firemedium", "filename": self.dataset, "phase": {"type": "hg", "g": 0.6}, **self.FIRE})
        with self.assertRaises(Exception) as e:
            mi.load_dict({"type": "firemedium", "filename": self.dataset, "phase": {"type": "hg", "g": 0.2},
                          **self.FIRE})
        self.assertIn("0.6", str(e.exception))
        self.assertIn("phase", str(e.exception))


if __name__ == "__main__":
    unittest.main()
