//! Refraction against closed forms: straight rays in a uniform index, circular orbits in a linear gradient,
//! Snell at a step, and the field baked from temperature.
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

/// n² = a + b y: the ray equation in σ (dσ = ds/n) is d²x/dσ² = ∇(n²/2) = (0, b/2, 0), a parabola
/// x(σ) = x₀ + v₀σ + (b/4) σ² ŷ with v₀ = n₀ t̂₀.
struct Parabolic {
    a: f64,
    b: f64,
}
impl IndexField for Parabolic {
    fn n(&self, p: DVec3) -> f64 {
        (self.a + self.b * p.y).sqrt()
    }
    fn grad(&self, p: DVec3) -> DVec3 {
        DVec3::new(0.0, 0.5 * self.b / self.n(p), 0.0)
    }
}

#[test]
fn the_parabola_of_a_linear_n_squared_at_each_integrators_order() {
    // Parabola: a constant force, which position Verlet integrates exactly at any step.
    let f = Parabolic { a: 1.0, b: 0.6 };
    let d0 = DVec3::new(1.0, 0.2, 0.0).normalize();
    for n in [3, 10, 40] {
        let steps = Steps {
            max_turn: 10.0,
            ..Steps::default()
        };
        let e = trace_verlet(
            &f,
            DVec3::ZERO,
            d0,
            1.0,
            1.0 / n as f64,
            1.0 / n as f64,
            &steps,
            |_, _| {},
            |_| false,
        );
        // Where the analytic parabola passes through the same x: σ = x / v₀ₓ.
        let sig = e.x.x / d0.x;
        let want_y = d0.y * sig + 0.25 * f.b * sig * sig;
        let want_d = DVec3::new(d0.x, d0.y + 0.5 * f.b * sig, 0.0).normalize();
        assert!(
            (e.x.y - want_y).abs() < 1e-12,
            "{n} steps: y {} vs {want_y}",
            e.x.y
        );
        assert!(
            (e.dir - want_d).length() < 1e-12,
            "{n} steps: {} vs {want_d}",
            e.dir
        );
    }
    // RK4 (in arc length, so the parabola is not its natural variable) on the same path: fourth order.
    let mut errs = Vec::new();
    for n in [5, 10, 20, 40] {
        let steps = Steps {
            h_max: 1.2 / n as f64,
            max_turn: 10.0,
            tol: f64::INFINITY,
            ..Steps::default()
        };
        let e = trace(&f, DVec3::ZERO, d0, 1.2, &steps, |_, _, _| {}, |_| false);
        let sig = e.x.x / d0.x;
        let want_y = d0.y * sig + 0.25 * f.b * sig * sig;
        let want_d = DVec3::new(d0.x, d0.y + 0.5 * f.b * sig, 0.0).normalize();
        errs.push(((e.x.y - want_y).abs(), (e.dir - want_d).length()));
    }
    eprintln!("rk4 parabola, 5/10/20/40 steps: (y, direction) errors {errs:?}");
    for w in errs.windows(2) {
        let (ry, rd) = (w[0].0 / w[1].0, w[0].1 / w[1].1);
        assert!((10.0..24.0).contains(&ry), "y error ratio {ry} ({errs:?})");
        assert!(
            (10.0..24.0).contains(&rd),
            "direction error ratio {rd} ({errs:?})"
        );
    }
    // Catenary (n linear, force ∝ n varies along the path): error ÷4 per halving of the step.
    let f = Linear { n0: 1.0, g: 0.4 };
    let mut errs = Vec::new();
    for n in [12, 24, 48, 96] {
        let steps = Steps {
            max_turn: 10.0,
            ..Steps::default()
        };
        let h = 1.5 / n as f64;
        let e = trace_verlet(
            &f,
            DVec3::ZERO,
            DVec3::X,
            1.5,
            h,
            h,
            &steps,
            |_, _| {},
            |_| false,
        );
        assert_eq!(e.steps, n);
        // Compare at the arc length travelled (the step's arc length is its chord, to second order).
        let (want_x, want_d) = catenary(1.0, 0.4, e.s);
        errs.push(((e.x - want_x).length(), (e.dir - want_d).length()));
    }
    eprintln!("verlet catenary, 12/24/48/96 steps: (position, direction) errors {errs:?}");
    for w in errs.windows(2) {
        let (rx, rd) = (w[0].0 / w[1].0, w[0].1 / w[1].1);
        assert!(
            (3.0..5.5).contains(&rx),
            "position error ratio {rx} ({errs:?})"
        );
        assert!(
            (3.0..5.5).contains(&rd),
            "direction error ratio {rd} ({errs:?})"
        );
    }
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
fn the_baked_grid_follows_ciddor_and_is_continuous() {
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
    let f = IndexGrid::from_temperature(&grid, p0, p1, 550.0, &amb, 1.0, u64::MAX).unwrap();
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
    // n is continuous across the planes of samples and falls to ambient at the padded box's faces.
    let x = p0.x + 3.0 * (p1.x - p0.x) / n as f64;
    let q = |x: f64| DVec3::new(x, 1.3, 0.7);
    assert!((f.n(q(x + 1e-9)) - f.n(q(x - 1e-9))).abs() < 1e-12);
    let [b0, _] = f.bounds();
    assert_eq!(f.n(DVec3::new(b0.x + 1e-9, 1.3, 0.7)), f.ambient());
    // Hot air is less dense: n falls along +x.
    assert!(f.grad(centre(3, 3, 3)).x < 0.0);
}

#[test]
fn the_index_gradient_converges_at_second_order() {
    // A Gaussian hot blob baked at 12³, 24³, 48³ voxels: the interpolated central differences of n²/2 over n
    // approach ∇n of the continuous field (Ciddor of the analytic temperature) as the voxel².
    let amb = air(293.15);
    let temp =
        |p: DVec3| 293.15 + 1500.0 * (-(p - DVec3::splat(0.5)).length_squared() / 0.04).exp();
    let n_true = |p: DVec3| ciddor::index(550.0, &air(temp(p)));
    let mut rng = crate::rng::Rng::new(9);
    let points: Vec<DVec3> = (0..100)
        .map(|_| {
            DVec3::new(0.3, 0.3, 0.3)
                + 0.4 * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64())
        })
        .collect();
    let mut errs = Vec::new();
    for res in [12usize, 24, 48] {
        let mut t = Vec::with_capacity(res * res * res);
        for k in 0..res {
            for j in 0..res {
                for i in 0..res {
                    let c = (DVec3::new(i as f64, j as f64, k as f64) + 0.5) / res as f64;
                    t.push(temp(c) as f32);
                }
            }
        }
        let grid = Grid::new([res, res, res], t).unwrap();
        let f =
            IndexGrid::from_temperature(&grid, DVec3::ZERO, DVec3::ONE, 550.0, &amb, 1.0, u64::MAX)
                .unwrap();
        let mut worst = 0.0f64;
        let mut scale = 0.0f64;
        for &p in &points {
            let h = 1e-4;
            let want = DVec3::new(
                n_true(p + DVec3::X * h) - n_true(p - DVec3::X * h),
                n_true(p + DVec3::Y * h) - n_true(p - DVec3::Y * h),
                n_true(p + DVec3::Z * h) - n_true(p - DVec3::Z * h),
            ) / (2.0 * h);
            worst = worst.max((f.grad(p) - want).length());
            scale = scale.max(want.length());
        }
        errs.push(worst / scale);
    }
    eprintln!("∇n relative error at 12³, 24³, 48³: {errs:?}");
    for w in errs.windows(2) {
        assert!(w[0] / w[1] > 3.0, "{errs:?}");
    }
    assert!(errs[2] < 0.015, "{errs:?}");
}

