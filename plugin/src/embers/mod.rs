//! Embers: Selle's marker particles as what they are — small glowing char spheres (an `embers` particle file,
//! [`read`]) — rendered by the fire volume as opaque grey bodies and sampled by the fire light.
//!
//! - **Emission.** An ember of emissivity ε at temperature T is a Lambertian surface of radiance ε B(T, λ)
//!   (absolute Planck, P&P eq. 6) in every channel (bin means, or the rgb bands' integrals, as the soot's). It is
//!   opaque: a ray that meets it sees its radiance through the fire in front, and nothing behind. The light it
//!   reflects (1 − ε of what falls on it) is left out: a glowing ember outshines what it reflects.
//! - **Cooling.** Each ember's temperature is its file's temperature cooled by radiation for its age
//!   (`firemedium_core::ember`: dT/dt = −3εσ(T⁴ − T_a⁴)/(ρ c r)) and, inside the shutter, for the ray's time.
//! - **Motion.** At time t (frames from the grids' time) an ember is at p + v·t/fps (v in medium units per
//!   second): averaged over the shutter's times, a moving ember draws its streak (motion blur).
//! - **Finding them.** A uniform grid over every ember's swept box (its sphere over the shutter), walked cell by
//!   cell along a ray (the majorant's DDA): a ray pays for the cells it crosses and the embers in them.
//! - **As a light.** The fire light samples an ember by its power and a point uniform in its ball; the point's
//!   direction has solid-angle density w/(W V_ball) ∫ s² ds over the ray's chord through the ball, closed form
//!   (s₁³ − s₀³)/3 — the same form as a voxel's, so the light's mixture of voxels and embers is exact.

#[cfg(test)]
mod tests;

pub(crate) use crate::dataset::particles::Particle;

use crate::majorant::walk;
use crate::Error;
use firemedium_core::ember::{burn, cooled_temperature, cooling_constant, Char};
use glam::DVec3;

/// An ember's material (the volume's `ember*` parameters) and its surroundings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Material {
    pub emissivity: f64,
    /// kg/m³.
    pub density: f64,
    /// J/(kg·K).
    pub heat_capacity: f64,
    /// K.
    pub ambient: f64,
    /// The air's oxygen mass fraction: the char burns in it (0: the embers only cool).
    pub oxygen: f64,
}

#[derive(Debug, Clone, Copy)]
struct Ember {
    /// Centre at time 0 (medium units).
    c: DVec3,
    /// Velocity, medium units per frame.
    v: DVec3,
    r: f64,
    /// Temperature at time 0 (K).
    t: f64,
    /// Cooling constant, K⁻³ s⁻¹.
    k: f64,
    /// A burning ember's temperatures at the shutter's [`Embers::burn_times`] (K), between which it is
    /// interpolated linearly (its char burns over seconds; a shutter lasts a fraction of a frame).
    burning: Option<[f64; 3]>,
}

