//! The medium level: a host tracking the fire itself through its majorant grid and point coefficients, at its
//! own wavelengths and times, a scattering fire, and the medium handle's refusals.

use super::*;

#[test]
fn a_host_tracks_the_fire_itself_through_its_majorant_grid_and_point_coefficients() {
    // ABI 0.11, the medium level's first part: what the volume holds (features) and its majorant grid, beside
    // the point coefficients. A host's own ratio tracking — its own DDA over the exported cells, the plugin
    // asked only for σ at its tentative collisions — gives the transmittance the plugin's own march gives.
    let p = plugin();
    let with = |extra: &[Param]| {
        let mut list = fire_params();
        list.extend_from_slice(extra);
        p.create_volume(&list).unwrap()
    };
    use firemedium_loader::{
        FM_FEATURE_EMITS, FM_FEATURE_EMITS_WITHOUT_ABSORPTION, FM_FEATURE_MOTION,
        FM_FEATURE_SCATTERS,
    };
    let v = with(&[]);
    assert_eq!(v.features().unwrap(), FM_FEATURE_EMITS);
    let blur = [
        Param::string("velocitygrid", "velocity"),
        Param::float("velocityscale", 0.05),
        Param::float("shutterclose", 0.5),
    ];
    assert_eq!(
        with(&blur).features().unwrap(),
        FM_FEATURE_EMITS | FM_FEATURE_MOTION
    );
    assert_eq!(
        with(&[Param::float("sigma_s", 1.0)]).features().unwrap(),
        FM_FEATURE_EMITS | FM_FEATURE_SCATTERS
    );
    assert_eq!(
        with(&[Param::string("emissiongrid", "flame")])
            .features()
            .unwrap(),
        FM_FEATURE_EMITS | FM_FEATURE_EMITS_WITHOUT_ABSORPTION
    );
    let grid = v.majorant_grid().unwrap();
    let cells = grid.counts.iter().product::<usize>();
    // With motion blur every cell's bound covers the shutter: at least the still fire's, more somewhere.
    let moving = with(&blur);
    let widened = moving.majorant_grid().unwrap();
    assert_eq!(widened.counts, grid.counts);
    assert!(widened
        .sigma_t
        .iter()
        .zip(grid.sigma_t)
        .all(|(w, s)| w >= s));
    assert!(widened.sigma_t.iter().zip(grid.sigma_t).any(|(w, s)| w > s));
    assert_eq!(grid.sigma_t.len(), cells);
    assert!(grid.sigma_t.iter().any(|&s| s > 0.0) && grid.sigma_t.iter().all(|&s| s >= 0.0));
    // The bound holds at every point, in every channel (2 000 points, the box and a margin around it).
    let c = v.info().channels as usize;
    let mut rng = 1u64;
    let mut u = move || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<[f64; 3]> = (0..2000)
        .map(|_| [0, 1, 2].map(|a| grid.lo[a] - 0.01 + (grid.hi[a] - grid.lo[a] + 0.02) * u()))
        .collect();
    let (mut sa, mut ss, mut j) = (
        vec![0f32; points.len() * c],
        vec![0f32; points.len() * c],
        vec![0f32; points.len() * c],
    );
    v.coefficients(&points, &mut sa, &mut ss, &mut j).unwrap();
    for (i, p) in points.iter().enumerate() {
        let most = (0..c)
            .map(|k| sa[i * c + k] as f64 + ss[i * c + k] as f64)
            .fold(0.0, f64::max);
        assert!(
            most <= grid.at(*p) * (1.0 + 1e-5),
            "{p:?}: σ_t {most} over the bound {}",
            grid.at(*p)
        );
    }
    // Ratio tracking by the host, cell by cell, against the plugin's march, in channel 16: first with the
    // plugin's bins (`coefficients`), then pbrt-v4's and Mitsuba's way, each path at a wavelength of its own
    // drawn across that bin (`point`: the closed forms at λ).
    let k = 16;
    let rs = rays(8);
    let mut plugin_t = vec![0f32; rs.len() * c];
    v.transmittance(&rs, &mut plugin_t).unwrap();
    let info = v.info();
    let width = (info.lambda_max - info.lambda_min) / c as f64;
    for at_wavelengths in [false, true] {
        let n = 400;
        for (r, ray) in rs.iter().enumerate() {
            let mut u = u; // (a copy: both passes draw the same numbers)
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let lambda = info.lambda_min + width * (k as f64 + u());
                let (tr, _) = host_path(&grid, ray, &mut u, &mut |x| {
                    if at_wavelengths {
                        let mut o = [firemedium_loader::Point::default()];
                        v.point(&[x], None, &[lambda], &mut o).unwrap();
                        (o[0].sigma_a + o[0].sigma_s, o[0].j)
                    } else {
                        let (mut a1, mut s1, mut j1) =
                            (vec![0f32; c], vec![0f32; c], vec![0f32; c]);
                        v.coefficients(&[x], &mut a1, &mut s1, &mut j1).unwrap();
                        (a1[k] as f64 + s1[k] as f64, j1[k] as f64)
                    }
                });
                sum += tr;
                sum2 += tr * tr;
            }
            let mean = sum / n as f64;
            let sd = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            let want = plugin_t[r * c + k] as f64;
            assert!(
                (mean - want).abs() <= 4.0 * sd + 2e-3,
                "ray {r} (wavelengths: {at_wavelengths}): the host's ratio tracking {mean} ± {sd}, the plugin's march {want}"
            );
            eprintln!("ray {r} (wavelengths: {at_wavelengths}): host {mean:.5} ± {sd:.5}, plugin {want:.5}");
        }
    }
    // The point query at a time: the blurred fire's lookups move (somewhere along the fan), and at time 0 it is
    // the still fire's.
    let pts: Vec<[f64; 3]> = (0..200)
        .map(|i| {
            [
                0.3 + 1.4 * (i % 20) as f64 / 20.0,
                1.0,
                0.3 + 0.2 * (i / 20) as f64,
            ]
        })
        .collect();
    let lambdas = vec![550.0; pts.len()];
    let query = |vol: &firemedium_loader::Volume, t: f64| {
        let mut o = vec![firemedium_loader::Point::default(); pts.len()];
        vol.point(&pts, Some(&vec![t; pts.len()]), &lambdas, &mut o)
            .unwrap();
        o
    };
    assert_eq!(query(&moving, 0.0), query(&v, 0.0));
    assert_ne!(query(&moving, 0.4), query(&v, 0.0));
    // A layer the closed forms cannot express is refused by name.
    let tinted = with(&[Param {
        name: "tint".into(),
        value: firemedium_loader::Value::Rgb(vec![1.0, 0.5, 0.2]),
        at: None,
    }]);
    let e = tinted
        .point(
            &pts[..1],
            None,
            &lambdas[..1],
            &mut [firemedium_loader::Point::default()],
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("art direction"), "{e}");
}

