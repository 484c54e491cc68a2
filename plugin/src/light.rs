//! The fire light (the thesis's "fire light shader"): the fire as a light source its surroundings are lit by,
//! importance-sampled as in Selle's CS348B project — a piecewise-constant 3D pdf over voxels, proportional to
//! each voxel's emitted power, sampled by inversion of Pr(z), Pr(y | z), Pr(x | z, y), then a point uniform in
//! the chosen voxel. Only non-zero voxels are stored.
//!
//! ## Weights
//! A voxel's weight is its emission at the voxel centre, either `power` (∫ j dλ over the volume's bins, the
//! default: 0.4–0.7 % lower error on the default scene, docs/RESULTS.md) or `luminance` (Σ_c j_c Y_c). The light's total power
//! is 4π V Σ ∫ j dλ over the **whole** spectrum (W) — soot ∫ κ(λ) B(T, λ) dλ over 10 nm–1 mm, lines summed —
//! and 4π V Σ_c j_c Y_c over the bins (lm). Medium units are taken as metres.
//!
//! ## Densities and their use
//! - `pdf(x)`: per unit medium-space volume, w_v / (W V_voxel) in the voxel holding x.
//! - `pdf_direction(o, ω)`: the solid-angle density of the sampled point's direction seen from o,
//!   ∫ pdf(o + s ω̂) s² ds along the whole ray (a per-voxel walk: exact for the piecewise-constant pdf).
//! - A host estimates the fire's light at a point p by T(x, p) j(x) G / pdf(x), with G = cosθ_p / |x − p|²
//!   (medium-space distance; the medium transform must be a similarity), and combines it with paths that reach
//!   the fire by themselves through MIS on directions: weight pdf_direction / (pdf_direction + pdf_bsdf) for the
//!   light sample and pdf_bsdf / (pdf_bsdf + pdf_direction) for the emission those paths collect.

use crate::blackbody::spectral_radiance_si;
use crate::majorant::walk;
use crate::volume::FireVolume;
use crate::Error;
use glam::DVec3;
use std::sync::Arc;
use std::time::Instant;

/// How voxels are weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Weighting {
    /// Σ_c j_c Y_c (luminance of the emission).
    Luminance,
    /// ∫ j dλ over the bins.
    Power,
}

/// A sampled point of the fire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSample {
    /// Medium-space point.
    pub point: DVec3,
    /// Density per unit medium-space volume.
    pub pdf: f64,
}

/// The fire light of one volume.
#[derive(Debug)]
pub struct FireLight {
    vol: Arc<FireVolume>,
    weighting: Weighting,
    dims: [usize; 3],
    voxel: DVec3,
    total: f64,
    cdf_z: Vec<f64>,
    /// Per z: prefix sums over y (ny entries).
    cdf_y: Vec<f64>,
    /// Per (z, y): range into `xs`/`cdf_x`.
    rows: Vec<(u32, u32)>,
    xs: Vec<u32>,
    cdf_x: Vec<f64>,
    /// The weight of each entry of `xs`, in voxel order (x fastest).
    ws: Vec<f32>,
    /// One bit per voxel: emitting. With `rank` (the emitting voxels before each 64-bit word), a voxel's entry
    /// in `ws` is rank + the set bits below it — a lookup in O(1) for the MIS density's walk.
    occupied: Vec<u64>,
    rank: Vec<u32>,
    power_w: f64,
    power_lm: f64,
    build_seconds: f64,
}

fn first_above(cdf: &[f64], target: f64) -> usize {
    cdf.partition_point(|&c| c <= target)
        .min(cdf.len().saturating_sub(1))
}

/// The error for a fire with nothing to sample.
fn no_emission() -> Error {
    Error::invalid(
        "light",
        "fire",
        "no emitting voxel",
        "a fire with some emission (temperature above 0 K and density or species)",
    )
}

