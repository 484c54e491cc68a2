//! A fire volume handle: its description, colour and temperature range, and the batch queries.

use crate::{abi, Error, Exit, Inner, Light, Ray, Scatter, VolumeInfo};
use std::fmt;
use std::sync::Arc;

/// How the rays of a whole-ray query are sampled.
#[derive(Debug, Clone, Copy, Default)]
pub struct Sampling<'a> {
    /// One time per ray (frames from the grids' time), or `None`: time 0.
    pub times: Option<&'a [f64]>,
    /// One uniform number in [0, 1) per ray, or `None`: the first random number each ray's estimator draws
    /// (the march's offset, tracking's first free flight) — the host's own, stratified as its sampler is.
    pub u: Option<&'a [f64]>,
    /// The march's step in medium units when longer than the volume's own (straight rays, no exits); 0: the
    /// volume's.
    pub step: f64,
}

impl<'a> Sampling<'a> {
    /// Each ray at its time (`None`: 0), the rest the plugin's own.
    pub fn at(times: Option<&'a [f64]>) -> Self {
        Sampling {
            times,
            ..Sampling::default()
        }
    }
}

/// A fire volume living in the plugin. Immutable; `Send + Sync`.
pub struct Volume {
    pub(crate) inner: Arc<Inner>,
    pub(crate) handle: *mut abi::FmVolume,
    pub(crate) info: abi::FmVolumeInfo,
    /// The host's pool the plugin may call while the volume lives (its address went to the plugin).
    pub(crate) _pool: Option<Box<crate::ThreadPool>>,
}

// SAFETY: the plugin guarantees volumes are immutable and safe to query from many threads (ABI contract), and
// `inner` keeps the library loaded.
unsafe impl Send for Volume {}
// SAFETY: as above.
unsafe impl Sync for Volume {}

impl fmt::Debug for Volume {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Volume({:?})", self.info)
    }
}

impl Drop for Volume {
    fn drop(&mut self) {
        // SAFETY: the handle came from volume_create and is destroyed exactly once, here.
        unsafe { (self.inner.api().volume_destroy)(self.handle) }
    }
}

impl Volume {
    /// Builds the fire light of this volume: `weighting` is `"power"` (default) or `"luminance"`.
    pub fn create_light(&self, weighting: Option<&str>) -> Result<Light, Error> {
        let params: Vec<crate::Param> = weighting
            .map(|w| crate::Param::string("weighting", w))
            .into_iter()
            .collect();
        self.create_light_with(&params)
    }

    /// Builds the fire light of this volume with the light's parameters (docs/reference/params.md, `light`: `weighting`,
    /// `cell`, …).
    pub fn create_light_with(&self, params: &[crate::Param]) -> Result<Light, Error> {
        let api = self.inner.api();
        let mut handle: *mut abi::FmLight = std::ptr::null_mut();
        let s = crate::with_c_params(params, |list, _| {
            // SAFETY: `list` and everything it points to live until after the call; handle is writable.
            unsafe { (api.light_create)(self.handle, list.as_ptr(), list.len(), &mut handle) }
        })?;
        self.inner.check(s)?;
        let mut info = abi::FmLightInfo::default();
        // SAFETY: a live handle and a writable info.
        let s = unsafe { (api.light_info)(handle, &mut info) };
        let light = Light {
            inner: self.inner.clone(),
            handle,
            info,
            channels: self.info.channels as usize,
        };
        self.inner.check(s)?;
        Ok(light)
    }

    /// What the volume is (bounds, channels, …).
    pub fn info(&self) -> VolumeInfo {
        self.info
    }

    /// The lowest and highest temperature of the volume's grid (K, after its mapping), `None` without a
    /// temperature grid.
    pub fn temperature_range(&self) -> Result<Option<[f64; 2]>, Error> {
        let mut out = [0.0f64; 2];
        // SAFETY: room for two doubles.
        let s =
            unsafe { (self.inner.api().volume_temperature_range)(self.handle, out.as_mut_ptr()) };
        self.inner.check(s)?;
        Ok((out != [0.0, 0.0]).then_some(out))
    }

