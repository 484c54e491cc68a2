"""firemedium from Python: the fire medium plugin through its C ABI, over numpy arrays.

A fire is a :class:`Volume` made from a dataset and the plugin's parameters (``docs/reference/params.md``)::

    import numpy as np
    import firemedium

    fire = firemedium.Volume({"filename": "scenes/campfire/campfire.vdb", "fuel": "propane"})
    print(fire.bounds, fire.features)
    radiance, transmittance = fire.integrate(origins, directions)   # the fast whole-ray path
    c = fire.point(points, lambdas)                                 # the medium level: sigma_a, sigma_s, Le, j
    light = fire.light()                                            # the fire light: sample, pdf, line estimate

The package loads the plugin library as the ``firemedium`` command does (:func:`find_plugin`); errors come back
as :class:`FiremediumError`, carrying the plugin's message and, where it has them, the parameter, the location
and the file at fault. Arrays in are anything numpy converts (shape ``(n, 3)`` for points and directions); arrays
out are numpy arrays, one row per ray or point.
"""

from __future__ import annotations

import ctypes as C
import json
import os
import shutil
import subprocess
import sys
import threading
import warnings
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import numpy as np

from . import _abi as abi

__all__ = [
    "FiremediumError",
    "Plugin",
    "Volume",
    "Light",
    "find_plugin",
    "plugin",
    "info",
    "FEATURES",
]

FEATURES = tuple(abi.FEATURES)
"""The names of the features a volume reports (:attr:`Volume.features`)."""


class FiremediumError(Exception):
    """A call into the plugin failed.

    ``str(error)`` is the plugin's message (it names the component, the parameter or file, the value and the
    expectation). The structure beside it, for a program: ``status`` (``"invalid parameter"``, ``"dataset"``,
    ``"unsupported"``, ...), ``parameter``, ``index`` (its place in the ``params`` the call was given, in their
    order), ``location`` (``file:line:col`` where the caller said the parameter came from), ``file`` and
    ``position`` (``"byte 1234"``) — each ``None`` when the error has no such part.
    """

    def __init__(
        self,
        message: str,
        status: str = "invalid argument",
        parameter: str | None = None,
        location: str | None = None,
        file: str | None = None,
        position: str | None = None,
        index: int | None = None,
    ):
        super().__init__(message)
        self.message = message
        self.status = status
        self.parameter = parameter
        self.location = location
        self.file = file
        self.position = position
        self.index = index


def _library_name() -> str:
    if sys.platform == "darwin":
        return "libfiremedium_plugin.dylib"
    if sys.platform == "win32":
        return "firemedium_plugin.dll"
    return "libfiremedium_plugin.so"


def find_plugin() -> Path:
    """The plugin library's path, looked up as the ``firemedium`` command looks it up.

    In order: the file ``FIREMEDIUM_PLUGIN`` names; the library in each folder of ``FIREMEDIUM_PLUGIN_PATH``;
    the one ``pip install`` built into this package (``firemedium/lib``); beside the ``firemedium`` command on
    the ``PATH`` and in its ``../lib/firemedium`` (what ``tools/install.sh`` installs). Raises
    :class:`FiremediumError` naming every place it looked.
    """
    named = os.environ.get("FIREMEDIUM_PLUGIN")
    if named:
        return Path(named)
    name = _library_name()
    dirs = [Path(d) for d in os.environ.get("FIREMEDIUM_PLUGIN_PATH", "").split(os.pathsep) if d]
    dirs.append(Path(__file__).resolve().parent / "lib")
    command = shutil.which("firemedium")
    if command:
        here = Path(command).resolve().parent
        dirs += [here, here.parent / "lib" / "firemedium", here / "deps"]
    for d in dirs:
        if (d / name).is_file():
            return d / name
    looked = ", ".join(str(d) for d in dirs) or "nowhere (no FIREMEDIUM_PLUGIN_PATH, no firemedium on the PATH)"
    raise FiremediumError(
        f"no firemedium plugin found (set FIREMEDIUM_PLUGIN to its file, or put the firemedium command on the PATH); looked in: {looked}",
        status="not found",
    )


