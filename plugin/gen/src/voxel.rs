//! Voxelisation: the blobs' kernels (round, or warped back through the wind) summed into grids.

use super::*;

/// The voxelised fields.
#[derive(Debug)]
pub struct Fields {
    pub dims: [usize; 3],
    pub p0: DVec3,
    pub voxel: f64,
    /// Soot volume fraction.
    pub density: Vec<f32>,
    /// Temperature, K (0 where no mass).
    pub temperature: Vec<f32>,
    /// Flame mass density (kg/m³), for species.
    pub flame: Vec<f32>,
    /// The gas's velocity (m/s): the mass-weighted wind of the blobs there (0 where no mass); empty unless
    /// asked for.
    pub velocity: [Vec<f32>; 3],
    /// The heat release rate of the reaction (W/m³): each blob's fuel reacting as it leaves the fuel, at
    /// m_f H / τ_r · e^(−age/τ_r), spread by its kernel — the blue core's source.
    pub reaction: Vec<f32>,
}

/// Heat of combustion of the generator's fuel (propane's lower heating value, 46.35 MJ/kg).
pub const HEAT_OF_COMBUSTION: f64 = 46.35e6;
/// The reaction's time scale τ_r (s): fuel released by a cell reacts in the first τ_r of its blob's life, at
/// the flame's base — where a flame's blue reaction zone sits, beneath its sooty yellow (its front is ~1 mm thick
/// in a laminar flame; the blobs resolve centimetres, so the zone is as thin as a few voxels allow). Over a blob's
/// life the released heat integrates to m_f H.
pub const REACTION_TIME: f64 = 0.02;

/// Stam & Fiume's warped blobs (§4, eq. 7): each point x is traced back through the wind for t₀ seconds to
/// x⁻¹ (ten Euler steps, as the paper found adequate), and a blob's kernel is evaluated there,
/// W_{σ − η t₀}(|x⁻¹ − x_k⁻¹|). Only the turbulent wind is traced: the buoyant lift is uniform over a blob, so it
/// cancels in x⁻¹ − x_k⁻¹. The turbulence is smooth at its length scale, so the back-traced displacement is
/// computed on a grid a quarter of that scale apart and interpolated trilinearly (10 Euler steps per node
/// instead of per voxel). A divergence-free wind keeps volumes, its interpolated back-trace only roughly: each
/// warped kernel is scaled by the back-trace's Jacobian determinant at its blob (tested: the mass kept to 3 %).
struct Warp {
    t0: f64,
    eta: f64,
    p0: DVec3,
    h: f64,
    dims: [usize; 3],
    disp: Vec<DVec3>,
    /// The largest displacement, m.
    reach: f64,
}

impl Warp {
    fn new(sim: &Sim, (t0, eta): (f64, f64), lo: DVec3, hi: DVec3) -> Warp {
        let h = sim.model.turbulence_scale / 4.0;
        let dims = [0, 1, 2].map(|k| ((hi[k] - lo[k]) / h).ceil() as usize + 2);
        let steps = 10;
        let dt = t0 / steps as f64;
        let disp: Vec<DVec3> = (0..dims[0] * dims[1] * dims[2])
            .into_par_iter()
            .map(|n| {
                let (i, j, k) = (
                    n % dims[0],
                    (n / dims[0]) % dims[1],
                    n / (dims[0] * dims[1]),
                );
                let x0 = lo + DVec3::new(i as f64, j as f64, k as f64) * h;
                let mut x = x0;
                // Midpoint steps backwards in time (second order: the map stays close to volume-preserving
                // where Euler's drifts).
                for s in 0..steps {
                    let t = sim.time - s as f64 * dt;
                    let mid = x - sim.turbulence(x, t) * (0.5 * dt);
                    x -= sim.turbulence(mid, t - 0.5 * dt) * dt;
                }
                x - x0
            })
            .collect();
        let reach = disp.iter().map(|d| d.length()).fold(0.0, f64::max);
        Warp {
            t0,
            eta,
            p0: lo,
            h,
            dims,
            disp,
            reach,
        }
    }
    /// x⁻¹: `x` traced back (the displacement interpolated trilinearly, clamped to the grid).
    fn back(&self, x: DVec3) -> DVec3 {
        let f = (x - self.p0) / self.h;
        let [nx, ny, nz] = self.dims;
        let c = |v: f64, n: usize| v.clamp(0.0, (n - 1) as f64 - 1e-9);
        let f = DVec3::new(c(f.x, nx), c(f.y, ny), c(f.z, nz));
        let (i, j, k) = (f.x as usize, f.y as usize, f.z as usize);
        let t = f - DVec3::new(i as f64, j as f64, k as f64);
        let at = |a: usize, b: usize, d: usize| {
            let (a, b, d) = (
                (i + a).min(nx - 1),
                (j + b).min(ny - 1),
                (k + d).min(nz - 1),
            );
            self.disp[a + nx * (b + ny * d)]
        };
        let lerp = |a: DVec3, b: DVec3, w: f64| a + (b - a) * w;
        let y0 = lerp(
            lerp(at(0, 0, 0), at(1, 0, 0), t.x),
            lerp(at(0, 1, 0), at(1, 1, 0), t.x),
            t.y,
        );
        let y1 = lerp(
            lerp(at(0, 0, 1), at(1, 0, 1), t.x),
            lerp(at(0, 1, 1), at(1, 1, 1), t.x),
            t.y,
        );
        x + lerp(y0, y1, t.z)
    }
    /// The warped kernel's σ: σ − η t₀, at least half of σ (the paper leaves the floor to the animator) and half
    /// a voxel (a narrower kernel falls between the grid's samples and loses or gains mass), never above σ.
    fn sigma(&self, s: f64, voxel: f64) -> f64 {
        (s - self.eta * self.t0)
            .max(0.5 * s)
            .max(0.5 * voxel)
            .min(s)
    }
}

