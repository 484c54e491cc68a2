"""An absorbing fire through the adapter equals Mitsuba's own `heterogeneous` medium over the same grid.

The fire is an inline density grid in pbrt mode (σ_a = scale · density, grey, no scattering, no emission); Mitsuba's
`heterogeneous` medium reads the same array as a `gridvolume` with the same scale and box. Both stand between the
camera and a uniform area light, so each pixel is the light's radiance times the transmittance along its rays; the
delta-tracking estimates are 0 or the light's radiance, so the noise of a mean over N samples of a pixel whose
transmittance is T is L·sqrt(T (1 − T) / N), summed over the pixels.
"""

import math
import unittest

import numpy as np

from common import mitsuba_or_skip

mi = mitsuba_or_skip()
import firemedium.mitsuba  # noqa: E402,F401 - registers the plugins

T = mi.ScalarTransform4f
N = 12  # grid cells per side
SPP = 64
RES = 24


def density() -> np.ndarray:
    """A blob of smoke in a grid whose outer layer is 0 (pbrt-v4's lookup fades to 0 outside the samples,
    Mitsuba's clamps to the edge: with zero edges the two lookups agree everywhere)."""
    c = (np.arange(N) + 0.5) / N - 0.5
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    d = np.exp(-((x - 0.1) ** 2 + y**2 + (z + 0.05) ** 2) / 0.04) + 0.3 * np.exp(-((x + 0.2) ** 2 + (y - 0.15) ** 2 + z**2) / 0.01)
    d[0, :, :] = d[-1, :, :] = d[:, 0, :] = d[:, -1, :] = d[:, :, 0] = d[:, :, -1] = 0.0
    return d


def scene(medium: dict, integrator: dict) -> "mi.Scene":
    return mi.load_dict({
        "type": "scene",
        "integrator": integrator,
        "sensor": {
            "type": "perspective", "fov": 30,
            "to_world": T().look_at(origin=[0, -3.2, 0.5], target=[0, 0, 0.5], up=[0, 0, 1]),
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": SPP, "seed": 3},
        },
        "light": {"type": "rectangle", "to_world": T().translate([0, 1.5, 0.5]).rotate([1, 0, 0], 90).scale(2.0),
                  "emitter": {"type": "area", "radiance": {"type": "spectrum", "value": 1.0}}},
        "box": {"type": "cube", "to_world": T().translate([0, 0, 0.5]).scale(0.5),
                "bsdf": {"type": "null"}, "interior": medium},
    })


def fire(d: np.ndarray) -> dict:
    return {"type": "firemedium", "mode": "pbrt", "density": mi.VolumeGrid(d.astype(np.float32)),
            "p0": [-0.5, -0.5, 0.0], "p1": [0.5, 0.5, 1.0], "sigma_s": 0.0, "scale": 12.0}


def grid(d: np.ndarray) -> dict:
    return {"type": "heterogeneous", "albedo": 0.0, "scale": 12.0,
            "sigma_t": {"type": "gridvolume", "grid": mi.VolumeGrid(d.astype(np.float32)),
                        "to_world": T().translate([-0.5, -0.5, 0.0])}}


def luminance(img) -> np.ndarray:
    a = np.array(img, dtype=np.float64)
    return a[..., 0] * 0.2126 + a[..., 1] * 0.7152 + a[..., 2] * 0.0722


class AbsorbingFire(unittest.TestCase):
    def test_the_adapter_equals_mitsubas_heterogeneous_medium(self):
        d = density()
        ref = luminance(mi.render(scene(grid(d), {"type": "volpath", "max_depth": 8})))
        # The light seen through the box (rows and columns the box covers).
        lit = ref > 1e-6
        t = np.clip(ref / ref.max(), 0.0, 1.0)
        sigma = ref.max() * math.sqrt(np.sum(t * (1.0 - t)) / SPP) / lit.sum()
        # Mitsuba's volpath over the adapter's medium, and the adapter's own integrator.
        for name, integrator in [("volpath", {"type": "volpath", "max_depth": 8}),
                                 ("firepath", {"type": "firepath", "max_depth": 8, "fire_light": False})]:
            img = luminance(mi.render(scene(fire(d), integrator), seed=11))
            diff = img[lit].mean() - ref[lit].mean()
            z = diff / (math.sqrt(2.0) * sigma)
            print(f"absorbing fire, {name}: mean {img[lit].mean():.5f} against heterogeneous {ref[lit].mean():.5f}"
                  f" (transmittance {ref[lit].mean() / ref.max():.3f}), {z:+.2f} standard deviations")
            self.assertLess(abs(z), 4.0, name)
            # And the fire is really there: the blob darkens the light.
            self.assertLess(img.min(), 0.5 * ref.max())


if __name__ == "__main__":
    unittest.main()
