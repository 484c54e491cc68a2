"""Structure-aware mutants of the surfaces a user and a host reach besides files (tools/mutants.py runs them):

  - names: `firemedium scene` on a plume under a name drawn from hostile text (quotes, backslashes, newlines,
    control characters, characters past U+00FF, bytes that are not UTF-8, a leading '-', names at and past 255
    bytes), with a random `--up`, then `render` of the scene it wrote under an output name drawn the same way:
    a scene said written must exist and render (or be refused), a render said done must leave its EXR;
  - bake: `firemedium bake` with parameters drawn from the plugin's own table at extreme values, hostile output
    names and frame ranges: a bake said done must leave its file, and one the plugin refuses leaves none;
  - python: a call of the Python package's public functions with arrays of random shapes, dtypes, counts and
    extreme values, and parameters past what C types hold: a Python exception, or finite numbers — never a crash
    of the interpreter, never NaN returned as an answer;
  - abi: the C ABI through ctypes with FmCreateInfo, FmRayQuery, FmPointQuery, FmTables and FmErrorDetail (a write
    past the host's struct_size counts as an abort) of every struct_size from 0 to
    past this build's, their tails random bytes (as an older or newer minor version's host passes them): a status,
    never a crash.

A names or bake case is one process; python and abi cases run 20 to a process (loading the plugin and building
the fire once), each reported on its own line — a process that dies charges it to the case it was in.
`run_case(harness, kind, rng, dir)` returns (outcome, last line) per case. Two more outcomes than mutants.py's:
`nan` (NaN in an answer given as OK) and `lost` (work said done with no output).
"""

import os
import random
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KINDS = ["names", "bake", "python", "abi"]

HOSTILE = ['"', "\\", "\n", "\t", "\r", "\x07", "\x1b[2J", "€", "火焰", "🔥", "\u202e", " ", "'", "$(x)", "`x`",
           "%04d", "####", "..", "/", "-", "--force", "WorldBegin", "# ", "\x00"]


def hostile_name(rng: random.Random, ext: str) -> bytes:
    """A file name drawn from hostile pieces (bytes: some are not UTF-8), ending in `ext`, 1 to ~300 bytes."""
    parts = [rng.choice(HOSTILE).encode("utf-8", "surrogatepass") if rng.random() < 0.6 else
             rng.choice([b"fire", b"\xff\xfe", b"a" * rng.randint(1, 300), b"x"]) for _ in range(rng.randint(1, 5))]
    name = b"".join(parts).replace(b"/", b"_").replace(b"\x00", b"_") + ext.encode()
    if rng.random() < 0.1:
        name = b"-" + name
    return name


def plume_seed(work: str) -> str:
    """A plume written once per harness (Houdini's conventions, through the project's own writer when OpenVDB's
    Python module is missing): the names and bake kinds' dataset."""
    path = os.path.join(work, "plume.vdb")
    if not os.path.exists(path):
        shutil.copy(os.path.join(ROOT, "tests", "data", "valid", "vdb", "mantaflow_fire_f030.vdb"), path)
    return path


def case_names(h, rng, d):
    seed = plume_seed(h.work)
    name = hostile_name(rng, ".vdb")
    data = os.path.join(d.encode(), name)
    try:
        shutil.copy(seed, data)
    except OSError:
        return "ok", "a name the file system refuses"
    argv = [h.bin.encode(), b"scene"]
    if rng.random() < 0.5:
        argv += [b"--up", rng.choice([b"x", b"-y", b"z", b"+y", b"w", b"", b"--", "\x1b".encode()])]
    out = hostile_name(rng, ".pbrt") if rng.random() < 0.5 else b"s.pbrt"
    # (After `--` half the time: a name starting with '-' is then a file, as a user passes one.)
    argv += [b"-o", out] + ([b"--", name] if rng.random() < 0.5 else [name])
    kind, last = h.run(argv, d)
    if kind != "ok":
        return kind, last
    if not os.path.exists(os.path.join(d.encode(), out)):
        return "lost", f"scene exited 0 without {out!r}"
    exr = hostile_name(rng, ".exr") if rng.random() < 0.5 else b"o.exr"
    kind, last = h.run([h.bin.encode(), b"render", out, b"--resolution", b"8x6", b"--spp", b"1", b"-q",
                        b"--threads", b"1", b"-o", exr], d)
    if kind == "ok" and not os.path.exists(os.path.join(d.encode(), exr)):
        return "lost", f"render exited 0 without {exr!r}"
    return kind, last


