//! Embers against closed forms: the particle files, a grey sphere's radiance (Planck bin means computed here),
//! cooling (the T_a → 0 closed form), opacity, motion, and the fire light's mixture (its directional pdf
//! integrates to 1, sample and pdf agree, and its estimate of a sphere's radiance over its solid angle is the
//! closed form L·2π(1 − cos α)).

use crate::blackbody::spectral_radiance;
use crate::dataset::particles::{parse, Particle};
use crate::light::{FireLight, Weighting};
use crate::params::Param;
use crate::volume::tests::slab_volume;
use crate::volume::{FireVolume, Ray};
use crate::Error;
use glam::DVec3;
use std::sync::Arc;

/// A file holding `bytes`, removed when dropped.
struct TempFile(std::path::PathBuf);

impl TempFile {
    fn new(name: &str, bytes: &[u8]) -> TempFile {
        let p =
            std::env::temp_dir().join(format!("firemedium-embers-{}-{name}", std::process::id()));
        std::fs::write(&p, bytes).unwrap();
        TempFile(p)
    }
    fn path(&self) -> String {
        self.0.to_string_lossy().into_owned()
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

const CSV: &str =
    "# two embers\nP[x], P[y], P[z], pscale, temperature, v[x], v[y], v[z], age, id\n\
0.5, 0.5, 0.5, 0.01, 1200, 0, 0, 2.4, 0, 7\n0.25, 0.75, 0.5, 0.002, 900.5, 1, -1, 0, 0.5, 8\n";

fn two() -> Vec<Particle> {
    vec![
        Particle {
            p: DVec3::splat(0.5),
            v: DVec3::new(0.0, 0.0, 2.4),
            r: 0.01,
            t: 1200.0,
            age: 0.0,
        },
        Particle {
            p: DVec3::new(0.25, 0.75, 0.5),
            v: DVec3::new(1.0, -1.0, 0.0),
            r: 0.002,
            t: 900.5,
            age: 0.5,
        },
    ]
}

fn ply_binary(big: bool, ps: &[Particle]) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_{}_endian 1.0\ncomment firemedium test\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty double radius\nproperty float temperature\nproperty float vx\nproperty float vy\nproperty float vz\nproperty float age\nproperty uchar flags\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
        if big { "big" } else { "little" },
        ps.len()
    )
    .into_bytes();
    for p in ps {
        let f = |x: f64| {
            if big {
                (x as f32).to_be_bytes()
            } else {
                (x as f32).to_le_bytes()
            }
        };
        for x in [p.p.x, p.p.y, p.p.z] {
            b.extend(f(x));
        }
        b.extend(if big {
            p.r.to_be_bytes()
        } else {
            p.r.to_le_bytes()
        });
        for x in [p.t, p.v.x, p.v.y, p.v.z, p.age] {
            b.extend(f(x));
        }
        b.push(3);
    }
    b
}