/// Splats the blobs onto a grid of `res` voxels along the domain's longest side (and their wind, with
/// `velocity`); with `sim.warp`, as warped blobs ([`Warp`]).
pub fn voxelise(sim: &Sim, res: usize, velocity: bool) -> Fields {
    let m = &sim.model;
    let size = DVec3::new(2.0 * m.half_width, 2.0 * m.half_width, m.height);
    let voxel = size.max_element() / res as f64;
    let dims = [0, 1, 2].map(|k| ((size[k] / voxel).round() as usize).max(1));
    let p0 = DVec3::new(-m.half_width, -m.half_width, 0.0);
    let (nx, ny, nz) = (dims[0], dims[1], dims[2]);
    let slab = nx * ny;
    let warp = sim.warp.map(|w| {
        Warp::new(
            sim,
            w,
            p0,
            p0 + DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) * voxel,
        )
    });
    // Blob footprints: 3σ boxes in voxel indices (widened by twice the warp's reach: x⁻¹ and x_k⁻¹ both move).
    let kappa = m.kappa;
    // Each blob with its σ, its footprint's index box and its wind; warped, with its kernel's σ and x_k⁻¹.
    type Footprint = (Blob, f64, [i64; 3], [i64; 3], DVec3, f64);
    let blobs: Vec<Footprint> = sim
        .blobs
        .par_iter()
        .map(|b| {
            let (s, centre, reach) = match &warp {
                Some(w) => (w.sigma(b.sigma(kappa), voxel), w.back(b.x), 2.0 * w.reach),
                None => (b.sigma(kappa), b.x, 0.0),
            };
            let lo = ((b.x - DVec3::splat(3.0 * s + reach) - p0) / voxel).floor();
            let hi = ((b.x + DVec3::splat(3.0 * s + reach) - p0) / voxel).ceil();
            let (lo, hi) = (
                [lo.x as i64, lo.y as i64, lo.z as i64],
                [hi.x as i64, hi.y as i64, hi.z as i64],
            );
            // Change of variables: the warped kernel integrates to 1/|det J| with J = ∂x⁻¹/∂x, which the
            // interpolated back-trace keeps near but not at 1 where the wind stretches hard; the gain |det J| at
            // the blob (central differences over σ) gives each blob back its mass to first order.
            let gain = match &warp {
                Some(w) => {
                    let d = |e: DVec3| (w.back(b.x + e * s) - w.back(b.x - e * s)) / (2.0 * s);
                    let det = glam::DMat3::from_cols(d(DVec3::X), d(DVec3::Y), d(DVec3::Z))
                        .determinant()
                        .abs();
                    if det.is_finite() {
                        det.clamp(0.1, 10.0)
                    } else {
                        1.0
                    }
                }
                None => 1.0,
            };
            (
                Blob { x: centre, ..*b },
                s,
                lo,
                hi,
                if velocity {
                    sim.wind(b.x, b.t)
                } else {
                    DVec3::ZERO
                },
                gain,
            )
        })
        .collect();
    // Per z-slice in parallel: sums of flame, smoke, mass × temperature (and mass × velocity).
    type Slice = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<DVec3>, Vec<f64>);
    let slices: Vec<Slice> = (0..nz)
        .into_par_iter()
        .map(|k| {
            let (mut f, mut s, mut mt) = (vec![0.0; slab], vec![0.0; slab], vec![0.0; slab]);
            let mut q = vec![0.0; slab];
            let mut mv = vec![DVec3::ZERO; if velocity { slab } else { 0 }];
            let z = p0.z + (k as f64 + 0.5) * voxel;
            // The slice's voxel centres, traced back when warping (the blobs' centres already are).
            let points: Vec<DVec3> = (0..if warp.is_some() { slab } else { 0 })
                .map(|idx| {
                    let x = DVec3::new(
                        p0.x + ((idx % nx) as f64 + 0.5) * voxel,
                        p0.y + ((idx / nx) as f64 + 0.5) * voxel,
                        z,
                    );
                    warp.as_ref().map_or(x, |w| w.back(x))
                })
                .collect();
            for (b, sg, lo, hi, v, gain) in &blobs {
                if (k as i64) < lo[2] || (k as i64) > hi[2] {
                    continue;
                }
                let norm = 1.0 / ((2.0 * std::f64::consts::PI).powf(1.5) * sg * sg * sg);
                let burn = (b.m_flame + b.m_smoke) * HEAT_OF_COMBUSTION / REACTION_TIME
                    * (-b.age / REACTION_TIME).exp();
                let inv = 1.0 / (2.0 * sg * sg);
                let dz2 = (z - b.x.z).powi(2);
                for j in lo[1].max(0)..=hi[1].min(ny as i64 - 1) {
                    let y = p0.y + (j as f64 + 0.5) * voxel;
                    let dyz = dz2 + (y - b.x.y).powi(2);
                    for i in lo[0].max(0)..=hi[0].min(nx as i64 - 1) {
                        let idx = i as usize + nx * j as usize;
                        let w = if warp.is_some() {
                            let r2 = points[idx].distance_squared(b.x);
                            // (Beyond 6σ a kernel is below e⁻¹⁸ of its peak: skipped.)
                            if r2 > 36.0 * sg * sg {
                                continue;
                            }
                            gain * norm * (-r2 * inv).exp()
                        } else {
                            // (Round kernels: the committed datasets' arithmetic, bit for bit.)
                            let x = p0.x + (i as f64 + 0.5) * voxel;
                            norm * (-(dyz + (x - b.x.x).powi(2)) * inv).exp()
                        };
                        f[idx] += b.m_flame * w;
                        s[idx] += b.m_smoke * w;
                        mt[idx] += (b.m_flame + b.m_smoke) * b.t * w;
                        q[idx] += burn * w;
                        if velocity {
                            mv[idx] += (b.m_flame + b.m_smoke) * w * *v;
                        }
                    }
                }
            }
            (f, s, mt, mv, q)
        })
        .collect();
    let n = nx * ny * nz;
    let (mut density, mut temperature, mut flame) = (vec![0f32; n], vec![0f32; n], vec![0f32; n]);
    let mut reaction = vec![0f32; n];
    let nv = if velocity { n } else { 0 };
    let mut vel = [vec![0f32; nv], vec![0f32; nv], vec![0f32; nv]];
    let peak = slices
        .iter()
        .flat_map(|(f, s, _, _, _)| f.iter().zip(s).map(|(a, b)| a + b))
        .fold(0.0f64, f64::max);
    for (k, (f, s, mt, mv, q)) in slices.into_iter().enumerate() {
        for idx in 0..slab {
            let rho = f[idx] + s[idx];
            let o = idx + slab * k;
            // Below 1e-6 of the peak there is no gas of the fire: background (0), so the file stays sparse.
            if rho > 1e-6 * peak && rho > 0.0 {
                density[o] = (m.soot_yield * rho / RHO_SOOT) as f32;
                temperature[o] = (mt[idx] / rho) as f32;
                flame[o] = f[idx] as f32;
                reaction[o] = q[idx] as f32;
                if velocity {
                    for (a, g) in vel.iter_mut().enumerate() {
                        g[o] = (mv[idx][a] / rho) as f32;
                    }
                }
            }
        }
    }
    Fields {
        dims,
        p0,
        voxel,
        density,
        temperature,
        flame,
        velocity: vel,
        reaction,
    }
}