#[test]
fn the_brick_layout_holds_the_dense_fields_values() {
    // Hot voxels in a few random bricks of a sparse 120 × 60 × 150 grid (sample 0 anywhere in its brick), the
    // rest 0 K (no data): at random points — in the copies, between them and on the padded box's faces — the
    // index and force of the copies equal the dense array's to the bit, with a fraction of the memory.
    let mut rng = crate::rng::Rng::new(3);
    for case in 0..4 {
        let dims: [usize; 3] = [120, 60, 150];
        let off = [case % 8, (3 * case) % 8, (5 * case) % 8];
        let nb = [0, 1, 2].map(|a| (dims[a] + off[a]).div_ceil(8));
        let keep: Vec<bool> = (0..nb[0] * nb[1] * nb[2])
            .map(|_| rng.next_f64() < 0.01)
            .collect();
        let topo = std::sync::Arc::new(
            crate::grid::Topology::build_offset(dims, off, |b| {
                keep[b[0] + nb[0] * (b[1] + nb[1] * b[2])]
            })
            .unwrap(),
        );
        let t: Vec<f32> = (0..dims[0] * dims[1] * dims[2])
            .map(|_| 300.0 + 1500.0 * rng.next_f64() as f32)
            .collect();
        let grid = Grid::from_dense(topo, &t, 0.0).unwrap();
        let amb = air(288.0);
        let (p0, p1) = (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 1.5, 3.0));
        let build = |dense| {
            IndexGrid::build(&grid, [p0, p1], 550.0, &amb, 50.0, u64::MAX, Some(dense)).unwrap()
        };
        let (d, b) = (build(true), build(false));
        assert!(b.topo.is_some() && d.topo.is_none());
        assert!(
            b.bytes() * 2 < d.bytes(),
            "{} vs {} bytes",
            b.bytes(),
            d.bytes()
        );
        let [c0, c1] = d.bounds();
        let (mut bent, mut checked) = (0, 0);
        for i in 0..40_000 {
            let u = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let mut p = c0 + (u * 1.1 - DVec3::splat(0.05)) * (c1 - c0);
            if i % 5 == 0 {
                p.x = if i % 2 == 0 { c0.x } else { c1.x };
            }
            let (nd, fd) = d.n_force(p);
            assert_eq!((nd, fd), b.n_force(p), "case {case} at {p}");
            bent += (fd != DVec3::ZERO) as usize;
            checked += 1;
        }
        assert!(
            bent > 200 && checked == 40_000,
            "{bent} points in a gradient"
        );
    }
}