def _floats(a: Any, what: str) -> np.ndarray:
    """`a` as float64 values: real numbers only (a complex array would lose its imaginary part silently)."""
    arr = np.asarray(a)
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"{what}: expected real numbers, got an array of {arr.dtype}")
    return arr.astype(np.float64, copy=False)


def _as_points(a: Any, what: str) -> np.ndarray:
    arr = np.ascontiguousarray(_floats(a, what))
    if arr.ndim == 1 and arr.size == 3:
        arr = arr.reshape(1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{what}: expected an array of shape (n, 3), got shape {arr.shape}")
    return arr


def _per_item(a: Any, n: int, what: str) -> np.ndarray | None:
    """`a` as n float64 values, one per item (a single number is repeated): checked here, before the plugin reads
    n of them; None stays None."""
    if a is None:
        return None
    arr = _floats(a, what)
    if arr.ndim > 1 or (arr.ndim == 1 and arr.size not in (1, n)):
        raise ValueError(f"{what}: expected a number or {n} values (one per item), got shape {arr.shape}")
    return np.ascontiguousarray(np.broadcast_to(arr.reshape(-1) if arr.ndim else arr, (n,)))


def _paired(origins: Any, directions: Any) -> tuple[np.ndarray, np.ndarray]:
    """Origins and directions as (n, 3) arrays of the same n (one origin for every direction is repeated):
    checked here, before the plugin reads n rows of each."""
    o = _as_points(origins, "origins")
    d = _as_points(directions, "directions")
    if len(o) == 1 and len(d) > 1:
        o = np.ascontiguousarray(np.broadcast_to(o, d.shape))
    if len(o) != len(d):
        raise ValueError(f"origins and directions: {len(o)} against {len(d)} rows (expected the same, or one origin)")
    return o, d


_INT64 = (-(1 << 63), (1 << 63) - 1)


def _dp(a: np.ndarray | None):
    return None if a is None else a.ctypes.data_as(abi.c_double_p)


def _fp(a: np.ndarray | None):
    return None if a is None else a.ctypes.data_as(abi.c_float_p)


class Plugin:
    """The loaded plugin library (one per process is plenty: :func:`plugin` keeps it).

    ``Plugin(path)`` loads the library at ``path`` and checks its ABI version: a plugin whose major version is
    not 1, or whose minor is older than this package's, is refused with both versions named.
    """

    def __init__(self, path: str | os.PathLike | None = None):
        self.path = Path(path) if path is not None else find_plugin()
        if not self.path.is_file():
            raise FiremediumError(f"{self.path}: no such plugin file", status="not found", file=str(self.path))
        self._lib = C.CDLL(str(self.path))
        entry = getattr(self._lib, abi.ENTRY_SYMBOL, None)
        if entry is None:
            raise FiremediumError(f"{self.path} is not a firemedium plugin: no {abi.ENTRY_SYMBOL}", file=str(self.path))
        entry.restype = C.POINTER(abi.FmApi)
        entry.argtypes = []
        table = entry()
        if not table:
            raise FiremediumError(f"{self.path}: its entry point returned no table", file=str(self.path))
        head = C.cast(table, C.POINTER(C.c_uint32 * 3)).contents
        major, minor, size = head[0], head[1], head[2]
        if major != abi.ABI_MAJOR or minor < abi.ABI_MINOR or size < C.sizeof(abi.FmApi):
            raise FiremediumError(
                f"{self.path}: plugin ABI {major}.{minor} (table of {size} bytes), this package speaks "
                f"{abi.ABI_MAJOR}.{abi.ABI_MINOR} (table of {C.sizeof(abi.FmApi)} bytes)",
                status="unsupported",
                file=str(self.path),
            )
        self.api = table.contents
        self.abi_version = (major, minor)
        self._types: dict[str, str] | None = None

    def _error(self) -> FiremediumError:
        n = self.api.last_error(None, 0)
        buf = C.create_string_buffer(n + 1)
        self.api.last_error(buf, n + 1)
        d = abi.FmErrorDetail(struct_size=C.sizeof(abi.FmErrorDetail), index=-1)
        parts: dict[str, Any] = {}
        if self.api.last_error_detail(C.byref(d)) == abi.OK:
            parts = {
                "status": abi.STATUS_NAMES.get(d.status, str(d.status)),
                "index": d.index if d.index >= 0 else None,
                **{k: (getattr(d, k).decode("utf-8", "replace") if getattr(d, k) else None)
                   for k in ("parameter", "location", "file", "position")},
            }
        return FiremediumError(buf.value.decode("utf-8", "replace"), **parts)

    def _check(self, status: int) -> None:
        if status != abi.OK:
            raise self._error()

    def parameters(self) -> list[dict[str, str]]:
        """Every row of the plugin's parameter tables: component, name, type, default, unit, range, doc."""
        rows = []
        for i in range(self.api.param_count()):
            r = abi.FmParamInfo(struct_size=C.sizeof(abi.FmParamInfo))
            self._check(self.api.param_info(i, C.byref(r)))
            rows.append({k: (getattr(r, k) or b"").decode() for k in
                         ("component", "name", "ty", "default_value", "unit", "range", "doc")})
        return rows

    def _type_of(self, name: str) -> str | None:
        if self._types is None:
            self._types = {}
            for r in self.parameters():
                self._types.setdefault(r["name"], r["ty"])
        return self._types.get(name)

    def _params(self, params: Mapping[str, Any]):
        """FmParam rows for `params`, typed by the plugin's own tables (a name it does not know goes as the
        value's natural type, so the plugin's error names it), and what keeps their values alive."""
        rows = (abi.FmParam * max(len(params), 1))()
        keep: list[Any] = []
        for i, (name, value) in enumerate(params.items()):
            ty = self._type_of(name)
            if ty is None:
                ty = ("bool" if isinstance(value, bool) else "integer" if isinstance(value, int)
                      else "string" if isinstance(value, (str, os.PathLike)) else "float")
            code = abi.TYPE_CODES[ty]
            values = value if isinstance(value, (list, tuple, np.ndarray)) else [value]
            if code == abi.TYPE_STRING:
                enc = [os.fsencode(v) if isinstance(v, os.PathLike) else str(v).encode() for v in values]
                for e in enc:
                    # (A C string ends at its first NUL: the plugin would read a shorter name than given.)
                    if b"\0" in e:
                        raise ValueError(f"{name}: {e!r} holds a NUL character, which a parameter's string cannot")
                arr = (C.c_char_p * len(enc))(*enc)
                keep.append(enc)
            elif code == abi.TYPE_INTEGER:
                ints = []
                for v in values:
                    if isinstance(v, float) and not v.is_integer():
                        raise ValueError(f"{name}: {v} is not an integer")
                    iv = int(v)
                    # (ctypes wraps an integer past 64 bits silently: 2**64 + 8 would reach the plugin as 8.)
                    if not _INT64[0] <= iv <= _INT64[1]:
                        raise ValueError(f"{name}: {iv} does not fit a 64-bit integer")
                    ints.append(iv)
                arr = (C.c_int64 * len(ints))(*ints)
            elif code == abi.TYPE_BOOL:
                arr = (C.c_uint8 * len(values))(*[1 if v else 0 for v in values])
            else:
                flat = np.asarray(values, dtype=np.float64).ravel()
                arr = (C.c_double * flat.size)(*flat.tolist())
            keep.append(arr)
            n = name.encode()
            keep.append(n)
            rows[i] = abi.FmParam(n, code, len(arr), C.cast(arr, C.c_void_p))
        return rows, keep


_PLUGIN: Plugin | None = None
_PLUGIN_LOCK = threading.Lock()


def plugin() -> Plugin:
    """The process's plugin, loaded on first use from :func:`find_plugin`."""
    global _PLUGIN
    with _PLUGIN_LOCK:
        if _PLUGIN is None:
            _PLUGIN = Plugin()
        return _PLUGIN


class Volume:
    """A fire volume: a dataset with the fire's parameters (``docs/reference/params.md``), built once, then queried.

    ``params`` maps parameter names to values: a ``str`` (or path) for strings, numbers, bools, sequences for
    arrays (a ``point3`` as 3 numbers, a spectrum as (nm, value) pairs flattened). Relative file names are
    resolved against ``directory`` (default: the working directory). ``threads`` bounds the build's threads
    (0: every core), ``max_bytes`` the memory a grid may take (0: the plugin's default), ``frame`` fills a
    ``####`` in a file name, ``shutter`` = (open, close) in frames enables motion blur where the data moves.
    ``kind`` says what the host's medium type means (``"fire"``, the paper's; ``"pbrt"``, pbrt-v4's grid media)
    and ``bins`` = (count, shortest nm, longest nm) the host's spectral bins; a parameter the scene gives itself
    (``mode``, ``bins``, ``lambdamin``, ``lambdamax``, ``threads``, ...) wins over these.
    """

    def __init__(
        self,
        params: Mapping[str, Any],
        *,
        directory: str | os.PathLike | None = None,
        threads: int = 0,
        max_bytes: int = 0,
        frame: int | None = None,
        shutter: tuple[float, float] | None = None,
        kind: str | None = None,
        bins: tuple[int, float, float] | None = None,
        plugin: Plugin | None = None,
    ):
        self.plugin = plugin or globals()["plugin"]()
        p = self.plugin
        rows, keep = p._params(params)
        info = abi.FmCreateInfo(struct_size=C.sizeof(abi.FmCreateInfo))
        info.params = rows
        info.count = len(params)
        info.threads = threads
        info.max_bytes = max_bytes
        if frame is not None:
            info.flags |= abi.CREATE_FRAME
            info.frame = frame
        if shutter is not None:
            info.flags |= abi.CREATE_SHUTTER
            info.shutter[0], info.shutter[1] = shutter
        d = os.fsencode(directory) if directory is not None else None
        info.directory = d
        kinds = {None: abi.KIND_SCENE, "fire": abi.KIND_FIRE, "pbrt": abi.KIND_PBRT}
        if kind not in kinds:
            raise FiremediumError(f"kind {kind!r}: expected 'fire', 'pbrt' or None (the scene's mode)")
        info.kind = kinds[kind]
        if bins is not None:
            info.bins = bins[0]
            info.wavelengths[0], info.wavelengths[1] = bins[1], bins[2]
        handle = C.c_void_p()
        p._check(p.api.volume_create(C.byref(info), C.byref(handle)))
        del keep
        self._h = handle
        vi = abi.FmVolumeInfo(struct_size=C.sizeof(abi.FmVolumeInfo))
        p._check(p.api.volume_info(self._h, C.byref(vi)))
        self.bounds = (tuple(vi.bounds_min), tuple(vi.bounds_max))
        """The medium-space box the fire fills: ((x0, y0, z0), (x1, y1, z1))."""
        self.channels = vi.channels
        """How many channels the fast path's radiance and transmittance have (spectral bins or XYZ)."""
        self.channel_space = "spectral" if vi.channel_space == abi.SPACE_SPECTRAL else "xyz"
        self.wavelength_range = (vi.lambda_min, vi.lambda_max)
        self.g = vi.g
        """The Henyey–Greenstein asymmetry of the fire's scattering."""
        self.step = vi.step
        self.bytes = vi.bytes
        self.build_seconds = vi.build_seconds
        self.lattice = (tuple(vi.dims), tuple(vi.lattice_min), tuple(vi.lattice_max))
        """The dataset's lattice: ((nx, ny, nz), lower corner, upper corner), samples cell-centred over the box
        — where :meth:`coefficients` bakes the fire's grids."""
        mask = C.c_uint64()
        p._check(p.api.volume_features(self._h, C.byref(mask)))
        self.features = frozenset(k for k, bit in abi.FEATURES.items() if mask.value & bit)
        """What the fire holds: a subset of :data:`FEATURES`. A host tracking the medium itself refuses or
        falls back for ``refraction``, ``embers``, ``thick_lines`` and ``diffusion``, which the medium level
        cannot express."""
        self.notes = self._notes()
        """What the plugin's build found that a user should hear (species whose lines fall outside the channels,
        flame colours the model cannot give), one line each; each is also issued as a :class:`UserWarning`."""
        for note in self.notes:
            warnings.warn(f"firemedium: {note}", stacklevel=2)

    def _notes(self) -> list[str]:
        p = self.plugin
        count = C.c_size_t()
        p._check(p.api.volume_note_count(self._h, C.byref(count)))
        out = []
        for i in range(count.value):
            n = C.c_size_t()
            p._check(p.api.volume_note(self._h, i, None, 0, C.byref(n)))
            buf = C.create_string_buffer(n.value + 1)
            p._check(p.api.volume_note(self._h, i, buf, len(buf), C.byref(n)))
            out.append(buf.value.decode("utf-8", "replace"))
        return out

    def __del__(self):
        h = getattr(self, "_h", None)
        if h:
            self.plugin.api.volume_destroy(h)
            self._h = None

    def __repr__(self) -> str:
        return (f"<firemedium.Volume {self.channels} {self.channel_space} channels, bounds {self.bounds}, "
                f"features {sorted(self.features)}>")

    # -- what it is -------------------------------------------------------------------------------------------

    def channel_xyz(self) -> np.ndarray:
        """(channels, 3): the CIE X, Y, Z of unit radiance in each channel (Y in cd/m² per W·m⁻²·sr⁻¹·nm⁻¹ of
        a spectral bin) — how a film turns the fast path's channels into colour."""
        out = np.zeros((self.channels, 3))
        self.plugin._check(self.plugin.api.volume_channel_xyz(self._h, _dp(out), out.size))
        return out

    def temperature_range(self) -> tuple[float, float]:
        """The lowest and highest temperature in the data, K."""
        out = np.zeros(2)
        self.plugin._check(self.plugin.api.volume_temperature_range(self._h, _dp(out)))
        return float(out[0]), float(out[1])

    def majorant_grid(self) -> dict[str, Any]:
        """The majorant grid, for free-path sampling of one's own: ``bounds`` (x0, y0, z0, x1, y1, z1),
        ``cell`` (its cells' size), ``counts`` (nx, ny, nz) and ``sigma_t``, an (nz, ny, nx) array bounding σ_t
        (per medium unit) over every point of each cell, every wavelength and the shutter."""
        g = abi.FmMajorantGrid(struct_size=C.sizeof(abi.FmMajorantGrid))
        self.plugin._check(self.plugin.api.volume_majorant_grid(self._h, C.byref(g)))
        nx, ny, nz = g.counts
        sig = np.ctypeslib.as_array(g.sigma_t, shape=(nz * ny * nx,)).copy().reshape(nz, ny, nx)
        return {"bounds": tuple(g.bounds), "cell": tuple(g.cell), "counts": (nx, ny, nz), "sigma_t": sig}

    # -- the medium level -------------------------------------------------------------------------------------

    def point(self, points: Any, lambdas: Any, times: Any = None) -> dict[str, np.ndarray]:
        """The fire's coefficients at points, each at wavelengths of its own: what pbrt-v4's ``SamplePoint`` and
        Mitsuba's ``get_scattering_coefficients`` ask.

        ``points`` (n, 3) in medium space; ``lambdas`` (n, k) nm — or (k,) for the same k at every point;
        ``times`` (n,) frames from the grids' time, or None. Returns ``sigma_a``, ``sigma_s`` (per medium unit),
        ``le`` (emitted radiance, W·m⁻²·sr⁻¹·nm⁻¹) and ``j`` = σ_a·Le, each (n, k). A fire whose layers the closed
        forms cannot express (atomic lines, art direction, diffusion, refraction, embers) raises
        :class:`FiremediumError` with status ``"unsupported"`` naming the layer.
        """
        pts = _as_points(points, "points")
        n = len(pts)
        lam = _floats(lambdas, "lambdas")
        if lam.ndim == 0:
            lam = lam.reshape(1)
        if lam.ndim == 1:
            lam = np.broadcast_to(lam, (n, lam.size))
        lam = np.ascontiguousarray(lam)
        if lam.ndim != 2 or lam.shape[0] != n or lam.shape[1] == 0:
            raise ValueError(f"lambdas: expected (k,) or ({n}, k) wavelengths (one row per point), got shape {lam.shape}")
        k = lam.shape[1]
        t = _per_item(times, n, "times")
        out = {name: np.zeros((n, k)) for name in ("sigma_a", "sigma_s", "le", "j")}
        q = abi.FmPointQuery(struct_size=C.sizeof(abi.FmPointQuery), n=n, points=_dp(pts), times=_dp(t), k=k,
                             lambdas=_dp(lam), sigma_a=_dp(out["sigma_a"]), sigma_s=_dp(out["sigma_s"]),
                             le=_dp(out["le"]), j=_dp(out["j"]))
        self.plugin._check(self.plugin.api.volume_point(self._h, C.byref(q)))
        return out

    def coefficients(self, points: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The fire's coefficients at points in its channels (the fast path's tables, as ``firemedium bake``
        reads them): σ_a, σ_s (per medium unit) and the emission coefficient j, each (n, channels) float32 —
        at every voxel centre of :attr:`lattice`, a bake of the fire."""
        pts = _as_points(points, "points")
        n = len(pts)
        out = [np.zeros((n, self.channels), dtype=np.float32) for _ in range(3)]
        self.plugin._check(self.plugin.api.volume_coefficients(self._h, _dp(pts), n, _fp(out[0]), _fp(out[1]),
                                                               _fp(out[2])))
        return out[0], out[1], out[2]

    def tables(self) -> dict[str, Any]:
        """The fire's coefficients in closed form, for a host that textures it (Dr.Jit, a GPU): ``absorption``
        (rows, channels) σ_a per unit density over T, ``scattering`` (channels,) σ_s per unit density,
        ``emission`` (rows, channels) j per unit of e over T (float32; row r at T = r·``dt`` K), ``t_emit`` (it
        emits where T > t_emit) and ``emission_grid`` (e = les, else d·les). With d, T, les from :meth:`fields`
        interpolated trilinearly: σ_a = d·A(T), σ_s = d·S, j = e·J(T), the tables linear in T — the volume's own
        coefficients at every point. :class:`FiremediumError` (``"unsupported"``) naming what is not of that form
        (atomic lines, a scatter colour grid, diffusion, refraction, embers, motion blur, a dataset not
        interpolated trilinearly)."""
        t = abi.FmTables(struct_size=C.sizeof(abi.FmTables))
        self.plugin._check(self.plugin.api.volume_tables(self._h, C.byref(t)))
        rows, c = t.rows, t.channels
        a = np.zeros((rows, c), dtype=np.float32)
        s = np.zeros(c, dtype=np.float32)
        j = np.zeros((rows, c), dtype=np.float32)
        t.absorption, t.scattering, t.emission = _fp(a), _fp(s), _fp(j)
        self.plugin._check(self.plugin.api.volume_tables(self._h, C.byref(t)))
        return {"dt": t.dt, "t_emit": t.t_emit, "emission_grid": bool(t.flags & abi.TABLES_EMISSION_GRID),
                "absorption": a, "scattering": s, "emission": j}

    def fields(self, points: Any) -> np.ndarray:
        """The fields the closed form (:meth:`tables`) reads at points: (n, 3) float32 of soot density d,
        temperature T (K) and the Lescale or emission grid's value les (1 without one), as the volume interpolates
        them; zeros outside. At :attr:`lattice`'s voxel centres, the voxels' own values."""
        pts = _as_points(points, "points")
        out = np.zeros((len(pts), 3), dtype=np.float32)
        self.plugin._check(self.plugin.api.volume_fields(self._h, _dp(pts), len(pts), _fp(out)))
        return out

    # -- the fast path ----------------------------------------------------------------------------------------

    def _rays(self, origins: Any, directions: Any, tmin: Any, tmax: Any, seed: int):
        o, d = _paired(origins, directions)
        n = len(o)
        if not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < (1 << 64):
            raise ValueError(f"seed: expected an integer from 0 to 2**64 - 1, got {seed!r}")
        seed = int(seed)
        rays = (abi.FmRay * max(n, 1))()
        lo = _per_item(tmin, n, "tmin")
        hi = _per_item(tmax, n, "tmax")
        for i in range(n):
            rays[i].origin[:] = o[i].tolist()
            rays[i].direction[:] = d[i].tolist()
            rays[i].tmin = float(lo[i])
            rays[i].tmax = float(hi[i])
            rays[i].seed = (seed + i * 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
        return rays, n

    def integrate(self, origins: Any, directions: Any, *, tmin: Any = 0.0, tmax: Any = 1e30, times: Any = None,
                  seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """The fire's emitted radiance and transmittance along whole rays, the plugin's fast path (its march,
        or its tracking in a scattering fire): two (n, channels) arrays in the volume's channels (see
        :meth:`channel_xyz`). Rays are straight segments ``origin + t·direction``, ``t`` in [tmin, tmax]."""
        rays, n = self._rays(origins, directions, tmin, tmax, seed)
        t = _per_item(times, n, "times")
        rad = np.zeros((n, self.channels), dtype=np.float32)
        tr = np.zeros((n, self.channels), dtype=np.float32)
        q = abi.FmRayQuery(struct_size=C.sizeof(abi.FmRayQuery), what=abi.QUERY_INTEGRATE, n=n, rays=rays,
                           times=_dp(t), radiance=_fp(rad), transmittance=_fp(tr))
        self.plugin._check(self.plugin.api.volume_query(self._h, C.byref(q)))
        return rad, tr

    def transmittance(self, origins: Any, directions: Any, *, tmin: Any = 0.0, tmax: Any = 1e30,
                      times: Any = None, seed: int = 0) -> np.ndarray:
        """Transmittance along rays (shadow rays): (n, channels)."""
        rays, n = self._rays(origins, directions, tmin, tmax, seed)
        t = _per_item(times, n, "times")
        tr = np.zeros((n, self.channels), dtype=np.float32)
        q = abi.FmRayQuery(struct_size=C.sizeof(abi.FmRayQuery), what=abi.QUERY_TRANSMITTANCE, n=n, rays=rays,
                           times=_dp(t), transmittance=_fp(tr))
        self.plugin._check(self.plugin.api.volume_query(self._h, C.byref(q)))
        return tr

    def light(self, params: Mapping[str, Any] | None = None) -> "Light":
        """The fire light of this volume (``docs/reference/params.md``, the light's table; ``{"weighting": "power"}`` by
        default): Selle's pdf over the emitting voxels, for next-event estimation towards the fire."""
        return Light(self, params or {})


