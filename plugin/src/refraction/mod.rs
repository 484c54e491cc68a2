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
//! samples and cost the Verlet march 10 % of the deflection (docs/results/log.md). Voxels colder than `T_amb` (0 K
//! where a simulation holds no data) count as ambient air. `scale` is the paper's Figure 2 exaggeration of
//! (n − 1).

use crate::ciddor::{self, Air};
use crate::grid::{Grid, Topology, BRICK};
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
    /// δ and its central-difference gradient (per medium unit) at the padded grid's samples, x fastest, in one
    /// of two layouts: a dense array over the cells' lower corners shifted by one (w = c + 1 ∈ [0, dims + 1]),
    /// or a `COPY` per brick of cells (copy 0: zeros, what cells in no copy read).
    data: Vec<Vec4>,
    /// The copies' table, for the brick layout.
    topo: Option<Topology>,
    /// Strides of `data` along y and z (a copy's, or the dense array's).
    sy: usize,
    sz: usize,
    /// The padded grid's dims (the temperature grid's + 2·PAD).
    dims: [usize; 3],
    p0: DVec3,
    size: DVec3,
    n_amb: f64,
}

/// Rings of ambient voxels around the baked grid: δ falls to 0 over the first, the gradient over the second.
const PAD: usize = 2;
/// Samples per side of a copy: a brick's 8 cells need 9.
const SIDE: usize = BRICK + 1;
/// Samples of a copy.
const COPY: usize = SIDE * SIDE * SIDE;

impl IndexGrid {
    /// Bakes δ per voxel from `temperature` (K) over the box `p0..p1`, at vacuum wavelength `lambda_nm`, for
    /// `air` (its temperature is the ambient one), with (n − 1) exaggerated by `scale`.
    ///
    /// Stored as the march lattice is (`volume::lattice`): dense over the padded box, or — when that is larger
    /// — a 9³ copy per brick of cells where δ or the force differs from zero (around the voxels hotter than
    /// ambient), zero elsewhere, so a sparse fire's field follows its hot voxels, not its box. Both layouts
    /// hold the same values and are read by the same lerps. `Err` with the bytes it would need when they
    /// exceed `budget` (or the allocator refuses them).
    pub fn from_temperature(
        temperature: &Grid,
        p0: DVec3,
        p1: DVec3,
        lambda_nm: f64,
        air: &Air,
        scale: f64,
        budget: u64,
    ) -> Result<IndexGrid, u64> {
        IndexGrid::build(temperature, [p0, p1], lambda_nm, air, scale, budget, None)
    }