#[test]
fn ply_and_csv_give_the_same_particles() {
    let want = two();
    let csv = parse("e.csv", CSV.as_bytes(), 1 << 20).unwrap();
    assert_eq!(csv, want);
    for big in [false, true] {
        let got = parse("e.ply", &ply_binary(big, &want), 1 << 20).unwrap();
        assert_eq!(got.len(), 2);
        for (g, w) in got.iter().zip(&want) {
            // (positions and temperatures went through f32)
            assert!((g.p - w.p).length() < 1e-6 && g.r == w.r && (g.t - w.t).abs() < 1e-3);
            assert!((g.v - w.v).length() < 1e-6 && (g.age - w.age).abs() < 1e-6);
        }
    }
    let ascii = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float width\nproperty float temp\nend_header\n0 0 0 0.02 1000\n1 2 3 0.004 800\n";
    let got = parse("a.ply", ascii.as_bytes(), 1 << 20).unwrap();
    assert_eq!(got[1].p, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!((got[0].r, got[1].r, got[1].t), (0.01, 0.002, 800.0));
    assert_eq!((got[0].v, got[0].age), (DVec3::ZERO, 0.0));
}

fn format_error(r: Result<Vec<Particle>, Error>) -> String {
    match r {
        Err(e @ (Error::Format { .. } | Error::TooLarge { .. })) => e.to_string(),
        other => panic!("expected a format error, got {other:?}"),
    }
}

#[test]
fn malformed_files_are_errors_that_say_where() {
    // A header claiming 10⁹ particles over a few bytes: refused before anything is allocated.
    let mut b = ply_binary(false, &two());
    let s = String::from_utf8_lossy(&b).replace("element vertex 2", "element vertex 1000000000");
    b = s.into_bytes();
    let m = format_error(parse("big.ply", &b, 1 << 40));
    assert!(
        m.contains("big.ply") && m.contains("1000000000 particles"),
        "{m}"
    );
    // Truncated body.
    let b = ply_binary(true, &two());
    let m = format_error(parse("cut.ply", &b[..b.len() - 5], 1 << 20));
    assert!(m.contains("cut.ply") && m.contains("bytes"), "{m}");
    // No radius.
    let m = format_error(parse("r.csv", b"x,y,z,temperature\n0,0,0,1000\n", 1 << 20));
    assert!(m.contains("radius"), "{m}");
    // A NaN temperature, named by line and column.
    let m = format_error(parse(
        "nan.csv",
        b"x,y,z,radius,temperature\n0,0,0,0.01,1000\n0,0,0,0.01,nan\n",
        1 << 20,
    ));
    assert!(
        m.contains("nan.csv") && m.contains("line 3, column 5") && m.contains("NaN"),
        "{m}"
    );
    // A negative radius, a row too short, a word for a number.
    for (text, want) in [
        ("x,y,z,radius,temperature\n0,0,0,-1,1000\n", "radius"),
        ("x,y,z,radius,temperature\n0,0,0,1\n", "5 columns"),
        ("x,y,z,radius,temperature\n0,0,zero,1,1000\n", "'zero'"),
    ] {
        let m = format_error(parse("bad.csv", text.as_bytes(), 1 << 20));
        assert!(m.contains(want) && m.contains("line 2"), "{m}");
    }
    // Binary without end_header, a list property on the vertices, a budget too small.
    let m = format_error(parse("h.ply", b"ply\nformat ascii 1.0\n", 1 << 20));
    assert!(m.contains("end_header"), "{m}");
    let m = format_error(parse(
        "l.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar int x\nend_header\n",
        1 << 20,
    ));
    assert!(m.contains("line 4"), "{m}");
    let m = format_error(parse("e.csv", CSV.as_bytes(), 64));
    assert!(m.contains("2 particles"), "{m}");
}

/// A 1 m empty box (density 0) with the embers of `csv` and the volume's `extra` parameters.
fn ember_volume(csv: &str, extra: Vec<Param>) -> (FireVolume, TempFile) {
    let f = TempFile::new(&format!("{:x}.csv", fxhash(csv, &extra)), csv.as_bytes());
    let mut list = vec![Param::string("embers", &f.path())];
    list.extend(extra);
    (slab_volume(0.0, 0.0, list), f)
}

fn fxhash(s: &str, extra: &[Param]) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    s.hash(&mut h);
    format!("{extra:?}").hash(&mut h);
    std::thread::current().id().hash(&mut h);
    h.finish()
}

/// ε B(T) averaged over the thesis's bin k (405 + 10k nm centres), by a 2000-point midpoint rule.
fn planck_bin(t: f64, k: usize) -> f64 {
    let lo = 400.0 + 10.0 * k as f64;
    (0..2000)
        .map(|i| spectral_radiance(t, lo + (i as f64 + 0.5) * 0.005))
        .sum::<f64>()
        / 2000.0
}

fn shoot(v: &FireVolume, o: DVec3, d: DVec3, time: f64) -> (Vec<f64>, Vec<f64>) {
    let c = v.channels();
    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
    let ray = Ray {
        o,
        d,
        t0: 0.0,
        t1: 10.0,
        seed: 1,
        first: None,
    };
    v.integrate_at(&ray, time, &mut l, &mut t);
    (l, t)
}

