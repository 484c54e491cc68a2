"""The starter path on a user's fire, as a new user takes it: plumes written by the reference OpenVDB library in each
simulator's conventions (tools/plumes.py: Houdini, Blender/Mantaflow, EmberGen, generic kelvin files; y and z up;
relative and kelvin temperatures; with and without a flame grid) and the Mantaflow caches this repository ships,
each through `firemedium scene FILE` and `firemedium render FILE.pbrt` with no option. The preview must read as a
fire: bright, warm (red > green > blue in the flame), upright (the flame taller than wide, as the plume is), and
not hidden by its smoke; the scene must say the convention the file was written in.

Run by tools/test-starter.sh (which installs Debian's python3-openvdb when missing) with Debian's Python; the
renders are small (160×90, 8 spp: the preview's shape and colour, not its noise, are checked).
"""

import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

try:
    import plumes  # noqa: E402  (needs pyopenvdb or openvdb)
except ImportError:
    if os.environ.get("FIREMEDIUM_REQUIRE_OPENVDB"):
        raise
    raise unittest.SkipTest("no OpenVDB Python module (Debian: apt-get install python3-openvdb)")


def command() -> str:
    exe = os.environ.get("FIREMEDIUM_COMMAND") or str(ROOT / "target" / "release" / "firemedium")
    if not Path(exe).is_file():
        raise unittest.SkipTest(f"{exe} is not built (cargo build --release)")
    return exe