/// A volume's embers.
#[derive(Debug, Clone)]
pub(crate) struct Embers {
    e: Vec<Ember>,
    seconds_per_frame: f64,
    /// Frames; times outside are held at its ends (the grid covers the embers' boxes over it alone).
    shutter: [f64; 2],
    /// Frames at which a burning ember's temperature is known: the shutter's ends and, between, the frame's
    /// time when the shutter holds it (else the middle).
    burn_times: [f64; 3],
    ambient: f64,
    emissivity: f64,
    /// Per row of temperature (step `dt`), the radiance per channel: ε B(T) × the fire's intensity.
    table: Vec<f64>,
    dt: f64,
    channels: usize,
    /// The grid over the embers' swept boxes: bounds, cells per axis, and per cell (x fastest) its embers,
    /// `items[start[c]..start[c + 1]]`.
    bounds: [DVec3; 2],
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

/// Rows of the radiance table (a 1.5 K step at 3000 K: linear interpolation within 4e-4 of Planck at 400 nm).
const ROWS: usize = 2049;

impl Embers {
    /// The embers of `particles` for a shutter of `shutter` frames at `fps`, with `radiance(T)` the per-channel
    /// radiance of a blackbody at T (times the fire's intensity); `max_bytes` bounds what is allocated.
    pub(crate) fn new(
        file: &str,
        particles: &[Particle],
        mat: Material,
        shutter: [f64; 2],
        fps: f64,
        radiance: &dyn Fn(f64) -> Vec<f64>,
        max_bytes: u64,
    ) -> Result<Embers, Error> {
        let too_large = |what: String, bytes: u64| Error::TooLarge {
            file: file.into(),
            what,
            bytes,
            cap: max_bytes,
        };
        let n = particles.len();
        let spf = 1.0 / fps;
        let mut e: Vec<Ember> = crate::alloc::with_capacity(n)
            .ok_or_else(|| too_large(format!("{n} embers"), (n * 64) as u64))?;
        let mut t_max: f64 = 0.0;
        let burn_times = [
            shutter[0],
            if shutter[0] <= 0.0 && 0.0 <= shutter[1] {
                0.0
            } else {
                0.5 * (shutter[0] + shutter[1])
            },
            shutter[1],
        ];
        let char_ = Char {
            emissivity: mat.emissivity,
            density: mat.density,
            heat_capacity: mat.heat_capacity,
            ambient: mat.ambient,
            oxygen: mat.oxygen,
        };
        for p in particles {
            let k = cooling_constant(mat.emissivity, mat.density, mat.heat_capacity, p.r);
            let (t, r, burning) = if mat.oxygen > 0.0 {
                // Burning: its temperature and radius by integration from its birth, at its age (its char may
                // be gone) and at the shutter's times (before its birth: as born).
                // (One integration from its birth through the four ages, in order.)
                let mut ages = [0usize, 1, 2, 3].map(|k| {
                    let s = if k < 3 { burn_times[k] } else { 0.0 };
                    ((p.age + s * spf).max(0.0), k)
                });
                ages.sort_by(|a, b| a.0.total_cmp(&b.0));
                let (mut state, mut at, mut out) = ((p.t, p.r), 0.0, [(0.0, 0.0); 4]);
                for (age, k) in ages {
                    state = burn(state.0, state.1, age - at, &char_);
                    at = age;
                    out[k] = state;
                }
                let (t, r) = out[3];
                if !(r > 0.0) {
                    continue;
                }
                let temps = [out[0].0, out[1].0, out[2].0];
                t_max = temps.iter().fold(t_max, |m, &x| m.max(x));
                (t, r, Some(temps))
            } else {
                let t = cooled_temperature(p.t, p.age, k, mat.ambient);
                // The hottest it is inside the shutter: at its opening (cooling runs forwards in time).
                let hottest = cooled_temperature(t, shutter[0].min(0.0) * spf, k, mat.ambient);
                t_max = t_max.max(hottest);
                (t, p.r, None)
            };
            t_max = t_max.max(t);
            e.push(Ember {
                c: p.p,
                v: p.v * spf,
                r,
                t,
                k,
                burning,
            });
        }
        let channels = radiance(1000.0).len();
        let dt = (t_max * 1.001 + 1.0) / (ROWS - 1) as f64;
        let mut table = crate::alloc::filled(ROWS * channels, 0.0).ok_or_else(|| {
            too_large(
                "the embers' radiance table".into(),
                (ROWS * channels * 8) as u64,
            )
        })?;
        for (row, out) in table.chunks_mut(channels).enumerate() {
            out.copy_from_slice(&radiance(row as f64 * dt));
        }
        // The swept boxes' union, and a cell edge giving about one ember per cell, doubled until the entries
        // (an ember in every cell its box touches) stay within 16 per ember.
        let swept = |m: &Ember| -> [DVec3; 2] {
            let (a, b) = (m.c + m.v * shutter[0], m.c + m.v * shutter[1]);
            // (Padded by a relative 1e-9: rounding never leaves a chord's entry in a cell the ember is not in.)
            let pad = DVec3::splat(m.r * (1.0 + 1e-9) + 1e-9 * a.abs().max(b.abs()).max_element());
            [a.min(b) - pad, a.max(b) + pad]
        };
        let mut bounds = [DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)];
        for m in &e {
            let [a, b] = swept(m);
            bounds = [bounds[0].min(a), bounds[1].max(b)];
        }
        if n == 0 {
            bounds = [DVec3::ZERO, DVec3::ZERO];
        }
        let ext = (bounds[1] - bounds[0]).max(DVec3::splat(1e-9));
        let mut h = (ext.x * ext.y * ext.z / n.max(1) as f64).cbrt();
        let cells_of = |h: f64| {
            ext.to_array()
                .map(|x| ((x / h).ceil() as usize).clamp(1, 256))
        };
        let span = |dims: [usize; 3], m: &Ember| -> [[usize; 2]; 3] {
            let [a, b] = swept(m);
            [0, 1, 2].map(|ax| {
                let f = |x: f64| {
                    let u = (x - bounds[0][ax]) / ext[ax] * dims[ax] as f64;
                    (u.max(0.0) as usize).min(dims[ax] - 1)
                };
                [f(a[ax]), f(b[ax])]
            })
        };
        let (dims, entries) = loop {
            let dims = cells_of(h);
            let entries: u64 = e
                .iter()
                .map(|m| {
                    span(dims, m)
                        .iter()
                        .map(|s| (s[1] - s[0] + 1) as u64)
                        .product::<u64>()
                })
                .sum();
            if entries <= 16 * n as u64 + 4096 || dims == [1, 1, 1] {
                break (dims, entries as usize);
            }
            h *= 2.0;
        };
        let cells = dims[0] * dims[1] * dims[2];
        let bytes = ((cells + 1 + entries) * 4 + n * 64 + ROWS * channels * 8) as u64;
        if bytes > max_bytes {
            return Err(too_large(format!("{n} embers and their grid"), bytes));
        }
        let mut start = crate::alloc::filled(cells + 1, 0u32)
            .ok_or_else(|| too_large("the embers' grid".into(), bytes))?;
        let mut items = crate::alloc::filled(entries, 0u32)
            .ok_or_else(|| too_large("the embers' grid".into(), bytes))?;
        let cell = |x: usize, y: usize, z: usize| x + dims[0] * (y + dims[1] * z);
        let each = |f: &mut dyn FnMut(usize, usize)| {
            for (i, m) in e.iter().enumerate() {
                let s = span(dims, m);
                for z in s[2][0]..=s[2][1] {
                    for y in s[1][0]..=s[1][1] {
                        for x in s[0][0]..=s[0][1] {
                            f(cell(x, y, z), i);
                        }
                    }
                }
            }
        };
        each(&mut |c, _| start[c + 1] += 1);
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        each(&mut |c, i| {
            items[fill[c] as usize] = i as u32;
            fill[c] += 1;
        });
        Ok(Embers {
            e,
            seconds_per_frame: spf,
            shutter,
            burn_times,
            ambient: mat.ambient,
            emissivity: mat.emissivity,
            table,
            dt,
            channels,
            bounds,
            dims,
            start,
            items,
        })
    }