#[test]
fn an_ember_is_an_opaque_grey_body_at_its_cooled_temperature() {
    let csv = "x,y,z,radius,temperature,age\n0.5,0.5,0.5,0.05,1300,0\n0.5,0.2,0.5,0.002,1300,0.7\n";
    let (v, _f) = ember_volume(
        csv,
        vec![
            Param::float("emberemissivity", 0.8),
            Param::float("ambienttemperature", 1.0),
            Param::float("intensity", 2.0),
            // (Radiation alone, as this test's closed form: no oxygen to burn in.)
            Param::float("emberoxygen", 0.0),
        ],
    );
    // Through the first ember's centre: 0.8 · 2 · B(1300 K) in every bin, nothing behind.
    let (l, t) = shoot(&v, DVec3::new(-0.5, 0.5, 0.5), DVec3::X, 0.0);
    for k in [0, 14, 29] {
        let want = 0.8 * 2.0 * planck_bin(1300.0, k);
        assert!(
            (l[k] / want - 1.0).abs() < 1e-3,
            "bin {k}: {} vs {want}",
            l[k]
        );
        assert_eq!(t[k], 0.0);
    }
    // Beside it: nothing.
    let (l, t) = shoot(&v, DVec3::new(-0.5, 0.5, 0.5 + 0.0501), DVec3::X, 0.0);
    assert!(l.iter().all(|&x| x == 0.0) && t.iter().all(|&x| x == 1.0));
    // The second is 0.7 s old: T = T0 (1 + 3 k T0³ t)^(-1/3) with k = 3εσ/(ρ c r) (defaults 250 kg/m³,
    // 1200 J/(kg K); the 1 K surroundings change T by < 1e-9).
    let k = 3.0 * 0.8 * 5.670_374_419e-8 / (250.0 * 1200.0 * 0.002);
    let t_now = 1300.0 * (1.0 + 3.0 * k * 1300f64.powi(3) * 0.7).powf(-1.0 / 3.0);
    assert!(t_now < 1100.0, "{t_now}");
    let (l, _) = shoot(&v, DVec3::new(-0.5, 0.2, 0.5), DVec3::X, 0.0);
    for k in [0, 29] {
        let want = 0.8 * 2.0 * planck_bin(t_now, k);
        assert!(
            (l[k] / want - 1.0).abs() < 2e-3,
            "bin {k}: {} vs {want}",
            l[k]
        );
    }
}

#[test]
fn a_burning_ember_glows_at_its_burning_temperature_for_seconds() {
    // Two 1 mm sparks thrown at 1650 K, 3 s ago: in air their char burns and holds each near the temperature
    // where oxidation meets radiation and convection (the steady root of that balance, firemedium_core's
    // `burning_temperature` at the radius it has burnt down to: 1099 K, its carbon burning to CO₂; its radiance
    // within 5 % of that temperature's), where radiation alone would have cooled it to 600 K, all but black.
    // Without oxygen, that cooled one.
    let csv = "x,y,z,radius,temperature,age\n0.5,0.5,0.5,0.001,1650,3\n";
    let render = |oxygen: f64| {
        let (v, _f) = ember_volume(csv, vec![Param::float("emberoxygen", oxygen)]);
        shoot(&v, DVec3::new(-0.5, 0.5, 0.5), DVec3::X, 0.0).0
    };
    let (burning, cooling) = (render(0.233), render(0.0));
    let air = firemedium_core::ember::Char {
        emissivity: 0.9,
        density: 250.0,
        heat_capacity: 1200.0,
        ambient: 293.15,
        oxygen: 0.233,
    };
    let (_, r_now) = firemedium_core::ember::burn(1650.0, 1e-3, 3.0, &air);
    let steady = firemedium_core::ember::burning_temperature(r_now, &air).unwrap();
    let k = 3.0 * 0.9 * 5.670_374_419e-8 / (250.0 * 1200.0 * 1e-3);
    let cooled = firemedium_core::ember::cooled_temperature(1650.0, 3.0, k, 293.15);
    for bin in [5, 24] {
        let (b, c) = (0.9 * planck_bin(steady, bin), 0.9 * planck_bin(cooled, bin));
        // (At 1300 K and 650 nm, 1 % in T is 17 % in B: 5 % in radiance holds T to 0.3 %.)
        assert!(
            (burning[bin] / b - 1.0).abs() < 0.05,
            "bin {bin}: {} vs {b} ({steady} K)",
            burning[bin]
        );
        assert!(
            (cooling[bin] / c - 1.0).abs() < 2e-3,
            "bin {bin}: {} vs {c}",
            cooling[bin]
        );
    }
    assert!(
        burning[24] > 1e3 * cooling[24],
        "{} vs {}",
        burning[24],
        cooling[24]
    );
    assert!(
        (1000.0..1200.0).contains(&steady) && cooled < 700.0,
        "{steady} K, {cooled} K"
    );
}