    /// [`IndexGrid::from_temperature`], `dense` choosing the layout (`None`: the smaller).
    fn build(
        temperature: &Grid,
        [p0, p1]: [DVec3; 2],
        lambda_nm: f64,
        air: &Air,
        scale: f64,
        budget: u64,
        dense: Option<bool>,
    ) -> Result<IndexGrid, u64> {
        let n = temperature.dims();
        let voxel = (p1 - p0) / DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        let amb = ciddor::refractivity(lambda_nm, air);
        let mut memo: std::collections::HashMap<i64, f64> = std::collections::HashMap::new();
        // δ of every stored temperature (0 at or below ambient: a simulation's empty voxels hold 0 K).
        let mut delta_of = |t: f32| -> f32 {
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
        };
        let vec4s = |count: u64| count.saturating_mul(16);
        let delta = temperature
            .map(&mut delta_of)
            .ok_or(temperature.bytes() as u64)?;
        let dims = [0, 1, 2].map(|a| n[a] + 2 * PAD);
        // The copies: those whose samples (padded P ∈ [8b − 1, 8b + 7]) come within one voxel of a stored
        // brick with δ ≠ 0 (P = data + PAD, and the gradient reaches one voxel further); every copy when the
        // background itself is hot.
        let data_topo = delta.topology();
        let wdims = dims.map(|d| d + 1);
        let topo = if delta.background() != 0.0 {
            Topology::full(wdims)
        } else {
            // (At most 27 copies per stored brick, each listed once per brick it borders.)
            let mut list = Vec::new();
            list.try_reserve(data_topo.active_bricks().saturating_mul(27))
                .map_err(|_| u64::MAX)?;
            data_topo.for_each_slot(|b, s| {
                if delta.slot_is(s, 0.0) {
                    return;
                }
                let mut range = [(0usize, 0usize); 3];
                for a in 0..3 {
                    // P from lo + PAD − 1 to hi − 1 + PAD + 1; copies b with 8b − 1 ≤ the end, 8b + 7 ≥ the start.
                    let (lo, hi) = data_topo.brick_span(b[a], a);
                    range[a] = ((lo + PAD - 1) / BRICK, (hi + PAD + 1) / BRICK);
                }
                for z in range[2].0..=range[2].1 {
                    for y in range[1].0..=range[1].1 {
                        for x in range[0].0..=range[0].1 {
                            list.push([x, y, z]);
                        }
                    }
                }
            });
            Topology::from_bricks(wdims, [0; 3], list)
        }
        .ok_or(u64::MAX)?;
        // The dense array over w ∈ [0, dims + 1] (a ring of zeros below and above the padded grid), unless the
        // copies take less.
        let dense_len = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d + 2));
        let copies = topo.active_bricks() + 1;
        let brick_len = copies.checked_mul(COPY);
        let (len, topo) = match (dense_len, brick_len) {
            (Some(d), Some(b)) if dense.unwrap_or(d <= b) => (d, None),
            (_, Some(b)) => (b, Some(topo)),
            (Some(d), None) => (d, None),
            (None, None) => return Err(u64::MAX),
        };
        let bytes = vec4s(len as u64).saturating_add(topo.as_ref().map_or(0, |t| t.bytes() as u64));
        if bytes > budget {
            return Err(bytes);
        }
        let mut data = crate::alloc::filled(len, Vec4::ZERO).ok_or(bytes)?;
        // The force of the ray equation, ∇(n²/2), by central differences of φ = n²/2 − n_amb²/2 = n_amb δ + δ²/2:
        // interpolated, its integral along an axis telescopes to the change of φ, so a ray leaves a region of
        // parallel layers in the direction it entered (Snell's invariant), as with the exact gradient.
        let n_amb = 1.0 + scale * amb;
        // Fills `out` (x fastest) with the samples w ∈ [lo, lo + side) (P = w − 1).
        let fill = |lo: [usize; 3], side: [usize; 3], out: &mut [Vec4]| {
            // δ over them and one more on each side: P from lo − 2 (data P − PAD).
            let e = side.map(|s| s + 2);
            let mut d = vec![0f32; e[0] * e[1] * e[2]];
            let base = lo.map(|v| v as i64 - 2 - PAD as i64);
            for z in 0..e[2] {
                for y in 0..e[1] {
                    for x in 0..e[0] {
                        d[x + e[0] * (y + e[1] * z)] =
                            delta.at(base[0] + x as i64, base[1] + y as i64, base[2] + z as i64);
                    }
                }
            }
            let phi = |i: usize| {
                let v = d[i] as f64;
                n_amb * v + 0.5 * v * v
            };
            let step = [1, e[0], e[0] * e[1]];
            for z in 0..side[2] {
                for y in 0..side[1] {
                    for x in 0..side[0] {
                        // Samples off the padded grid stay zero (as its outside reads).
                        let w = [lo[0] + x, lo[1] + y, lo[2] + z];
                        if (0..3).any(|a| w[a] == 0 || w[a] > dims[a]) {
                            continue;
                        }
                        let i = (x + 1) + e[0] * ((y + 1) + e[1] * (z + 1));
                        let g = |a: usize| {
                            ((phi(i + step[a]) - phi(i - step[a])) / (2.0 * voxel[a])) as f32
                        };
                        out[x + side[0] * (y + side[1] * z)] = Vec4::new(d[i], g(0), g(1), g(2));
                    }
                }
            }
        };
        let threads = crate::par::threads(8);
        let (sy, sz) = match &topo {
            Some(topo) => {
                let mut of = crate::alloc::filled(copies, [0usize; 3]).ok_or(bytes)?;
                topo.for_each_slot(|b, s| of[s] = b);
                let per = (copies - 1).div_ceil(threads).max(1);
                crate::par::scope(|s| {
                    for (k, chunk) in data[COPY..].chunks_mut(COPY * per).enumerate() {
                        let (of, fill) = (&of, &fill);
                        s.spawn(move || {
                            for (c, out) in chunk.chunks_exact_mut(COPY).enumerate() {
                                fill(of[1 + k * per + c].map(|v| BRICK * v), [SIDE; 3], out);
                            }
                        });
                    }
                });
                (SIDE, SIDE * SIDE)
            }
            None => {
                // z-slabs of the dense array over the threads.
                let side = dims.map(|d| d + 2);
                let slab = side[0] * side[1];
                let per = side[2].div_ceil(threads).max(1);
                crate::par::scope(|s| {
                    for (k, chunk) in data.chunks_mut(slab * per).enumerate() {
                        let fill = &fill;
                        s.spawn(move || {
                            let h = chunk.len() / slab;
                            fill([0, 0, k * per], [side[0], side[1], h], chunk);
                        });
                    }
                });
                (side[0], slab)
            }
        };
        let pad = voxel * PAD as f64;
        Ok(IndexGrid {
            data,
            topo,
            sy,
            sz,
            dims,
            p0: p0 - pad,
            size: p1 - p0 + 2.0 * pad,
            n_amb,
        })
    }

    /// The ambient index (outside the volume).
    pub fn ambient(&self) -> f64 {
        self.n_amb
    }
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.data.len() * std::mem::size_of::<Vec4>()
            + self.topo.as_ref().map_or(0, Topology::bytes)
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
        // The cell's lower corner c ∈ [−1, d − 1] (u ∈ [0, 1]); its copy from w = c + 1, zeros when it has none.
        let w = [fl.x + 1.0, fl.y + 1.0, fl.z + 1.0].map(|c| c as usize);
        let (sy, sz) = (self.sy, self.sz);
        let o = match &self.topo {
            Some(t) => {
                t.slot(w.map(|c| c / BRICK)) * COPY
                    + (w[0] % BRICK)
                    + SIDE * ((w[1] % BRICK) + SIDE * (w[2] % BRICK))
            }
            None => w[0] + sy * w[1] + sz * w[2],
        };
        let r = |o: usize| match self.data.get(o..o + 2) {
            Some(&[a, b]) => (a, b),
            _ => (Vec4::ZERO, Vec4::ZERO),
        };
        let corners = [r(o), r(o + sy), r(o + sz), r(o + sy + sz)];
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

#[cfg(test)]
mod tests;