PARAMS = None


def bake_params(h):
    """The plugin's parameter table (name, type), read once through `firemedium info`-free means: the package."""
    global PARAMS
    if PARAMS is None:
        code = ("import firemedium as fm, json; print(json.dumps([(r['name'], r['ty']) for r in "
                "fm.plugin().parameters()]))")
        p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=h.env)
        import json
        PARAMS = json.loads(p.stdout) if p.returncode == 0 else [("fuel", "string"), ("sootscale", "float")]
    return PARAMS


EXTREME = ["0", "-1", "1e39", "-1e300", "nan", "inf", "1e-320", "4294967297", "18446744073709551617", "",
           "1e9", "0.5", "x", "propane", "kelvin", "-0", "1,2,3"]


def case_bake(h, rng, d):
    seed = plume_seed(h.work)
    shutil.copy(seed, os.path.join(d, "f.vdb"))
    argv = [h.bin.encode(), b"bake"]
    for _ in range(rng.randint(0, 3)):
        name, ty = rng.choice(bake_params(h))
        argv += [f"--param={name}={rng.choice(EXTREME)}".encode("utf-8", "surrogateescape")]
    out = hostile_name(rng, ".vdb") if rng.random() < 0.6 else b"b-firemedium.vdb"
    argv += [b"-o", out, b"--max-memory", b"1"]
    if rng.random() < 0.15:
        argv += [b"--frames", rng.choice([b"1-2", b"2-1", b"0-999999999", b"x"])]
    argv += [b"--", b"f.vdb"]
    kind, last = h.run(argv, d)
    path = os.path.join(d.encode(), out)
    if kind == "ok" and b"#" not in out and not os.path.exists(path):
        return "lost", f"bake exited 0 without {out!r}"
    if kind == "refused" and os.path.exists(path) and out != b"f.vdb":
        return "lost", f"bake refused but left {out!r}"
    return kind, last


PY_CALLS = [
    "v.point({a}, {lam}, times={t})",
    "v.integrate({a}, {b}, tmin={t}, tmax={t2}, times={t}, seed={seed})",
    "v.transmittance({a}, {b}, times={t})",
    "l.sample({u}, times={t})",
    "l.pdf({a}, times={t})",
    "l.pdf_direction({a}, {b}, times={t})",
    "l.integrate({a}, {b}, times={t})",
    "v.fields({a})",
    "fm.Volume(dict(filename=CAMPFIRE, **{params})).tables()['emission']",
    "fm.Volume(dict(filename=CAMPFIRE, **{params}))",
]


def py_array(rng):
    shape = rng.choice(["(0, 3)", "(1, 3)", "(3, 3)", "(5, 3)", "(3,)", "(3, 2)", "(2, 3, 3)", "()", "(7, 6)",
                        "(4, 6)", "(6,)"])
    fill = rng.choice(["0.3", "1e300", "-1e300", "np.nan", "np.inf", "1e-320", "0", "0.5", "-0.4"])
    dtype = rng.choice(["np.float64", "np.float32", "np.int64", "complex", "object", "np.float64", "np.float64"])
    if rng.random() < 0.2:
        return rng.choice(["None", "'abc'", "[[1, 2, 3]]", "[[0.1, -2.0, 0.5]] * 4", "[0.0, 1.0, 0.0]"])
    return f"np.full({shape}, {fill}, dtype={dtype})"


BATCH = 20


def py_expr(rng):
    call = rng.choice(PY_CALLS)
    params = rng.choice(["{'bins': 2 ** 64 + 8}", "{'bins': -1}", "{'fuel': 'propane\\x00x'}", "{'bins': 12}",
                         "{'sootscale': float('nan')}", "{'g': 2.0}", "{'species': ['Na', 'Zz']}",
                         "{'threads': 2 ** 40}", "{'maxbytes': 1.0}", "{'colormode': 'rgb'}"])
    expr = call.format(a=py_array(rng), b=py_array(rng), lam=rng.choice(["[550.0]", "[1e-61]", "[]", "[[550.0]]",
                       "np.zeros((3, 2))", "[2e6, 500.0]", "550.0"]), t=rng.choice(["None", "0.0", "[0.0, 1.0]",
                       "np.nan", "np.zeros(3)"]), t2=rng.choice(["1e30", "np.inf", "-1.0", "[1.0, 2.0]"]),
                       seed=rng.choice(["0", "-1", "2 ** 64", "1.5", "7"]), u=py_array(rng), params=params)
    return expr


