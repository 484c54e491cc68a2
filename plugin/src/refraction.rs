//! Refraction of hot air (Pegoraro & Parker 2006 §3.7): an index-of-refraction field baked from the temperature
//! field with Ciddor's formula, and curved rays through it by the ray equation of Stam & Languénou (1996),
//!
//! ```text
//!     d/ds (n dx/ds) = ∇n,
//! ```
//!
//! written as a first-order system in arc length s for the position x and the optical direction v = n dx/ds:
//! dx/ds = v / n(x), dv/ds = ∇n(x). Steps are classical fourth-order Runge–Kutta; after each step v is rescaled to
//! |v| = n(x) (the invariant of the system; a projection, so the order stays four). Each step is checked against
//! two half steps and halved until they agree within `tol` (step doubling), and ends just past the next plane of
//! grid samples, where the trilinear gradient has a kink. The first guess of a step is the smaller of
//! `h_max` and the length over which the ray turns by `max_turn` radians (curvature |∇n⊥| / n), so a steep
//! gradient — the index jumping within one voxel — is crossed in small steps, and total internal reflection comes
//! out as the ray turning back smoothly rather than as a jump. With a field that reports its kinks (a grid), a
//! step of up to a voxel stays inside one trilinear cell; without, `h_max` must not exceed half the length over
//! which the field changes, or a step could land inside a jump it never saw.
//!
//! ## The baked field
//! [`IndexGrid`] stores δ = scale · ((n(T) − 1) − (n(T_amb) − 1)) per voxel (f32: |δ| ≤ 3e-4 · scale, f32 keeps
//! 7 digits of it), padded by one ring of δ = 0 voxels, so n = n_amb + δ with the zero-outside trilinear lookup
//! is continuous everywhere: ambient outside the padded box, and entering or leaving bends the ray smoothly
//! over the last voxel and a half. Voxels colder than `T_amb` (0 K where a simulation holds
//! no data) count as ambient air. `scale` is the paper's Figure 2 exaggeration of (n − 1). The gradient is the
//! analytic gradient of the trilinear interpolant.

use crate::ciddor::{self, Air};
use crate::grid::Grid;
use glam::DVec3;

/// An index-of-refraction field: n(x) and ∇n(x) at medium-space points.
pub trait IndexField {
    /// The index at `p`.
    fn n(&self, p: DVec3) -> f64;
    /// Its gradient at `p`.
    fn grad(&self, p: DVec3) -> DVec3;
    /// Both at once (one lookup for fields that compute them together).
    fn n_grad(&self, p: DVec3) -> (f64, DVec3) {
        (self.n(p), self.grad(p))
    }
    /// Distance from `p` along unit `dir` to the next place the gradient may jump (for a trilinear grid, the
    /// next plane of sample centres): steps end there so that each RK4 step sees a smooth field.
    fn next_kink(&self, _p: DVec3, _dir: DVec3) -> f64 {
        f64::INFINITY
    }
}

/// Step control of [`trace`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Steps {
    /// Longest step (medium units).
    pub h_max: f64,
    /// Largest turn of the direction in one step, radians.
    pub max_turn: f64,
    /// Shortest step (medium units): below it the field is treated as a discontinuity and crossed at h_min.
    pub h_min: f64,
    /// Most steps before giving up (the ray then ends where it is).
    pub max_steps: usize,
    /// Largest difference allowed between one step and two half steps (position, plus direction × h_max):
    /// a step that misses it is halved (step doubling; the two half steps are kept).
    pub tol: f64,
}

impl Default for Steps {
    fn default() -> Self {
        Steps {
            h_max: 0.05,
            max_turn: 0.02,
            h_min: 1e-7,
            max_steps: 1 << 20,
            tol: 1e-10,
        }
    }
}

/// Where a traced ray ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exit {
    /// End point.
    pub x: DVec3,
    /// Unit direction there.
    pub dir: DVec3,
    /// Arc length travelled.
    pub s: f64,
    /// Steps taken.
    pub steps: usize,
}

fn index_at(f: &impl IndexField, p: DVec3) -> f64 {
    let n = f.n(p);
    if n.is_finite() {
        n.max(1e-6)
    } else {
        1.0
    }
}

fn grad_at(f: &impl IndexField, p: DVec3) -> DVec3 {
    let g = f.grad(p);
    if g.is_finite() {
        g
    } else {
        DVec3::ZERO
    }
}