class Light:
    """The fire light: samples points by the fire's power, their densities, and the line estimate of the fire's
    radiance along a sampled direction. Keeps its volume alive."""

    def __init__(self, volume: Volume, params: Mapping[str, Any]):
        self.volume = volume
        p = volume.plugin
        self.plugin = p
        rows, keep = p._params(params)
        handle = C.c_void_p()
        p._check(p.api.light_create(volume._h, rows, len(params), C.byref(handle)))
        del keep
        self._h = handle
        li = abi.FmLightInfo(struct_size=C.sizeof(abi.FmLightInfo))
        p._check(p.api.light_info(self._h, C.byref(li)))
        self.power_w = li.power_w
        """The fire's radiant power over the whole spectrum, W."""
        self.power_lm = li.power_lm
        self.voxels = li.voxels
        self.bytes = li.bytes

    def __del__(self):
        h = getattr(self, "_h", None)
        if h:
            self.plugin.api.light_destroy(h)
            self._h = None

    def sample(self, u: Any, times: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Points sampled by the fire's power from ``u``, (n, 6) uniform numbers in [0, 1): (points (n, 3),
        pdf (n,) per unit medium volume, emission j at each point (n, channels))."""
        uu = _floats(u, "u")
        if uu.ndim == 1 and uu.size == 6:
            uu = uu.reshape(1, 6)
        if uu.ndim != 2 or uu.shape[1] != 6:
            raise ValueError(f"u: expected an array of shape (n, 6), got shape {uu.shape}")
        uu = np.ascontiguousarray(uu)
        n = len(uu)
        t = _per_item(times, n, "times")
        pts = np.zeros((n, 3))
        pdf = np.zeros(n)
        em = np.zeros((n, self.volume.channels), dtype=np.float32)
        self.plugin._check(self.plugin.api.light_sample(self._h, _dp(uu), _dp(t), n, _dp(pts), _dp(pdf), _fp(em)))
        return pts, pdf, em

    def pdf(self, points: Any, times: Any = None) -> np.ndarray:
        """The density per unit medium volume of sampling each point: (n,)."""
        pts = _as_points(points, "points")
        t = _per_item(times, len(pts), "times")
        out = np.zeros(len(pts))
        self.plugin._check(self.plugin.api.light_pdf(self._h, _dp(pts), _dp(t), len(pts), _dp(out)))
        return out

    def pdf_direction(self, origins: Any, directions: Any, times: Any = None) -> np.ndarray:
        """The solid-angle density with which a sampled point lies in each direction from each origin: (n,)."""
        o, d = _paired(origins, directions)
        t = _per_item(times, len(d), "times")
        out = np.zeros(len(d))
        self.plugin._check(self.plugin.api.light_pdf_direction(self._h, _dp(o), _dp(d), _dp(t), len(d), _dp(out)))
        return out

    def integrate(self, origins: Any, directions: Any, *, tmin: Any = 0.0, tmax: Any = 1e30, times: Any = None,
                  seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """The line estimate: the fire's radiance and transmittance along straight rays as the light estimates
        them for next-event estimation (its coarser march): two (n, channels) arrays."""
        rays, n = self.volume._rays(origins, directions, tmin, tmax, seed)
        t = _per_item(times, n, "times")
        rad = np.zeros((n, self.volume.channels), dtype=np.float32)
        tr = np.zeros((n, self.volume.channels), dtype=np.float32)
        self.plugin._check(self.plugin.api.light_integrate(self._h, rays, _dp(t), n, _fp(rad), _fp(tr)))
        return rad, tr


def info(path: str | os.PathLike, *, command: str | os.PathLike | None = None, **options: Any) -> dict[str, Any]:
    """What ``firemedium info --json`` says of a dataset file: dims, bounds, grids with statistics, bytes and load
    time. Runs the ``firemedium`` command (``command``, else the one on the PATH, else the one beside the plugin);
    ``options`` become its flags (``grid="density"`` → ``--grid density``). Raises :class:`FiremediumError` with
    the command's one-line message when the file is refused."""
    exe = command or shutil.which("firemedium")
    if exe is None:
        beside = find_plugin().parent / ("firemedium.exe" if sys.platform == "win32" else "firemedium")
        if beside.is_file():
            exe = beside
        else:
            raise FiremediumError("info: no firemedium command on the PATH or beside the plugin", status="not found")
    args = [os.fspath(exe), "info", os.fspath(path), "--json"]
    for k, v in options.items():
        args += [f"--{k.replace('_', '-')}", str(v)]
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        msg = r.stderr.strip().removeprefix("firemedium: ")
        raise FiremediumError(msg, status="dataset", file=os.fspath(path))
    return json.loads(r.stdout)
