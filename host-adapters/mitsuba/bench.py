"""The Mitsuba adapter against Mitsuba's own medium, as a Mitsuba user times it (a benchmark, not a test).

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so python3 host-adapters/mitsuba/bench.py [--variant llvm_ad_rgb]

1. The `firemedium` medium under Mitsuba's `volpath` against Mitsuba's `heterogeneous` medium over the same σ grid
   (a 64³ smoke blob; absorbing, and scattering at albedo 0.8), an area light behind it, 128², 64 spp: the time
   per sample of each, alternating, the median of five renders after one that compiles the kernels.
2. `firepath` on the emitting campfire over a floor (tests/data/scenes/campfire-floor.pbrt) against `firemedium
   render` of the same scene on the same 2 threads: relMSE (against firemedium render at 2048 spp) × time.
3. The 1280×720, 256-spp time each would take, from the measured time per sample.
4. (`--accuracy`) The fire's level: the campfire's brightest line of sight (15× its soot) through `firepath`, one
   pixel at 2¹⁸ samples, against the plugin's own march along it; and the campfire-floor scene and its scattering
   twin at 2048 spp against `firemedium render` at 16 384 spp (flame pixels and floor rows).
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
# (This folder holds the adapter's mitsuba.py, which would shadow Mitsuba's own package.)
sys.path = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--variant", default="llvm_ad_rgb")
ap.add_argument("--rounds", type=int, default=5)
ap.add_argument("--accuracy", action="store_true", help="also the fire's level against the plugin's (about a minute)")
a = ap.parse_args()

import mitsuba as mi  # noqa: E402

mi.set_variant(a.variant)
import drjit as dr  # noqa: E402

import firemedium.mitsuba as fmm  # noqa: E402

T = mi.ScalarTransform4f
N, RES, SPP = 64, 128, 64


def blob() -> np.ndarray:
    c = (np.arange(N) + 0.5) / N - 0.5
    z, y, x = np.meshgrid(c, c, c, indexing="ij")
    d = np.exp(-((x - 0.1) ** 2 + y ** 2 + (z + 0.05) ** 2) / 0.04) + 0.3 * np.exp(
        -((x + 0.2) ** 2 + (y - 0.15) ** 2 + z ** 2) / 0.01)
    d[0, :, :] = d[-1, :, :] = d[:, 0, :] = d[:, -1, :] = d[:, :, 0] = d[:, :, -1] = 0.0
    return d.astype(np.float32)


def scene(medium: dict) -> "mi.Scene":
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": 8},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": T().look_at(origin=[0, -3.2, 0.5], target=[0, 0, 0.5], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": RES, "height": RES, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": SPP}},
        "light": {"type": "rectangle", "to_world": T().translate([0, 1.5, 0.5]).rotate([1, 0, 0], 90).scale(2.0),
                  "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.0}}},
        "box": {"type": "cube", "to_world": T().translate([0, 0, 0.5]).scale(0.5), "bsdf": {"type": "null"},
                "interior": medium},
    })


def campfire_floor(spp: int, extra: dict | None = None) -> "mi.Scene":
    """tests/data/scenes/campfire-floor.pbrt in Mitsuba under `firepath`: the campfire at 15× its soot over a floor,
    32², `spp` independent samples; `extra` parameters for the fire (a look)."""
    return mi.load_dict({
        "type": "scene", "integrator": {"type": "firepath", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 40, "fov_axis": "smaller",
                   "to_world": T().look_at(origin=[0, -4.2, 1.6], target=[0, 0, 0.55], up=[0, 0, 1])
                   @ T().scale([-1, 1, 1]),
                   "film": {"type": "hdrfilm", "width": 32, "height": 32, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "floor": {"type": "rectangle", "to_world": T().scale([10, 10, 1]),
                  "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.5}}},
        "fire": {"type": "cube", "to_world": T().translate([0, 0, 0.8025]).scale([0.6, 0.6, 0.7975]),
                 "bsdf": {"type": "null"},
                 "interior": {"type": "firemedium", "filename": str(ROOT / "scenes" / "campfire" / "campfire.vdb"),
                              "fuel": "propane", "firescale": 15, "smokescale": 15, **(extra or {})}},
    })


def timed(sc, seed) -> float:
    t = time.perf_counter()
    img = mi.render(sc, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    return time.perf_counter() - t


d = blob()
print(f"Mitsuba {mi.__version__} {a.variant}, {os.cpu_count()} threads; {RES}² {SPP} spp; volpath max_depth 8")
for albedo in (0.0, 0.8):
    ours = scene({"type": "firemedium", "mode": "pbrt", "density": mi.VolumeGrid(d), "p0": [-0.5, -0.5, 0.0],
                  "p1": [0.5, 0.5, 1.0], "sigma_a": 12.0 * (1.0 - albedo), "sigma_s": 12.0 * albedo, "scale": 1.0})
    theirs = scene({"type": "heterogeneous", "albedo": albedo, "scale": 12.0,
                    "sigma_t": {"type": "gridvolume", "grid": mi.VolumeGrid(d),
                                "to_world": T().translate([-0.5, -0.5, 0.0])}})
    timed(ours, 1), timed(theirs, 1)  # the kernels compiled
    t_ours, t_theirs = [], []
    for r in range(a.rounds):
        t_ours.append(timed(ours, 10 + r))
        t_theirs.append(timed(theirs, 10 + r))
    mo, mt = statistics.median(t_ours), statistics.median(t_theirs)
    per = lambda s: s / (RES * RES * SPP) * 1e9
    print(f"albedo {albedo}: firemedium {mo:.3f} s ({per(mo):.1f} ns/sample), heterogeneous {mt:.3f} s "
          f"({per(mt):.1f} ns/sample): {mo / mt:.2f}x; 1280x720 at 256 spp: {per(mo) * 1280 * 720 * 256 / 1e9:.0f} s "
          f"against {per(mt) * 1280 * 720 * 256 / 1e9:.0f} s")

# 2. firepath on the emitting campfire against firemedium render (same threads), relMSE × time.
exe = os.environ.get("FIREMEDIUM_COMMAND") or str(ROOT / "target" / "release" / "firemedium")
scene_pbrt = ROOT / "tests" / "data" / "scenes" / "campfire-floor.pbrt"
with tempfile.TemporaryDirectory() as tmp:
    tmp = Path(tmp)
    subprocess.run([exe, "render", str(scene_pbrt), "-o", str(tmp / "ref.exr"), "--quiet", "--spp", "2048"],
                   check=True)
    ref = np.asarray(mi.Bitmap(str(tmp / "ref.exr")), dtype=np.float64)[..., :3]

    def rel_mse(img):
        img = np.asarray(img, dtype=np.float64)[..., :3]
        return float(np.mean((img - ref) ** 2 / (ref ** 2 + 0.01 * np.mean(ref) ** 2)))

    sys.path.insert(0, str(ROOT / "host-adapters" / "mitsuba" / "tests"))
    spp = 64
    sc = campfire_floor(spp)
    timed(sc, 1)
    rows = []
    for r in range(a.rounds):
        t = time.perf_counter()
        img = mi.render(sc, seed=20 + r)
        dr.eval(img)
        t_m = time.perf_counter() - t
        e_m = rel_mse(np.asarray(img) * fmm.CD_M2_PER_UNIT)
        t = time.perf_counter()
        subprocess.run([exe, "render", str(scene_pbrt), "-o", str(tmp / "fm.exr"), "--quiet", "--spp", str(spp),
                        "--seed", str(20 + r)], check=True)
        t_f = time.perf_counter() - t
        e_f = rel_mse(mi.Bitmap(str(tmp / "fm.exr")))
        rows.append((t_m, e_m, t_f, e_f))
    t_m, e_m, t_f, e_f = (statistics.median(c) for c in zip(*rows))
    print(f"campfire over a floor, 32², {spp} spp: firepath {t_m:.3f} s relMSE {e_m:.3e} (×time {e_m * t_m:.3e}); "
          f"firemedium render {t_f:.3f} s relMSE {e_f:.3e} (×time {e_f * t_f:.3e}): "
          f"{(e_m * t_m) / (e_f * t_f):.2f}x")

if a.accuracy:
    import firemedium as fm

    campfire = str(ROOT / "scenes" / "campfire" / "campfire.vdb")
    fire = {"fuel": "propane", "firescale": 15, "smokescale": 15}
    box = {"type": "cube", "to_world": T().translate([0, 0, 0.8025]).scale([0.6, 0.6, 0.7975]), "bsdf": {"type": "null"}}
    o, target = [0.0, -3.0, 0.3], [0.0, 0.0, 0.3]
    sc = mi.load_dict({
        "type": "scene", "integrator": {"type": "firepath", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 0.05, "to_world": T().look_at(origin=o, target=target, up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": 1, "height": 1, "pixel_format": "xyz",
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": 1 << 18}},
        "fire": {**box, "interior": {"type": "firemedium", "filename": campfire, **fire}}})
    y = float(np.asarray(mi.render(sc), dtype=np.float64)[0, 0, 1]) * fmm.CD_M2_PER_UNIT
    v = fm.Volume({"dataset": campfire, **fire})
    rad, _ = v.integrate([o], [[0.0, 1.0, 0.0]])
    y_ref = float(rad[0] @ v.channel_xyz()[:, 1])
    print(f"the brightest line of sight: firepath {y:.1f} cd/m², the plugin's march {y_ref:.1f}: {y / y_ref:.4f}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, extra in (("campfire-floor.pbrt", {}), ("campfire-floor-scattering.pbrt", {"look": "campfire"})):
            ref_exr = Path(tmp) / "ref.exr"
            subprocess.run([exe, "render", str(ROOT / "tests" / "data" / "scenes" / name), "-o", str(ref_exr),
                            "--quiet", "--spp", "16384"], check=True)
            lum = lambda a: np.asarray(a, dtype=np.float64)[..., :3] @ np.array([0.2126, 0.7152, 0.0722])
            ref = lum(mi.Bitmap(str(ref_exr)))
            sc = campfire_floor(2048, extra)
            img = lum(mi.render(sc, seed=3)) * fmm.CD_M2_PER_UNIT
            flame = ref > 0.05 * ref.max()
            floor = np.zeros_like(flame)
            floor[-8:, :] = True
            floor &= ~flame
            print(f"{name}, 2048 spp against firemedium render at 16384: flame "
                  f"{img[flame].mean() / ref[flame].mean():.4f}, floor {img[floor].mean() / ref[floor].mean():.4f}")
