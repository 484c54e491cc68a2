#!/usr/bin/env python3
"""Fire plumes as simulators write them, through the reference OpenVDB library.

Each convention is one simulator's: its grid names, its temperature's unit, its up axis and its transform. The
plume is the same physical shape in every one — a flame at the foot of a smoke column that rises and widens — so
that a reader's choices (which grid is soot, which temperature, which axis is up) can be checked against what was
written. Written with Debian's `python3-openvdb` (module `pyopenvdb`, OpenVDB 10) or the `openvdb` module Blender's
`bpy` ships; run it with the Python that has one of them (Debian's is /usr/bin/python3).

    /usr/bin/python3 tools/plumes.py OUT_DIR [NAME ...]     # every convention when no NAME is given
    /usr/bin/python3 tools/plumes.py --list

Conventions (what the simulator writes; see docs/guide/your-vdb.md):

  houdini-y        Houdini Pyro: density, temperature relative to ambient (0 ambient, ~1 in the flame), flame 0-1,
                   vel (vector); y up; 5 cm voxels.
  houdini-noflame  the same without a flame grid (older setups).
  blender-z        Blender's Mantaflow cache: density, flame 0-1, temperature = Mantaflow's heat (1.5 + 1.5 flame
                   where fuel burns), velocity (vector), shadow (-1 everywhere after a headless bake); z up.
  blender-y        the same cache exported y up (through a tool that turns Blender's z up into y up).
  embergen-y       EmberGen: smoke, temperature in kelvin, flames, fuel, velocity; y up.
  kelvin-z         a generic file: density and temperature in kelvin (300 K ambient); z up.
  kelvin-y         the same, y up.
  kelvin-noflame-z a smouldering column: density and kelvin temperature, no flame region above 1 200 K.
"""

import math
import os
import sys

import numpy as np

try:
    import pyopenvdb as vdb
except ImportError:  # Blender's bpy ships the same library as `openvdb`
    import openvdb as vdb

# The plume in its own frame: u, v across, h up, each in [0, 1] over a 40 x 40 x 80 lattice (h twice as long).
N_ACROSS, N_UP = 40, 80


def plume(seed=7):
    """Smoke density (0-1), flame (0-1), relative temperature (0 ambient, ~1.2 in the flame) and upward speed
    (m/s) on the plume's lattice, indexed [u][v][h]."""
    rng = np.random.default_rng(seed)
    u = (np.arange(N_ACROSS) + 0.5) / N_ACROSS - 0.5
    h = (np.arange(N_UP) + 0.5) / N_UP
    U, V, H = np.meshgrid(u, u, h, indexing="ij")
    # A few octaves of smooth noise (random sines) for the turbulence a simulation has.
    noise = np.zeros_like(U)
    for octave in range(4):
        f = 2.0 ** octave * 3.0
        for _ in range(3):
            k = rng.normal(size=3)
            k *= f / np.linalg.norm(k)
            phase = rng.uniform(0, 2 * math.pi)
            noise += np.sin(2 * math.pi * (k[0] * U + k[1] * V + 0.5 * k[2] * H) + phase) / (2.0 ** octave)
    noise /= 3.0
    # The column: its radius grows with height (an entraining plume), swaying with the noise.
    radius = 0.12 + 0.22 * H
    r = np.sqrt((U - 0.04 * noise) ** 2 + (V - 0.04 * np.roll(noise, 7, axis=2)) ** 2) / radius
    column = np.clip(1.0 - r ** 2, 0.0, 1.0)
    # The flame: a tapering tongue at the foot, up to 40 % of the height.
    tongue = 0.4 * (1.0 + 0.15 * noise)
    flame_r = np.sqrt(U ** 2 + V ** 2) / (0.16 * np.clip(1.0 - H / tongue, 0.0, 1.0) ** 0.6 + 1e-6)
    flame = np.where(H < tongue, np.clip(1.0 - flame_r ** 2, 0.0, 1.0), 0.0)
    flame *= np.clip(H / 0.05, 0.0, 1.0)
    flame = np.clip(flame * (1.0 + 0.3 * noise), 0.0, 1.0)
    # Smoke: thin in the flame, thickening as it rises and cools, fading at the top.
    smoke = column * np.clip((H - 0.1) / 0.5, 0.05, 1.0) * np.clip((1.0 - H) / 0.15, 0.0, 1.0)
    smoke = np.clip(smoke * (0.9 + 0.4 * noise), 0.0, None)
    # Relative temperature: hot in the flame, cooling along the column.
    temp = np.maximum(1.2 * flame, 0.6 * column * np.exp(-np.clip(H - 0.3, 0, None) / 0.25))
    speed = 3.0 * np.maximum(column, flame)
    return (smoke.astype(np.float32), flame.astype(np.float32), temp.astype(np.float32),
            speed.astype(np.float32))