impl FireLight {
    /// Builds the light of `vol` (the light's own parameter, `weighting`, is `luminance` or `power`).
    pub fn new(vol: Arc<FireVolume>, weighting: Weighting) -> Result<FireLight, Error> {
        let start = Instant::now();
        // Nothing to sample: refused before a weight per voxel is allocated (a 16-byte raw file claiming 600³
        // voxels and no temperature built a 3.4 GB light).
        if !vol.can_emit() {
            return Err(no_emission());
        }
        let ds = vol.dataset();
        let dims = ds.dims();
        let voxel = ds.voxel_size();
        let [p0, _] = ds.bounds();
        let c = vol.channels();
        let xyz = vol.channel_xyz();
        let widths: Vec<f64> = match vol.color_mode() {
            crate::volume::ColorMode::Spectral(g) => vec![g.width_nm(); g.count()],
            crate::volume::ColorMode::Rgb => vec![1.0; 3],
        };
        // Full-spectrum power per unit density over T (soot), and per unit N (lines), physical mode only.
        let src = vol.source().cloned();
        let soot_power = |t: f64| -> f64 {
            let Some(s) = &src else { return 0.0 };
            let (lo, hi) = (10e-9f64.ln(), 1e-3f64.ln());
            crate::quadrature::gauss_legendre(
                |u| {
                    let l = u.exp();
                    s.soot.kappa(l * 1e9, 1.0, s.alpha) * spectral_radiance_si(t, l) * l
                },
                lo,
                hi,
                60,
            )
        };
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        let n = dims[0] * dims[1] * dims[2];
        // Per voxel: a weight and its dilated copy (4 + 4 bytes) and an occupancy bit with its rank; within
        // what the volume's budget (`maxbytes`) leaves after its grids and tables.
        let need = (n as u64).saturating_mul(9);
        // The weights are per voxel of the box, so a sparse fire in a big box (a far-away second copy) would
        // spend on empty space many times what its grids store: refused while the light is dense, so the memory
        // a render takes follows the active voxels (the host then leaves the light out and says so).
        let stored = ds.bytes() as u64;
        if need > stored.saturating_mul(8).max(1 << 26) {
            return Err(Error::invalid(
                "light",
                "fire",
                format!(
                    "a sparse fire in a {} × {} × {} box (its grids store {stored} bytes; the light's per-voxel weights would take {need})",
                    dims[0], dims[1], dims[2]
                ),
                "a box whose per-voxel weights (9 bytes a voxel) stay within 8× what the grids store",
            ));
        }
        if need > vol.spare_bytes() {
            return Err(Error::TooLarge {
                file: "fire light".into(),
                what: format!(
                    "the weights of {} × {} × {} voxels",
                    dims[0], dims[1], dims[2]
                ),
                bytes: need,
                cap: vol.spare_bytes(),
            });
        }
        let mut w = crate::alloc::filled(n, 0f32).ok_or_else(|| {
            Error::invalid(
                "light",
                "fire",
                format!("{n} voxels"),
                "a grid whose per-voxel weights (4 bytes each) the allocator can hold",
            )
        })?;
        let (mut pw, mut plm) = (0.0, 0.0);
        // Soot power depends on T only: memoise per 0.5 K.
        let mut memo: std::collections::HashMap<i64, f64> = std::collections::HashMap::new();
        let dch = vol.density_channel();
        let tch = vol.temperature_channel();
        for k in 0..dims[2] {
            for jy in 0..dims[1] {
                for i in 0..dims[0] {
                    let idx = i + dims[0] * (jy + dims[1] * k);
                    let p = p0 + (DVec3::new(i as f64, jy as f64, k as f64) + 0.5) * voxel;
                    vol.coefficients(p, &mut sa, &mut ss, &mut j);
                    let lum: f64 = (0..c).map(|q| j[q] * xyz[q].y).sum();
                    let band: f64 = (0..c).map(|q| j[q] * widths[q]).sum();
                    if !(lum > 0.0 || band > 0.0) {
                        continue;
                    }
                    w[idx] = match weighting {
                        Weighting::Luminance => lum,
                        Weighting::Power => band,
                    } as f32;
                    plm += lum;
                    pw += match &src {
                        None => band,
                        Some(s) => {
                            let chs = ds.channels();
                            let at = |q: usize| chs[q].grid.at(i as i64, jy as i64, k as i64);
                            let d = at(dch).max(0.0) as f64;
                            let t = tch.map(|q| at(q) as f64).unwrap_or(0.0);
                            let key = (t * 2.0).round() as i64;
                            let soot = *memo
                                .entry(key)
                                .or_insert_with(|| soot_power(key as f64 / 2.0));
                            let mut v = d * s.soot_scale * soot;
                            for (e, ch, scale) in &s.species {
                                let nn = at(*ch).max(0.0) as f64 * scale;
                                if nn > 0.0 {
                                    v += nn * s.intensity * line_power(e, t);
                                }
                            }
                            v
                        }
                    };
                }
            }
        }
        // With trilinear interpolation a voxel whose centre is dark still emits where it borders a bright one
        // (up to half the neighbour's value at the shared face, about 1/8 of it averaged over the voxel): the
        // pdf's support must cover that, or MIS would drop it. Such voxels get 1/8 of their brightest neighbour.
        if ds.interpolation() == crate::grid::Interpolation::Trilinear {
            w = dilate(&w, dims, 0.125);
        }
        let vv = voxel.x * voxel.y * voxel.z;
        let power_w = 4.0 * std::f64::consts::PI * vv * pw;
        let power_lm = 4.0 * std::f64::consts::PI * vv * plm;
        // Hierarchical CDFs.
        let (nx, ny, nz) = (dims[0], dims[1], dims[2]);
        let mut cdf_z = Vec::with_capacity(nz);
        let mut cdf_y = Vec::with_capacity(nz * ny);
        let mut rows = Vec::with_capacity(nz * ny);
        let (mut xs, mut cdf_x, mut ws) = (Vec::new(), Vec::new(), Vec::new());
        let mut tz = 0.0;
        for k in 0..nz {
            let mut ty = 0.0;
            for jy in 0..ny {
                let start = xs.len() as u32;
                let mut tx = 0.0;
                for i in 0..nx {
                    let idx = i + nx * (jy + ny * k);
                    if w[idx] > 0.0 {
                        tx += w[idx] as f64;
                        xs.push(i as u32);
                        cdf_x.push(tx);
                        ws.push(w[idx]);
                    }
                }
                rows.push((start, xs.len() as u32 - start));
                ty += tx;
                cdf_y.push(ty);
            }
            tz += ty;
            cdf_z.push(tz);
        }
        let mut occupied = vec![0u64; (nx * ny * nz).div_ceil(64)];
        for (idx, &v) in w.iter().enumerate() {
            if v > 0.0 {
                occupied[idx / 64] |= 1 << (idx % 64);
            }
        }
        let mut rank = Vec::with_capacity(occupied.len());
        let mut before = 0u32;
        for m in &occupied {
            rank.push(before);
            before += m.count_ones();
        }
        if !(tz > 0.0) {
            return Err(no_emission());
        }
        Ok(FireLight {
            vol,
            weighting,
            dims,
            voxel,
            total: tz,
            cdf_z,
            cdf_y,
            rows,
            xs,
            cdf_x,
            ws,
            occupied,
            rank,
            power_w,
            power_lm,
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The volume the light belongs to.
    pub fn volume(&self) -> &FireVolume {
        &self.vol
    }
    /// The weighting.
    pub fn weighting(&self) -> Weighting {
        self.weighting
    }
    /// Total emitted power over the whole spectrum, W (pbrt mode: over the bins, relative units).
    pub fn power_w(&self) -> f64 {
        self.power_w
    }
    /// Luminous power over the bins, lm.
    pub fn power_lm(&self) -> f64 {
        self.power_lm
    }
    /// Emitting voxels.
    pub fn voxels(&self) -> usize {
        self.ws.len()
    }
    /// Bytes held by the distribution.
    pub fn bytes(&self) -> usize {
        (self.cdf_z.len() + self.cdf_y.len() + self.cdf_x.len()) * 8
            + self.rows.len() * 8
            + self.xs.len() * 4
            + self.ws.len() * 4
            + self.occupied.len() * 8
            + self.rank.len() * 4
    }
    /// Seconds to build.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// Samples a point from six uniform numbers (three choose the voxel, three place the point in it).
    pub fn sample(&self, u: [f64; 6]) -> LightSample {
        let ny = self.dims[1];
        let k = first_above(&self.cdf_z, u[0] * self.total);
        let zbase = if k == 0 { 0.0 } else { self.cdf_z[k - 1] };
        let rowy = &self.cdf_y[k * ny..(k + 1) * ny];
        let wz = self.cdf_z[k] - zbase;
        let jy = first_above(rowy, u[1] * wz);
        let ybase = if jy == 0 { 0.0 } else { rowy[jy - 1] };
        let (start, len) = self.rows[k * ny + jy];
        let xs = &self.xs[start as usize..(start + len) as usize];
        let cx = &self.cdf_x[start as usize..(start + len) as usize];
        let wy = rowy[jy] - ybase;
        let m = first_above(cx, u[2] * wy);
        let i = xs[m] as usize;
        let wv = self.ws[start as usize + m] as f64;
        let [p0, _] = self.vol.dataset().bounds();
        let point = p0
            + (DVec3::new(i as f64, jy as f64, k as f64) + DVec3::new(u[3], u[4], u[5]))
                * self.voxel;
        LightSample {
            point,
            pdf: wv / (self.total * self.voxel.x * self.voxel.y * self.voxel.z),
        }
    }

    fn weight(&self, idx: usize) -> f64 {
        let (word, bit) = (idx / 64, idx % 64);
        let (Some(&m), Some(&r)) = (self.occupied.get(word), self.rank.get(word)) else {
            return 0.0;
        };
        if m >> bit & 1 == 0 {
            return 0.0;
        }
        let below = (m & ((1u64 << bit) - 1)).count_ones();
        self.ws
            .get(r as usize + below as usize)
            .map_or(0.0, |&w| w as f64)
    }

    /// Density of a medium-space point, per unit volume.
    pub fn pdf(&self, p: DVec3) -> f64 {
        let [p0, p1] = self.vol.dataset().bounds();
        if !(p.cmpge(p0).all() && p.cmplt(p1).all()) {
            return 0.0;
        }
        let q = ((p - p0) / self.voxel).floor();
        let [i, j, k] = [0, 1, 2].map(|a| (q[a].max(0.0) as usize).min(self.dims[a] - 1));
        self.weight(i + self.dims[0] * (j + self.dims[1] * k))
            / (self.total * self.voxel.x * self.voxel.y * self.voxel.z)
    }

    /// Solid-angle density of the direction `d` from `o`: ∫ pdf(o + s d̂) s² ds over s ≥ 0.
    pub fn pdf_direction(&self, o: DVec3, d: DVec3) -> f64 {
        let len = d.length();
        if !(len > 0.0 && len.is_finite() && o.is_finite()) {
            return 0.0;
        }
        let dn = d / len;
        let ds = self.vol.dataset();
        let scale = 1.0 / (self.total * self.voxel.x * self.voxel.y * self.voxel.z);
        let mut sum = 0.0;
        for seg in walk(ds.bounds(), self.dims, 1, o, dn, 0.0, f64::INFINITY) {
            let w = self.weight(seg.brick);
            if w > 0.0 {
                sum += w * (seg.t1.powi(3) - seg.t0.powi(3)) / 3.0;
            }
        }
        sum * scale
    }
}

/// `max(w, f · max of the 26 neighbours)` per voxel (a separable 3×3×3 max filter).
fn dilate(w: &[f32], dims: [usize; 3], f: f32) -> Vec<f32> {
    let mut m = w.to_vec();
    let strides = [1, dims[0], dims[0] * dims[1]];
    for axis in 0..3 {
        let src = m.clone();
        let (stride, n) = (strides[axis], dims[axis]);
        for (idx, out) in m.iter_mut().enumerate() {
            let c = (idx / stride) % n;
            if c > 0 {
                *out = out.max(src[idx - stride]);
            }
            if c + 1 < n {
                *out = out.max(src[idx + stride]);
            }
        }
    }
    w.iter().zip(&m).map(|(&a, &b)| a.max(f * b)).collect()
}

/// Full line emission per unit number density, W·sr⁻¹ (all shipped lines of `e` at T).
fn line_power(e: &crate::species::Element, t: f64) -> f64 {
    use crate::constants::{BOLTZMANN, PLANCK, SPEED_OF_LIGHT};
    if !(t > 0.0) {
        return 0.0;
    }
    let kt = BOLTZMANN * t;
    let z = e.partition_function(t);
    e.lines()
        .iter()
        .map(|l| {
            PLANCK * SPEED_OF_LIGHT / (4.0 * std::f64::consts::PI * l.lambda_nm * 1e-9)
                * l.a_ki
                * l.g_k as f64
                * (-l.e_k / kt).exp()
                / z
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;
    use crate::rng::Rng;

    fn sphere_fire(n: usize, r: f64, fv: f64, t: f64, extra: Vec<Param>) -> Arc<FireVolume> {
        // A uniform sphere of grey soot (alpha 0, constant n, k) in an n³ grid over [−1, 1]³, nearest lookup.
        let mut dens = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                    dens.push(if c(i).powi(2) + c(j).powi(2) + c(k).powi(2) < r * r {
                        fv
                    } else {
                        0.0
                    });
                }
            }
        }
        let mut list = vec![
            Param::floats("density", &dens),
            Param::floats("temperature", &vec![t; n * n * n]),
            Param::int("nx", n as i64),
            Param::int("ny", n as i64),
            Param::int("nz", n as i64),
            Param::point3("p0", [-1.0; 3]),
            Param::point3("p1", [1.0; 3]),
            Param::string("interpolation", "nearest"),
            Param::string("fuel", "custom"),
            Param::floats("fuelnk", &[500.0, 1.6, 0.5]),
            Param::float("alpha", 0.0),
        ];
        list.extend(extra);
        Arc::new(FireVolume::new(&list).unwrap())
    }

    #[test]
    fn sampled_pdf_equals_evaluated_pdf() {
        let light = FireLight::new(
            sphere_fire(24, 0.8, 1e-6, 1500.0, vec![]),
            Weighting::Luminance,
        )
        .unwrap();
        let mut rng = Rng::new(3);
        for _ in 0..20_000 {
            let u = [(); 6].map(|_| rng.next_f64());
            let s = light.sample(u);
            let p = light.pdf(s.point);
            assert!(
                s.pdf > 0.0 && ((p - s.pdf) / s.pdf).abs() < 1e-5,
                "{} vs {p} at {}",
                s.pdf,
                s.point
            );
        }
    }

    #[test]
    fn thin_grey_sphere_radiates_four_kappa_sigma_t4_v() {
        // Optically thin uniform emitter: P = 4 κ σ T⁴ V (shared/data), V the voxelised sphere's volume.
        let (n, fv, t) = (32, 1e-9, 1500.0);
        let vol = sphere_fire(n, 0.8, fv, t, vec![]);
        let light = FireLight::new(vol.clone(), Weighting::Power).unwrap();
        let kappa = vol_kappa(&vol);
        let v = light.voxels() as f64 * (2.0 / n as f64).powi(3);
        let want = 4.0 * kappa * crate::constants::STEFAN_BOLTZMANN * t.powi(4) * v;
        assert!(
            (light.power_w() / want - 1.0).abs() < 0.005,
            "{} W vs 4κσT⁴V = {want} W",
            light.power_w()
        );
    }

    fn vol_kappa(vol: &FireVolume) -> f64 {
        let c = vol.channels();
        let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        vol.coefficients(DVec3::ZERO, &mut a, &mut s, &mut j);
        a[0]
    }

    #[test]
    fn monte_carlo_power_equals_the_computed_power() {
        // E[L_v(x)/pdf(x)] = Σ_v w_v V: the luminous power from samples within 3σ of the tabulated one.
        let vol = sphere_fire(20, 0.9, 1e-7, 1800.0, vec![]);
        let light = FireLight::new(vol.clone(), Weighting::Power).unwrap();
        let xyz = vol.channel_xyz();
        let c = vol.channels();
        let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        let mut rng = Rng::new(9);
        let n = 40_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let smp = light.sample([(); 6].map(|_| rng.next_f64()));
            vol.coefficients(smp.point, &mut a, &mut s, &mut j);
            let lum: f64 =
                (0..c).map(|q| j[q] * xyz[q].y).sum::<f64>() * 4.0 * std::f64::consts::PI;
            let x = lum / smp.pdf;
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
        assert!(
            (mean - light.power_lm()).abs() <= 3.0 * se + 1e-9 * mean,
            "{mean} ± {se} vs {}",
            light.power_lm()
        );
    }

    #[test]
    fn direction_pdf_integrates_to_one_over_the_sphere() {
        // ∫ pdf_direction dω = 1 for a point outside the fire (all the pdf is seen from there).
        let light = FireLight::new(
            sphere_fire(16, 0.7, 1e-6, 1600.0, vec![]),
            Weighting::Luminance,
        )
        .unwrap();
        let o = DVec3::new(0.3, -3.0, 0.2);
        let mut rng = Rng::new(5);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let z = 1.0 - 2.0 * rng.next_f64();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
            sum += light.pdf_direction(o, DVec3::new(r * phi.cos(), r * phi.sin(), z))
                * 4.0
                * std::f64::consts::PI;
        }
        let mean = sum / n as f64;
        assert!((mean - 1.0).abs() < 0.03, "∫ pdf dω = {mean}");
        // And it is consistent with point sampling: pdf_direction ≥ pdf(x) s² ds piece for the sampled direction.
        let s = light.sample([0.5; 6]);
        assert!(light.pdf_direction(o, s.point - o) > 0.0);
    }

    #[test]
    fn irradiance_beside_a_fire_equals_brute_force_quadrature() {
        // E_Y(p) = ∫ T(p, x) j_Y(x) cosθ / |x − p|² dV over a smooth, trilinear, optically thick-ish fire
        // (τ ≈ 1 across): the light's estimator against a midpoint quadrature on 4³ points per voxel.
        let n = 10;
        let (mut dens, mut temp) = (Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                    let r2 = c(i).powi(2) + c(j).powi(2) + (c(k) + 0.2).powi(2);
                    dens.push((1.0 - r2 / 0.8).max(0.0) * 2e-7);
                    temp.push(1200.0 + 800.0 * (1.0 - r2 / 2.0).max(0.0));
                }
            }
        }
        let vol = Arc::new(
            FireVolume::new(&[
                Param::floats("density", &dens),
                Param::floats("temperature", &temp),
                Param::int("nx", n as i64),
                Param::int("ny", n as i64),
                Param::int("nz", n as i64),
                Param::point3("p0", [-1.0; 3]),
                Param::point3("p1", [1.0; 3]),
                Param::string("fuel", "propane"),
                Param::float("stepsize", 0.25),
            ])
            .unwrap(),
        );
        let light = FireLight::new(vol.clone(), Weighting::Luminance).unwrap();
        let xyz = vol.channel_xyz();
        let c = vol.channels();
        let p = DVec3::new(1.7, 0.3, -0.4);
        let nrm = DVec3::new(-1.0, 0.0, 0.3).normalize();
        let (mut a, mut s, mut j, mut t) = (vec![0.0; c], vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        let mut tau_max = 0.0f64;
        let mut f = |x: DVec3| -> f64 {
            let v = x - p;
            let r2 = v.length_squared();
            let cos = nrm.dot(v) / r2.sqrt();
            if cos <= 0.0 {
                return 0.0;
            }
            vol.coefficients(x, &mut a, &mut s, &mut j);
            if j.iter().all(|&q| q == 0.0) {
                return 0.0;
            }
            let ray = crate::volume::Ray {
                o: p,
                d: v,
                t0: 0.0,
                t1: 1.0,
                seed: 1,
            };
            vol.transmittance(&ray, &mut t);
            tau_max = tau_max.max(-t[c / 2].ln());
            (0..c).map(|q| j[q] * t[q] * xyz[q].y).sum::<f64>() * cos / r2
        };
        // Brute force.
        let m = 4 * n;
        let h = 2.0 / m as f64;
        let mut quad = 0.0;
        for k in 0..m {
            for jy in 0..m {
                for i in 0..m {
                    let x = DVec3::new(i as f64 + 0.5, jy as f64 + 0.5, k as f64 + 0.5) * h - 1.0;
                    quad += f(x) * h * h * h;
                }
            }
        }
        // The light.
        let mut rng = Rng::new(21);
        let ns = 40_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..ns {
            let smp = light.sample([(); 6].map(|_| rng.next_f64()));
            let x = f(smp.point) / smp.pdf;
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / ns as f64;
        let se = ((sum2 / ns as f64 - mean * mean).max(0.0) / ns as f64).sqrt();
        assert!(
            tau_max > 0.3,
            "the test fire should shadow itself (τ_max = {tau_max})"
        );
        assert!(
            (mean - quad).abs() <= 3.0 * se,
            "fire light {mean} ± {se} vs quadrature {quad} (rel. σ {})",
            se / mean
        );
    }

    #[test]
    fn a_fire_that_cannot_emit_is_refused_before_its_voxels_are_weighed() {
        // No temperature grid: nothing emits. Refused up front (a 600³ grid of this kind built a 3.4 GB light).
        let vol = FireVolume::new(&[
            Param::floats("density", &[1.0; 8]),
            Param::int("nx", 2),
            Param::int("ny", 2),
            Param::int("nz", 2),
        ])
        .unwrap();
        assert!(!vol.can_emit());
        let e = FireLight::new(Arc::new(vol), Weighting::Power)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no emitting voxel"), "{e}");
        assert!(sphere_fire(8, 0.8, 1e-6, 1500.0, vec![]).can_emit());
    }
}
