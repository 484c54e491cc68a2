#!/usr/bin/env python3
"""Mutation harness: feeds the built `firemedium` binary mutated copies of every kind of file it reads, each run
under an address-space limit and a time limit, and counts what must never happen.

    python3 tools/mutants.py --count 20000 [--seed 1] [--jobs 2] [--limit-gb 8] [--timeout 30] [--keep DIR]

Kinds (seeds from the repository, mutated byte-wise: flips, random bytes, interesting integers, deletions,
duplicated and truncated runs):
  - datasets: tests/data/valid/{vdb,nvdb}, thesis ASCII (dense, sparse) and raw2 made here; `firemedium info`;
  - scenes: scenes/*/scene.pbrt (text-aware mutations: numbers replaced by extreme values, tokens dropped or
    duplicated) rendered at 8×8, 1 spp, `--max-memory 1`;
  - images: a small EXR and PNG written by the binary itself; `firemedium tonemap`;
  - meshes: a PLY (ascii and binary) referenced by a scene; `firemedium render`;
  - vdb-tree, nvdb-tree: structure-aware OpenVDB and NanoVDB node tables (tools/tree_mutants.py: trees drawn at
    random and written by a writer that lies, valid files patched field by field); `firemedium info`, or a
    render of the file as a fire lighting a floor (so the lattice, majorants and fire light walk it too).

    python3 tools/mutants.py --count 20000 --kinds vdb-tree,nvdb-tree   # the node-table run alone
  - names, bake, python, abi: the surfaces beside files (tools/surface_mutants.py): `scene` and `render` under
    hostile names, `bake` with the plugin's parameters at extreme values, the Python package's calls with arrays
    of any shape, the C ABI's structs at every struct_size (older and newer minor versions' hosts).

    python3 tools/mutants.py --count 5000 --kinds names,bake,python,abi   # the new surfaces alone

Outcome per run: ok (exit 0), refused (exit 1 or 2 with one line on stderr), panic (exit 101), abort (a
signal: SIGABRT, SIGSEGV…), hang (killed at the time limit), over the RSS limit (peak RSS above --rss-gb,
measured by /usr/bin/time), nan (NaN given as an answer) or lost (work said done, its output missing). It prints the counts and exits 1 if any run was not ok or refused, 0 otherwise.
Failing inputs are kept under --keep for replay. Used for issue 21 (docs/results/log.md has the runs).
"""
import argparse
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import surface_mutants  # noqa: E402
import tree_mutants  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

INTERESTING = [0, 1, 0x7F, 0x80, 0xFF, 0x7FFF, 0xFFFF, 0x7FFFFFFF, 0xFFFFFFFF, 2**31, 2**63 - 1]
EXTREME_NUMBERS = ["0", "-1", "1e39", "-1e39", "1e308", "1e-320", "nan", "inf", "-inf", "1e9", "4294967296",
                   "99999999999", "-0", "3.4e38", "1e-45"]


def mutate_bytes(data: bytes, rng: random.Random) -> bytes:
    b = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        if not b:
            b = bytearray(rng.randbytes(rng.randint(1, 64)))
            continue
        op = rng.randrange(7)
        i = rng.randrange(len(b))
        if op == 0:
            b[i] ^= 1 << rng.randrange(8)
        elif op == 1:
            b[i] = rng.randrange(256)
        elif op == 2:
            v = rng.choice(INTERESTING)
            w = rng.choice([1, 2, 4, 8])
            b[i:i + w] = (v % (1 << (8 * w))).to_bytes(w, rng.choice(["little", "big"]))
        elif op == 3:
            del b[i:i + rng.randint(1, 64)]
        elif op == 4:
            j = rng.randrange(len(b))
            b[j:j] = b[i:i + rng.randint(1, 256)]
        elif op == 5:
            b = b[:i]
        else:
            b[i:i] = rng.randbytes(rng.randint(1, 16))
    return bytes(b)


def mutate_text(text: str, rng: random.Random) -> str:
    tokens = re.split(r"(\s+)", text)
    for _ in range(rng.randint(1, 3)):
        if not tokens:
            break
        i = rng.randrange(len(tokens))
        op = rng.randrange(5)
        if op == 0 and re.fullmatch(r"-?[0-9.eE+-]+", tokens[i] or "x"):
            tokens[i] = rng.choice(EXTREME_NUMBERS)
        elif op == 1:
            del tokens[i]
        elif op == 2:
            tokens.insert(i, tokens[rng.randrange(len(tokens))])
        elif op == 3:
            tokens[i] = rng.choice(["[", "]", "\"", "AttributeBegin", "ObjectInstance \"x\"", "Include \"/dev/zero\"",
                                    "\"float radius\" 1e39", "Scale 1e300 1 1", "\"integer xresolution\" 1000000000"])
        else:
            return mutate_bytes(text.encode(), rng).decode("utf-8", "replace")
    return "".join(tokens)