#[test]
fn the_fire_in_front_attenuates_it_and_nothing_passes() {
    let csv = "x,y,z,radius,temperature\n0.7,0.5,0.5,0.05,1500\n";
    let f = TempFile::new("front.csv", csv.as_bytes());
    // Cold soot (no emission) filling the box: the ember is seen through 0.65 m of it.
    let v = slab_volume(1e-8, 0.0, vec![Param::string("embers", &f.path())]);
    let (mut sa, mut ss, mut j) = (vec![0.0; 30], vec![0.0; 30], vec![0.0; 30]);
    v.coefficients(DVec3::splat(0.5), &mut sa, &mut ss, &mut j);
    let (l, t) = shoot(&v, DVec3::new(-0.5, 0.5, 0.5), DVec3::X, 0.0);
    for k in [0, 15, 29] {
        let want = 0.9 * planck_bin(1500.0, k) * (-(sa[k] + ss[k]) * 0.65).exp();
        assert!(
            (l[k] / want - 1.0).abs() < 2e-3,
            "bin {k}: {} vs {want}",
            l[k]
        );
        assert_eq!(t[k], 0.0);
    }
    // Shadow rays and scattering events stop there too.
    let mut tr = vec![0.0; 30];
    let ray = Ray {
        o: DVec3::new(-0.5, 0.5, 0.5),
        d: DVec3::X,
        t0: 0.0,
        t1: 10.0,
        seed: 3,
        first: None,
    };
    v.transmittance(&ray, &mut tr);
    assert!(tr.iter().all(|&x| x == 0.0));
    // A scattering event's weights estimate the transmittance (delta tracking): the ember's light on average.
    let (mut le, mut w, mut mean) = (vec![0.0; 30], vec![0.0; 30], 0.0);
    for seed in 0..4000 {
        let ev = v.sample_scatter(&Ray { seed, ..ray }, &mut le, &mut w);
        assert_eq!(ev, crate::volume::Event::Absorbed);
        mean += le[15] / 4000.0;
    }
    assert!((mean / l[15] - 1.0).abs() < 0.02, "{mean} vs {}", l[15]);
}

#[test]
fn a_moving_ember_is_where_its_velocity_carried_it() {
    // 2.4 m/s upwards at 24 fps: 0.1 m per frame; at time 0.5 frames the ember is 5 cm up, clear of where it
    // was (radius 1 cm).
    let csv = "x,y,z,radius,temperature,vz\n0.5,0.5,0.3,0.01,1200,2.4\n";
    let (v, _f) = ember_volume(
        csv,
        vec![
            Param::float("shutteropen", -0.5),
            Param::float("shutterclose", 0.5),
        ],
    );
    let at = |z: f64, time: f64| shoot(&v, DVec3::new(-0.5, 0.5, z), DVec3::X, time).1[0];
    assert_eq!(at(0.3, 0.0), 0.0);
    assert_eq!(at(0.3, 0.5), 1.0);
    assert_eq!(at(0.35, 0.5), 0.0);
    assert_eq!(at(0.25, -0.5), 0.0);
    // Times outside the shutter are held at its ends.
    assert_eq!(at(0.35, 3.0), 0.0);
}