def batch_outcomes(h, script, labels, d):
    """Runs `script`, which prints one line per case (OK, REFUSED …, NAN), and returns each case's outcome: a
    process that dies charges its death to the case it was in and leaves the rest unrun (not counted)."""
    kind, _ = h.run([sys.executable, "-c", script], d, env=h.env)
    words = {"OK": "ok", "REFUSED": "refused", "NAN": "nan", "OVERRUN": "abort"}
    lines = [l for l in h.last_stdout.splitlines() if l.split(" ")[0] in words]
    out = []
    for label, line in zip(labels, lines):
        out.append((words[line.split(" ")[0]], f"{label}: {line}"[:300]))
    # (A process that stopped short without dying — the script itself failing — has lost the cases it did not
    # report: counted, never passed over.)
    if len(lines) < len(labels):
        out.append((kind if kind not in ("ok", "refused") else "lost", labels[len(lines)]))
    return out


def case_python(h, rng, d):
    exprs = [py_expr(rng) for _ in range(BATCH)]
    body = "".join(
        "try:\n"
        f"    r = {e}\n"
        "except (ValueError, TypeError, fm.FiremediumError) as e:\n"
        "    print('REFUSED', type(e).__name__, str(e)[:200].replace('\\n', ' '), flush=True)\n"
        "else:\n"
        "    rs = r if isinstance(r, tuple) else (r,)\n"
        "    arrays = [np.asarray(x, dtype=float) for x in rs if isinstance(x, np.ndarray)]\n"
        "    print('NAN' if any(np.isnan(x).any() for x in arrays) else 'OK', flush=True)\n"
        for e in exprs)
    script = (
        "import warnings, numpy as np, firemedium as fm\n"
        "warnings.simplefilter('ignore')\n"
        f"CAMPFIRE = {os.path.join(ROOT, 'scenes', 'campfire', 'campfire.vdb')!r}\n"
        "v = fm.Volume({'filename': CAMPFIRE, 'fuel': 'propane'})\n"
        "l = v.light()\n" + body
    )
    return batch_outcomes(h, script, exprs, d)


