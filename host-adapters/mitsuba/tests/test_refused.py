"""What the medium level cannot express is refused when the scene loads, naming it — never a silently wrong fire."""

import unittest
from pathlib import Path

from common import mitsuba_or_skip, repository

mi = mitsuba_or_skip()
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


if __name__ == "__main__":
    unittest.main()