/// One classical RK4 step of length `h` from (x, v), v = n t̂; returns the new (x, v) with |v| = n(x).
pub fn rk4_step(f: &impl IndexField, x: DVec3, v: DVec3, h: f64) -> (DVec3, DVec3) {
    let d = |x: DVec3, v: DVec3| {
        let (n, g) = f.n_grad(x);
        let n = if n.is_finite() { n.max(1e-6) } else { 1.0 };
        let g = if g.is_finite() { g } else { DVec3::ZERO };
        (v / n, g)
    };
    let (k1x, k1v) = d(x, v);
    let (k2x, k2v) = d(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    let (k3x, k3v) = d(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    let (k4x, k4v) = d(x + h * k3x, v + h * k3v);
    let x1 = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    let v1 = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    let len = v1.length();
    let v1 = if len > 0.0 && len.is_finite() {
        v1 * (index_at(f, x1) / len)
    } else {
        // The direction collapsed (cannot happen for h within the step control): keep the old one.
        v * (index_at(f, x1) / v.length().max(1e-300))
    };
    (x1, v1)
}

/// Traces a curved ray from `x0` along `dir` (any length) for arc length `s_max`, calling `visit(a, b, h)` for
/// every step from a to b of arc length h (for the radiative transfer along the path); stops early when `stop`
/// says the point left the region of interest.
pub fn trace(
    f: &impl IndexField,
    x0: DVec3,
    dir: DVec3,
    s_max: f64,
    steps: &Steps,
    mut visit: impl FnMut(DVec3, DVec3, f64),
    mut stop: impl FnMut(DVec3) -> bool,
) -> Exit {
    let t = dir.normalize_or_zero();
    let t = if t == DVec3::ZERO || !t.is_finite() {
        DVec3::X
    } else {
        t
    };
    let (mut x, mut v) = (x0, t * index_at(f, x0));
    let mut s = 0.0;
    let mut n_steps = 0;
    let s_max = if s_max.is_nan() { 0.0 } else { s_max.max(0.0) };
    while s < s_max && n_steps < steps.max_steps {
        let n = index_at(f, x);
        let g = grad_at(f, x);
        let tt = v / v.length().max(1e-300);
        let curvature = (g - g.dot(tt) * tt).length() / n;
        let mut h = steps.h_max.min(s_max - s);
        if curvature > 0.0 {
            h = h.min(steps.max_turn / curvature);
        }
        // End the step just past the next kink of the field's gradient.
        let kink = f.next_kink(x, tt);
        if kink.is_finite() {
            h = h.min(kink + steps.h_min);
        }
        let mut h = h.max(steps.h_min.min(s_max - s));
        // Step doubling: where one step and two half steps disagree (a kink of the trilinear gradient inside
        // the step, a steep jump), halve.
        let (x1, v1) = loop {
            if steps.tol == f64::INFINITY {
                break rk4_step(f, x, v, h);
            }
            let (xa, va) = rk4_step(f, x, v, h);
            let (xm, vm) = rk4_step(f, x, v, 0.5 * h);
            let (xb, vb) = rk4_step(f, xm, vm, 0.5 * h);
            let err = (xa - xb).length() + (va - vb).length() / n * steps.h_max;
            if !(err > steps.tol) || h <= steps.h_min {
                break (xb, vb);
            }
            h = (0.5 * h).max(steps.h_min);
        };
        visit(x, x1, h);
        x = x1;
        v = v1;
        s += h;
        n_steps += 1;
        if stop(x) {
            break;
        }
    }
    Exit {
        x,
        dir: v / v.length().max(1e-300),
        s,
        steps: n_steps,
    }
}

/// The index field of a temperature grid (module docs).
#[derive(Debug, Clone)]
pub struct IndexGrid {
    delta: Grid,
    p0: DVec3,
    size: DVec3,
    n_amb: f64,
}

impl IndexGrid {
    /// Bakes δ per voxel from `temperature` (K) over the box `p0..p1`, at vacuum wavelength `lambda_nm`, for
    /// `air` (its temperature is the ambient one), with (n − 1) exaggerated by `scale`.
    pub fn from_temperature(
        temperature: &Grid,
        p0: DVec3,
        p1: DVec3,
        lambda_nm: f64,
        air: &Air,
        scale: f64,
    ) -> IndexGrid {
        // One ring of ambient (δ = 0) voxels around the grid: the zero-outside trilinear lookup of the padded grid
        // then falls to exactly 0 at its own bounds, so n is continuous everywhere (the unpadded grid would jump
        // from half the edge sample to 0 at the bounds, a refraction the ray equation cannot see).
        let [nx, ny, nz] = temperature.dims();
        let voxel = (p1 - p0) / DVec3::new(nx as f64, ny as f64, nz as f64);
        let amb = ciddor::refractivity(lambda_nm, air);
        let mut memo: std::collections::HashMap<i64, f64> = std::collections::HashMap::new();
        let baked: Vec<f32> = temperature
            .data()
            .iter()
            .map(|&t| {
                let t = t as f64;
                if !(t > air.temperature_k) {
                    return 0.0;
                }
                // Memoised per 0.1 K (n − 1 changes by < 1e-4 relative over it at flame temperatures).
                let key = (t * 10.0).round() as i64;
                let r = *memo.entry(key).or_insert_with(|| {
                    ciddor::refractivity(
                        lambda_nm,
                        &Air {
                            temperature_k: key as f64 / 10.0,
                            ..*air
                        },
                    )
                });
                (scale * (r - amb)) as f32
            })
            .collect();
        let dims = [nx + 2, ny + 2, nz + 2];
        let mut data = vec![0f32; dims[0] * dims[1] * dims[2]];
        for k in 0..nz {
            for j in 0..ny {
                let src = nx * (j + ny * k);
                let dst = 1 + dims[0] * (j + 1 + dims[1] * (k + 1));
                data[dst..dst + nx].copy_from_slice(&baked[src..src + nx]);
            }
        }
        IndexGrid {
            delta: Grid::new(dims, data).unwrap_or_else(|| temperature.clone()),
            p0: p0 - voxel,
            size: p1 - p0 + 2.0 * voxel,
            n_amb: 1.0 + scale * amb,
        }
    }

    /// The ambient index (outside the volume).
    pub fn ambient(&self) -> f64 {
        self.n_amb
    }
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.delta.bytes()
    }
    /// The box where n differs from ambient: the grid's, one voxel wider on every side.
    pub fn bounds(&self) -> [DVec3; 2] {
        [self.p0, self.p0 + self.size]
    }

    /// Trilinear value and gradient (per medium unit) of δ at `p`, zero outside.
    fn eval(&self, p: DVec3) -> (f64, DVec3) {
        let u = (p - self.p0) / self.size;
        if !(u.cmpge(DVec3::ZERO).all() && u.cmple(DVec3::ONE).all()) {
            return (0.0, DVec3::ZERO);
        }
        let dims = self.delta.dims();
        let mut base = [0i64; 3];
        let mut fr = [0f64; 3];
        for a in 0..3 {
            let s = u[a] * dims[a] as f64 - 0.5;
            let fl = s.floor();
            base[a] = fl as i64;
            fr[a] = s - fl;
        }
        let [i, j, k] = base;
        let c = |di: i64, dj: i64, dk: i64| self.delta.at(i + di, j + dj, k + dk) as f64;
        let [fx, fy, fz] = fr;
        let (c000, c100, c010, c110) = (c(0, 0, 0), c(1, 0, 0), c(0, 1, 0), c(1, 1, 0));
        let (c001, c101, c011, c111) = (c(0, 0, 1), c(1, 0, 1), c(0, 1, 1), c(1, 1, 1));
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let (x00, x10) = (lerp(c000, c100, fx), lerp(c010, c110, fx));
        let (x01, x11) = (lerp(c001, c101, fx), lerp(c011, c111, fx));
        let (y0, y1) = (lerp(x00, x10, fy), lerp(x01, x11, fy));
        let value = lerp(y0, y1, fz);
        let dx = lerp(
            lerp(c100 - c000, c110 - c010, fy),
            lerp(c101 - c001, c111 - c011, fy),
            fz,
        );
        let dy = lerp(x10 - x00, x11 - x01, fz);
        let dz = y1 - y0;
        let scale = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) / self.size;
        (value, DVec3::new(dx, dy, dz) * scale)
    }
}