def orient(a, up):
    """The plume's [u][v][h] array as [x][y][z] with h along `up` ('z': u v h; 'y': u h v, v flipped so the frame
    stays right-handed)."""
    if up == "z":
        return a
    return np.ascontiguousarray(np.flip(np.swapaxes(a, 1, 2), axis=2))


def float_grid(name, a, voxel, cls=None, background=0.0):
    g = vdb.FloatGrid(background)
    g.copyFromArray(a, ijk=(0, 0, 0), tolerance=0.0)
    g.name = name
    g.transform = vdb.createLinearTransform(voxelSize=voxel)
    if cls is not None:
        g.gridClass = cls
    return g


def vector_grid(name, speed, up, voxel):
    v = np.zeros(speed.shape + (3,), dtype=np.float32)
    v[..., "xyz".index(up)] = speed
    g = vdb.Vec3SGrid()
    g.copyFromArray(v, ijk=(0, 0, 0), tolerance=(0.0, 0.0, 0.0))
    g.name = name
    g.transform = vdb.createLinearTransform(voxelSize=voxel)
    g.vectorType = vdb.VectorType.CONTRAVARIANT_RELATIVE
    return g


def convention(name):
    """The grids of one convention, and the file's metadata."""
    smoke, flame, rel, speed = plume()
    if name.startswith("houdini"):
        up, voxel = "y", 0.05
        grids = [float_grid("density", orient(smoke, up), voxel, vdb.GridClass.FOG_VOLUME),
                 float_grid("temperature", orient(rel, up), voxel)]
        if name != "houdini-noflame":
            grids.append(float_grid("flame", orient(flame, up), voxel))
        grids.append(vector_grid("vel", orient(speed, up), up, voxel))
        return grids, {"creator": "Houdini 20.5 (as written by tools/plumes.py)"}
    if name.startswith("blender"):
        up, voxel = name[-1], 0.04
        heat = np.where(flame > 0.0, 1.5 + 1.5 * flame, 2.0 * rel).astype(np.float32)
        shadow = np.full(smoke.shape, -1.0, dtype=np.float32)
        grids = [float_grid("density", orient(smoke, up), voxel, vdb.GridClass.FOG_VOLUME),
                 float_grid("flame", orient(flame, up), voxel, vdb.GridClass.FOG_VOLUME),
                 float_grid("temperature", orient(heat, up), voxel, vdb.GridClass.FOG_VOLUME),
                 float_grid("shadow", orient(shadow, up), voxel),
                 vector_grid("velocity", orient(speed, up), up, voxel)]
        return grids, {"creator": "Blender/Mantaflow (as written by tools/plumes.py)"}
    if name == "embergen-y":
        up, voxel = "y", 0.05
        kelvin = np.where(rel > 0.0, 300.0 + 1500.0 * rel, 0.0).astype(np.float32)
        fuel = (flame * 0.5).astype(np.float32)
        grids = [float_grid("smoke", orient(smoke, up), voxel),
                 float_grid("temperature", orient(kelvin, up), voxel),
                 float_grid("flames", orient(flame, up), voxel),
                 float_grid("fuel", orient(fuel, up), voxel),
                 vector_grid("velocity", orient(speed, up), up, voxel)]
        return grids, {"creator": "EmberGen 1.2 (as written by tools/plumes.py)"}
    if name.startswith("kelvin"):
        up, voxel = name[-1], 0.03
        gain = 700.0 if "noflame" in name else 1500.0
        kelvin = np.where(rel > 0.0, 300.0 + gain * rel, 0.0).astype(np.float32)
        grids = [float_grid("density", orient(smoke, up), voxel),
                 float_grid("temperature", orient(kelvin, up), voxel)]
        return grids, {}
    raise SystemExit(f"plumes.py: unknown convention {name!r} (--list names them)")


NAMES = ["houdini-y", "houdini-noflame", "blender-z", "blender-y", "embergen-y", "kelvin-z", "kelvin-y",
         "kelvin-noflame-z"]


def main(argv):
    if argv[1:2] == ["--list"]:
        print("\n".join(NAMES))
        return 0
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    out = argv[1]
    os.makedirs(out, exist_ok=True)
    for name in argv[2:] or NAMES:
        grids, meta = convention(name)
        path = os.path.join(out, name + ".vdb")
        vdb.write(path, grids=grids, metadata=meta)
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
