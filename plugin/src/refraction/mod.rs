//! Refraction of hot air (Pegoraro & Parker 2006 §3.7): an index-of-refraction field baked from the temperature
//! field with Ciddor's formula, and curved rays through it by the ray equation of Stam & Languénou (1996),
//!
//! ```text
//!     d/ds (n dx/ds) = ∇n,
//! ```
//!
//! Two integrators:
//!
//! - [`trace_verlet`], the fire volume's default: one step per march step, position Störmer–Verlet in the
//!   parameter σ with dσ = ds / n, where the equation reads d²x/dσ² = ∇(n²/2) — a separable Hamiltonian system,
//!   so the scheme is symplectic and second order, exact for a constant ∇(n²) (the parabola). Its single force
//!   lookup is at the step's midpoint, where the march samples the medium: a curved ray costs one index lookup
//!   per sample more than a straight one.
//! - [`trace`], the accurate reference: in arc length s for x and the optical direction v = n dx/ds
//!   (dx/ds = v / n, dv/ds = ∇n), classical RK4 rescaled to |v| = n after each step, each step checked against two
//!   half steps and halved until they agree within `tol` (step doubling), and ending just past the next plane of
//!   grid samples. `refractionintegrator "rk4"` selects it.
//!
//! Both limit the turn per step to `max_turn` radians (relative change of v, for Verlet), so a steep gradient —
//! the index jumping within one voxel — is crossed in small steps, and total internal reflection comes out as the
//! ray turning back smoothly rather than as a jump.
//!
//! ## The baked field
//! [`IndexGrid`] stores per voxel δ = scale · ((n(T) − 1) − (n(T_amb) − 1)) and the force ∇(n²/2) by central
//! differences of n²/2 (as the paper takes ∇n by central differences), four f32 (|δ| ≤ 3e-4 · scale, f32 keeps
//! 7 digits of it), padded by two rings of ambient voxels, and interpolates all four trilinearly (zero outside):
//! n = n_amb + δ is continuous everywhere and ambient outside the padded box, and the force is continuous too and
//! zero beyond 1.5 voxels outside the grid, so entering and leaving bend the ray smoothly. The interpolated force
//! converges to the continuous field's at second order in the voxel size, and its integral along an axis
//! telescopes to the change of n²/2, so a ray leaves a slab of parallel layers in the direction it entered
//! (Snell's invariant) — the analytic gradient of the trilinear n, tried first, is discontinuous at every plane of
//! samples and cost the Verlet march 10 % of the deflection (docs/RESULTS.md). Voxels colder than `T_amb` (0 K
//! where a simulation holds no data) count as ambient air. `scale` is the paper's Figure 2 exaggeration of
//! (n − 1).