/// A host's own free-flight sampling along `ray` over a volume's majorant grid (its own DDA, one cell at a
/// time): `collide(x, σ̄)` at each tentative collision, which says whether to go on. Returns whether the ray left
/// the cells (rather than being stopped).
fn walk(
    grid: &firemedium_loader::MajorantGrid,
    ray: &Ray,
    u: &mut impl FnMut() -> f64,
    collide: &mut dyn FnMut([f64; 3], f64) -> bool,
) -> bool {
    let at = |t: f64| [0, 1, 2].map(|a| ray.origin[a] + t * ray.direction[a]);
    let speed = ray.direction.iter().map(|d| d * d).sum::<f64>().sqrt();
    // The ray's part inside the cells' box.
    let (mut t0, mut t1) = (ray.tmin, ray.tmax);
    for a in 0..3 {
        let (lo, hi) = (
            (grid.lo[a] - ray.origin[a]) / ray.direction[a],
            (grid.hi[a] - ray.origin[a]) / ray.direction[a],
        );
        t0 = t0.max(lo.min(hi));
        t1 = t1.min(lo.max(hi));
    }
    let mut t = t0;
    while t < t1 {
        // The cell at t and where the ray leaves it.
        let cell = grid.cell_of(at(t + 1e-9));
        let mut exit = t1;
        for a in 0..3 {
            if ray.direction[a] != 0.0 {
                let side = cell[a] + (ray.direction[a] > 0.0) as usize;
                let te =
                    (grid.lo[a] + side as f64 * grid.cell[a] - ray.origin[a]) / ray.direction[a];
                if te > t {
                    exit = exit.min(te);
                }
            }
        }
        let bound = grid.sigma_t[cell[0] + grid.counts[0] * (cell[1] + grid.counts[1] * cell[2])];
        let step = if bound > 0.0 {
            -(1.0 - u()).ln() / (bound * speed)
        } else {
            f64::INFINITY
        };
        if t + step >= exit {
            t = exit;
            continue;
        }
        t += step;
        if !collide(at(t), bound) {
            return false;
        }
    }
    true
}