    /// What the volume's build found that a user should hear (species whose lines fall outside the channels,
    /// flame colours the model cannot give), one line each: a host shows them as warnings.
    pub fn notes(&self) -> Result<Vec<String>, Error> {
        let api = self.inner.api();
        let mut count = 0usize;
        // SAFETY: a live handle and a writable usize.
        let s = unsafe { (api.volume_note_count)(self.handle, &mut count) };
        self.inner.check(s)?;
        let mut out = Vec::new();
        for i in 0..count {
            let mut len = 0usize;
            // SAFETY: a live handle; a null buffer asks for the length into a writable usize.
            let s = unsafe { (api.volume_note)(self.handle, i, std::ptr::null_mut(), 0, &mut len) };
            self.inner.check(s)?;
            // (A note is a line of text: a length past 64 KiB is a broken plugin's, not a buffer to allocate.)
            let len = len.min(1 << 16);
            let mut buf = vec![0u8; len + 1];
            let mut full = 0usize;
            // SAFETY: `buf` holds len + 1 writable bytes, as `cap` says.
            let s = unsafe {
                (api.volume_note)(
                    self.handle,
                    i,
                    buf.as_mut_ptr().cast(),
                    buf.len(),
                    &mut full,
                )
            };
            self.inner.check(s)?;
            let len = full.min(len);
            buf.truncate(len);
            out.push(String::from_utf8_lossy(&buf).into_owned());
        }
        Ok(out)
    }

    /// The temperature whose blackbody a viewer adapts to for this volume (K): its hottest when its colour is
    /// the physics', `None` when its colour is art-directed (a tint or a colour ramp: seen against D65) or it has
    /// no temperature grid.
    pub fn white_temperature(&self) -> Result<Option<f64>, Error> {
        let mut out = 0.0f64;
        // SAFETY: a live handle and a writable double.
        let s = unsafe { (self.inner.api().volume_white_temperature)(self.handle, &mut out) };
        self.inner.check(s)?;
        Ok((out > 0.0).then_some(out))
    }

    /// What the volume holds beyond absorption: `FM_FEATURE_*` bits. A host that tracks the medium
    /// itself refuses, or keeps to the whole-ray queries for, what it cannot handle.
    pub fn features(&self) -> Result<u64, Error> {
        let mut out = 0u64;
        // SAFETY: a live handle and a writable u64.
        let s = unsafe { (self.inner.api().volume_features)(self.handle, &mut out) };
        self.inner.check(s)?;
        Ok(out)
    }

