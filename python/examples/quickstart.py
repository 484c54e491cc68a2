"""firemedium from Python: a fire from a dataset, the three questions a renderer asks of it, and a small picture.

    python3 python/examples/quickstart.py [DATASET]

Prints what the fire is, the coefficients at a point at four wavelengths, the radiance along a ray (the fast path)
and the fire light's power, then writes quickstart.pgm: the fire's luminance seen by a pinhole camera (64 × 64).
"""

import sys
from pathlib import Path

import numpy as np

import firemedium

dataset = sys.argv[1] if len(sys.argv) > 1 else str(Path(__file__).resolve().parents[2] / "scenes/campfire/campfire.vdb")
fire = firemedium.Volume({"filename": dataset, "fuel": "propane"})
print(fire)
print("temperatures %.0f–%.0f K" % fire.temperature_range())

# The medium level: σ_a, σ_s, Le and j at a point, at a path's four wavelengths (what pbrt-v4 and Mitsuba ask).
lo, hi = np.array(fire.bounds)
centre = (lo + hi) / 2 * [1, 1, 0.5]
c = fire.point([centre], [450.0, 550.0, 600.0, 650.0])
print("at", centre.round(3), "σ_a", c["sigma_a"][0].round(3), "1/m; Le", c["le"][0].round(4), "W/(m² sr nm)")

# The fast path: radiance and transmittance along whole rays, in the fire's channels; Y through the film weights.
y = fire.channel_xyz()[:, 1]
eye = np.array([0.0, lo[1] - 3.0 * (hi[1] - lo[1]), centre[2]])
radiance, transmittance = fire.integrate([eye], [centre - eye])
print("looking through the middle: %.1f cd/m², transmittance %.3f" % (radiance[0] @ y, transmittance[0].mean()))

# The fire light: its power, and a point sampled by it.
light = fire.light()
points, pdf, _ = light.sample(np.random.default_rng(1).random((1, 6)))
print("the fire radiates %.4g W; a sampled point %s (density %.3g per m³)" % (light.power_w, points[0].round(3), pdf[0]))

# A picture: 64 × 64 rays from the eye, one batch per row.
n = 64
top = np.array([0.0, 0.0, 1.0]) * (hi[2] - lo[2]) * 0.6
side = np.array([1.0, 0.0, 0.0]) * (hi[2] - lo[2]) * 0.6
image = np.zeros((n, n))
for j in range(n):
    targets = [centre + top * (1 - 2 * (j + 0.5) / n) + side * (2 * (i + 0.5) / n - 1) for i in range(n)]
    rad, _ = fire.integrate(np.repeat([eye], n, axis=0), np.array(targets) - eye)
    image[j] = rad @ y
grey = (255 * (image / image.max()) ** (1 / 2.2)).astype(np.uint8)
Path("quickstart.pgm").write_bytes(b"P5 %d %d 255\n" % (n, n) + grey.tobytes())
print("wrote quickstart.pgm (brightest pixel %.0f cd/m²)" % image.max())