/// One path of a host's own ratio tracking along `ray` ([`walk`]): the transmittance, and the emission collected
/// pbrt-v4's way — T·j/σ̄ at each tentative collision — with `sigma(x)` giving (σ_t, j) at a collision.
fn host_path(
    grid: &firemedium_loader::MajorantGrid,
    ray: &Ray,
    u: &mut impl FnMut() -> f64,
    sigma: &mut dyn FnMut([f64; 3]) -> (f64, f64),
) -> (f64, f64) {
    let (mut tr, mut l) = (1.0f64, 0.0f64);
    walk(grid, ray, u, &mut |x, bound| {
        let (sigma_t, j) = sigma(x);
        l += tr * j / bound;
        tr *= 1.0 - sigma_t / bound;
        tr > 0.0
    });
    (tr, l)
}

/// A unit direction uniform on the sphere (the isotropic phase function's sample).
fn isotropic(u: &mut impl FnMut() -> f64) -> [f64; 3] {
    let z = 1.0 - 2.0 * u();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * u();
    [r * phi.cos(), r * phi.sin(), z]
}

#[test]
fn a_host_collects_the_fires_emission_at_its_own_wavelengths_and_times() {
    // The medium level alone renders the fire's expected radiance: a host's ratio tracking at one wavelength per
    // path across bin 16, emission collected at its tentative collisions (T·j/σ̄, pbrt-v4's way), against the
    // plugin's whole-ray march — the still fire, and the motion-blurred one at a time in its shutter (the
    // point query's lookups displaced, the cells' bounds widened over the shutter).
    let p = plugin();
    let blur = [
        Param::string("velocitygrid", "velocity"),
        Param::float("velocityscale", 0.05),
        Param::float("shutterclose", 0.5),
    ];
    let make = |extra: &[Param]| {
        let mut list = fire_params();
        list.extend_from_slice(extra);
        p.create_volume(&list).unwrap()
    };
    let (still, moving) = (make(&[]), make(&blur));
    // The expected radiance from the plugin: its march at a tenth of the default step (0.05 voxels), over 32
    // seeds (one march's random offset on this spiky emission moves a ray's value by tens of per cent).
    let fine = |extra: &[Param]| make(&[extra, &[Param::float("stepsize", 0.05)]].concat());
    let (still_fine, moving_fine) = (fine(&[]), fine(&blur));
    let rs = rays(16);
    let c = still.info().channels as usize;
    let k = 16;
    let info = still.info();
    let width = (info.lambda_max - info.lambda_min) / c as f64;
    let mut rng = 7u64;
    let mut u = move || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for (v, reference, time) in [(&still, &still_fine, 0.0), (&moving, &moving_fine, 0.4)] {
        let grid = v.majorant_grid().unwrap();
        let times = vec![time; rs.len()];
        let mut pl = vec![0f64; rs.len() * c];
        let seeds = 32;
        for s in 0..seeds {
            let rs: Vec<Ray> = rs
                .iter()
                .map(|r| Ray {
                    seed: 100 + s,
                    ..*r
                })
                .collect();
            let mut l = vec![0f32; rs.len() * c];
            reference
                .integrate_at(&rs, Some(&times), &mut l, None, None)
                .unwrap();
            for (a, b) in pl.iter_mut().zip(&l) {
                *a += *b as f64 / seeds as f64;
            }
        }
        let n = 2000;
        let mut seen = 0;
        for (r, ray) in rs.iter().enumerate() {
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let lambda = info.lambda_min + width * (k as f64 + u());
                let (_, l) = host_path(&grid, ray, &mut u, &mut |x| {
                    let mut o = [firemedium_loader::Point::default()];
                    v.point(&[x], Some(&[time]), &[lambda], &mut o).unwrap();
                    (o[0].sigma_a + o[0].sigma_s, o[0].j)
                });
                sum += l;
                sum2 += l * l;
            }
            let mean = sum / n as f64;
            let sd = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            let want = pl[r * c + k];
            eprintln!("time {time}, ray {r}: host {mean:.6e} ± {sd:.2e}, plugin {want:.6e}");
            assert!(
                (mean - want).abs() <= 4.0 * sd + 0.01 * want,
                "time {time}, ray {r}: the host's radiance {mean} ± {sd}, the plugin's march {want}"
            );
            seen += (want > 0.0) as usize;
        }
        assert!(seen >= 4, "the fan crosses the fire: {seen} rays see it");
    }
}