    /// The volume's majorant grid, borrowed from the volume: cells tiling a box, per cell a bound on
    /// σ_t over every channel and point (and the shutter, with motion blur), for the host's own free paths.
    pub fn majorant_grid(&self) -> Result<MajorantGrid<'_>, Error> {
        let mut g = abi::FmMajorantGrid::default();
        // SAFETY: a live handle and a struct of the size it says.
        let s = unsafe { (self.inner.api().volume_majorant_grid)(self.handle, &mut g) };
        self.inner.check(s)?;
        let n = g.counts.iter().map(|&c| c as usize).product::<usize>();
        if g.sigma_t.is_null() || n == 0 {
            return Err(Error::Status {
                code: abi::FM_INVALID_ARGUMENT,
                message: "volume_majorant_grid: no cells".into(),
                detail: Default::default(),
            });
        }
        Ok(MajorantGrid {
            lo: [g.bounds[0], g.bounds[1], g.bounds[2]],
            hi: [g.bounds[3], g.bounds[4], g.bounds[5]],
            cell: g.cell,
            counts: g.counts.map(|c| c as usize),
            // SAFETY: the plugin's array of `n` doubles, owned by the volume this borrow keeps alive.
            sigma_t: unsafe { std::slice::from_raw_parts(g.sigma_t, n) },
        })
    }

    /// σ_a, σ_s, Le and j at `points`, each at its time (`times`, frames; `None`: 0) and at its own `k =
    /// lambdas.len() / points.len()` wavelengths (nm, point-major), into `out` (as many as `lambdas`): the
    /// closed forms at each wavelength, not the bins. A volume with layers they cannot express is
    /// refused with `FM_UNSUPPORTED` naming the layer.
    pub fn point(
        &self,
        points: &[[f64; 3]],
        times: Option<&[f64]>,
        lambdas: &[f64],
        out: &mut [Point],
    ) -> Result<(), Error> {
        let n = points.len();
        let k = lambdas.len().checked_div(n).unwrap_or(0);
        if k * n != lambdas.len() || out.len() != lambdas.len() || u32::try_from(k).is_err() {
            return Err(Error::Buffer(format!(
                "point: {} wavelengths and {} outputs for {n} points (k each, the same for every point)",
                lambdas.len(),
                out.len()
            )));
        }
        if let Some(t) = times.filter(|t| t.len() != n) {
            return Err(Error::Buffer(format!(
                "point: {} times for {n} points",
                t.len()
            )));
        }
        let mut v = vec![0f64; 4 * lambdas.len()];
        let (sa, rest) = v.split_at_mut(lambdas.len());
        let (ss, rest) = rest.split_at_mut(lambdas.len());
        let (le, j) = rest.split_at_mut(lambdas.len());
        let q = abi::FmPointQuery {
            struct_size: std::mem::size_of::<abi::FmPointQuery>(),
            n,
            points: points.as_ptr().cast(),
            times: times.map_or(std::ptr::null(), <[f64]>::as_ptr),
            k: k as u32,
            reserved: 0,
            lambdas: lambdas.as_ptr(),
            sigma_a: sa.as_mut_ptr(),
            sigma_s: ss.as_mut_ptr(),
            le: le.as_mut_ptr(),
            j: j.as_mut_ptr(),
        };
        // SAFETY: a live handle; every array sized as the query says (checked above).
        let s = unsafe { (self.inner.api().volume_point)(self.handle, &q) };
        self.inner.check(s)?;
        for (i, o) in out.iter_mut().enumerate() {
            *o = Point {
                sigma_a: sa[i],
                sigma_s: ss[i],
                le: le[i],
                j: j[i],
            };
        }
        Ok(())
    }

    /// The volume as pbrt-v4 and Mitsuba 3 see a medium ([`Medium`]): refused, naming the layer, when the
    /// volume holds one that point coefficients and majorants cannot carry (refraction, embers, atomic lines,
    /// art direction, diffusion) — the whole-ray queries still render such a volume.
    pub fn medium(&self) -> Result<Medium<'_>, Error> {
        let features = self.features()?;
        let grid = self.majorant_grid()?;
        // One point at the cells' centre asks the plugin whether its layers have closed forms.
        let centre = [0, 1, 2].map(|a| 0.5 * (grid.lo[a] + grid.hi[a]));
        self.point(&[centre], None, &[550.0], &mut [Point::default()])?;
        Ok(Medium {
            volume: self,
            grid,
            features,
        })
    }

    /// How many rays' tracking stopped at the plugin's per-ray collision cap so far (each cut short as if
    /// absorbed; report it).
    pub fn capped_rays(&self) -> Result<u64, Error> {
        let mut n = 0u64;
        // SAFETY: a live handle and a writable u64.
        let s = unsafe { (self.inner.api().volume_capped_rays)(self.handle, &mut n) };
        self.inner.check(s)?;
        Ok(n)
    }

    /// The XYZ of unit radiance in each channel.
    pub fn channel_xyz(&self) -> Result<Vec<[f64; 3]>, Error> {
        let c = self.info.channels as usize;
        let mut out = vec![0.0; 3 * c];
        // SAFETY: room for 3·c doubles.
        let s = unsafe {
            (self.inner.api().volume_channel_xyz)(self.handle, out.as_mut_ptr(), out.len())
        };
        self.inner.check(s)?;
        Ok(out.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    fn need(&self, what: &str, len: usize, n: usize) -> Result<(), Error> {
        let want = n * self.info.channels as usize;
        if len < want {
            return Err(Error::Buffer(format!(
                "{what}: {len} floats for {n} rays × {} channels = {want}",
                self.info.channels
            )));
        }
        Ok(())
    }

    /// The ABI version (major, minor) of the plugin that made this volume.
    pub fn abi_version(&self) -> (u32, u32) {
        let api = self.inner.api();
        (api.abi_major, api.abi_minor)
    }

    /// Emitted radiance (and optionally transmittance and exit points) along `rays`; buffers hold
    /// `rays.len() × channels` floats, channel fastest.
    pub fn integrate(
        &self,
        rays: &[Ray],
        radiance: &mut [f32],
        transmittance: Option<&mut [f32]>,
        exits: Option<&mut [Exit]>,
    ) -> Result<(), Error> {
        self.integrate_at(rays, None, radiance, transmittance, exits)
    }

    /// Checks that `what`, when given, has one entry per ray; its pointer (null for none).
    fn per_ray(what: &str, v: Option<&[f64]>, rays: usize) -> Result<*const f64, Error> {
        match v {
            Some(t) if t.len() != rays => Err(Error::Buffer(format!(
                "{what}: {} entries for {rays} rays",
                t.len()
            ))),
            Some(t) => Ok(t.as_ptr()),
            None => Ok(std::ptr::null()),
        }
    }

    /// `FmRayQuery` for `rays` sampled as `s`, every output null.
    fn query(what: u32, rays: &[Ray], s: &Sampling) -> Result<abi::FmRayQuery, Error> {
        Ok(abi::FmRayQuery {
            what,
            n: rays.len(),
            rays: rays.as_ptr(),
            times: Self::per_ray("times", s.times, rays.len())?,
            u: Self::per_ray("u", s.u, rays.len())?,
            step: s.step,
            ..abi::FmRayQuery::default()
        })
    }

    /// The fast path's one entry: `q`, whose buffers the caller sized.
    fn run(&self, q: &abi::FmRayQuery) -> Result<(), Error> {
        // SAFETY: `q` and the buffers it points to, sized by the caller for `q.n` rays, live across the call.
        let s = unsafe { (self.inner.api().volume_query)(self.handle, q) };
        self.inner.check(s)
    }

    /// As [`integrate`](Self::integrate), each ray at its time (`times`: frames from the grids' time, one per
    /// ray; `None`: time 0). A volume with motion blur is looked up where its velocity carried it from.
    pub fn integrate_at(
        &self,
        rays: &[Ray],
        times: Option<&[f64]>,
        radiance: &mut [f32],
        transmittance: Option<&mut [f32]>,
        exits: Option<&mut [Exit]>,
    ) -> Result<(), Error> {
        let s = Sampling::at(times);
        self.integrate_with(rays, &s, radiance, transmittance, exits)
    }

    /// As [`integrate`](Self::integrate), the rays sampled as `sampling` says (times, the host's first uniform
    /// numbers, a coarser step).
    pub fn integrate_with(
        &self,
        rays: &[Ray],
        sampling: &Sampling,
        radiance: &mut [f32],
        transmittance: Option<&mut [f32]>,
        exits: Option<&mut [Exit]>,
    ) -> Result<(), Error> {
        let mut q = Self::query(abi::FM_QUERY_INTEGRATE, rays, sampling)?;
        self.need("radiance", radiance.len(), rays.len())?;
        q.radiance = radiance.as_mut_ptr();
        if let Some(t) = transmittance {
            self.need("transmittance", t.len(), rays.len())?;
            q.transmittance = t.as_mut_ptr();
        }
        match exits {
            Some(e) if e.len() >= rays.len() => q.exits = e.as_mut_ptr(),
            Some(e) => {
                return Err(Error::Buffer(format!(
                    "exits: {} entries for {} rays",
                    e.len(),
                    rays.len()
                )))
            }
            None => {}
        }
        self.run(&q)
    }

    /// Transmittance along `rays` (`rays.len() × channels` floats).
    pub fn transmittance(&self, rays: &[Ray], transmittance: &mut [f32]) -> Result<(), Error> {
        self.transmittance_at(rays, None, transmittance)
    }

    /// As [`transmittance`](Self::transmittance), each ray at its time (as [`integrate_at`](Self::integrate_at)).
    pub fn transmittance_at(
        &self,
        rays: &[Ray],
        times: Option<&[f64]>,
        transmittance: &mut [f32],
    ) -> Result<(), Error> {
        let s = Sampling::at(times);
        self.transmittance_with(rays, &s, transmittance)
    }

    /// As [`transmittance`](Self::transmittance), the rays sampled as `sampling` says.
    pub fn transmittance_with(
        &self,
        rays: &[Ray],
        sampling: &Sampling,
        transmittance: &mut [f32],
    ) -> Result<(), Error> {
        let mut q = Self::query(abi::FM_QUERY_TRANSMITTANCE, rays, sampling)?;
        self.need("transmittance", transmittance.len(), rays.len())?;
        q.transmittance = transmittance.as_mut_ptr();
        self.run(&q)
    }

    /// The first real scattering event per ray, with weights and the emission before it.
    pub fn sample_scatter(
        &self,
        rays: &[Ray],
        events: &mut [Scatter],
        weights: &mut [f32],
        emitted: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        self.sample_scatter_at(rays, None, events, weights, emitted)
    }

    /// As [`sample_scatter`](Self::sample_scatter), each ray at its time (as
    /// [`integrate_at`](Self::integrate_at)).
    pub fn sample_scatter_at(
        &self,
        rays: &[Ray],
        times: Option<&[f64]>,
        events: &mut [Scatter],
        weights: &mut [f32],
        emitted: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        let s = Sampling::at(times);
        self.sample_scatter_with(rays, &s, events, weights, emitted)
    }

    /// As [`sample_scatter`](Self::sample_scatter), the rays sampled as `sampling` says (its `u`: each ray's
    /// first free-flight sample).
    pub fn sample_scatter_with(
        &self,
        rays: &[Ray],
        sampling: &Sampling,
        events: &mut [Scatter],
        weights: &mut [f32],
        emitted: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        let mut q = Self::query(abi::FM_QUERY_SCATTER, rays, sampling)?;
        if events.len() < rays.len() {
            return Err(Error::Buffer(format!(
                "events: {} entries for {} rays",
                events.len(),
                rays.len()
            )));
        }
        q.events = events.as_mut_ptr();
        self.need("weights", weights.len(), rays.len())?;
        q.weights = weights.as_mut_ptr();
        if let Some(l) = emitted {
            self.need("emitted", l.len(), rays.len())?;
            q.radiance = l.as_mut_ptr();
        }
        self.run(&q)
    }

    /// σ_a, σ_s and j per channel at medium-space points.
    pub fn coefficients(
        &self,
        points: &[[f64; 3]],
        sigma_a: &mut [f32],
        sigma_s: &mut [f32],
        emission: &mut [f32],
    ) -> Result<(), Error> {
        for (what, b) in [
            ("sigma_a", &*sigma_a),
            ("sigma_s", &*sigma_s),
            ("emission", &*emission),
        ] {
            self.need(what, b.len(), points.len())?;
        }
        // SAFETY: buffers sized above; points are 3 contiguous f64 each.
        let s = unsafe {
            (self.inner.api().volume_coefficients)(
                self.handle,
                points.as_ptr() as *const f64,
                points.len(),
                sigma_a.as_mut_ptr(),
                sigma_s.as_mut_ptr(),
                emission.as_mut_ptr(),
            )
        };
        self.inner.check(s)
    }

    /// The fire's coefficients in closed form over its fields (see [`Tables`]), for a host that textures it;
    /// a status error (`FM_UNSUPPORTED`) naming what is not of that form.
    pub fn tables(&self) -> Result<Tables, Error> {
        let api = self.inner.api();
        let mut t = abi::FmTables::default();
        // SAFETY: a live handle; a sized FmTables whose null table pointers ask for the sizes.
        let s = unsafe { (api.volume_tables)(self.handle, &mut t) };
        self.inner.check(s)?;
        let (rows, c) = (t.rows as usize, t.channels as usize);
        let cells = rows.checked_mul(c).ok_or_else(|| {
            Error::Buffer(format!(
                "volume_tables: {rows} rows × {c} channels overflow"
            ))
        })?;
        let alloc = |n: usize| {
            let mut v: Vec<f32> = Vec::new();
            v.try_reserve_exact(n).map_err(|_| {
                Error::Buffer(format!("volume_tables: {n} floats do not fit in memory"))
            })?;
            v.resize(n, 0.0);
            Ok::<_, Error>(v)
        };
        let (mut a, mut s, mut j) = (alloc(cells)?, alloc(c)?, alloc(cells)?);
        t.absorption = a.as_mut_ptr();
        t.scattering = s.as_mut_ptr();
        t.emission = j.as_mut_ptr();
        // SAFETY: each buffer holds the floats the first call's rows and channels call for.
        let status = unsafe { (api.volume_tables)(self.handle, &mut t) };
        self.inner.check(status)?;
        Ok(Tables {
            channels: c,
            rows,
            dt: t.dt,
            t_emit: t.t_emit,
            emission_grid: t.flags & abi::FM_TABLES_EMISSION_GRID != 0,
            absorption: a,
            scattering: s,
            emission: j,
        })
    }

    /// The closed form's fields at medium-space points into `out`: [d, T, les] each, as the volume interpolates
    /// them (see [`Tables`]).
    pub fn fields(&self, points: &[[f64; 3]], out: &mut [[f32; 3]]) -> Result<(), Error> {
        if out.len() < points.len() {
            return Err(Error::Buffer(format!(
                "fields: {} outputs for {} points",
                out.len(),
                points.len()
            )));
        }
        // SAFETY: `out` holds 3 floats per point (checked); points are 3 contiguous f64 each.
        let s = unsafe {
            (self.inner.api().volume_fields)(
                self.handle,
                points.as_ptr() as *const f64,
                points.len(),
                out.as_mut_ptr() as *mut f32,
            )
        };
        self.inner.check(s)
    }

    /// The bricks of 8³ samples the volume's grids store: the lattice index of each one's first sample (below 0
    /// where the lattice starts inside a brick), in no set order — what the dataset holds, not its box.
    pub fn bricks(&self) -> Result<Vec<[i64; 3]>, Error> {
        let mut n = 0usize;
        // SAFETY: null `out` with `cap` 0 asks for the count alone; `n` is writable.
        let s = unsafe {
            (self.inner.api().volume_bricks)(self.handle, std::ptr::null_mut(), 0, &mut n)
        };
        self.inner.check(s)?;
        let mut out: Vec<[i64; 3]> = Vec::new();
        out.try_reserve_exact(n).map_err(|_| {
            Error::Buffer(format!(
                "bricks: {n} bricks: the allocator refused their list"
            ))
        })?;
        out.resize(n, [0; 3]);
        let mut got = 0usize;
        // SAFETY: `out` holds `n` × 3 int64 (`[i64; 3]` has no padding); `got` is writable.
        let s = unsafe {
            (self.inner.api().volume_bricks)(self.handle, out.as_mut_ptr() as *mut i64, n, &mut got)
        };
        self.inner.check(s)?;
        out.truncate(got);
        Ok(out)
    }
}

/// A volume's coefficients in closed form ([`Volume::tables`]): with d, T and les the fields
/// ([`Volume::fields`]) interpolated trilinearly from the lattice's voxel values, d and les clamped at 0, and
/// the tables linear between rows r = clamp(T / dt, 0, rows − 1): σ_a = d·A(r), σ_s = d·S, j = e·J(r) where
/// T > `t_emit`, e = les with an emission grid, d·les without — the volume's own coefficients at every point.
#[derive(Debug, Clone, PartialEq)]
pub struct Tables {
    pub channels: usize,
    pub rows: usize,
    /// Kelvin between rows.
    pub dt: f64,
    pub t_emit: f64,
    pub emission_grid: bool,
    /// σ_a per unit density, rows × channels.
    pub absorption: Vec<f32>,
    /// σ_s per unit density, per channel.
    pub scattering: Vec<f32>,
    /// j per unit of e, rows × channels.
    pub emission: Vec<f32>,
}

/// A volume's majorant grid ([`Volume::majorant_grid`]).
#[derive(Debug, Clone, Copy)]
pub struct MajorantGrid<'a> {
    /// The cells' box, medium space.
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    /// A cell's edge per axis (the last cell per axis may be cut by the box).
    pub cell: [f64; 3],
    /// Cells per axis.
    pub counts: [usize; 3],
    /// Per cell, x fastest, a bound on σ_t (medium units⁻¹).
    pub sigma_t: &'a [f64],
}

