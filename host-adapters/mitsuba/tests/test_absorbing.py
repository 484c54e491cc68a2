"""The adapter's medium and `firepath` against Mitsuba's own `heterogeneous` medium over the same grid: an area
light behind a smoke blob in a box, lighting a floor under it — absorbing, and scattering (albedo 0.8, g 0.3).

The fire is an inline density grid in pbrt mode (σ_a, σ_s = scale · density, no emission); Mitsuba's
`heterogeneous` medium reads the same array as a `gridvolume` with the same σ_t, albedo, box and phase function.
Mitsuba's `volpath` over the adapter, `firepath` over the adapter and `firepath` over Mitsuba's own medium (which
it tracks as it tracks the fire) must each equal `volpath` over `heterogeneous` within four standard errors and
1 %, the light seen through the blob and the floor separately. The standard errors come from two independent
renders of each (their difference, pixel by pixel).
"""

import math
import unittest

import numpy as np

from common import mitsuba_or_skip

mi = mitsuba_or_skip()
import firemedium.mitsuba  # noqa: E402,F401 - registers the plugins

T = mi.ScalarTransform4f
N = 12  # grid cells per side
SPP = 256
RES = 32


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
            "type": "perspective", "fov": 40,
            "to_world": T().look_at(origin=[0, -3.2, 0.9], target=[0, 0, 0.3], up=[0, 0, 1]),
            "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": SPP},
        },
        "light": {"type": "rectangle", "to_world": T().translate([0, 1.5, 0.8]).rotate([1, 0, 0], 110).scale(1.5),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}}},
        "floor": {"type": "rectangle", "to_world": T().translate([0, 0, -0.01]).scale(4.0),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.5}}},
        "box": {"type": "cube", "to_world": T().translate([0, 0, 0.5]).scale(0.5),
                "bsdf": {"type": "null"}, "interior": medium},
    })


def fire(d: np.ndarray, albedo: float, g: float) -> dict:
    return {"type": "firemedium", "mode": "pbrt", "density": mi.VolumeGrid(d.astype(np.float32)),
            "p0": [-0.5, -0.5, 0.0], "p1": [0.5, 0.5, 1.0], "sigma_a": 1.0 - albedo, "sigma_s": albedo,
            "scale": 12.0, "g": g}


def grid(d: np.ndarray, albedo: float, g: float) -> dict:
    return {"type": "heterogeneous", "albedo": albedo, "scale": 12.0, "phase": {"type": "hg", "g": g},
            "sigma_t": {"type": "gridvolume", "grid": mi.VolumeGrid(d.astype(np.float32)),
                        "to_world": T().translate([-0.5, -0.5, 0.0])}}


def luminance(img) -> np.ndarray:
    a = np.array(img, dtype=np.float64)
    return a[..., 0] * 0.2126 + a[..., 1] * 0.7152 + a[..., 2] * 0.0722


def twice(sc) -> tuple[np.ndarray, np.ndarray]:
    """The render's mean of two independent renders and the per-pixel variance of that mean."""
    a, b = (luminance(mi.render(sc, seed=s)) for s in (11, 12))
    return (a + b) / 2, ((a - b) / 2) ** 2


class Media(unittest.TestCase):
    def test_the_adapter_and_firepath_equal_mitsubas_heterogeneous_medium(self):
        d = density()
        for albedo, g in ((0.0, 0.0), (0.8, 0.3)):
            ref, ref_var = twice(scene(grid(d, albedo, g), {"type": "volpath", "max_depth": 16}))
            # The light seen through the blob (the top rows, where the box hides the light) and the floor (the
            # bottom rows).
            regions = {"through the blob": np.s_[2:14, 10:22], "floor": np.s_[26:32, :]}
            for name, medium, integrator in [
                ("volpath over the adapter", fire(d, albedo, g), {"type": "volpath", "max_depth": 16}),
                ("firepath over the adapter", fire(d, albedo, g),
                 {"type": "firepath", "max_depth": 16, "fire_light": False}),
                ("firepath over heterogeneous", grid(d, albedo, g),
                 {"type": "firepath", "max_depth": 16, "fire_light": False}),
            ]:
                img, var = twice(scene(medium, integrator))
                for region, sl in regions.items():
                    n = img[sl].size
                    m, r = img[sl].mean(), ref[sl].mean()
                    se = math.sqrt((var[sl].sum() + ref_var[sl].sum()) / n ** 2)
                    z = (m - r) / se
                    print(f"albedo {albedo}, g {g}, {name}, {region}: {m:.5f} against {r:.5f} "
                          f"({m / r:.4f}), {z:+.2f} standard errors")
                    with self.subTest(albedo=albedo, integrator=name, region=region):
                        self.assertLess(abs(z), 4.0)
                        self.assertLess(abs(m / r - 1.0), 0.01 + 4.0 * se / r)
                        self.assertLess(4.0 * se / r, 0.02)


if __name__ == "__main__":
    unittest.main()