#[test]
fn a_host_tracks_a_scattering_fire_through_the_medium_level_alone() {
    // A scattering fire (σ_s = 8 m⁻¹ per unit density beside soot's σ_a ≈ 8: albedo about ½, isotropic) rendered
    // twice by a host's own volumetric path tracer: once through the medium level alone — delta tracking over the
    // exported majorant grid with the point coefficients at one wavelength per path across bin 16, emission
    // collected pbrt-v4's way (j/σ̄ at every tentative collision), absorption, scattering or a null collision
    // chosen by σ_a/σ̄ and σ_s/σ̄ — and once through the fast path (the plugin's scattering events and their
    // weights, the host sampling the phase function). The same expected radiance along each ray, within the
    // noise of both.
    use firemedium_loader::{Point, Scatter, FM_FEATURE_SCATTERS};
    let p = plugin();
    let mut list = fire_params();
    list.push(Param::float("sigma_s", 8.0));
    let v = p.create_volume(&list).unwrap();
    assert_ne!(v.features().unwrap() & FM_FEATURE_SCATTERS, 0);
    let info = v.info();
    assert_eq!(info.g, 0.0, "isotropic");
    let grid = v.majorant_grid().unwrap();
    let c = info.channels as usize;
    let k = 16;
    let width = (info.lambda_max - info.lambda_min) / c as f64;
    // (One stream, shared by the free flights and the collisions' choices: a copyable closure over a cell.)
    let rng = std::cell::Cell::new(11u64);
    let u = || {
        rng.set(
            rng.get()
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407),
        );
        (rng.get() >> 11) as f64 / (1u64 << 53) as f64
    };
    const DEPTH: usize = 64;
    let (n, rs) = (8000, rays(16));
    let (mut scattered, mut seen) = (0usize, 0);
    for (r, ray) in rs.iter().enumerate() {
        let (mut host, mut fast) = ((0.0, 0.0), (0.0, 0.0));
        for i in 0..n {
            // The medium level alone.
            let lambda = info.lambda_min + width * (k as f64 + u());
            let (mut l, mut path) = (0.0, *ray);
            for _ in 0..DEPTH {
                let mut next = None;
                let escaped = walk(&grid, &path, &mut { u }, &mut |x, bound| {
                    let mut o = [Point::default()];
                    v.point(&[x], None, &[lambda], &mut o).unwrap();
                    l += o[0].j / bound;
                    let xi = u();
                    if xi < o[0].sigma_a / bound {
                        return false;
                    }
                    if xi < (o[0].sigma_a + o[0].sigma_s) / bound {
                        next = Some(x);
                        return false;
                    }
                    true
                });
                match next {
                    Some(x) if !escaped => {
                        scattered += 1;
                        path = Ray {
                            origin: x,
                            direction: isotropic(&mut { u }),
                            tmin: 0.0,
                            tmax: f64::INFINITY,
                            ..path
                        };
                    }
                    _ => break,
                }
            }
            host.0 += l;
            host.1 += l * l;
            // The fast path: the plugin's events, the host's phase function.
            let (mut l, mut beta, mut path) = (0.0, 1.0, *ray);
            for d in 0..DEPTH {
                path.seed = (i * DEPTH + d) as u64 * 977 + r as u64;
                let mut ev = [Scatter::default()];
                let (mut w, mut e) = (vec![0f32; c], vec![0f32; c]);
                v.sample_scatter(std::slice::from_ref(&path), &mut ev, &mut w, Some(&mut e))
                    .unwrap();
                l += beta * e[k] as f64;
                if ev[0].event != firemedium_abi::FM_EVENT_SCATTERED {
                    break;
                }
                beta *= w[k] as f64;
                path = Ray {
                    origin: ev[0].point,
                    direction: isotropic(&mut { u }),
                    tmin: 0.0,
                    tmax: f64::INFINITY,
                    ..path
                };
            }
            fast.0 += l;
            fast.1 += l * l;
        }
        let stats = |(s, s2): (f64, f64)| {
            let m = s / n as f64;
            (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
        };
        let ((hm, hs), (fm, fs)) = (stats(host), stats(fast));
        let sd = (hs * hs + fs * fs).sqrt();
        eprintln!("ray {r}: medium level {hm:.6e} ± {hs:.1e}, fast path {fm:.6e} ± {fs:.1e}");
        assert!(
            (hm - fm).abs() <= 4.0 * sd + 0.01 * fm,
            "ray {r}: through the medium level {hm} ± {hs}, through the fast path {fm} ± {fs}"
        );
        seen += (fm > 0.0) as usize;
    }
    assert!(seen >= 4, "the fan crosses the fire: {seen} rays see it");
    assert!(
        scattered > n,
        "paths scatter in the fire: {scattered} events"
    );
}