impl MajorantGrid<'_> {
    /// The cell holding `p` (clamped to the grid: a point of the medium outside the box takes the nearest
    /// cell's bound).
    pub fn cell_of(&self, p: [f64; 3]) -> [usize; 3] {
        [0, 1, 2].map(|a| {
            let c = ((p[a] - self.lo[a]) / self.cell[a]).floor();
            (c.max(0.0) as usize).min(self.counts[a] - 1)
        })
    }
    /// The bound on σ_t at `p`.
    pub fn at(&self, p: [f64; 3]) -> f64 {
        let [x, y, z] = self.cell_of(p);
        self.sigma_t[x + self.counts[0] * (y + self.counts[1] * z)]
    }
}

/// The coefficients at one point and wavelength ([`Volume::point`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Point {
    /// σ_a, medium units⁻¹.
    pub sigma_a: f64,
    /// σ_s, medium units⁻¹.
    pub sigma_s: f64,
    /// The emitted radiance Le (0 where σ_a = 0: an emission grid's j still emits there).
    pub le: f64,
    /// j = σ_a·Le.
    pub j: f64,
}

/// A volume seen as pbrt-v4 (`Medium::SamplePoint`, `SampleRay`) and Mitsuba 3 (`get_scattering_coefficients`,
/// `get_majorant`) see a medium, for a host that tracks the fire itself: the coefficients at a point — at the
/// host's wavelengths and time — and a bound on σ_t per cell. Made by [`Volume::medium`].
pub struct Medium<'v> {
    volume: &'v Volume,
    grid: MajorantGrid<'v>,
    features: u64,
}

