"""firemedium in Mitsuba 3: a ``firemedium`` medium and a ``firepath`` integrator, registered with Mitsuba.

Mitsuba 3 has no emissive media: its volumetric path tracer ignores medium emission. This module adds both
halves a fire needs, written against ABI 1.0's medium level:

- the **medium** ``firemedium`` (a :class:`FireMedium`): Mitsuba asks it what pbrt-v4 asks of a medium — the
  coefficients σ_a, σ_s at a point at the path's own wavelengths and time (``get_scattering_coefficients``, from the
  plugin's ``volume_point``), and a majorant (``get_majorant``: the largest cell of the exported majorant grid);
  its ``emission`` is j = σ_a·Le at the same wavelengths. A fire whose layers the medium level cannot express
  (refraction's curved rays, embers' opaque spheres, atomic lines across their profiles, diffusion) is refused
  when the scene loads, naming the feature: the fire would otherwise be silently wrong.
- the **integrator** ``firepath``: a volumetric path tracer (delta tracking against the majorant, Mitsuba's
  BSDFs, emitters and phase functions) that collects medium emission as pbrt-v4 does — β·σ_a·Le/σ̄ at every
  tentative collision — and estimates the fire's light at every surface and medium vertex by next-event
  estimation towards the fire light (points sampled by the fire's power; its line estimate along the sampled
  direction), weighed by MIS against the paths that find the fire by themselves. Mitsuba's own emitters are
  sampled too, their shadow rays attenuated through the fire by ratio tracking.

It runs in Mitsuba's ``scalar_spectral`` variant (the fire's colour is its spectrum; Python media and integrators
run per ray there: small images, or many cores). The medium's parameters are the plugin's (``docs/reference/params.md``), given as the medium's
properties; ``to_world`` places the fire's medium space in the scene (rotation, translation and a uniform scale).

    import mitsuba as mi
    mi.set_variant("scalar_spectral")
    import firemedium.mitsuba            # registers "firemedium" and "firepath"
    scene = mi.load_dict({...  "medium": {"type": "firemedium", "filename": "campfire.vdb"} ...})
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

import firemedium as fm

try:
    import mitsuba as mi
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError("firemedium.mitsuba needs Mitsuba 3: pip install mitsuba==3.9.1") from e

if mi.variant() is None:
    raise ImportError("firemedium.mitsuba: choose a Mitsuba variant first (mi.set_variant('scalar_spectral'))")
if mi.variant() != "scalar_spectral":
    raise ImportError(
        f"firemedium.mitsuba runs in Mitsuba's scalar_spectral variant (the fire's colour is its spectrum); the variant is {mi.variant()}"
    )
# Features the medium level cannot express: refused, never silently lost.
_REFUSED = ("refraction", "embers", "thick_lines", "diffusion")
# Properties that are Mitsuba's, not the fire's.
_MITSUBA_PROPS = {"type", "id", "to_world", "sample_emitters", "max_threads"}


def _lambdas(wavelengths) -> np.ndarray:
    return np.array([float(wavelengths[i]) for i in range(len(wavelengths))])


def _spectrum(values) -> Any:
    return mi.Spectrum([float(v) for v in values])


class FireMedium(mi.Medium):
    """The fire as a Mitsuba medium (``"type": "firemedium"``); every other property is a fire parameter."""

    def __init__(self, props: mi.Properties):
        super().__init__(props)
        self.m_is_homogeneous = False
        self.m_has_spectral_extinction = True
        params: dict[str, Any] = {}
        self.to_world = mi.ScalarTransform4f()
        for name in props.keys():
            value = props[name]
            if name == "to_world":
                self.to_world = mi.ScalarTransform4f(value)
            elif name in _MITSUBA_PROPS:
                continue
            elif isinstance(value, mi.VolumeGrid):
                # An inline grid (pbrt-v4's uniformgrid arrays: density, temperature, Lescale): Mitsuba's own
                # grid type, x fastest, its shape giving nx, ny, nz unless the scene says them.
                a = np.array(value, dtype=np.float64)
                if a.ndim == 4 and a.shape[3] != 1:
                    raise fm.FiremediumError(
                        f"firemedium (Mitsuba): grid '{name}' has {a.shape[3]} channels; expected 1", status="invalid parameter", parameter=name)
                nz, ny, nx = a.shape[:3]
                for k, v in (("nx", nx), ("ny", ny), ("nz", nz)):
                    if k not in props:
                        params[k] = v
                params[name] = a.ravel()
            elif isinstance(value, mi.Object):
                continue  # the phase function: Mitsuba's, read by Medium
            elif isinstance(value, (str, bool, int, float)):
                params[name] = value
            else:
                # Mitsuba's vectors, points and colours: their components.
                params[name] = [float(x) for x in value]
        # The next-event line estimate reads the fire's bins: span the wavelengths Mitsuba samples.
        params.setdefault("lambdamin", 360.0)
        params.setdefault("lambdamax", 830.0)
        params.setdefault("bins", 47)
        self.volume = fm.Volume(params)
        refused = [f for f in _REFUSED if f in self.volume.features]
        if refused:
            raise fm.FiremediumError(
                "firemedium (Mitsuba): the fire holds " + ", ".join(refused)
                + ", which a host tracking the medium itself cannot express (the medium level's features mask); "
                "render it with `firemedium render`, or leave those parameters out",
                status="unsupported",
            )
        self.to_medium = self.to_world.inverse()
        # Uniform scale of to_world (σ per medium unit → per world unit divides by it).
        m = np.array(self.to_world.matrix, dtype=float)[:3, :3]
        self.scale = abs(np.linalg.det(m)) ** (1.0 / 3.0)
        grid = self.volume.majorant_grid()
        self.majorant = float(grid["sigma_t"].max()) / self.scale
        self._grid = grid
        lo, hi = self.volume.bounds
        corners = [mi.ScalarPoint3f(x, y, z) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        self.bbox = mi.BoundingBox3f()
        for c in corners:
            self.bbox.expand(mi.Point3f(self.to_world @ c))
        self.emits = "emits" in self.volume.features
        self._light = None

    # -- the medium level, at Mitsuba's wavelengths ----------------------------------------------------------

    def _medium_point(self, p) -> list[float]:
        q = self.to_medium @ mi.ScalarPoint3f(float(p[0]), float(p[1]), float(p[2]))
        return [float(q[0]), float(q[1]), float(q[2])]

    def coefficients(self, mei) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """σ_a, σ_s and j = σ_a·Le at the interaction's point, wavelengths and time, per world unit."""
        c = self.volume.point([self._medium_point(mei.p)], _lambdas(mei.wavelengths), [float(mei.time)])
        s = self.scale
        return c["sigma_a"][0] / s, c["sigma_s"][0] / s, c["j"][0] / s

    def segments(self, ray, tmax: float):
        """The majorant along `ray` from its origin to `tmax` (world units), cell by cell of the exported majorant
        grid (pbrt-v4's DDA majorant iterator): a list of (t0, t1, σ̄ per world unit). The cells at the grid's
        edges stretch to the volume's bounds, as the ABI says."""
        ray = mi.Ray3f(ray)
        ray.maxt = tmax
        hit, mint, maxt = self.bbox.ray_intersect(ray)
        if not hit:
            return []
        t0, t1 = max(float(mint), 0.0), min(float(maxt), tmax)
        if not t1 > t0:
            return []
        o = np.array(self._medium_point(ray.o))
        d = np.array(_medium_dir(self, ray.d))
        g = self._grid
        b0 = np.array(g["bounds"][:3])
        cell = np.array(g["cell"])
        n = np.array(g["counts"])
        sig = g["sigma_t"]
        p = o + t0 * d
        idx = np.clip(np.floor((p - b0) / cell).astype(int), 0, n - 1)
        step = np.where(d > 0, 1, -1)
        nxt = np.full(3, math.inf)
        for a in range(3):
            if d[a] != 0.0:
                # The next interior face in the direction of travel (edge cells stretch outwards).
                k = idx[a] + (1 if d[a] > 0 else 0)
                if 0 < k < n[a]:
                    nxt[a] = (b0[a] + k * cell[a] - o[a]) / d[a]
        out = []
        t = t0
        # σ per medium unit → per unit of t: |d_m| (d is a unit world direction).
        per_t = float(np.linalg.norm(d))
        for _ in range(int(n.sum()) + 3):
            a = int(np.argmin(nxt))
            end = min(float(nxt[a]), t1)
            if end > t:
                out.append((t, end, float(sig[idx[2], idx[1], idx[0]]) * per_t))
            if end >= t1:
                break
            t = end
            idx[a] += step[a]
            k = idx[a] + (1 if d[a] > 0 else 0)
            nxt[a] = (b0[a] + k * cell[a] - o[a]) / d[a] if 0 < k < n[a] else math.inf
        return out

    def collisions(self, ray, tmax: float, sampler):
        """Tentative collisions along `ray` up to `tmax`, sampled against the local majorant: (t, σ̄) pairs."""
        for a, b, m in self.segments(ray, tmax):
            if not m > 0.0:
                continue
            t = a
            while True:
                t -= math.log(1.0 - sampler.next_1d()) / m
                if t >= b:
                    break
                yield t, m

    def get_majorant(self, mei, active=True):
        return mi.Spectrum(self.majorant)

    def get_scattering_coefficients(self, mei, active=True):
        sa, ss, _ = self.coefficients(mei)
        st = sa + ss
        return _spectrum(ss), _spectrum(np.maximum(self.majorant - st, 0.0)), _spectrum(st)

    def emission(self, mei):
        """The emission coefficient j = σ_a·Le (W·m⁻³·sr⁻¹·nm⁻¹ in world units) at the interaction."""
        return _spectrum(self.coefficients(mei)[2])

    def intersect_aabb(self, ray):
        return self.bbox.ray_intersect(ray)

    # -- the fire light ----------------------------------------------------------------------------------------

    def light(self) -> fm.Light | None:
        """The fire light (built on first use), or None for a fire that does not emit."""
        if self._light is None and self.emits:
            self._light = self.volume.light({"weighting": "power"})
        return self._light

    def bin_of(self, lam: float) -> int:
        lo, hi = self.volume.wavelength_range
        n = self.volume.channels
        if not lo <= lam < hi:
            return -1
        return min(int((lam - lo) / (hi - lo) * n), n - 1)

    def to_string(self):
        return f"FireMedium[{self.volume!r}]"