#[test]
fn the_light_samples_embers_as_its_pdfs_say() {
    let csv = "x,y,z,radius,temperature,vx\n0.5,0.5,0.5,0.05,1300,0\n0.2,0.6,0.4,0.02,1100,2.4\n";
    let (v, _f) = ember_volume(csv, vec![Param::float("shutterclose", 1.0)]);
    let v = Arc::new(v);
    let light = FireLight::new(v.clone(), Weighting::Power).unwrap();
    // The total power: ε σ T⁴ 4π r² of each (no voxel emits).
    let want: f64 = [(0.05, 1300.0), (0.02, 1100.0f64)]
        .iter()
        .map(|(r, t)| 0.9 * 5.670_374_419e-8 * t.powi(4) * 4.0 * std::f64::consts::PI * r * r)
        .sum();
    assert!(
        (light.power_w() / want - 1.0).abs() < 1e-9,
        "{} vs {want}",
        light.power_w()
    );
    let mut rng = firemedium_core::rng::Rng::new(5);
    let time = 0.5;
    for _ in 0..200 {
        let s = light.sample_at([(); 6].map(|_| rng.next_f64()), time);
        assert!((s.pdf / light.pdf_at(s.point, time) - 1.0).abs() < 1e-12);
        // Inside one of the balls where they are at that time (the second moved 5 cm along x).
        let c = [DVec3::splat(0.5), DVec3::new(0.25, 0.6, 0.4)];
        assert!(
            (s.point - c[0]).length() <= 0.05 + 1e-12 || (s.point - c[1]).length() <= 0.02 + 1e-12
        );
    }
    // ∫ pdf_direction dω = 1 from outside: the density is 0 but in the two balls' (disjoint) cones, each
    // integrated by a 400 × 400 midpoint rule in (cos θ, φ) about its axis.
    let o = DVec3::new(0.5, -0.6, 0.5);
    let mut total = 0.0;
    for (c, r) in [
        (DVec3::splat(0.5), 0.05),
        (DVec3::new(0.25, 0.6, 0.4), 0.02),
    ] {
        let axis = (c - o).normalize();
        let cos_a = (1.0 - (r / (c - o).length()).powi(2)).sqrt();
        let (t1, t2) = (
            axis.any_orthonormal_vector(),
            axis.cross(axis.any_orthonormal_vector()),
        );
        let n = 400;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let z = 1.0 - (1.0 - cos_a) * (i as f64 + 0.5) / n as f64;
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n as f64;
                let s = (1.0 - z * z).sqrt();
                sum += light.pdf_direction_at(
                    o,
                    axis * z + (t1 * phi.cos() + t2 * phi.sin()) * s,
                    time,
                );
            }
        }
        total += sum * 2.0 * std::f64::consts::PI * (1.0 - cos_a) / (n * n) as f64;
    }
    assert!((total - 1.0).abs() < 2e-3, "∫ pdf dω = {total}");
}

#[test]
fn the_light_estimates_an_embers_solid_angle_integral() {
    // The host's estimate of ∫ L dω from a point: L(ω)/pdf_direction(ω) along sampled directions, L from the
    // volume. For one sphere of radiance L_e: L_e · 2π (1 − cos α), sin α = r/D.
    let csv = "x,y,z,radius,temperature\n0.5,0.5,0.6,0.08,1250\n";
    let (v, _f) = ember_volume(csv, vec![]);
    let v = Arc::new(v);
    let light = FireLight::new(v.clone(), Weighting::Luminance).unwrap();
    let o = DVec3::new(0.5, 0.5, 0.1);
    let (n, mut sum, mut sum2) = (20_000, 0.0, 0.0);
    let mut rng = firemedium_core::rng::Rng::new(9);
    for _ in 0..n {
        let s = light.sample_at([(); 6].map(|_| rng.next_f64()), 0.0);
        let d = (s.point - o).normalize();
        let (l, _) = shoot(&v, o, d, 0.0);
        let x = l[12] / light.pdf_direction_at(o, d, 0.0);
        sum += x;
        sum2 += x * x;
    }
    let mean = sum / n as f64;
    let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
    let sin_a: f64 = 0.08 / 0.5;
    let want = 0.9
        * planck_bin(1250.0, 12)
        * 2.0
        * std::f64::consts::PI
        * (1.0 - (1.0 - sin_a * sin_a).sqrt());
    eprintln!("{mean} ± {se} vs {want}: {:+.2e}", mean / want - 1.0);
    assert!(
        (mean - want).abs() < 4.0 * se + 1e-3 * want,
        "{mean} ± {se} vs {want}"
    );
    assert!(se < 0.05 * want, "{se} of {want}");
}