    /// How many embers.
    pub(crate) fn len(&self) -> usize {
        self.e.len()
    }

    /// Their emissivity.
    pub(crate) fn emissivity(&self) -> f64 {
        self.emissivity
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.e.len() * std::mem::size_of::<Ember>()
            + (self.table.len()) * 8
            + (self.start.len() + self.items.len()) * 4
    }

    /// Ember `i`'s centre at `time` (frames).
    fn centre(&self, i: usize, time: f64) -> DVec3 {
        let m = &self.e[i];
        m.c + m.v * self.held(time)
    }

    /// `time` held inside the shutter.
    fn held(&self, time: f64) -> f64 {
        time.clamp(self.shutter[0], self.shutter[1])
    }

    /// Ember `i`'s radius.
    pub(crate) fn radius(&self, i: usize) -> f64 {
        self.e[i].r
    }

    /// Ember `i`'s temperature (K) at `time` (frames).
    pub(crate) fn temperature(&self, i: usize, time: f64) -> f64 {
        let m = &self.e[i];
        let time = self.held(time);
        if time == 0.0 {
            return m.t;
        }
        match m.burning {
            None => cooled_temperature(m.t, time * self.seconds_per_frame, m.k, self.ambient),
            Some(temps) => {
                let s = self.burn_times;
                let (i, j) = if time <= s[1] { (0, 1) } else { (1, 2) };
                let span = s[j] - s[i];
                if span > 0.0 {
                    let f = ((time - s[i]) / span).clamp(0.0, 1.0);
                    temps[i] + f * (temps[j] - temps[i])
                } else {
                    temps[j]
                }
            }
        }
    }

    /// Ember `i`'s radiance per channel at `time`, into `out`.
    pub(crate) fn radiance(&self, i: usize, time: f64, out: &mut [f64]) {
        let u = self.temperature(i, time) / self.dt;
        let r = (u.max(0.0) as usize).min(ROWS - 2);
        let f = (u - r as f64).clamp(0.0, 1.0);
        let c = self.channels;
        let (a, b) = (
            &self.table[r * c..(r + 1) * c],
            &self.table[(r + 1) * c..(r + 2) * c],
        );
        for k in 0..c.min(out.len()) {
            out[k] = a[k] + f * (b[k] - a[k]);
        }
    }