def _medium_dir(medium: FireMedium, d) -> list[float]:
    v = medium.to_medium @ mi.ScalarVector3f(float(d[0]), float(d[1]), float(d[2]))
    return [float(v[0]), float(v[1]), float(v[2])]


def _luminance_weight(spec) -> float:
    return max(float(spec[i]) for i in range(len(spec)))


class FirePath(mi.SamplingIntegrator):
    """``"type": "firepath"``: Mitsuba's volumetric path tracing with the fire's emission and the fire light.

    Properties: ``max_depth`` (default 8: scattering events, as Mitsuba counts them), ``rr_depth`` (5), and
    ``fire_light`` (true: next-event estimation towards every ``firemedium`` medium's fire light).
    """

    def __init__(self, props: mi.Properties):
        super().__init__(props)
        self.max_depth = int(props.get("max_depth", 8))
        self.rr_depth = int(props.get("rr_depth", 5))
        self.fire_light = bool(props.get("fire_light", True))
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

    # -- transmittance through media and null surfaces (shadow rays) --------------------------------------

    def _transmittance(self, scene, sampler, ray, medium, dist: float):
        """Ratio tracking through the fire media along `ray` up to `dist`, crossing null surfaces; 0 when an
        opaque surface blocks."""
        tr = mi.Spectrum(1.0)
        ray = mi.Ray3f(ray)
        left = dist
        for _ in range(64):
            ray.maxt = left
            si = scene.ray_intersect(ray)
            seg = float(si.t) if si.is_valid() else left
            if isinstance(medium, FireMedium):
                for t, m in medium.collisions(ray, seg, sampler):
                    mei = mi.MediumInteraction3f()
                    mei.p = ray(t)
                    mei.wavelengths = ray.wavelengths
                    mei.time = ray.time
                    sa, ss, _ = medium.coefficients(mei)
                    tr *= _spectrum(np.maximum(1.0 - (sa + ss) / m, 0.0))
                    if _luminance_weight(tr) <= 0.0:
                        return mi.Spectrum(0.0)
            if not si.is_valid():
                return tr
            bsdf = si.bsdf()
            if not mi.has_flag(bsdf.flags(), mi.BSDFFlags.Null):
                return mi.Spectrum(0.0)
            medium = si.target_medium(ray.d)
            left -= float(si.t)
            if left <= 1e-6:
                return tr
            ray = si.spawn_ray(ray.d)
        return tr

    # -- next-event estimation towards the fire light -------------------------------------------------------

    def _fire_nee(self, scene, sampler, ray_origin_it, eval_fn, time, wavelengths):
        """The fire lights' contribution at a vertex: per fire, a point sampled by its power, the line
        estimate along the direction to it, MIS against the vertex's own sampling (eval_fn(wo) → (value, pdf))."""
        total = mi.Spectrum(0.0)
        for fire in self._fires_of(scene):
            light = fire.light()
            if light is None:
                continue
            u = [sampler.next_1d() for _ in range(6)]
            pts, pdf_v, _ = light.sample([u], times=[time])
            if not pdf_v[0] > 0.0:
                continue
            target = fire.to_world @ mi.ScalarPoint3f(*[float(x) for x in pts[0]])
            o = ray_origin_it.p
            d = mi.Vector3f(target) - o
            dist = dr_norm(d)
            if dist <= 1e-7:
                continue
            wo = d / dist
            o_m = fire._medium_point(o)
            d_m = _medium_dir(fire, wo)
            pdf_dir = float(light.pdf_direction([o_m], [d_m], times=[time])[0])
            if not pdf_dir > 0.0:
                continue
            value, pdf_other = eval_fn(wo)
            if _luminance_weight(value) <= 0.0:
                continue
            # Opaque surfaces before the fire end the line there; null ones (the fire's boundary) are crossed.
            reach, blocked = self._reach(scene, ray_origin_it, wo, fire)
            if blocked:
                continue
            rad, _ = light.integrate([o_m], [d_m], tmin=0.0, tmax=reach * 1.0 / fire.scale, times=[time])
            le = _spectrum([rad[0][fire.bin_of(lam)] if fire.bin_of(lam) >= 0 else 0.0
                            for lam in _lambdas(wavelengths)])
            w = pdf_dir / (pdf_dir + pdf_other) if pdf_other > 0.0 else 1.0
            total += value * le * (w / pdf_dir)
        return total

    def _reach(self, scene, it, wo, fire):
        """How far a line from `it` along `wo` sees (world units) before an opaque surface, and whether an
        opaque surface hides the fire's box entirely."""
        ray = it.spawn_ray(wo)
        hit_box, mint, maxt = fire.intersect_aabb(ray)
        if not hit_box or float(maxt) <= 0.0:
            return 0.0, True
        travelled = 0.0
        for _ in range(16):
            si = scene.ray_intersect(ray)
            if not si.is_valid():
                return 1e30, False
            travelled += float(si.t)
            if not mi.has_flag(si.bsdf().flags(), mi.BSDFFlags.Null):
                return travelled, travelled <= max(float(mint), 0.0)
            ray = si.spawn_ray(wo)
        return travelled, False

    # -- the path ---------------------------------------------------------------------------------------------

    def sample(self, scene, sampler, ray, medium=None, active=True):
        ray = mi.Ray3f(ray)
        L = mi.Spectrum(0.0)
        beta = mi.Spectrum(1.0)
        depth = 0
        # The MIS weight's other density for emission a path finds by itself: the fire light's direction density
        # from the last scattering vertex, computed when the path meets an emitting fire (None: camera ray or
        # specular vertex, weight 1).
        prev = None  # (origin interaction, pdf of the sampled direction)
        fire_w_cache: dict[int, float] = {}
        si = scene.ray_intersect(ray)
        for _ in range(1024):
            if isinstance(medium, FireMedium):
                surf_t = float(si.t) if si.is_valid() else math.inf
                event = None
                for t, m in medium.collisions(ray, surf_t, sampler):
                    mei = _interaction(ray, t)
                    sa, ss, j = medium.coefficients(mei)
                    if medium.emits:
                        w = self._emission_weight(medium, prev, ray, fire_w_cache)
                        L += beta * _spectrum(j / m) * w
                    # Scattering is sampled (hero wavelength), absorption is a weight: pbrt-v4's events with
                    # the absorbed share carried as ratio tracking, which keeps the fire's emission behind its own
                    # soot at the noise of a weight instead of a coin.
                    p_scatter = min(ss[0] / m, 1.0)
                    if p_scatter > 0.0 and sampler.next_1d() < p_scatter:
                        event = (mei, ss)
                        break
                    beta *= _spectrum(np.maximum(m - (sa + ss), 0.0) / (m - ss[0]))
                    b = _luminance_weight(beta)
                    if b < 0.05:
                        # Russian roulette on the weight (unbiased: survivors carry 1/q).
                        if sampler.next_1d() >= b / 0.05:
                            beta = mi.Spectrum(0.0)
                            break
                        beta /= b / 0.05
                if _luminance_weight(beta) <= 0.0:
                    break
                if event is not None:
                    mei, ss = event
                    beta *= _spectrum(ss / ss[0])
                    depth += 1
                    if depth >= self.max_depth:
                        break
                    phase = medium.phase_function()
                    ctx = mi.PhaseFunctionContext(sampler)
                    # The fire light at the scattering point.
                    if self.fire_light:
                        def eval_phase(wo, mei=mei, phase=phase, ctx=ctx):
                            v, p = phase.eval_pdf(ctx, mei, wo)
                            return mi.Spectrum(v), float(p)
                        L += beta * self._fire_nee(scene, sampler, mei, eval_phase, float(ray.time),
                                                   ray.wavelengths)
                    wo, w_phase, pdf = phase.sample(ctx, mei, sampler.next_1d(), sampler.next_2d())
                    if not float(pdf) > 0.0:
                        break
                    beta *= mi.Spectrum(w_phase)
                    prev = (mei, float(pdf))
                    fire_w_cache = {}
                    ray = mei.spawn_ray(wo)
                    si = scene.ray_intersect(ray)
                    continue
            if si.is_valid() and mi.has_flag(si.bsdf(ray).flags(), mi.BSDFFlags.Null):
                # The fire's boundary: cross it, the path's direction and MIS state unchanged.
                medium = si.target_medium(ray.d)
                ray = si.spawn_ray(ray.d)
                si = scene.ray_intersect(ray)
                continue
            # Mitsuba's emitters the path finds (an area light, or the environment when it escapes), weighed
            # against emitter sampling from the last scattering vertex.
            emitter = si.emitter(scene)
            if emitter is not None:
                le = emitter.eval(si)
                if prev is None:
                    L += beta * le
                else:
                    ds = mi.DirectionSample3f(scene, si, prev[0])
                    pdf_e = float(scene.pdf_emitter_direction(prev[0], ds))
                    L += beta * le * (prev[1] / (prev[1] + pdf_e))
            if not si.is_valid():
                break
            bsdf = si.bsdf(ray)
            depth += 1
            if depth >= self.max_depth:
                break
            ctx = mi.BSDFContext()
            # Mitsuba's emitters, by emitter sampling (MIS with BSDF sampling; shadow rays through the fire).
            if len(scene.emitters()) > 0 and mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth):
                ds, em_w = scene.sample_emitter_direction(si, sampler.next_2d(), False)
                if float(ds.pdf) > 0.0:
                    wo_local = si.to_local(ds.d)
                    v, pdf_b = bsdf.eval_pdf(ctx, si, wo_local)
                    if _luminance_weight(v) > 0.0:
                        tr = self._transmittance(scene, sampler, si.spawn_ray(ds.d), si.target_medium(ds.d),
                                                 float(ds.dist) * (1.0 - 1e-4))
                        w = 1.0 if ds.delta else float(ds.pdf) / (float(ds.pdf) + float(pdf_b))
                        L += beta * v * em_w * tr * w
            # The fire light at the surface.
            if self.fire_light and mi.has_flag(bsdf.flags(), mi.BSDFFlags.Smooth):
                def eval_bsdf(wo, si=si, bsdf=bsdf, ctx=ctx):
                    v, p = bsdf.eval_pdf(ctx, si, si.to_local(wo))
                    return v, float(p)
                L += beta * self._fire_nee(scene, sampler, si, eval_bsdf, float(ray.time), ray.wavelengths)
            bs, w_bsdf = bsdf.sample(ctx, si, sampler.next_1d(), sampler.next_2d())
            if not float(bs.pdf) > 0.0:
                break
            beta *= w_bsdf
            delta = mi.has_flag(bs.sampled_type, mi.BSDFFlags.Delta)
            wo = si.to_world(bs.wo)
            prev = None if delta else (si, float(bs.pdf))
            fire_w_cache = {}
            if depth >= self.rr_depth:
                q = min(_luminance_weight(beta), 0.95)
                if sampler.next_1d() >= q:
                    break
                beta /= q
            medium = si.target_medium(wo)
            ray = si.spawn_ray(wo)
            si = scene.ray_intersect(ray)
        return L, True, []

    def _emission_weight(self, fire: FireMedium, prev, ray, cache: dict[int, float]) -> float:
        """MIS weight of emission a path finds by itself along its current direction: its sampling density
        against the fire light's direction density from the last scattering vertex (the same along the whole
        straight line, so computed once per fire and segment)."""
        if prev is None or not self.fire_light or fire.light() is None:
            return 1.0
        key = id(fire)
        if key not in cache:
            it, pdf_path = prev
            pdf_light = float(fire.light().pdf_direction([fire._medium_point(it.p)], [_medium_dir(fire, ray.d)],
                                                         times=[float(ray.time)])[0])
            cache[key] = pdf_path / (pdf_path + pdf_light)
        return cache[key]

    def aov_names(self):
        return []

    def to_string(self):
        return f"FirePath[max_depth={self.max_depth}, fire_light={self.fire_light}]"


def _interaction(ray, t: float):
    """A medium interaction at distance `t` along `ray`, as Mitsuba's phase functions read one."""
    mei = mi.MediumInteraction3f()
    mei.t = t
    mei.p = ray(t)
    mei.wi = -ray.d
    mei.sh_frame = mi.Frame3f(mei.wi)
    mei.wavelengths = ray.wavelengths
    mei.time = ray.time
    return mei


def dr_norm(v) -> float:
    return math.sqrt(float(v[0]) ** 2 + float(v[1]) ** 2 + float(v[2]) ** 2)


mi.register_medium("firemedium", lambda props: FireMedium(props))
mi.register_integrator("firepath", lambda props: FirePath(props))