#[test]
fn embers_need_a_fire() {
    let f = TempFile::new(
        "pbrt.csv",
        b"x,y,z,radius,temperature\n0.5,0.5,0.5,0.05,1300\n",
    );
    let e = FireVolume::new(&[
        Param::string("mode", "pbrt"),
        Param::floats("density", &[1.0]),
        Param::string("embers", &f.path()),
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("embers") && e.contains("pbrt"), "{e}");
    let e = FireVolume::new(&[
        Param::floats("density", &[0.0]),
        Param::string("embers", "/no/such/embers.csv"),
    ])
    .unwrap_err()
    .to_string();
    assert!(e.contains("/no/such/embers.csv"), "{e}");
}

#[test]
fn the_parameters_defaults_are_the_generators_char() {
    use firemedium_core::ember::{CHAR_DENSITY, CHAR_EMISSIVITY, CHAR_HEAT_CAPACITY};
    let default = |name: &str| -> f64 {
        let row = crate::volume::params::VOLUME
            .params
            .iter()
            .find(|p| p.name == name)
            .unwrap();
        row.default.parse().unwrap()
    };
    assert_eq!(default("emberemissivity"), CHAR_EMISSIVITY);
    assert_eq!(default("emberdensity"), CHAR_DENSITY);
    assert_eq!(default("emberheatcapacity"), CHAR_HEAT_CAPACITY);
}

#[test]
fn mutated_particle_files_are_errors_or_particles_never_panics() {
    // Bytes flipped, runs deleted or repeated, digits and signs inserted, files cut: every result is the
    // particles or an error naming the file, within the budget.
    let ascii = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float radius\nproperty float temperature\nend_header\n0 0 0 0.02 1000\n1 2 3 0.004 800\n";
    let seeds: Vec<(&str, Vec<u8>)> = vec![
        ("m.csv", CSV.as_bytes().to_vec()),
        ("m.ply", ascii.as_bytes().to_vec()),
        ("b.ply", ply_binary(false, &two())),
    ];
    let mut rng = firemedium_core::rng::Rng::new(27);
    let mut pick = |n: usize| (rng.next_f64() * n as f64) as usize % n.max(1);
    let (mut ok, mut err) = (0, 0);
    for round in 0..6000 {
        let (name, seed) = &seeds[round % seeds.len()];
        let mut b = seed.clone();
        for _ in 0..1 + pick(4) {
            let at = pick(b.len().max(1));
            match pick(6) {
                0 if !b.is_empty() => {
                    let i = at.min(b.len() - 1);
                    b[i] ^= 1 << pick(8);
                }
                1 => b.truncate(at),
                2 => b.insert(at.min(b.len()), b"-9e99.0,\n"[pick(9)]),
                3 if !b.is_empty() => {
                    let end = (at + pick(16)).min(b.len());
                    b.drain(at.min(end)..end);
                }
                4 => {
                    let end = (at + pick(32)).min(b.len());
                    let run = b[at.min(end)..end].to_vec();
                    b.splice(
                        at.min(b.len())..at.min(b.len()),
                        run.into_iter().cycle().take(64),
                    );
                }
                _ => b.insert(at.min(b.len()), b'9'),
            }
        }
        match parse(name, &b, 1 << 16) {
            Ok(p) => {
                ok += 1;
                assert!(p
                    .iter()
                    .all(|q| q.r > 0.0 && q.t.is_finite() && q.p.is_finite()));
            }
            Err(e) => {
                err += 1;
                assert!(e.to_string().contains(name), "{e}");
            }
        }
    }
    assert!(ok > 100 && err > 100, "{ok} read, {err} refused");
}
