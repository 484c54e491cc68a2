"""What the medium level cannot express is refused when the scene loads, naming it — never a silently wrong fire;
what the closed form cannot express (atomic lines) is baked as coefficients instead."""

import unittest
from pathlib import Path

from common import mitsuba_or_skip, repository

mi = mitsuba_or_skip()
import drjit as dr  # noqa: E402
import numpy as np  # noqa: E402

import firemedium  # noqa: E402
import firemedium.mitsuba  # noqa: E402,F401


class Refused(unittest.TestCase):
    def test_a_refracting_fire_is_refused_naming_refraction(self):
        campfire = str(repository() / "scenes" / "campfire" / "campfire.vdb")
        with self.assertRaises(Exception) as e:
            mi.load_dict({"type": "scene", "box": {"type": "cube", "bsdf": {"type": "null"},
                          "interior": {"type": "firemedium", "filename": campfire, "refraction": True}}})
        self.assertIn("refraction", str(e.exception))
        self.assertIn("firemedium render", str(e.exception))

    def test_a_bad_parameter_is_the_plugins_error(self):
        with self.assertRaises(Exception) as e:
            mi.load_dict({"type": "scene", "box": {"type": "cube", "bsdf": {"type": "null"},
                          "interior": {"type": "firemedium", "filename": "no-such-fire.vdb"}}})
        self.assertIn("no-such-fire.vdb", str(e.exception))

    def test_a_fire_with_atomic_lines_is_baked_as_coefficients(self):
        # The sodium torch: a species grid (its D lines, thin: box-shaped in their bins) beside the soot — not the
        # closed form.
        torch = str(repository() / "scenes" / "spectroscopy" / "torch.vdb")
        fire = {"type": "firemedium", "filename": torch, "species": "Na", "speciesscale": 0.5, "sootscale": 1e-6,
                "lineshape": "box"}
        with self.assertRaises(firemedium.FiremediumError) as e:
            firemedium.Volume({"dataset": torch, "species": "Na", "speciesscale": 0.5}).tables()
        self.assertIn("atomic lines", str(e.exception))
        medium = mi.load_dict(fire)
        self.assertIsNone(medium._tables)
        # At a voxel centre the baked emission is the plugin's coefficients there, in the variant's colours.
        (nx, ny, nz), lo, hi = medium.volume.lattice
        p = [lo[a] + (hi[a] - lo[a]) * (n // 2 + 0.5) / n for a, n in enumerate((nx, ny, nz))]
        _, _, j = medium.volume.coefficients([p])
        want = (j.astype(float) @ medium._channel_weights()[1])[0] / medium.scale
        mei = dr.zeros(mi.MediumInteraction3f)
        mei.p = mi.Point3f(*p)
        if mi.is_spectral:
            # Four bins, each read at its centre.
            bins = [3, 8, 12, 20]
            l0, l1 = medium.volume.wavelength_range
            mei.wavelengths = mi.Spectrum(*[l0 + (b + 0.5) * (l1 - l0) / medium.channels for b in bins])
            want = want[bins]
        got = np.array(medium.emission(mei)).ravel()
        self.assertGreater(want.max(), 0.0)
        np.testing.assert_allclose(got, want, rtol=1e-4)


if __name__ == "__main__":
    unittest.main()
