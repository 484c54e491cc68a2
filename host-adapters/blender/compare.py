"""The campfire over a grey floor three ways, side by side: `firemedium render`, Cycles with the baked grids (the
add-on), and Cycles' own Principled Volume blackbody on the dataset's grids — the picture and the numbers of the
Blender guide (docs/guide/blender.md, docs/results/log.md).

    python3 host-adapters/blender/compare.py [--size 160x120] [--spp 64] [-o docs/img/blender-side-by-side.png]

Needs `bpy` (pip install bpy, 4.5 for Python 3.11) and the release build. Prints, per render, its time and the
flame's and the floor's mean luminance (cd/m²) and the flame's chromaticity; writes the three at one exposure (the
flame's mean luminance of firemedium's render as mid-grey), sRGB, left to right.
"""

import argparse
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(HERE / "tests"))
sys.path.insert(0, str(HERE))

import bpy  # noqa: E402

import test_cycles as tc  # noqa: E402


def srgb(v: np.ndarray) -> np.ndarray:
    v = np.clip(v, 0.0, 1.0)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("-o", "--output", default=str(ROOT / "docs" / "img" / "blender-side-by-side.png"))
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    exe = tc.command()
    dataset = str(ROOT / "scenes" / "campfire" / "campfire.vdb")
    images, seconds = {}, {}
    with tempfile.TemporaryDirectory(prefix="firemedium-compare-") as d:
        d = Path(d)
        t = time.perf_counter()
        subprocess.run([exe, "render", str(ROOT / "tests/data/scenes/campfire-floor.pbrt"), "-o", str(d / "ref.exr"),
                        "--resolution", f"{w}x{h}", "--spp", str(a.spp), "--quiet"], check=True)
        seconds["firemedium render"] = time.perf_counter() - t
        images["firemedium render"] = tc.read_rgb(d / "ref.exr")
        for kind, label in (("baked", "Cycles, baked grids"), ("blackbody", "Cycles, Principled Volume blackbody")):
            t = time.perf_counter()
            tc.cycles_scene(dataset, d / f"{kind}.exr", size=(w, h), spp=a.spp, fire=kind)
            seconds[label] = time.perf_counter() - t
            images[label] = tc.read_rgb(d / f"{kind}.exr")[:, ::-1]
    ref = images["firemedium render"]
    y_ref = ref @ tc.M[1]
    flame = y_ref > 0.05 * y_ref.max()
    floor = np.zeros_like(flame)
    floor[-h // 4:, :] = True
    floor &= ~flame
    for label, img in images.items():
        y = img @ tc.M[1]
        X = img[flame].sum(axis=0) @ tc.M.T
        xy = X[:2] / X.sum()
        print(f"{label}: {seconds[label]:.1f} s; flame {y[flame].mean():.4g} cd/m² ({y[flame].mean() / y_ref[flame].mean():.4f} "
              f"of firemedium's), floor {y[floor].mean():.4g} ({y[floor].mean() / y_ref[floor].mean():.4f}), "
              f"flame xy ({xy[0]:.4f}, {xy[1]:.4f})")
    # One exposure: firemedium's flame mean as mid-grey. The blackbody's level is Cycles' own (σT⁴ × 1e-6/π per
    # metre, whatever the soot), far from the fire's: its panel is brought to the same flame mean, and by how much
    # is printed.
    k = 0.18 / y_ref[flame].mean()
    gains = {label: k for label in images}
    bb = "Cycles, Principled Volume blackbody"
    y_bb = (images[bb] @ tc.M[1])[flame].mean()
    if y_bb > 0:
        gains[bb] = 0.18 / y_bb
        print(f"{bb}: shown {math.log2(gains[bb] / k):+.1f} stops brighter than the others (×{gains[bb] / k:.3g})")
    strip = np.concatenate([srgb(images[label] * gains[label]) for label in images], axis=1)
    pic = bpy.data.images.new("side-by-side", width=strip.shape[1], height=h, alpha=False)
    rgba = np.concatenate([strip, np.ones((h, strip.shape[1], 1))], axis=2)[::-1]
    pic.pixels[:] = rgba.ravel().astype(np.float32)
    pic.filepath_raw = a.output
    pic.file_format = "PNG"
    pic.save()
    print(f"wrote {a.output} ({strip.shape[1]}×{h}: {', '.join(images)}; exposure {math.log2(k):+.1f} stops)")


if __name__ == "__main__":
    main()