impl std::fmt::Debug for Medium<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Medium")
            .field("features", &self.features)
            .field("cells", &self.grid.counts)
            .finish()
    }
}

impl<'v> Medium<'v> {
    /// The volume behind it (its whole-ray queries, its light).
    pub fn volume(&self) -> &'v Volume {
        self.volume
    }

    /// What the medium holds: `FM_FEATURE_*` bits (emits, scatters, moves).
    pub fn features(&self) -> u64 {
        self.features
    }

    /// The Henyey–Greenstein g of its scattering.
    pub fn g(&self) -> f64 {
        self.volume.info.g
    }

    /// The majorant grid: cells with a bound on σ_t each (over the shutter, with motion blur).
    pub fn majorant_grid(&self) -> &MajorantGrid<'v> {
        &self.grid
    }

    /// The bound on σ_t at `p` (medium space): its cell's.
    pub fn majorant(&self, p: [f64; 3]) -> f64 {
        self.grid.at(p)
    }

    /// σ_a, σ_s, Le and j at `points`, each at its time and its own wavelengths (see [`Volume::point`]).
    pub fn point(
        &self,
        points: &[[f64; 3]],
        times: Option<&[f64]>,
        lambdas: &[f64],
        out: &mut [Point],
    ) -> Result<(), Error> {
        self.volume.point(points, times, lambdas, out)
    }
}