#[test]
fn the_medium_handle_carries_what_the_medium_level_can_and_refuses_the_rest() {
    // Volume::medium: the majorants and point coefficients of a plain fire (the same as the volume's own
    // answers), and an error naming the layer for a volume whose layers they cannot carry.
    use firemedium_loader::{Point, FM_FEATURE_EMITS};
    let p = plugin();
    let v = p.create_volume(&fire_params()).unwrap();
    let m = v.medium().unwrap();
    assert_eq!(m.features(), FM_FEATURE_EMITS);
    assert_eq!(m.g(), 0.0);
    let grid = v.majorant_grid().unwrap();
    assert_eq!(m.majorant_grid().sigma_t, grid.sigma_t);
    let x = [1.0, 1.0, 0.6];
    assert_eq!(m.majorant(x), grid.at(x));
    let (mut a, mut b) = ([Point::default(); 2], [Point::default(); 2]);
    m.point(&[x], None, &[450.0, 650.0], &mut a).unwrap();
    v.point(&[x], None, &[450.0, 650.0], &mut b).unwrap();
    assert_eq!(a, b);
    assert!(a[1].sigma_a > 0.0 && a[1].sigma_a <= m.majorant(x));
    for (extra, layer) in [
        (
            Param {
                name: "tint".into(),
                value: Value::Rgb(vec![1.0, 0.5, 0.2]),
                at: None,
            },
            "art direction",
        ),
        (Param::bool("refraction", true), "refraction"),
    ] {
        let mut list = fire_params();
        list.push(extra);
        let e = p
            .create_volume(&list)
            .unwrap()
            .medium()
            .unwrap_err()
            .to_string();
        assert!(e.contains(layer), "{e}");
    }
}