def read_png(path: Path) -> tuple[int, int, list[list[tuple[int, int, int]]]]:
    """An 8-bit RGB or RGBA PNG (non-interlaced, as firemedium writes its previews): width, height, rows of RGB."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        (n,), kind = struct.unpack(">I", data[pos:pos + 4]), data[pos + 4:pos + 8]
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, colour = struct.unpack(">IIBB", body[:10])
            assert depth == 8 and colour in (2, 6), (depth, colour)
            bpp = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], (prev[i - bpp] if i >= bpp else 0)
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[x * bpp:x * bpp + 3]) for x in range(w)])
        prev = line
    return w, h, rows


def reads_as_fire(png: Path) -> dict:
    """What the preview shows of its flame: the pixels within 80 % of the brightest's luminance (8-bit), the mean
    colour of the bright body around them, and their shape — the rows they span against their median width in a
    row (the fire-lit floor under a flame is a few wide rows; the flame, many narrow ones)."""
    w, h, rows = read_png(png)
    lum = lambda p: 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
    peak = max(lum(p) for r in rows for p in r)
    flame = [(x, y, p) for y, r in enumerate(rows) for x, p in enumerate(r) if lum(p) >= 0.8 * peak]
    # The flame's colour: its edge and body, where the core has not saturated to white (60–95 % of the peak).
    body = [p for r in rows for p in r if 0.3 * peak <= lum(p) < 0.95 * peak] or [p for _, _, p in flame]
    mean = [sum(p[c] for p in body) / len(body) for c in range(3)]
    per_row: dict[int, int] = {}
    for _, y, _ in flame:
        per_row[y] = per_row.get(y, 0) + 1
    widths = sorted(per_row.values())
    return {
        "peak": peak,
        "pixels": len(flame) / (w * h),
        "mean": mean,
        "width": widths[len(widths) // 2],
        "height": len(per_row),
    }


class Starter(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.exe = command()
        cls.dir = Path(tempfile.mkdtemp(prefix="firemedium-starter-"))
        for name in plumes.NAMES:
            grids, meta = plumes.convention(name)
            plumes.vdb.write(str(cls.dir / f"{name}.vdb"), grids=grids, metadata=meta)
        for f in ("mantaflow_fire_f030.vdb", "mantaflow_fire_f060.vdb"):
            shutil.copy(ROOT / "tests" / "data" / "valid" / "vdb" / f, cls.dir / f)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def starter(self, vdb: str) -> tuple[str, str, dict]:
        """`firemedium scene` then `render` with no option (but a small film): what scene said, the scene, and
        what the preview shows."""
        r = subprocess.run([self.exe, "scene", vdb], cwd=self.dir, capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        scene = self.dir / (Path(vdb).stem + ".pbrt")
        text = scene.read_text()
        r2 = subprocess.run([self.exe, "render", scene.name, "--resolution", "160x90", "--spp", "8", "--quiet"],
                            cwd=self.dir, capture_output=True, text=True)
        self.assertEqual(r2.returncode, 0, r2.stderr)
        self.assertNotIn("warning", r2.stderr)
        return r.stdout, text, reads_as_fire(scene.with_suffix(".png"))

    def assert_fire(self, name: str, seen: dict):
        # Bright: the flame saturates the preview somewhere; visible: it covers a part of the picture (the smoke
        # does not hide it); warm: red over green over blue in its body; upright: taller than wide.
        self.assertGreater(seen["peak"], 200, f"{name}: {seen}")
        self.assertGreater(seen["pixels"], 0.003, f"{name}: {seen}")
        r, g, b = seen["mean"]
        self.assertTrue(r > g + 10 and g > b + 10, f"{name}: not warm: {seen}")
        self.assertGreater(seen["height"], 1.5 * seen["width"], f"{name}: not upright: {seen}")

    def test_every_convention_renders_as_a_fire_with_no_option(self):
        expect = {
            "houdini-y": ("houdini", "0 1 0", "temperaturescale"),
            "houdini-noflame": ("houdini", "0 1 0", "temperaturescale"),
            "blender-z": ("blender", "0 0 1", "flamemax"),
            "blender-y": ("blender", "0 1 0", "flamemax"),
            "embergen-y": ("embergen", "0 1 0", None),
            "kelvin-z": ("kelvin", "0 0 1", None),
            "kelvin-y": ("kelvin", "0 1 0", None),
            "kelvin-noflame-z": ("kelvin", "0 0 1", None),
        }
        for name, (tool, up, unit) in expect.items():
            with self.subTest(name):
                said, text, seen = self.starter(f"{name}.vdb")
                print(f"{name}: {seen}", file=sys.stderr)
                self.assertIn(f'"string source" "{tool}"', text)
                look_at = re.search(r"^LookAt .*   (\S+ \S+ \S+)$", text, re.M)
                self.assertEqual(look_at.group(1), up, text)
                self.assertIn('"float sootscale"', text)
                if unit:
                    self.assertIn(unit, text)
                for what in ("source", "smoke", "temperature", "unit", "up", "sootscale"):
                    self.assertRegex(said, rf"\n  {what} +\S", said)
                self.assert_fire(name, seen)

    def test_the_shipped_mantaflow_caches_render_as_fire(self):
        for f in ("mantaflow_fire_f030.vdb", "mantaflow_fire_f060.vdb"):
            with self.subTest(f):
                said, text, seen = self.starter(f)
                print(f"{f}: {seen}", file=sys.stderr)
                self.assertIn('"string source" "blender"', text)
                self.assert_fire(f, seen)

    def test_a_look_on_a_simulators_plume_still_reads_as_a_fire(self):
        # The looks' scattering is per unit of soot: on Houdini's or EmberGen's density (a soot scale near 1e-7) the
        # smoke keeps the look's albedo (a σ_s per unit density made it 10⁷ times too thick: every ray at the
        # collision cap, a render of hours).
        for name, look in (("houdini-y", "campfire"), ("embergen-y", "explosion")):
            with self.subTest(name=name, look=look):
                r = subprocess.run([self.exe, "scene", f"{name}.vdb", "-o", f"{name}-{look}.pbrt"], cwd=self.dir,
                                   capture_output=True, text=True)
                self.assertEqual(r.returncode, 0, r.stderr)
                scene = self.dir / f"{name}-{look}.pbrt"
                text = re.sub(r'^(  "string source" "\w+")$', rf'\1 "string look" "{look}"',
                              scene.read_text(), count=1, flags=re.M)
                self.assertIn(f'"string look" "{look}"', text)
                scene.write_text(text)
                r = subprocess.run([self.exe, "render", scene.name, "--resolution", "160x90", "--spp", "8",
                                    "--quiet"], cwd=self.dir, capture_output=True, text=True, timeout=300)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertNotIn("warning", r.stderr)
                seen = reads_as_fire(scene.with_suffix(".png"))
                print(f"{name} + {look}: {seen}", file=sys.stderr)
                self.assert_fire(f"{name} + {look}", seen)

    def test_a_sequence_gets_one_scene_covering_every_frame(self):
        for f, n in (("mantaflow_fire_f030.vdb", 1), ("mantaflow_fire_f060.vdb", 2)):
            shutil.copy(self.dir / f, self.dir / f"seq_{n:04d}.vdb")
        r = subprocess.run([self.exe, "scene", "seq_####.vdb"], cwd=self.dir, capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("2 frames", r.stdout)
        self.assertIn("--frames 1-2", r.stdout)
        text = (self.dir / "seq.pbrt").read_text()
        self.assertIn('"string dataset" "seq_####.vdb"', text)
        r = subprocess.run([self.exe, "render", "seq.pbrt", "--frames", "1-2", "--resolution", "32x18", "--spp", "1",
                            "--quiet"], cwd=self.dir, capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue((self.dir / "seq.0001.exr").is_file() and (self.dir / "seq.0002.exr").is_file())

    def test_the_guides_python_and_commands_run_as_written(self):
        guide = (ROOT / "docs" / "guide" / "your-vdb.md").read_text(encoding="utf-8")
        python = re.findall(r"```python\n(.*?)```", guide, re.S)
        commands = [l.split("#")[0].strip() for b in re.findall(r"```sh\n(.*?)```", guide, re.S)
                    for l in b.strip().splitlines()]
        self.assertEqual(len(python), 1)
        self.assertEqual(commands, ["firemedium scene fire.vdb", "firemedium render fire.pbrt"])
        d = self.dir / "guide"
        d.mkdir()
        r = subprocess.run([sys.executable, "-c", python[0]], cwd=d, capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        for c in commands:
            r = subprocess.run([self.exe] + c.split()[1:], cwd=d, capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, f"{c}: {r.stderr}")
        seen = reads_as_fire(d / "fire.png")
        print(f"the guide's fire: {seen}", file=sys.stderr)
        self.assert_fire("the guide's fire", seen)

    def test_up_given_overrides_the_data(self):
        r = subprocess.run([self.exe, "scene", "kelvin-z.vdb", "--up", "-x", "-o", "sideways.pbrt"], cwd=self.dir,
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("-x: given (--up)", r.stdout)
        self.assertRegex((self.dir / "sideways.pbrt").read_text(), r"LookAt .*   -1 0 0\n")


if __name__ == "__main__":
    unittest.main()