impl IndexField for IndexGrid {
    fn n(&self, p: DVec3) -> f64 {
        self.n_amb + self.eval(p).0
    }
    fn grad(&self, p: DVec3) -> DVec3 {
        self.eval(p).1
    }
    fn n_grad(&self, p: DVec3) -> (f64, DVec3) {
        let (d, g) = self.eval(p);
        (self.n_amb + d, g)
    }
    fn next_kink(&self, p: DVec3, dir: DVec3) -> f64 {
        let dims = self.delta.dims();
        let mut best = f64::INFINITY;
        for a in 0..3 {
            let cell = self.size[a] / dims[a] as f64;
            if !(dir[a].abs() > 1e-12) || !(cell > 0.0) {
                continue;
            }
            // Sample centres sit at p0 + (i + ½)·cell.
            let s = (p[a] - self.p0[a]) / cell - 0.5;
            let next = if dir[a] > 0.0 {
                s.floor() + 1.0
            } else {
                s.ceil() - 1.0
            };
            let d = (next - s) * cell / dir[a];
            if d.is_finite() && d > 0.0 {
                best = best.min(d);
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// n = n0 + g·y.
    struct Linear {
        n0: f64,
        g: f64,
    }
    impl IndexField for Linear {
        fn n(&self, p: DVec3) -> f64 {
            self.n0 + self.g * p.y
        }
        fn grad(&self, _: DVec3) -> DVec3 {
            DVec3::new(0.0, self.g, 0.0)
        }
    }

    /// A step in y of height `jump` over width `w` (tanh profile): n = n_lo + jump (1 − tanh(y / w)) / 2.
    struct Step {
        n_lo: f64,
        jump: f64,
        w: f64,
    }
    impl IndexField for Step {
        fn n(&self, p: DVec3) -> f64 {
            self.n_lo + self.jump * 0.5 * (1.0 - (p.y / self.w).tanh())
        }
        fn grad(&self, p: DVec3) -> DVec3 {
            let c = (p.y / self.w).cosh();
            DVec3::new(0.0, -self.jump * 0.5 / (self.w * c * c), 0.0)
        }
    }

    #[test]
    fn uniform_index_keeps_rays_straight() {
        let f = Linear { n0: 1.3, g: 0.0 };
        let d = DVec3::new(0.3, -0.2, 0.9).normalize();
        let steps = Steps {
            h_max: 1e-3,
            ..Steps::default()
        };
        let e = trace(&f, DVec3::ZERO, d, 1.0, &steps, |_, _, _| {}, |_| false);
        assert_eq!(e.steps, 1000);
        let angle = e.dir.dot(d).clamp(-1.0, 1.0).acos();
        assert!(angle < 1e-6, "angle error {angle} rad");
        assert!((e.x - d).length() < 1e-9, "{}", e.x);
    }

    /// The catenary of n = n0 + g y for a ray starting horizontally at y = 0 (Snell: n cosθ = n0 = c):
    /// x(s) = (c/g) asinh(g s / c), y(s) = (c/g)(√(1 + (g s/c)²) − 1), direction ∝ (1, g s / c).
    fn catenary(n0: f64, g: f64, s: f64) -> (DVec3, DVec3) {
        let u = g * s / n0;
        (
            DVec3::new(
                n0 / g * u.asinh(),
                n0 / g * ((1.0 + u * u).sqrt() - 1.0),
                0.0,
            ),
            DVec3::new(1.0, u, 0.0).normalize(),
        )
    }

    #[test]
    fn a_linear_index_gives_the_catenary_at_fourth_order() {
        let f = Linear { n0: 1.0, g: 0.4 };
        let s_end = 1.5;
        let (want_x, want_d) = catenary(1.0, 0.4, s_end);
        let mut errs = Vec::new();
        for n in [6, 12, 24, 48] {
            // Fixed steps (no doubling: each step is two RK4 half steps).
            let steps = Steps {
                h_max: s_end / n as f64,
                max_turn: 10.0,
                tol: f64::INFINITY,
                ..Steps::default()
            };
            let e = trace(
                &f,
                DVec3::ZERO,
                DVec3::X,
                s_end,
                &steps,
                |_, _, _| {},
                |_| false,
            );
            assert_eq!(e.steps, n);
            let ex = (e.x - want_x).length();
            let ed = (e.dir - want_d).length();
            errs.push((ex, ed));
        }
        let shown: Vec<String> = errs
            .iter()
            .map(|(a, b)| format!("({a:.3e}, {b:.3e})"))
            .collect();
        eprintln!(
            "catenary, 6/12/24/48 steps: (position, direction) errors {}",
            shown.join(" ")
        );
        for w in errs.windows(2) {
            let (rx, rd) = (w[0].0 / w[1].0, w[0].1 / w[1].1);
            // Halving h divides the error by 2⁴ = 16 for a fourth-order method.
            assert!(
                (12.0..22.0).contains(&rx),
                "position error ratio {rx} ({errs:?})"
            );
            assert!(
                (12.0..22.0).contains(&rd),
                "direction error ratio {rd} ({errs:?})"
            );
        }
        assert!(errs[3].0 < 1e-7, "{errs:?}");
    }

    #[test]
    fn a_jump_within_a_voxel_turns_the_ray_back_without_garbage() {
        // n from 1.5 down to 1.0 within ~0.01 (one voxel of a 100-voxel grid; refractionscale-style extremes):
        // a ray at 30° above the horizontal has n cosθ = 1.299 > 1, so it is totally reflected.
        let f = Step {
            n_lo: 1.0,
            jump: 0.5,
            w: 0.005,
        };
        let d = DVec3::new(30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0);
        let x0 = DVec3::new(0.0, -0.5, 0.0);
        let mut y_max = f64::MIN;
        let mut bad = false;
        // h_max is half the "voxel" (the width over which n jumps), as the volume sets it.
        let steps = Steps {
            h_max: 0.005,
            ..Steps::default()
        };
        let e = trace(
            &f,
            x0,
            d,
            2.0,
            &steps,
            |_, b, h| {
                y_max = y_max.max(b.y);
                bad |= !(b.is_finite() && h > 0.0);
            },
            |_| false,
        );
        eprintln!(
            "total internal reflection: {} steps, y_max {y_max:.5}, exit direction {:.6}",
            e.steps, e.dir
        );
        assert!(!bad && e.x.is_finite() && e.dir.is_finite());
        assert!((e.dir.length() - 1.0).abs() < 1e-12);
        assert!(e.dir.y < 0.0, "the ray should come back down: {}", e.dir);
        // It turns where n = n cosθ_0 = 1.299, i.e. inside the step, never reaching the n = 1 side.
        assert!(y_max < 0.01, "y_max {y_max}");
        // Mirror symmetry of total internal reflection: it leaves at -30°, with n cosθ conserved.
        assert!((e.dir.y + 0.5).abs() < 1e-4, "{}", e.dir);
        // The steep part was crossed in short steps, not skipped.
        assert!(e.steps > 100, "{} steps", e.steps);
        // A jump 10⁴ times larger (refractionscale 1e4 on a 1e-2 jump): still finite and unit.
        let f = Step {
            n_lo: 1.0,
            jump: 100.0,
            w: 0.005,
        };
        let e = trace(&f, x0, d, 2.0, &steps, |_, _, _| {}, |_| false);
        assert!(
            e.x.is_finite() && (e.dir.length() - 1.0).abs() < 1e-12,
            "{e:?}"
        );
    }

    fn air(t: f64) -> Air {
        Air {
            temperature_k: t,
            ..Air::STANDARD
        }
    }

    #[test]
    fn the_baked_grid_follows_ciddor_and_its_gradient_is_exact() {
        // 6³ temperatures from 288 K (ambient) to 1800 K along x, varying in y and z too.
        let n = 6;
        let mut t = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    t.push((288.0 + 300.0 * i as f64 + 20.0 * j as f64 + 7.0 * k as f64) as f32);
                }
            }
        }
        let grid = Grid::new([n, n, n], t).unwrap();
        let (p0, p1) = (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 3.0, 2.0));
        let amb = air(288.0);
        let f = IndexGrid::from_temperature(&grid, p0, p1, 550.0, &amb, 1.0);
        // At a voxel centre the index is Ciddor's at that voxel's temperature.
        let centre = |i: usize, j: usize, k: usize| {
            p0 + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) / n as f64 * (p1 - p0)
        };
        let tv = 288.0 + 300.0 * 4.0 + 20.0 * 2.0 + 7.0;
        let want = ciddor::index(550.0, &air(tv));
        let have = f.n(centre(4, 2, 1));
        assert!((have - want).abs() < 1e-9, "{have} vs {want}");
        // Outside, the ambient index; the flame-temperature index is about 288/1500 of (n − 1) at 288 K.
        assert_eq!(f.n(DVec3::new(5.0, 0.0, 0.0)), ciddor::index(550.0, &amb));
        let r = ciddor::refractivity(550.0, &air(1500.0)) / ciddor::refractivity(550.0, &amb);
        assert!((r - 288.0 / 1500.0).abs() < 0.005, "{r}");
        // Analytic gradient vs central differences at points inside.
        let mut rng = crate::rng::Rng::new(4);
        for _ in 0..200 {
            let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let p = p0 + (0.05 + 0.9 * u) * (p1 - p0);
            let h = 1e-6;
            let fd = DVec3::new(
                (f.n(p + DVec3::X * h) - f.n(p - DVec3::X * h)) / (2.0 * h),
                (f.n(p + DVec3::Y * h) - f.n(p - DVec3::Y * h)) / (2.0 * h),
                (f.n(p + DVec3::Z * h) - f.n(p - DVec3::Z * h)) / (2.0 * h),
            );
            let g = f.grad(p);
            // Central differences of n ≈ 1.0003 at h = 1e-6 carry ~1e-10 of rounding.
            assert!((g - fd).length() < 1e-9, "{g} vs {fd} at {p}");
        }
        // Hot air is less dense: n falls along +x.
        assert!(f.grad(centre(3, 3, 3)).x < 0.0);
    }
}