    /// The ray o + t·d's chord through ember `i` at `time`: (entry, exit) parameters, if it meets it.
    fn chord(&self, i: usize, time: f64, o: DVec3, d: DVec3) -> Option<(f64, f64)> {
        let len = d.length();
        let dn = d / len;
        let oc = o - self.centre(i, time);
        let tca = -oc.dot(dn);
        let perp = oc + dn * tca;
        let r = self.e[i].r;
        let h2 = r * r - perp.length_squared();
        if !(h2 >= 0.0) {
            return None;
        }
        let th = h2.sqrt();
        Some(((tca - th) / len, (tca + th) / len))
    }

    /// The embers listed in grid cell `[x, y, z]`.
    fn cell_items(&self, [x, y, z]: [usize; 3]) -> &[u32] {
        let c = x + self.dims[0] * (y + self.dims[1] * z);
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// Calls `f(i, entry, exit)` for the embers whose chord meets [t0, t1], each once, cell by cell along the
    /// ray; `f` returns false to stop after the current cell (cells are visited in order: the first ember met
    /// is found once a hit lies before the exit of the cell being visited).
    fn crossing(
        &self,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        time: f64,
        f: &mut dyn FnMut(usize, f64, f64, f64) -> bool,
    ) {
        if self.e.is_empty() {
            return;
        }
        let (mut first, mut stop) = (true, false);
        for seg in walk(self.bounds, self.dims, 1, o, d, t0, t1) {
            for &i in self.cell_items(seg.cell) {
                let i = i as usize;
                let Some((a, b)) = self.chord(i, time, o, d) else {
                    continue;
                };
                if b < t0 || a > t1 {
                    continue;
                }
                // Once: in the cell where the chord (clipped to the ray) begins, or in the first cell visited
                // when it began before the walk did.
                let entry = a.max(t0);
                if entry < seg.t1 && (entry >= seg.t0 || first) && !f(i, a, b, seg.t1) {
                    stop = true;
                }
            }
            if stop {
                return;
            }
            first = false;
        }
    }

    /// The first ember the ray o + t·d meets in [t0, t1] at `time`: (parameter, ember). A ray starting inside an
    /// ember meets it at t0.
    pub(crate) fn hit(
        &self,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        time: f64,
    ) -> Option<(f64, usize)> {
        let mut best: Option<(f64, usize)> = None;
        self.crossing(o, d, t0, t1, time, &mut |i, a, _, cell_end| {
            let t = a.max(t0);
            if best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, i));
            }
            // Embers in later cells begin after this cell's exit: stop once the best lies before it.
            !best.is_some_and(|(bt, _)| bt <= cell_end)
        });
        best
    }

    /// Σ over the embers the ray o + s·d̂ (s ≥ 0, d̂ unit) passes of weight(i)/V_ball ∫ s² ds over its chord.
    pub(crate) fn chord_moment(&self, o: DVec3, dn: DVec3, time: f64, weight: &[f64]) -> f64 {
        let mut sum = 0.0;
        self.crossing(o, dn, 0.0, f64::INFINITY, time, &mut |i, a, b, _| {
            let (a, b) = (a.max(0.0), b.max(0.0));
            let r = self.e[i].r;
            let v = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
            sum += weight[i] / v * (b * b * b - a * a * a) / 3.0;
            true
        });
        sum
    }

    /// Whether `p` lies in ember `i` at `time`.
    pub(crate) fn contains(&self, i: usize, p: DVec3, time: f64) -> bool {
        (p - self.centre(i, time)).length_squared() <= self.e[i].r * self.e[i].r
    }

    /// The embers whose ball holds `p` at `time` (a brute-force check of the cell holding `p`).
    pub(crate) fn containing(&self, p: DVec3, time: f64, f: &mut dyn FnMut(usize)) {
        if self.e.is_empty() || !(p.cmpge(self.bounds[0]).all() && p.cmple(self.bounds[1]).all()) {
            return;
        }
        let ext = (self.bounds[1] - self.bounds[0]).max(DVec3::splat(1e-9));
        let q = [0, 1, 2].map(|a| {
            (((p[a] - self.bounds[0][a]) / ext[a] * self.dims[a] as f64).max(0.0) as usize)
                .min(self.dims[a] - 1)
        });
        for &i in self.cell_items(q) {
            if self.contains(i as usize, p, time) {
                f(i as usize);
            }
        }
    }

    /// A point uniform in ember `i`'s ball at `time`, from three uniform numbers.
    pub(crate) fn sample_ball(&self, i: usize, u: [f64; 3], time: f64) -> DVec3 {
        let r = self.e[i].r * u[0].cbrt();
        let z = 1.0 - 2.0 * u[1];
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI * u[2];
        self.centre(i, time) + DVec3::new(s * phi.cos(), s * phi.sin(), z) * r
    }
}