def case_abi(h, rng, d):
    cases = [(rng.choice(["create", "query", "point", "tables", "detail"]),
              rng.choice([0, 1, 8, 47, 48, 55, 56, 87, 88, 95, 96, 97, 104, 112, 120, 128, 4096,
                          rng.randint(0, 300)]))
             for _ in range(BATCH)]
    script = (
        "import ctypes as C, os, random, warnings\n"
        "warnings.simplefilter('ignore')\n"
        "import firemedium as fm\nfrom firemedium import _abi as abi\n"
        f"rng = random.Random({rng.randrange(1 << 30)})\n"
        "p = fm.plugin(); api = p.api\n"
        "def buf(struct, fill, size):\n"
        "    n = max(size, C.sizeof(struct)) + 64\n"
        "    raw = (C.c_ubyte * n)(*[rng.randrange(256) for _ in range(n)])\n"
        "    C.memmove(raw, C.byref(fill), C.sizeof(struct))\n"
        "    C.cast(raw, C.POINTER(C.c_size_t))[0] = size\n"
        "    return raw\n"
        f"CAMPFIRE = {os.path.join(ROOT, 'scenes', 'campfire', 'campfire.vdb').encode()!r}\n"
        "name = b'filename'; val = (C.c_char_p * 1)(CAMPFIRE)\n"
        "rows = (abi.FmParam * 1)(abi.FmParam(name, abi.TYPE_STRING, 1, C.cast(val, C.c_void_p)))\n"
        "ci = abi.FmCreateInfo(struct_size=C.sizeof(abi.FmCreateInfo), params=rows, count=1)\n"
        "h = C.c_void_p()\n"
        "assert api.volume_create(C.byref(ci), C.byref(h)) == abi.OK\n"
        f"for which, size in {cases!r}:\n"
        "    if which == 'create':\n"
        "        h2 = C.c_void_p()\n"
        "        s = api.volume_create(C.cast(buf(abi.FmCreateInfo, ci, size), C.POINTER(abi.FmCreateInfo)),\n"
        "                              C.byref(h2))\n"
        "        if s == abi.OK: api.volume_destroy(h2)\n"
        "        vals = []\n"
        "    elif which == 'query':\n"
        "        ch = 32\n"
        "        rays = (abi.FmRay * 2)()\n"
        "        for r in rays:\n"
        "            r.origin[:] = [0.0, -2.0, 0.5]; r.direction[:] = [0.0, 1.0, 0.0]; r.tmax = 1e30\n"
        "        out = (C.c_float * (2 * ch))(); tr = (C.c_float * (2 * ch))()\n"
        "        q = abi.FmRayQuery(struct_size=C.sizeof(abi.FmRayQuery), what=abi.QUERY_INTEGRATE, n=2, rays=rays,\n"
        "                           radiance=C.cast(out, abi.c_float_p), transmittance=C.cast(tr, abi.c_float_p))\n"
        "        s = api.volume_query(h, C.cast(buf(abi.FmRayQuery, q, size), C.POINTER(abi.FmRayQuery)))\n"
        "        vals = list(out) + list(tr)\n"
        "    elif which == 'tables':\n"
        "        t0 = abi.FmTables(struct_size=C.sizeof(abi.FmTables))\n"
        "        assert api.volume_tables(h, C.byref(t0)) == abi.OK\n"
        "        a = (C.c_float * (t0.rows * t0.channels))(); j = (C.c_float * (t0.rows * t0.channels))()\n"
        "        sc = (C.c_float * t0.channels)()\n"
        "        t = abi.FmTables(struct_size=C.sizeof(abi.FmTables), absorption=C.cast(a, abi.c_float_p),\n"
        "                         scattering=C.cast(sc, abi.c_float_p), emission=C.cast(j, abi.c_float_p))\n"
        "        s = api.volume_tables(h, C.cast(buf(abi.FmTables, t, size), C.POINTER(abi.FmTables)))\n"
        "        vals = list(j)[-64:] + list(a)[-64:]\n"
        "    elif which == 'detail':\n"
        "        api.volume_create(None, None)\n"
        "        raw = buf(abi.FmErrorDetail, abi.FmErrorDetail(), size)\n"
        "        before = bytes(raw)\n"
        "        s = api.last_error_detail(C.cast(raw, C.POINTER(abi.FmErrorDetail)))\n"
        "        vals = []\n"
        "        if bytes(raw)[max(size, 8):] != before[max(size, 8):]:\n"
        "            print('OVERRUN', which, size, s, flush=True)\n"
        "            continue\n"
        "    else:\n"
        "        pts = (C.c_double * 3)(0.0, 0.0, 0.5); lam = (C.c_double * 2)(450.0, 650.0)\n"
        "        o = [(C.c_double * 2)() for _ in range(4)]\n"
        "        q = abi.FmPointQuery(struct_size=C.sizeof(abi.FmPointQuery), n=1, points=pts, k=2, lambdas=lam,\n"
        "                             sigma_a=o[0], sigma_s=o[1], le=o[2], j=o[3])\n"
        "        s = api.volume_point(h, C.cast(buf(abi.FmPointQuery, q, size), C.POINTER(abi.FmPointQuery)))\n"
        "        vals = [x for a in o for x in a]\n"
        "    nan = s == abi.OK and any(v != v for v in vals)\n"
        "    print('NAN' if nan else ('OK' if s == abi.OK else 'REFUSED'), which, size, s, flush=True)\n"
    )
    return batch_outcomes(h, script, [f"{w} struct_size {n}" for w, n in cases], d)


def run_case(h, kind, rng, d):
    """The outcomes of one process of `kind`: a list of (outcome, last line), one per case it ran."""
    if kind == "python":
        return case_python(h, rng, d)
    if kind == "abi":
        return case_abi(h, rng, d)
    return [{"names": case_names, "bake": case_bake}[kind](h, rng, d)]