class Harness:
    def __init__(self, a):
        self.a = a
        self.bin = os.path.join(ROOT, "target", "release", "firemedium")
        self.work = tempfile.mkdtemp(prefix="firemedium-mutants-")
        self.seeds = self.make_seeds()
        every = ["dataset", "dataset", "scene", "scene", "image", "mesh", "vdb-tree", "nvdb-tree"] + \
            surface_mutants.KINDS
        # The Python package's and the ABI's cases load the plugin this build made.
        lib = os.path.join(ROOT, "target", "release", "libfiremedium_plugin.so")
        self.env = dict(os.environ, FIREMEDIUM_PLUGIN=lib)
        self.kinds = [k for k in every if not a.kinds or k in a.kinds.split(",")]
        if not self.kinds:
            sys.exit(f"--kinds {a.kinds}: expected some of {', '.join(sorted(set(every)))}")

    def run(self, argv, cwd, env=None):
        limit = self.a.limit_gb * 1024 * 1024
        cmd = ["/usr/bin/time", "-f", "RSS %M", "bash", "-c",
               f"ulimit -v {limit}; exec \"$@\"", "x"] + argv
        try:
            p = subprocess.run(cmd, cwd=cwd, capture_output=True, timeout=self.a.timeout, env=env)
        except subprocess.TimeoutExpired:
            return "hang", ""
        err = p.stderr.decode("utf-8", "replace")
        m = re.search(r"RSS (\d+)\s*$", err)
        rss_kb = int(m.group(1)) if m else 0
        err = err[:m.start()] if m else err
        signalled = "Command terminated by signal" in err
        err = "\n".join(l for l in err.splitlines() if not l.startswith("Command "))
        code = p.returncode
        if signalled or code < 0 or code >= 128 and code != 130:
            kind = "abort"
        elif code == 101 or "panicked" in err:
            kind = "panic"
        elif code in (0, 1, 2):
            kind = "ok" if code == 0 else "refused"
        else:
            kind = "abort"
        if rss_kb > self.a.rss_gb * 1024 * 1024:
            kind = "rss"
        out = p.stdout.decode("utf-8", "replace").strip()
        self.last_stdout = out
        last = err.strip().splitlines()[-1] if err.strip() else (out.splitlines()[-1] if out else "")
        return kind, last

    def make_seeds(self):
        s = {}
        d = os.path.join(ROOT, "tests", "data", "valid")
        for sub, ext in (("vdb", ".vdb"), ("nvdb", ".nvdb")):
            for f in sorted(os.listdir(os.path.join(d, sub))):
                if f.endswith(ext) and os.path.getsize(os.path.join(d, sub, f)) < 4 << 20:
                    s.setdefault("dataset", []).append((ext, open(os.path.join(d, sub, f), "rb").read()))
        s["dataset"].append((".txt", b"4 4 4\n" + b" ".join(str(i % 7).encode() for i in range(64)) + b"\n"))
        s["dataset"].append((".txt", b"8 8 8\n3\n0.5\n0 0 0 7\n2 1 0 9\n7 7 7 1\n"))
        raw = b"".join(struct.pack("<iiiBBB", x, y, z, 200, 10, 10) for x in range(1, 5) for y in range(1, 5) for z in range(1, 3))
        s["dataset"].append((".raw2", raw))
        s["scene"] = []
        for name in sorted(os.listdir(os.path.join(ROOT, "scenes"))):
            p = os.path.join(ROOT, "scenes", name, "scene.pbrt")
            if os.path.isfile(p):
                s["scene"].append((name, open(p).read()))
        # A scene with this phase's parameters: Blender's cache as its source, its velocity blurring it over an
        # open shutter, its flame as the emission grid, and the art-direction controls.
        vdb = os.path.join(ROOT, "tests", "data", "valid", "vdb", "mantaflow_fire_f060.vdb")
        s["scene"].append(("mantaflow", (
            'LookAt 1 -4 1.5  1 1 1.2  0 0 1\n'
            'Camera "perspective" "float fov" 40 "float shutteropen" 0 "float shutterclose" 0.5\n'
            'Film "rgb" "integer xresolution" 16 "integer yresolution" 12\n'
            'Sampler "zsobol" "integer pixelsamples" 1\nIntegrator "volpath" "integer maxdepth" 2\nWorldBegin\n'
            f'MakeNamedMedium "f" "string type" "fire" "string filename" "{vdb}" "string source" "blender"\n'
            '  "string velocitygrid" "velocity" "float velocityscale" 0.05 "float fps" 24 "string emissiongrid" "flame"\n'
            '  "float smokescale" 0.5 "rgb tint" [1 0.8 0.6] "float colorramp" [1000 1 0.2 0.1 2000 1 0.8 0.4]\n'
            '  "float physical" 0.3\n'
            'AttributeBegin\nMediumInterface "f" ""\nMaterial "interface"\nShape "sphere" "float radius" 3\n'
            'AttributeEnd\nAttributeBegin\nMaterial "diffuse"\n'
            'Shape "trianglemesh" "point3 P" [-9 -9 0 9 -9 0 9 9 0 -9 9 0] "integer indices" [0 1 2 0 2 3]\n'
            'AttributeEnd\n')))
        # An EXR and a PNG written by the binary itself (a tiny render and its preview).
        img = os.path.join(self.work, "seed")
        os.makedirs(img, exist_ok=True)
        subprocess.run([self.bin, "render", os.path.join(ROOT, "scenes", "campfire", "scene.pbrt"), "--resolution",
                        "16x12", "--spp", "1", "-q", "-o", os.path.join(img, "seed.exr")], check=True)
        s["image"] = [(".exr", open(os.path.join(img, "seed.exr"), "rb").read()),
                      (".png", open(os.path.join(img, "seed.png"), "rb").read())]
        ply_ascii = (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                     b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
        verts = b"".join(struct.pack("<fff", *v) for v in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
        ply_bin = (b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                   b"property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n" + verts +
                   struct.pack("<Biii", 3, 0, 1, 2) + struct.pack("<Biii", 3, 0, 2, 3))
        s["mesh"] = [(".ply", ply_ascii), (".ply", ply_bin)]
        nv = os.path.join(d, "nvdb")
        s["nvdb-tree"] = [open(os.path.join(nv, f), "rb").read() for f in ("ramp16.nvdb", "plume48.nvdb")]
        return s

    def one(self, k):
        rng = random.Random(self.a.seed * 1_000_003 + k)
        kind = rng.choice(self.kinds)
        d = os.path.join(self.work, f"m{k}")
        os.makedirs(d, exist_ok=True)
        if kind in surface_mutants.KINDS:
            results = surface_mutants.run_case(self, kind, rng, d)
            shutil.rmtree(d, ignore_errors=True)
            return [(kind, outcome, last) for outcome, last in results]
        if kind == "dataset":
            ext, data = rng.choice(self.seeds["dataset"])
            f = os.path.join(d, "m" + ext)
            open(f, "wb").write(mutate_bytes(data, rng))
            argv = [self.bin, "info", f, "--max-memory", "1"]
        elif kind == "scene":
            name, text = rng.choice(self.seeds["scene"])
            f = os.path.join(ROOT, "scenes", name, f".mutant-{os.getpid()}-{k}.pbrt")
            open(f, "w").write(mutate_text(text, rng))
            argv = [self.bin, "render", f, "--resolution", "8x8", "--spp", "1", "--threads", "1", "-q",
                    "--max-memory", "1", "-o", os.path.join(d, "o.exr")]
        elif kind == "image":
            ext, data = rng.choice(self.seeds["image"])
            f = os.path.join(d, "m" + ext)
            open(f, "wb").write(mutate_bytes(data, rng))
            argv = [self.bin, "tonemap", f, "-o", os.path.join(d, "t.png")]
        elif kind in ("vdb-tree", "nvdb-tree"):
            if kind == "vdb-tree":
                data, ext = tree_mutants.openvdb(rng), ".vdb"
            else:
                data, ext = tree_mutants.nanovdb(rng.choice(self.seeds["nvdb-tree"]), rng), ".nvdb"
            if rng.random() < 0.125:
                data = mutate_bytes(data, rng)
            f = os.path.join(d, "m" + ext)
            open(f, "wb").write(data)
            if rng.random() < 0.5:
                argv = [self.bin, "info", f, "--max-memory", "1"]
            else:
                scene = os.path.join(d, "s.pbrt")
                open(scene, "w").write(
                    'LookAt 0 -3 1  0 0 0.3  0 0 1\nCamera "perspective" "float fov" 50\n'
                    'Film "rgb" "integer xresolution" 8 "integer yresolution" 8\n'
                    'Integrator "volpath" "integer maxdepth" 3\nWorldBegin\n'
                    f'MakeNamedMedium "f" "string type" "fire" "string dataset" "m{ext}" "string fuel" "propane"\n'
                    'AttributeBegin\nMediumInterface "f" ""\nMaterial "interface"\nShape "sphere" "float radius" 2\n'
                    'AttributeEnd\nMaterial "diffuse"\n'
                    'Shape "trianglemesh" "point3 P" [-9 -9 -1 9 -9 -1 9 9 -1 -9 9 -1] "integer indices" [0 1 2 0 2 3]\n')
                argv = [self.bin, "render", scene, "--spp", "1", "--threads", "1", "-q", "--max-memory", "1",
                        "--fire-light", "power", "-o", os.path.join(d, "o.exr")]
        else:
            ext, data = rng.choice(self.seeds["mesh"])
            f = os.path.join(d, "m.ply")
            open(f, "wb").write(mutate_bytes(data, rng))
            scene = os.path.join(d, "s.pbrt")
            open(scene, "w").write('Camera "perspective"\nFilm "rgb" "integer xresolution" 8 "integer yresolution" 8\n'
                                   'WorldBegin\nLightSource "distant"\nShape "plymesh" "string filename" "m.ply"\n')
            argv = [self.bin, "render", scene, "--spp", "1", "-q", "--max-memory", "1", "-o", os.path.join(d, "o.exr")]
        return [self.finish(k, kind, argv, d, f)]

    def finish(self, k, kind, argv, d, f):
        """Runs mutant `k`'s command and keeps its input when it failed: (kind, outcome, last line)."""
        outcome, last = self.run(argv, d)
        if kind == "scene":
            if outcome not in ("ok", "refused") and self.a.keep:
                shutil.copy(f, os.path.join(self.a.keep, f"scene-{k}.pbrt"))
            os.remove(f)
        elif outcome not in ("ok", "refused") and self.a.keep:
            shutil.copy(f, os.path.join(self.a.keep, f"{kind}-{k}{os.path.splitext(f)[1]}"))
        shutil.rmtree(d, ignore_errors=True)
        return kind, outcome, last

    def main(self):
        if self.a.keep:
            os.makedirs(self.a.keep, exist_ok=True)
        counts = {}
        bad = []
        cases = 0
        with ThreadPoolExecutor(self.a.jobs) as pool:
            for i, results in enumerate(pool.map(self.one, range(self.a.count))):
                for kind, outcome, last in results:
                    cases += 1
                    counts.setdefault(kind, {}).setdefault(outcome, 0)
                    counts[kind][outcome] += 1
                    if outcome not in ("ok", "refused"):
                        bad.append((i, kind, outcome, last))
                if (i + 1) % 1000 == 0:
                    print(f"{i + 1} mutants", file=sys.stderr, flush=True)
        shutil.rmtree(self.work, ignore_errors=True)
        outcomes = ["ok", "refused", "panic", "abort", "hang", "rss", "nan", "lost"]
        print(f"| kind | {' | '.join(outcomes)} |")
        print("|---|" + "---|" * len(outcomes))
        for kind in sorted(counts):
            print(f"| {kind} | " + " | ".join(str(counts[kind].get(o, 0)) for o in outcomes) + " |")
        total = {o: sum(c.get(o, 0) for c in counts.values()) for o in outcomes}
        print("| all | " + " | ".join(str(total[o]) for o in outcomes) + " |")
        for i, kind, outcome, last in bad[:50]:
            print(f"mutant {i} ({kind}): {outcome} {last}")
        # The plain closing line CI reads: a mutant passes when it rendered or was refused with one line.
        print(f"mutants: {cases - len(bad)} passed, {len(bad)} failed")
        return 1 if bad else 0


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--limit-gb", type=int, default=8, help="address-space limit (ulimit -v), GB")
    ap.add_argument("--rss-gb", type=float, default=1.5, help="peak RSS above which a run counts as a failure")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds before a run counts as a hang")
    ap.add_argument("--keep", help="directory for the inputs of failing runs")
    ap.add_argument("--kinds", help="comma-separated kinds to mutate (default: all)")
    sys.exit(Harness(ap.parse_args()).main())