use crate::ciddor::{self, Air};
use crate::grid::Grid;
use glam::{DVec3, Vec4};

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
    /// n and the force of the ray equation in σ, n∇n = ∇(n²/2), at `p`.
    fn n_force(&self, p: DVec3) -> (f64, DVec3) {
        let (n, g) = self.n_grad(p);
        (n, n * g)
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

/// The initial state (x, v = n t̂) of a ray from `x0` along `dir` (any length; a zero or non-finite direction
/// becomes +x).
fn start(f: &impl IndexField, x0: DVec3, dir: DVec3) -> (DVec3, DVec3) {
    let t = dir.normalize_or_zero();
    let t = if t == DVec3::ZERO || !t.is_finite() {
        DVec3::X
    } else {
        t
    };
    (x0, t * index_at(f, x0))
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
    let (mut x, mut v) = start(f, x0, dir);
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

/// One step of the fire volume's curved march: position Störmer–Verlet for the ray equation in the parameter σ
/// with dσ = ds / n, where it reads d²x/dσ² = ∇(n²/2) — a separable Hamiltonian system (H = |v|²/2 − n²/2,
/// v = dx/dσ = n t̂), so the scheme is symplectic and second order, and a constant ∇(n²) (n² linear: the parabola)
/// is integrated exactly. From (x, v) a half step along t̂ reaches the midpoint m, where n and ∇n are looked up
/// once (and where the march evaluates the medium); then v₁ = v + dσ n∇n(m) and x₁ = m + (dσ/2) v₁, with
/// dσ = h / |v| for an arc length h. |v| stays n(x) up to the scheme's bounded energy error. A step whose
/// velocity would change by more than `max_turn` relative (a turn, or a steep jump along the ray) is halved
/// down to `h_min`, so total internal reflection turns the ray back over several short steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerletStep {
    /// The midpoint (the medium's sample point).
    pub mid: DVec3,
    /// New position.
    pub x: DVec3,
    /// New optical velocity (|v| ≈ n).
    pub v: DVec3,
    /// Arc length taken: the polyline x → mid → x₁ (`asked` to first order).
    pub h: f64,
    /// The step length asked for, after halving (twice the distance to the midpoint).
    pub asked: f64,
}

/// See [`VerletStep`]: one step of arc length up to `h` from (x, v), v ≠ 0.
pub fn verlet_step(f: &impl IndexField, x: DVec3, v: DVec3, h: f64, steps: &Steps) -> VerletStep {
    let speed = v.length();
    let (speed, t) = if speed > 0.0 && speed.is_finite() {
        (speed, v / speed)
    } else {
        (1.0, DVec3::X)
    };
    let mut h = h;
    loop {
        let mid = x + t * (0.5 * h);
        let (_, force) = f.n_force(mid);
        let force = if force.is_finite() {
            force
        } else {
            DVec3::ZERO
        };
        let dsig = h / speed;
        let dv = force * dsig;
        if dv.length() > steps.max_turn * speed && h > steps.h_min {
            h = (0.5 * h).max(steps.h_min);
            continue;
        }
        let mut v1 = t * speed + dv;
        if !(v1.length() > 1e-9 * speed) {
            // Stopped dead at h_min inside a discontinuity: keep the old direction.
            v1 = t * speed;
        }
        // The arc length taken: the two halves of the step (the second is |v₁|/|v| of the first).
        return VerletStep {
            mid,
            x: mid + v1 * (0.5 * dsig),
            v: v1,
            h: 0.5 * h + 0.5 * dsig * v1.length(),
            asked: h,
        };
    }
}

/// Marches a curved ray from `x0` along `dir` for arc length `s_max` in [`verlet_step`]s of arc length `h`,
/// the first one `first` long (a jittered start, as the straight march), calling `visit(mid, h)` per step;
/// stops early when `stop` says the point left the region of interest.
#[allow(clippy::too_many_arguments)]
pub fn trace_verlet(
    f: &impl IndexField,
    x0: DVec3,
    dir: DVec3,
    s_max: f64,
    h: f64,
    first: f64,
    steps: &Steps,
    mut visit: impl FnMut(DVec3, f64),
    mut stop: impl FnMut(DVec3) -> bool,
) -> Exit {
    let (mut x, mut v) = start(f, x0, dir);
    let s_max = if s_max.is_nan() { 0.0 } else { s_max.max(0.0) };
    let h = if h > 0.0 && h.is_finite() { h } else { s_max };
    // s: arc length travelled; u: the same counted in the lengths asked for, which sets the step boundaries (so
    // the first-order difference between the two never leaves slivers of steps).
    let (mut s, mut u) = (0.0, 0.0);
    let mut next = if first > 0.0 && first <= h { first } else { h };
    let mut n_steps = 0;
    while s < s_max && n_steps < steps.max_steps {
        let want = (next - u).min(s_max - s).max(steps.h_min.min(s_max - s));
        let st = verlet_step(f, x, v, want, steps);
        visit(st.mid, st.h);
        x = st.x;
        v = st.v;
        s += st.h;
        u += st.asked;
        n_steps += 1;
        while next <= u * (1.0 + 1e-12) {
            next += h;
        }
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
    /// Per padded voxel: δ and its central-difference gradient (per medium unit), x fastest.
    data: Vec<Vec4>,
    dims: [usize; 3],
    p0: DVec3,
    size: DVec3,
    n_amb: f64,
}

/// Rings of ambient voxels around the baked grid: δ falls to 0 over the first, the gradient over the second.
const PAD: usize = 2;

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
        let [nx, ny, nz] = temperature.dims();
        let voxel = (p1 - p0) / DVec3::new(nx as f64, ny as f64, nz as f64);
        let amb = ciddor::refractivity(lambda_nm, air);
        let mut memo: std::collections::HashMap<i64, f64> = std::collections::HashMap::new();
        let dims = [nx + 2 * PAD, ny + 2 * PAD, nz + 2 * PAD];
        let mut delta = vec![0f32; dims[0] * dims[1] * dims[2]];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let t = temperature.at(i as i64, j as i64, k as i64) as f64;
                    if !(t > air.temperature_k) {
                        continue;
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
                    delta[i + PAD + dims[0] * (j + PAD + dims[1] * (k + PAD))] =
                        (scale * (r - amb)) as f32;
                }
            }
        }
        let at = |i: usize, j: usize, k: usize, a: usize, o: i64| -> f32 {
            let mut c = [i as i64, j as i64, k as i64];
            c[a] += o;
            if c.iter().zip(dims).any(|(&c, d)| c < 0 || c >= d as i64) {
                return 0.0;
            }
            delta[c[0] as usize + dims[0] * (c[1] as usize + dims[1] * c[2] as usize)]
        };
        // The force of the ray equation, ∇(n²/2), by central differences of φ = n²/2 − n_amb²/2 = n_amb δ + δ²/2:
        // interpolated, its integral along an axis telescopes to the change of φ, so a ray leaves a region of
        // parallel layers in the direction it entered (Snell's invariant), as with the exact gradient.
        let n_amb = 1.0 + scale * amb;
        let phi = |i: usize, j: usize, k: usize, a: usize, o: i64| -> f64 {
            let d = at(i, j, k, a, o) as f64;
            n_amb * d + 0.5 * d * d
        };
        let mut data = Vec::with_capacity(delta.len());
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let g = |a: usize| {
                        ((phi(i, j, k, a, 1) - phi(i, j, k, a, -1)) / (2.0 * voxel[a])) as f32
                    };
                    data.push(Vec4::new(at(i, j, k, 0, 0), g(0), g(1), g(2)));
                }
            }
        }
        let pad = voxel * PAD as f64;
        IndexGrid {
            data,
            dims,
            p0: p0 - pad,
            size: p1 - p0 + 2.0 * pad,
            n_amb,
        }
    }

    /// The ambient index (outside the volume).
    pub fn ambient(&self) -> f64 {
        self.n_amb
    }
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.data.len() * std::mem::size_of::<Vec4>()
    }
    /// The box where n differs from ambient: the grid's, two voxels wider on every side.
    pub fn bounds(&self) -> [DVec3; 2] {
        [self.p0, self.p0 + self.size]
    }

    /// Trilinear δ and force ∇(n²/2) (per medium unit) at `p`, zero outside.
    fn eval(&self, p: DVec3) -> (f64, DVec3) {
        let u = (p - self.p0) / self.size;
        if !(u.cmpge(DVec3::ZERO).all() && u.cmple(DVec3::ONE).all()) {
            return (0.0, DVec3::ZERO);
        }
        let d = self.dims;
        let s = u * DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64) - 0.5;
        let fl = DVec3::new(
            crate::grid::floor(s.x),
            crate::grid::floor(s.y),
            crate::grid::floor(s.z),
        );
        let f = (s - fl).as_vec3();
        let [i, j, k] = [fl.x as i64, fl.y as i64, fl.z as i64];
        // The padding keeps every lookup inside the fire's box off the array's edges; only the outer half of the
        // last ring reads past them (as zeros).
        let corners = if i >= 0
            && j >= 0
            && k >= 0
            && i + 1 < d[0] as i64
            && j + 1 < d[1] as i64
            && k + 1 < d[2] as i64
        {
            // All eight inside (everywhere but the outer half of the last ring): two rows of two pairs.
            let o = i as usize + d[0] * (j as usize + d[1] * k as usize);
            let (sy, sz) = (d[0], d[0] * d[1]);
            let r = |o: usize| (self.data[o], self.data[o + 1]);
            [r(o), r(o + sy), r(o + sz), r(o + sy + sz)]
        } else {
            let c = |di: i64, dj: i64, dk: i64| -> Vec4 {
                let (a, b, cc) = (i + di, j + dj, k + dk);
                if a < 0
                    || b < 0
                    || cc < 0
                    || a >= d[0] as i64
                    || b >= d[1] as i64
                    || cc >= d[2] as i64
                {
                    return Vec4::ZERO;
                }
                self.data[a as usize + d[0] * (b as usize + d[1] * cc as usize)]
            };
            [
                (c(0, 0, 0), c(1, 0, 0)),
                (c(0, 1, 0), c(1, 1, 0)),
                (c(0, 0, 1), c(1, 0, 1)),
                (c(0, 1, 1), c(1, 1, 1)),
            ]
        };
        let [x00, x10, x01, x11] = corners.map(|(a, b)| a.lerp(b, f.x));
        let v = x00.lerp(x10, f.y).lerp(x01.lerp(x11, f.y), f.z);
        (v.x as f64, DVec3::new(v.y as f64, v.z as f64, v.w as f64))
    }
}

impl IndexField for IndexGrid {
    fn n(&self, p: DVec3) -> f64 {
        self.n_amb + self.eval(p).0
    }
    fn grad(&self, p: DVec3) -> DVec3 {
        self.n_grad(p).1
    }
    /// n, and ∇n as the interpolated force over n (so n ∇n, what both integrators use, is the force itself).
    fn n_grad(&self, p: DVec3) -> (f64, DVec3) {
        let (d, force) = self.eval(p);
        let n = self.n_amb + d;
        (n, force / n)
    }
    fn n_force(&self, p: DVec3) -> (f64, DVec3) {
        let (d, force) = self.eval(p);
        (self.n_amb + d, force)
    }
    fn next_kink(&self, p: DVec3, dir: DVec3) -> f64 {
        let dims = self.dims;
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

pub(crate) mod march;

#[cfg(test)]
mod tests;
