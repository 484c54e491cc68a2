"""firemedium in Mitsuba 3: a ``firemedium`` medium and a ``firepath`` integrator, registered with Mitsuba, in
Mitsuba's vectorised variants (``llvm_*``, ``cuda_*``) at Mitsuba's own speed.

Mitsuba 3 has no emissive media: its volumetric path tracers ignore a medium's emission. This module adds both
halves a fire needs (in the vectorised variants; the scalar ones run a Python call per ray, which a fire's
millions of collisions cannot afford):

- the **medium** ``firemedium`` (a :class:`FireMedium`). At load it builds the fire through the plugin and asks
  it, through the ABI, for the fire in closed form (``volume_tables``, ``volume_fields``: the plugin stays the one
  source of the fire's physics): soot density, temperature and emission scale at every voxel centre of the fire's
  lattice, kept as one Dr.Jit texture, and per unit density σ_a, σ_s and j over temperature — at 1-nm bins read at
  Mitsuba's own wavelengths in spectral variants, projected to linear Rec.709 in RGB ones — kept as a table
  texture. A lookup interpolates the fields, as the plugin does, then reads the table: the fire the plugin
  renders, not its coefficients interpolated between voxels (Planck's law is convex in T: that brightens a
  flame). A fire not of that form (a scatter colour grid, atomic lines) is baked as coefficients at the voxel
  centres instead. Mitsuba's integrators (``volpath``, ``volpathmis``, ``prbvolpath``) then track it as they
  track their own ``heterogeneous`` medium — a majorant, coefficients at points — in one compiled kernel,
  no Python call per point. Its phase function is Henyey–Greenstein with the fire's ``g`` unless the scene gives
  one (a different one is an error). A fire whose layers the medium level cannot express (refraction's curved
  rays, embers' opaque spheres, atomic lines across their profiles, diffusion) is refused when the scene loads,
  naming the feature: the fire would otherwise be silently wrong.
- the **integrator** ``firepath``: a volumetric path tracer written as one Dr.Jit loop over the wavefront. It
  tracks every medium of the scene (the fire, and Mitsuba's own) by delta tracking against its majorant, collects
  the fire's emission at every tentative collision, samples Mitsuba's emitters at surface and medium vertices with
  MIS against BSDF and phase sampling (as ``volpathmis``), and samples the **fire light** — a point by the fire's
  emitted luminance, voxel by voxel — with MIS against the emission the path finds by itself. Shadow rays cross
  null surfaces (the fire's boundary) segment by segment, each segment's length measured from its own origin, and
  their transmittance is ratio-tracked through every medium.

Units: in spectral variants the fire's emission is in W·m⁻³·sr⁻¹·nm⁻¹ (Mitsuba's film: a constant spectrum of 1 is
Y = 1); in RGB variants the same luminance, so a fire renders at the same level in both (× 683 lm/W · 106.857 nm
gives ``firemedium render``'s cd/m²). ``to_world`` places the fire's medium space in the scene (rotation,
translation and a uniform scale).

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")         # llvm_* needs an LLVM Dr.Jit can use (docs/guide/mitsuba.md)
    import firemedium.mitsuba            # registers "firemedium" and "firepath"
    scene = mi.load_dict({...  "medium": {"type": "firemedium", "filename": "campfire.vdb"} ...})
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

import firemedium as fm

try:
    import drjit as dr
    import mitsuba as mi
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError("firemedium.mitsuba needs Mitsuba 3: pip install mitsuba==3.9.1") from e

if mi.variant() is None:
    raise ImportError("firemedium.mitsuba: choose a Mitsuba variant first (mi.set_variant('llvm_ad_rgb'))")
if mi.is_polarized:
    raise ImportError(f"firemedium.mitsuba: the variant {mi.variant()} tracks polarisation, which the fire does not")
if not dr.is_jit_v(mi.Float):
    raise ImportError(
        f"firemedium.mitsuba runs in Mitsuba's vectorised variants (llvm_ad_rgb, llvm_ad_spectral, cuda_*), one compiled "
        f"kernel over the wavefront; the variant is {mi.variant()}. The llvm variants need an LLVM Dr.Jit can use: "
        "DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so (Debian's libllvm19)")

# Features the medium level cannot express: refused, never silently lost.
_REFUSED = ("refraction", "embers", "thick_lines", "diffusion")
# Properties that are Mitsuba's, not the fire's.
_MITSUBA_PROPS = {"type", "id", "to_world", "sample_emitters", "max_threads", "phase"}
# Properties naming files (resolved against the scene's folder as Mitsuba resolves its own).
_FILE_PROPS = {"filename", "dataset", "embersfile", "densityfile", "temperaturefile", "speciesfiles"}
# Y per unit of Mitsuba's relative film, in cd/m²: 683 lm/W × ∫ȳ dλ (nm).
CD_M2_PER_UNIT = 683.0 * 106.856895
# Linear Rec.709 (sRGB primaries, D65) from XYZ.
_XYZ_TO_RGB = np.array([[3.2404542, -1.5371385, -0.4985314],
                        [-0.9692660, 1.8760108, 0.0415560],
                        [0.0556434, -0.2040259, 1.0572252]])
# The most bytes of textures a fire may take (three of them: σ_t, σ_s, j).
_TEXTURE_BUDGET = 8 << 30
# Spectral variants: the tables' bins over Mitsuba's 360–830 nm (1 nm), and the bins of a fire baked as coefficients.
_TABLE_BINS, _BAKED_BINS = 470, 24
# The most temperature rows a table texture keeps (the plugin's are ≤ 0.5 K apart; every k-th row is kept beyond).
_TABLE_ROWS = 4096


def _fire_params(props: mi.Properties) -> dict[str, Any]:
    """The fire's parameters from the medium's properties (every one but Mitsuba's own)."""
    params: dict[str, Any] = {}
    for name in props.keys():
        if name in _MITSUBA_PROPS:
            continue
        value = props[name]
        if isinstance(value, mi.VolumeGrid):
            # An inline grid (pbrt-v4's uniformgrid arrays: density, temperature, Lescale): Mitsuba's own grid
            # type, x fastest, its shape giving nx, ny, nz unless the scene says them.
            a = np.array(value, dtype=np.float64)
            if a.ndim == 4 and a.shape[3] != 1:
                raise fm.FiremediumError(f"firemedium (Mitsuba): grid '{name}' has {a.shape[3]} channels; expected 1",
                                         status="invalid parameter", parameter=name)
            nz, ny, nx = a.shape[:3]
            for k, v in (("nx", nx), ("ny", ny), ("nz", nz)):
                if k not in props:
                    params[k] = v
            params[name] = a.ravel()
        elif isinstance(value, mi.Object):
            continue
        elif isinstance(value, str) and name in _FILE_PROPS:
            # A file named relative to the scene: Mitsuba's file resolver holds the XML file's folder while it loads.
            resolved = Path(str(mi.Thread.thread().file_resolver().resolve(value)))
            params[name] = str(resolved) if not Path(value).is_absolute() and resolved.exists() else value
        elif isinstance(value, (str, bool, int, float)):
            params[name] = value
        else:
            # Mitsuba's vectors, points and colours: their components.
            params[name] = [float(x) for x in value]
    return params


def _bins(count: int) -> tuple[int, float, float] | None:
    """The spectral variants' bins, beside the scene's parameters (its own ``bins``, ``lambdamin`` and
    ``lambdamax`` win): the wavelengths Mitsuba samples, 1 nm each for the closed form's tables, read between bin
    centres at Mitsuba's wavelengths (the spectrum itself; a fire baked as coefficients takes 24 bins)."""
    return (count, 360.0, 830.0) if mi.is_spectral else None


def _phase_g(phase) -> float | None:
    """The g of a Henyey–Greenstein phase function; 0 for an isotropic one; None for any other."""
    name = phase.class_name() if hasattr(phase, "class_name") else type(phase).__name__
    if "Isotropic" in name:
        return 0.0
    if "HG" in name or "Henyey" in name:
        return float(mi.traverse(phase)["g"][0]) if hasattr(mi.traverse(phase)["g"], "__len__") else \
            float(mi.traverse(phase)["g"])
    return None


class FireMedium(mi.Medium):
    """The fire as a Mitsuba medium (``"type": "firemedium"``); every other property is a fire parameter."""

    def __init__(self, props: mi.Properties):
        params = _fire_params(props)
        self.to_world = mi.ScalarTransform4f(props["to_world"]) if "to_world" in props else mi.ScalarTransform4f()
        volume = fm.Volume(params, bins=_bins(_TABLE_BINS))
        try:
            tables = volume.tables()
        except fm.FiremediumError as e:
            if e.status != "unsupported":
                raise
            tables = None
            if mi.is_spectral and "bins" not in props:
                volume = fm.Volume(params, bins=_bins(_BAKED_BINS))
        refused = [f for f in _REFUSED if f in volume.features]
        if refused:
            raise fm.FiremediumError(
                "firemedium (Mitsuba): the fire holds " + ", ".join(refused)
                + ", which a host tracking the medium itself cannot express (the medium level's features mask); "
                "render it with `firemedium render`, or leave those parameters out",
                status="unsupported",
            )
        # The phase function: the fire's Henyey–Greenstein g, unless the scene gives one; a different one is an error.
        given = [props[n] for n in props.keys() if isinstance(props[n], mi.PhaseFunction)]
        if given:
            g = _phase_g(given[0])
            if volume.g != 0.0 and (g is None or abs(g - volume.g) > 1e-6):
                raise fm.FiremediumError(
                    f"firemedium (Mitsuba): the scene gives the fire a phase function ({given[0].class_name()}"
                    f"{'' if g is None else f', g {g}'}) other than its own (Henyey–Greenstein, g {volume.g}): "
                    "leave the phase out, or give the fire's g",
                    status="invalid parameter", parameter="phase")
        elif volume.g != 0.0:
            props["phase"] = mi.load_dict({"type": "hg", "g": float(volume.g)})
        super().__init__(props)
        self.volume = volume
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        self.to_medium = self.to_world.inverse()
        m = np.array(self.to_world.matrix, dtype=float)[:3, :3]
        # Uniform scale of to_world (σ per medium unit → per world unit divides by it).
        self.scale = abs(np.linalg.det(m)) ** (1.0 / 3.0)
        self.emits = "emits" in volume.features
        self._tables = tables
        if tables is not None:
            self._bake_fields(tables)
        else:
            self._bake()
        lo, hi = volume.bounds
        self.bbox = mi.ScalarBoundingBox3f()
        for c in [mi.ScalarPoint3f(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]:
            self.bbox.expand(self.to_world @ c)
        self._to_medium = mi.Transform4f(self.to_medium)
        self._light = None

    # -- the fire's grids, baked once -------------------------------------------------------------------------

    def _channel_weights(self) -> tuple[np.ndarray, np.ndarray]:
        """How the plugin's channels become the variant's: (σ weights (C, K), emission weights (C, K)) — in RGB
        variants each channel's linear Rec.709 (σ: by the positive part of its light in each component; j: its
        colour, scaled to Mitsuba's relative film), in monochromatic ones its luminance, in spectral ones the
        identity (bins)."""
        c = self.volume.channels
        if mi.is_spectral:
            eye = np.eye(c)
            return eye, eye
        xyz = self.volume.channel_xyz()
        if mi.is_monochromatic:
            y = xyz[:, 1:2]
            return y / max(float(y.sum()), 1e-300), y / CD_M2_PER_UNIT
        rgb = xyz @ _XYZ_TO_RGB.T  # (C, 3)
        pos = np.maximum(rgb, 0.0)
        w_sigma = pos / np.maximum(pos.sum(axis=0, keepdims=True), 1e-300)
        return w_sigma, rgb / CD_M2_PER_UNIT

    def _lattice_slabs(self, what: str, k: int, per_voxel):
        """An array (nz + 2, ny + 2, nx + 2, k) of `per_voxel(points)` ((n, k) at the lattice's voxel centres), a
        zero layer around (the lookup fades to 0 past the outer samples, as the plugin's does), z slab by z slab;
        refused above the texture budget. Also sets the padded box the textures span and the lattice."""
        (nx, ny, nz), lo, hi = self.volume.lattice
        lo, hi = np.array(lo), np.array(hi)
        voxel = (hi - lo) / np.array([nx, ny, nz])
        need = 4 * k * (nx + 2) * (ny + 2) * (nz + 2)
        if need > _TEXTURE_BUDGET:
            raise fm.FiremediumError(
                f"firemedium (Mitsuba): the fire's {what} need {need / 2**30:.1f} GiB ({nx}×{ny}×{nz} voxels × {k} "
                f"floats), above {_TEXTURE_BUDGET / 2**30:.0f} GiB: an RGB variant, or fewer bins",
                status="unsupported")
        out = np.zeros((nz + 2, ny + 2, nx + 2, k), dtype=np.float32)
        xs = lo[0] + (np.arange(nx) + 0.5) * voxel[0]
        ys = lo[1] + (np.arange(ny) + 0.5) * voxel[1]
        yy, xx = np.meshgrid(ys, xs, indexing="ij")
        for z in range(nz):
            pts = np.stack([xx.ravel(), yy.ravel(), np.full(xx.size, lo[2] + (z + 0.5) * voxel[2])], axis=1)
            out[z + 1, 1:-1, 1:-1] = per_voxel(pts).reshape(ny, nx, k)
        self.tex_lo = mi.ScalarPoint3f(*(lo - voxel))
        self.tex_size = mi.ScalarVector3f(*((hi - lo) + 2 * voxel))
        self.lattice = ((nx, ny, nz), lo, voxel)
        return out

    @staticmethod
    def _rgb_absorption(a: np.ndarray, j: np.ndarray, w_sigma: np.ndarray, w_emit: np.ndarray) -> np.ndarray:
        """σ_a per unit density over T in RGB (or luminance) channels, from the bins' (rows × C): each channel's
        mean of the bins' σ weighted by the light that crosses it — where the fire glows (its luminance at T
        within 10⁻³ of its hottest), its own: the bins' emission in that channel (a Planck mean, the channel's
        optically thin and thick limits both exact); where it does not (below 10⁻⁴, smoke lit by other lights),
        a white light's (the channel's response to each bin); between, a blend. Only where the channel's
        signed sum is a fifth of its absolute one or more (the colour matching functions' negative lobes could
        make a mean of anything), and kept within the bins' range. On the campfire's brightest line of sight the
        white weights alone leave the flame 2.5 % dark against the spectral render; these, 0.2 %."""
        white = a @ w_sigma
        signed, absolute = j @ w_emit, j @ np.abs(w_emit)
        ok = (absolute > 0.0) & (np.abs(signed) >= 0.2 * absolute)
        glow = np.where(ok, (a * j) @ w_emit / np.where(ok, signed, 1.0), white)
        glow = np.clip(glow, a.min(axis=1, keepdims=True), a.max(axis=1, keepdims=True))
        y = signed @ (np.array([0.2126, 0.7152, 0.0722]) if signed.shape[1] == 3 else np.ones(1))
        level = np.log10(np.maximum(y, 1e-300) / max(float(y.max()), 1e-300))
        f = np.clip(level + 4.0, 0.0, 1.0)[:, None]
        return f * glow + (1.0 - f) * white

    def _bake_fields(self, tables: dict):
        """The closed form: the fields d, T, les on the lattice as one texture, and σ_a, σ_s, j per unit density
        over T as a table texture in the variant's channels (spectral: [A, S, J] over rows × 1-nm bins)."""
        fields = self._lattice_slabs("fields", 3, self.volume.fields)
        a, sc, j = tables["absorption"].astype(np.float64), tables["scattering"].astype(np.float64), \
            tables["emission"].astype(np.float64)
        # Every k-th row up to the last (the hottest voxel's T), at most _TABLE_ROWS: the tables are smooth in T.
        rows = a.shape[0]
        k = max(1, math.ceil((rows - 1) / (_TABLE_ROWS - 1)))
        keep = np.minimum(np.arange(math.ceil((rows - 1) / k) + 1) * k, rows - 1)
        a, j = a[keep], j[keep]
        self.rows, self.dt = len(keep), tables["dt"] * k
        self.t_emit = float(tables["t_emit"])
        self.emission_grid = tables["emission_grid"]
        w_sigma, w_emit = self._channel_weights()
        a_rows = a @ w_sigma if mi.is_spectral else self._rgb_absorption(a, j, w_sigma, w_emit)
        # Per world unit (the medium's unit × scale).
        a, sc, j = a_rows / self.scale, sc @ w_sigma / self.scale, j @ w_emit / self.scale
        self.channels = a.shape[1]
        if mi.is_spectral:
            tab = np.stack([a, np.broadcast_to(sc, a.shape), j], axis=2).astype(np.float32)  # (rows, bins, 3)
            self.table_tex = mi.Texture2f(mi.TensorXf(tab), filter_mode=dr.FilterMode.Linear,
                                          wrap_mode=dr.WrapMode.Clamp)
        else:
            tab = np.concatenate([a, np.broadcast_to(sc, a.shape), j], axis=1).astype(np.float32)  # (rows, 3K)
            self.table_tex = mi.Texture1f(mi.TensorXf(tab), filter_mode=dr.FilterMode.Linear,
                                          wrap_mode=dr.WrapMode.Clamp)
        self.fields_tex = mi.Texture3f(mi.TensorXf(fields), filter_mode=dr.FilterMode.Linear,
                                       wrap_mode=dr.WrapMode.Clamp)
        d_max = float(np.maximum(fields[..., 0], 0.0).max())
        self.majorant_value = d_max * float((a + sc).max())
        lo, hi = self.volume.bounds
        self._bounds_m = mi.ScalarBoundingBox3f(mi.ScalarPoint3f(*lo), mi.ScalarPoint3f(*hi))
        if self.emits:
            # Each voxel's emitted luminance (its centre's), for the fire light's distribution.
            y = self._luminance_weights()
            y_of_row = j @ y
            d, t, les = (fields[1:-1, 1:-1, 1:-1, i].astype(np.float64) for i in range(3))
            e = np.maximum(les, 0.0) if self.emission_grid else np.maximum(d, 0.0) * np.maximum(les, 0.0)
            lum = e * np.interp(t / self.dt, np.arange(self.rows), y_of_row) * (t > self.t_emit)
            self._voxel_luminance = np.maximum(lum, 0.0).astype(np.float32)  # (nz, ny, nx)
        else:
            self._voxel_luminance = None

    def _luminance_weights(self) -> np.ndarray:
        """Luminance per unit of each of the variant's channels: the bins' Y (spectral), 1 (monochromatic), Rec. 709's
        weights (RGB)."""
        if mi.is_spectral:
            return self.volume.channel_xyz()[:, 1] / CD_M2_PER_UNIT
        if mi.is_monochromatic:
            return np.ones(1)
        return np.array([0.2126, 0.7152, 0.0722])

    def _bake(self):
        """A fire not of the closed form: σ_t, σ_s and j at every voxel centre in the variant's channels, each a
        texture (linear between voxel centres)."""
        w_sigma, w_emit = self._channel_weights()
        k = w_sigma.shape[1]

        def coefficients(pts):
            sa, ss, j = (x.astype(np.float64) for x in self.volume.coefficients(pts))
            return np.concatenate([(sa + ss) @ w_sigma, ss @ w_sigma, j @ w_emit], axis=1)

        both = self._lattice_slabs("textures", 3 * k, coefficients)
        # World units: σ and j per world unit (the medium's unit × scale).
        both /= self.scale
        sigma_t, sigma_s, emit = both[..., :k], both[..., k:2 * k], both[..., 2 * k:]
        self.channels = k
        self.majorant_value = float(sigma_t.max())
        tex = lambda a: mi.Texture3f(mi.TensorXf(np.ascontiguousarray(a)), filter_mode=dr.FilterMode.Linear,
                                     wrap_mode=dr.WrapMode.Clamp)
        self.sigma_t_tex, self.sigma_s_tex = tex(sigma_t), tex(sigma_s)
        self.emit_tex = tex(emit) if self.emits else None
        if self.emits:
            # Each voxel's emitted luminance (its centre's), for the fire light's distribution.
            y = self._luminance_weights()
            lum = np.tensordot(emit[1:-1, 1:-1, 1:-1], y, axes=([3], [0]))
            self._voxel_luminance = np.maximum(lum, 0.0).astype(np.float32)  # (nz, ny, nx)
        else:
            self._voxel_luminance = None

    # -- what Mitsuba asks of a medium --------------------------------------------------------------------------

    def _uvw(self, p_world):
        p = self._to_medium @ p_world
        return (p - mi.Point3f(self.tex_lo)) / mi.Vector3f(self.tex_size)

    def _lookup(self, tex, mei):
        """A baked texture's value at the interaction, in the variant's Spectrum (spectral: each wavelength's bin)."""
        vals = tex.eval(self._uvw(mei.p))
        if not mi.is_spectral:
            return mi.Spectrum(vals[0], vals[1], vals[2]) if not mi.is_monochromatic else mi.Spectrum(vals[0])
        lo, hi = self.volume.wavelength_range
        out = dr.zeros(mi.Spectrum)
        for i in range(dr.size_v(mi.Spectrum)):
            lam = mei.wavelengths[i]
            b = mi.Int32(dr.floor((lam - lo) / (hi - lo) * self.channels))
            v = mi.Float(0.0)
            for c in range(self.channels):
                v = dr.select(b == c, vals[c], v)
            out[i] = v
        return out

    def _closed_form(self, mei):
        """σ_a, σ_s and j at the interaction from the closed form: the fields interpolated (zero outside the
        volume's bounds, d and les clamped at 0), then the table at their temperature (and, spectral, at each of
        the interaction's wavelengths)."""
        p = self._to_medium @ mei.p
        f = self.fields_tex.eval((p - mi.Point3f(self.tex_lo)) / mi.Vector3f(self.tex_size))
        inside = mi.BoundingBox3f(mi.Point3f(self._bounds_m.min), mi.Point3f(self._bounds_m.max)).contains(p)
        d = dr.select(inside, dr.maximum(f[0], 0.0), 0.0)
        t = f[1]
        les = dr.select(inside, dr.maximum(f[2], 0.0), 0.0)
        e = les if self.emission_grid else d * les
        e = dr.select(t > self.t_emit, e, 0.0)
        row = (t / self.dt + 0.5) / self.rows
        if mi.is_spectral:
            sa, ss, j = dr.zeros(mi.Spectrum), dr.zeros(mi.Spectrum), dr.zeros(mi.Spectrum)
            lo, hi = self.volume.wavelength_range
            for i in range(dr.size_v(mi.Spectrum)):
                v = self.table_tex.eval(mi.Point2f((mei.wavelengths[i] - lo) / (hi - lo), row))
                sa[i], ss[i], j[i] = v[0], v[1], v[2]
        else:
            v = self.table_tex.eval(mi.Point1f(row))
            k = self.channels
            sa, ss, j = (mi.Spectrum(*v[o:o + k]) for o in (0, k, 2 * k))
        return d * sa, d * ss, e * j

    def get_majorant(self, mei, active=True):
        return mi.Spectrum(self.majorant_value)

    def get_scattering_coefficients(self, mei, active=True):
        if self._tables is not None:
            sigma_a, sigma_s, _ = self._closed_form(mei)
            sigma_t = sigma_a + sigma_s
        else:
            sigma_t = self._lookup(self.sigma_t_tex, mei)
            sigma_s = self._lookup(self.sigma_s_tex, mei)
        sigma_n = dr.maximum(mi.Spectrum(self.majorant_value) - sigma_t, 0.0)
        return sigma_s, sigma_n, sigma_t

    def emission(self, mei, active=True):
        """The emission coefficient j = σ_a·Le at the interaction, per world unit (Mitsuba's units)."""
        if not self.emits:
            return mi.Spectrum(0.0)
        j = self._closed_form(mei)[2] if self._tables is not None else self._lookup(self.emit_tex, mei)
        return dr.select(active, j, mi.Spectrum(0.0))

    def intersect_aabb(self, ray):
        bbox = mi.BoundingBox3f(mi.Point3f(self.bbox.min), mi.Point3f(self.bbox.max))
        return bbox.ray_intersect(ray)

    # -- the fire light -----------------------------------------------------------------------------------------

    def light(self) -> "FireLight | None":
        """The fire light (built on first use), or None for a fire that emits nothing."""
        if self._light is None and self._voxel_luminance is not None and self._voxel_luminance.sum() > 0.0:
            self._light = FireLight(self)
        return self._light

    def traverse(self, callback):
        pass

    def parameters_changed(self, keys):
        pass

    def to_string(self):
        return f"FireMedium[{self.volume!r}]"


class FireLight:
    """Selle's piecewise-constant pdf over the fire's voxels, by emitted luminance: a point sampled uniformly in a
    voxel chosen by its light, and that density at any point (per unit world volume)."""

    def __init__(self, fire: FireMedium):
        self.fire = fire
        (nx, ny, nz), lo, voxel = fire.lattice
        self.n = (nx, ny, nz)
        self.lo = mi.ScalarPoint3f(*lo)
        self.voxel = mi.ScalarVector3f(*voxel)
        w = fire._voxel_luminance.ravel().astype(np.float64)  # x fastest
        self.dist = mi.DiscreteDistribution(mi.Float(w.astype(np.float32)))
        self.pmf = mi.Float(w / w.sum())
        self.voxel_volume_world = float(np.prod(voxel)) * fire.scale ** 3

    def sample(self, u1, u2):
        """A world point and its density per unit world volume, from uniforms u1 (1D) and u2 (3D as 2D + 1D)."""
        idx = self.dist.sample(u1)
        nx, ny, _ = self.n
        i = idx % nx
        j = (idx // nx) % ny
        k = idx // (nx * ny)
        frac = mi.Vector3f(u2[0], u2[1], u2[2])
        p_m = mi.Point3f(self.lo) + (mi.Vector3f(mi.Float(i), mi.Float(j), mi.Float(k)) + frac) * \
            mi.Vector3f(self.voxel)
        p = mi.Transform4f(self.fire.to_world) @ p_m
        pdf = dr.gather(mi.Float, self.pmf, idx) / self.voxel_volume_world
        return p, pdf

    def pdf(self, p_world, active=True):
        """The density per unit world volume of sampling the point."""
        p = self.fire._to_medium @ p_world
        c = (p - mi.Point3f(self.lo)) / mi.Vector3f(self.voxel)
        nx, ny, nz = self.n
        i, j, k = mi.Int32(dr.floor(c.x)), mi.Int32(dr.floor(c.y)), mi.Int32(dr.floor(c.z))
        inside = active & (i >= 0) & (j >= 0) & (k >= 0) & (i < nx) & (j < ny) & (k < nz)
        idx = mi.UInt32(dr.select(inside, i + nx * (j + ny * k), 0))
        return dr.select(inside, dr.gather(mi.Float, self.pmf, idx, inside) / self.voxel_volume_world, 0.0)


def _is(medium, fire):
    """Where the medium pointer is the fire: a mask over the wavefront."""
    return medium == mi.MediumPtr(fire)


def _mis(a, b):
    """The balance heuristic's weight of a density `a` against `b` (0 where both are 0)."""
    s = a + b
    return dr.select(s > 0.0, a / s, 0.0)


class FirePath(mi.SamplingIntegrator):
    """``"type": "firepath"``: volumetric path tracing with the fire's emission and its light, in one Dr.Jit loop.

    Properties: ``max_depth`` (default 8: scattering events and surface bounces, as Mitsuba counts them),
    ``rr_depth`` (5), ``fire_light`` (true: next-event estimation towards every ``firemedium`` medium's fire
    light, MIS against the emission paths find), ``hide_emitters`` (false).
    """

    def __init__(self, props: mi.Properties):
        super().__init__(props)
        self.max_depth = int(props.get("max_depth", 8))
        self.rr_depth = int(props.get("rr_depth", 5))
        self.fire_light = bool(props.get("fire_light", True))
        self.hide_emitters = bool(props.get("hide_emitters", False))
        self._fires: list[FireMedium] | None = None

    def _fires_of(self, scene) -> list[FireMedium]:
        if self._fires is None:
            found = {}
            for shape in scene.shapes():
                for m in (shape.interior_medium(), shape.exterior_medium()):
                    if isinstance(m, FireMedium):
                        found[id(m)] = m
            self._fires = list(found.values())
        return self._fires

    # -- transmittance along a shadow segment, through null surfaces and every medium ----------------------------

    @dr.syntax
    def _transmittance(self, scene, sampler, it, target, medium, channel, active):
        """Ratio tracking from the interaction `it` to the world point `target`: each segment (to the next
        surface, crossed when it is null) starts from its own origin and is measured to the target from there;
        an opaque surface before the target blocks. Returns the transmittance (0 when blocked)."""
        tr = mi.Spectrum(1.0)
        ray = it.spawn_ray_to(target)
        active = mi.Bool(active)
        medium = mi.MediumPtr(medium)
        si = dr.zeros(mi.SurfaceInteraction3f)
        needs_si = mi.Bool(True)
        while dr.hint(active, label="firepath shadow ray"):
            si[needs_si] = scene.ray_intersect(ray, needs_si & active)
            needs_si &= ~active
            in_medium = active & (medium != None)
            mei = medium.sample_interaction(ray, sampler.next_1d(in_medium), channel, in_medium)
            collided = in_medium & mei.is_valid() & (mei.t < si.t)
            # A tentative collision: the null share carries on (ratio tracking).
            tr[collided] *= mei.sigma_n / mei.combined_extinction
            ray.o[collided] = mei.p
            ray.maxt[collided] = ray.maxt - mei.t
            si.t[collided] = si.t - mei.t
            # No collision before the surface (or the segment's end): the segment is done.
            at_surface = active & ~collided
            reached = at_surface & ~si.is_valid()
            active &= ~reached
            hit = at_surface & si.is_valid()
            bsdf = si.bsdf(ray)
            null = hit & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null)
            blocked = hit & ~null
            tr[blocked] = 0.0
            active &= ~blocked
            # Cross the null surface: a new segment from it, measured to the target from there.
            medium[null] = si.target_medium(ray.d)
            ray[null] = si.spawn_ray_to(target)
            needs_si |= null
            active &= dr.any(tr > 0.0)
        return tr

    # -- next-event estimation ---------------------------------------------------------------------------------

    def _emitters_nee(self, scene, sampler, it, medium, channel, eval_fn, active):
        """Mitsuba's emitters from the vertex `it`: (contribution without the path throughput)."""
        active = mi.Bool(active)  # (a copy: the caller's mask is not changed in place)
        ds, em_w = scene.sample_emitter_direction(it, sampler.next_2d(active), False, active)
        active &= ds.pdf > 0.0
        value, pdf_other = eval_fn(ds.d, active)
        tr = self._transmittance(scene, sampler, it, ds.p, medium, channel, active & dr.any(value > 0.0))
        w = dr.select(ds.delta, 1.0, _mis(ds.pdf, pdf_other))
        return dr.select(active, value * em_w * tr * w, 0.0)

    def _fire_nee(self, scene, sampler, it, medium, channel, eval_fn, active):
        """Every fire's light from the vertex `it`: a point sampled by the fire's light, MIS against the emission
        the path would find along that direction (the same weights as `_emission_weight`)."""
        total = mi.Spectrum(0.0)
        for fire in self._fires_of(scene):
            light = fire.light()
            if light is None:
                continue
            u1 = sampler.next_1d(active)
            u2 = sampler.next_2d(active)
            u3 = sampler.next_1d(active)
            p, pdf_v = light.sample(u1, mi.Point3f(u2.x, u2.y, u3))
            d = p - it.p
            dist2 = dr.squared_norm(d)
            ok = active & (pdf_v > 0.0) & (dist2 > 1e-14)
            wo = d * dr.rsqrt(dist2)
            value, pdf_dir = eval_fn(wo, ok)
            ok &= dr.any(value > 0.0)
            mei = dr.zeros(mi.MediumInteraction3f)
            mei.p = p
            mei.wavelengths = it.wavelengths
            j = fire.emission(mei, ok)
            tr = self._transmittance(scene, sampler, it, p, medium, channel, ok & dr.any(j > 0.0))
            # Densities per unit volume at p: the light's, and the path's (its direction's density over t², times
            # the rate of its tentative collisions, the majorant).
            p_path = pdf_dir * fire.majorant_value / dist2
            w = _mis(pdf_v, p_path)
            total += dr.select(ok, value * tr * j * w / (pdf_v * dist2), 0.0)
        return total

    # -- the path ---------------------------------------------------------------------------------------------

    @dr.syntax
    def sample(self, scene, sampler, ray, medium=None, active=True):
        fires = self._fires_of(scene)
        ray = mi.Ray3f(ray)
        L = mi.Spectrum(0.0)
        beta = mi.Spectrum(1.0)
        depth = mi.UInt32(0)
        active = mi.Bool(active)
        medium = dr.zeros(mi.MediumPtr) if medium is None else mi.MediumPtr(medium)
        si = dr.zeros(mi.SurfaceInteraction3f)
        needs_si = mi.Bool(True)
        # The last real scattering vertex and the density of the direction sampled there (MIS of what the path
        # finds after it); `direct`: a camera ray or one after a specular bounce (no other strategy: weight 1).
        prev = dr.zeros(mi.Interaction3f)
        prev_pdf = mi.Float(1.0)
        direct = mi.Bool(True)
        channel = mi.UInt32(0)
        if dr.hint(mi.is_rgb, mode="scalar"):
            n_ch = dr.size_v(mi.Spectrum)
            channel = mi.UInt32(dr.minimum(n_ch * sampler.next_1d(active), n_ch - 1))
        while dr.hint(active, label="firepath"):
            active &= dr.any(beta != 0.0)
            # Russian roulette on the throughput past rr_depth.
            q = dr.minimum(dr.max(beta), 0.95)
            rr = active & (depth >= self.rr_depth)
            active &= ~rr | (sampler.next_1d(active) < q)
            beta[rr] = beta / q

            si[needs_si & active] = scene.ray_intersect(ray, needs_si & active)
            needs_si &= ~active
            in_medium = active & (medium != None)
            mei = medium.sample_interaction(ray, sampler.next_1d(in_medium), channel, in_medium)
            collided = in_medium & mei.is_valid() & (mei.t < si.t)

            # ---- a tentative collision in a medium: the fire's emission, then scatter or carry on
            for fire in fires:
                is_fire = collided & _is(medium, fire)
                j = fire.emission(mei, is_fire)
                light = fire.light() if self.fire_light else None
                w = mi.Float(1.0)
                if light is not None:
                    t2 = dr.squared_norm(mei.p - prev.p)
                    p_path = prev_pdf * fire.majorant_value / dr.maximum(t2, 1e-14)
                    w = dr.select(direct, 1.0, _mis(p_path, light.pdf(mei.p, is_fire)))
                L[is_fire] += beta * j * w / mei.combined_extinction
            # Scattering by the mean of the channels' probabilities; absorption and null collisions carry on, the
            # absorbed share a weight (the fire's emission behind its own soot at the noise of a weight).
            p_scatter = dr.mean(mei.sigma_s / mei.combined_extinction)
            want = collided & (sampler.next_1d(collided) < p_scatter)
            carry = collided & ~want
            beta[carry] *= mei.sigma_n / (mei.combined_extinction * (1.0 - p_scatter))
            ray.o[carry] = mei.p
            ray.maxt[carry] = ray.maxt - mei.t
            si.t[carry] = si.t - mei.t
            beta[want] *= mei.sigma_s / (mei.combined_extinction * p_scatter)
            depth[want] += 1
            scatter = want & (depth < self.max_depth)
            active &= ~(want & ~scatter)
            phase_ctx = mi.PhaseFunctionContext(sampler)
            phase = mei.medium.phase_function()
            phase[~scatter] = dr.zeros(mi.PhaseFunctionPtr)

            def eval_phase(wo, act, mei=mei, phase=phase, phase_ctx=phase_ctx):
                v, p = phase.eval_pdf(phase_ctx, mei, wo, act)
                return mi.Spectrum(v), p

            L[scatter] += beta * self._emitters_nee(scene, sampler, mei, medium, channel, eval_phase, scatter)
            if dr.hint(self.fire_light, mode="scalar"):
                L[scatter] += beta * self._fire_nee(scene, sampler, mei, medium, channel, eval_phase, scatter)
            wo, w_phase, pdf_phase = phase.sample(phase_ctx, mei, sampler.next_1d(scatter), sampler.next_2d(scatter),
                                                  scatter)
            scatter &= pdf_phase > 0.0
            beta[scatter] *= w_phase
            prev[scatter] = mei
            prev_pdf[scatter] = pdf_phase
            direct[scatter] = False
            ray[scatter] = mei.spawn_ray(wo)
            needs_si |= scatter

            # ---- the surface the ray reaches (no collision before it)
            at_surface = active & ~collided
            emitter = si.emitter(scene)
            hit_emitter = at_surface & (emitter != None) & ~(self.hide_emitters & (depth == 0))
            ds = mi.DirectionSample3f(scene, si, prev)
            pdf_em = scene.pdf_emitter_direction(prev, ds, hit_emitter & ~direct)
            le = emitter.eval(si, hit_emitter)
            L[hit_emitter] += beta * le * dr.select(direct, 1.0, _mis(prev_pdf, pdf_em))
            at_surface &= si.is_valid()
            active &= ~(active & ~collided & ~si.is_valid())
            bsdf = si.bsdf(ray)
            null = at_surface & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null)
            # A null surface (the fire's boundary): crossed, the path's direction and MIS state unchanged.
            medium[null] = si.target_medium(ray.d)
            ray[null] = si.spawn_ray(ray.d)
            needs_si |= null
            real = at_surface & ~null
            depth[real] += 1
            real &= depth < self.max_depth
            active &= ~(at_surface & ~null & (depth >= self.max_depth))
            ctx = mi.BSDFContext()
            smooth = real & mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth)

            def eval_bsdf(wo, act, si=si, bsdf=bsdf, ctx=ctx):
                return bsdf.eval_pdf(ctx, si, si.to_local(wo), act)

            L[smooth] += beta * self._emitters_nee(scene, sampler, si, medium, channel, eval_bsdf, smooth)
            if dr.hint(self.fire_light, mode="scalar"):
                L[smooth] += beta * self._fire_nee(scene, sampler, si, medium, channel, eval_bsdf, smooth)
            bs, w_bsdf = bsdf.sample(ctx, si, sampler.next_1d(real), sampler.next_2d(real), real)
            real &= bs.pdf > 0.0
            active &= ~(at_surface & ~null & ~real)
            beta[real] *= w_bsdf
            wo = si.to_world(bs.wo)
            delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            prev[real] = si
            prev_pdf[real] = bs.pdf
            direct[real] = delta
            medium[real] = si.target_medium(wo)
            ray[real] = si.spawn_ray(wo)
            needs_si |= real
        return L, mi.Bool(True), []

    def aov_names(self):
        return []

    def to_string(self):
        return f"FirePath[max_depth={self.max_depth}, fire_light={self.fire_light}]"


mi.register_medium("firemedium", lambda props: FireMedium(props))
mi.register_integrator("firepath", lambda props: FirePath(props))
