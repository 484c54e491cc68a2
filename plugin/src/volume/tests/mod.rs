//! The fire volume against closed forms and independent references: homogeneous slabs across optical depth,
//! the tables' bin means, tracking against the march, rgb against spectral, pbrt mode, species lines, extremes,
//! and parameter errors. Shared helpers for the march's and refraction's tests live here too.

use super::basis::Basis;
use super::tables::RangeMax;
use super::tables::TTable;
use super::*;
use crate::blackbody::{spectral_radiance, WIEN};
use crate::cie::cmf_table::CMF;
use crate::params::Param;
use crate::soot::SootOptics;
use crate::species::Element;

pub(crate) fn slab_volume(d: f64, t: f64, extra: Vec<Param>) -> FireVolume {
    // A 4×4×4 constant grid over [0, 1]³, nearest lookup: exactly homogeneous inside the box.
    let n = 64;
    let mut list = vec![
        Param::floats("density", &vec![d; n]),
        Param::floats("temperature", &vec![t; n]),
        Param::int("nx", 4),
        Param::int("ny", 4),
        Param::int("nz", 4),
        Param::string("interpolation", "nearest"),
    ];
    list.extend(extra);
    FireVolume::new(&thesis_bins(list)).unwrap_or_else(|e| panic!("{e}"))
}

/// `list` with the thesis's spectrum — 30 bins of 10 nm over 400–700 nm, bin k centred at 405 + 10k nm, the
/// layout the closed forms of these tests index — unless it names its own bins.
pub(crate) fn thesis_bins(mut list: Vec<Param>) -> Vec<Param> {
    if !list.iter().any(|p| p.name == "bins") {
        list.push(Param::int("bins", 30));
        list.push(Param::float("lambdamax", 700.0));
    }
    list
}

pub(crate) fn ray_x(seed: u64) -> Ray {
    Ray {
        o: DVec3::new(-0.5, 0.5, 0.5),
        d: DVec3::X,
        t0: 0.0,
        t1: 3.0,
        seed,
        first: None,
    }
}

pub(crate) fn run(v: &FireVolume, ray: &Ray) -> (Vec<f64>, Vec<f64>) {
    let c = v.channels();
    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
    v.integrate(ray, &mut l, &mut t);
    (l, t)
}

/// Every channel of `got` within 1e-12 (relative) of `want`, the same number of channels.
pub(crate) fn assert_bins_agree(got: &[f64], want: &[f64], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}");
    for (c, (g, w)) in got.iter().zip(want).enumerate() {
        let e = (g / w - 1.0).abs();
        assert!(e < 1e-12, "{what}, bin {c}: {g} vs {w} ({e:e})");
    }
}

/// A trilinear 40×36×44 grid over [0, 2] × [0, 1.8] × [0, 2.2] with a hot blob in one corner and a slab on
/// the far x side (so many bricks are empty) and `extra` parameters (pbrt mode adds a Lescale grid); `species` adds a sodium grid
/// (files: species grids are not inline parameters).
/// The blob volume with `extra` parameters in the lanes' precision (the default) and in f64.
/// `n` rays from around the blob of [`blob_volume`] toward points about its ball (seeds from `seed`).
pub(crate) fn blob_rays(n: u64, seed: u64) -> Vec<Ray> {
    (0..n)
        .map(|k| {
            let mut rng = crate::rng::Rng::new(seed + k);
            let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 4.0 - 1.0;
            let target = DVec3::new(0.6, 0.63, 0.55)
                + (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5);
            Ray {
                o,
                d: target - o,
                t0: 0.0,
                t1: 5.0,
                seed: k,
                first: None,
            }
        })
        .collect()
}

pub(crate) fn blob_pair(extra: &[Param], species: bool) -> (FireVolume, FireVolume) {
    let mut e64 = extra.to_vec();
    e64.push(Param::string("precision", "f64"));
    (
        blob_volume(extra.to_vec(), species),
        blob_volume(e64, species),
    )
}

pub(crate) fn blob_volume(extra: Vec<Param>, species: bool) -> FireVolume {
    let [nx, ny, nz] = [40usize, 36, 44];
    let (mut d, mut t, mut les, mut na) = (vec![], vec![], vec![], vec![]);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = DVec3::new(
                    i as f64 / nx as f64,
                    j as f64 / ny as f64,
                    k as f64 / nz as f64,
                );
                let r2 = (p - DVec3::new(0.3, 0.35, 0.25)).length_squared() / 0.04;
                let w = if r2 < 1.0 { (1.0 - r2).powi(2) } else { 0.0 };
                // And a hot slab with a sharp face, right after empty bricks along x.
                let slab = if i >= 27 { 1.0 } else { 0.0 };
                d.push(3e-6 * w + 1e-6 * slab);
                t.push(300.0 + 1700.0 * w + 1200.0 * slab);
                les.push(0.5 + p.x);
                na.push(w * (1.0 - p.z));
            }
        }
    }
    let mut list = vec![
        Param::point3("p0", [0.0, 0.0, 0.0]),
        Param::point3("p1", [2.0, 1.8, 2.2]),
    ];
    // The species grids' files, in a folder of this call's own (removed once the volume has read them).
    static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "firemedium-kernel-{}-{}",
        std::process::id(),
        CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    if species {
        std::fs::create_dir_all(&dir).unwrap();
        let f = |name: &str, v: &[f64]| {
            let p = dir.join(name);
            let body: Vec<String> = v.iter().map(|x| x.to_string()).collect();
            std::fs::write(&p, format!("{nx} {ny} {nz}\n{}\n", body.join(" "))).unwrap();
            p.display().to_string()
        };
        list.extend([
            Param::string("densityfile", &f("d.txt", &d)),
            Param::string("temperaturefile", &f("t.txt", &t)),
            Param::strings("species", &["Na"]),
            Param::strings("speciesfiles", &[&f("na.txt", &na)]),
            Param::float("speciesscale", 1e15),
        ]);
    } else {
        if extra.iter().any(|p| p.name == "mode") {
            // (pbrt mode: σ_a per unit density, and a per-voxel emission scale.)
            list.extend([
                Param::floats("Lescale", &les),
                Param::spectrum("sigma_a", &[200.0, 2e5, 900.0, 3e5]),
            ]);
        }
        list.extend([
            Param::floats("density", &d),
            Param::floats("temperature", &t),
            Param::int("nx", nx as i64),
            Param::int("ny", ny as i64),
            Param::int("nz", nz as i64),
        ]);
    }
    list.extend(extra);
    let v = FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_dir_all(&dir);
    v
}

/// One voxel of dense soot (f_v = 1e4 · sootscale) in a 4³ brick of thin smoke (nearest lookups), with `extra`.
fn dense_voxel_in_smoke(extra: &[Param]) -> FireVolume {
    let mut d = vec![1e-6; 64];
    d[63] = 1e4;
    let mut list = vec![
        Param::floats("density", &d),
        Param::floats("temperature", &[1500.0; 64]),
        Param::int("nx", 4),
        Param::int("ny", 4),
        Param::int("nz", 4),
        Param::string("interpolation", "nearest"),
        Param::float("sootscale", 1.0),
    ];
    list.extend_from_slice(extra);
    FireVolume::new(&list).unwrap()
}

/// A 4³ slab over [0, 1]³ holding sodium at `n` m⁻³ (and soot `fv` as density), with `extra`: at `t` K, or
/// with `t_front` K in its first half along x (x < 0.5).
fn sodium_slab(dir: &std::path::Path, n: f64, t: f64, fv: f64, extra: Vec<Param>) -> FireVolume {
    sodium_layers(dir, n, [t, t], fv, extra)
}

/// The parameters of [`sodium_layers`]'s volume.
fn sodium_params(
    dir: &std::path::Path,
    n: f64,
    [t_front, t_back]: [f64; 2],
    fv: f64,
    extra: Vec<Param>,
) -> Vec<Param> {
    std::fs::create_dir_all(dir).unwrap();
    let f = |name: &str, v: &dyn Fn(usize) -> f64| {
        let p = dir.join(name);
        // (x fastest: value i sits at x = i % 4.)
        let body: Vec<String> = (0..64).map(|i| v(i).to_string()).collect();
        std::fs::write(&p, format!("4 4 4\n{}\n", body.join(" "))).unwrap();
        p.display().to_string()
    };
    let temperature = |i: usize| if i % 4 < 2 { t_front } else { t_back };
    let (d, tt, na) = (
        f("d.txt", &|_| fv),
        f("t.txt", &temperature),
        f("na.txt", &|_| 1.0),
    );
    let mut list = vec![
        Param::string("densityfile", &d),
        Param::string("temperaturefile", &tt),
        Param::strings("species", &["Na"]),
        Param::strings("speciesfiles", &[&na]),
        Param::float("speciesscale", n),
        Param::string("interpolation", "nearest"),
    ];
    // Per-bin means (what the line-by-line references integrate), unless a test asks for the film's colour.
    if !extra.iter().any(|p| p.name == "linecolour") {
        list.push(Param::string("linecolour", "binmean"));
    }
    list.extend(extra);
    thesis_bins(list)
}

fn sodium_layers(
    dir: &std::path::Path,
    n: f64,
    temps: [f64; 2],
    fv: f64,
    extra: Vec<Param>,
) -> FireVolume {
    FireVolume::new(&sodium_params(dir, n, temps, fv, extra)).unwrap_or_else(|e| panic!("{e}"))
}

/// The line-by-line absorption cross-section of sodium's D doublet at T: σ(λ) per atom (m²) from each line's
/// Voigt profile (the defaults' mass and collisional width) — the references of the line model's tests.
pub(crate) fn sodium_d_kappa(t: f64) -> impl Fn(f64) -> f64 {
    use crate::species::line_cross_sections;
    use crate::species::profile::line_profile_nm;
    let na = Element::by_symbol("Na").unwrap();
    let (kt, ln_z) = (crate::constants::BOLTZMANN * t, na.ln_partition_function(t));
    let lines: Vec<_> = na
        .lines()
        .iter()
        .filter(|l| (588.0..591.0).contains(&l.lambda_nm))
        .copied()
        .collect();
    assert_eq!(lines.len(), 2);
    move |lam: f64| {
        lines
            .iter()
            .map(|ln| {
                let phi = line_profile_nm(lam - ln.lambda_nm, ln.lambda_nm, t, 22.990, 0.08);
                line_cross_sections(ln, kt, ln_z, phi * 1e9).0
            })
            .sum()
    }
}

/// Line-by-line: the bin [lo, lo + 10] nm's mean radiance and transmittance through `length` m of sodium at
/// `n` m⁻³ and T (no continuum), on a uniform 2e-5 nm grid — B at each wavelength, the Voigt profile of each D
/// line.
fn sodium_line_by_line(n: f64, t: f64, length: f64, lo: f64) -> (f64, f64) {
    let kappa = sodium_d_kappa(t);
    let steps = 500_000;
    let h = 10.0 / steps as f64;
    let (mut l, mut tr) = (0.0, 0.0);
    for i in 0..steps {
        let lam = lo + (i as f64 + 0.5) * h;
        let trans = (-n * kappa(lam) * length).exp();
        l += spectral_radiance(t, lam) * (1.0 - trans) * h;
        tr += trans * h;
    }
    (l / 10.0, tr / 10.0)
}

/// The fire's radiance along `ray` by path tracing its own light through its smoke: repeated scattering events
/// (isotropic phase function) until the path escapes or is absorbed, `paths` paths; per channel.
fn random_walk_radiance(v: &FireVolume, ray: &Ray, paths: usize) -> Vec<f64> {
    let c = v.channels();
    let mut sum = vec![0.0; c];
    let mut rng = crate::rng::Rng::new(99);
    let (mut l, mut w) = (vec![0.0; c], vec![0.0; c]);
    for k in 0..paths {
        let mut thr = vec![1.0; c];
        let mut r = Ray {
            seed: k as u64 * 7919 + 1,
            ..*ray
        };
        for bounce in 0..10_000 {
            let ev = v.sample_scatter(&r, &mut l, &mut w);
            for ch in 0..c {
                sum[ch] += thr[ch] * l[ch];
            }
            let Event::Scattered(t) = ev else { break };
            for ch in 0..c {
                thr[ch] *= w[ch];
            }
            let z = 2.0 * rng.next_f64() - 1.0;
            let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
            let s = (1.0 - z * z).max(0.0).sqrt();
            r = Ray {
                o: r.o + r.d * t,
                d: DVec3::new(s * phi.cos(), s * phi.sin(), z),
                t0: 1e-9,
                t1: 10.0,
                seed: r
                    .seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(bounce + 1),
                first: None,
            };
        }
    }
    sum.iter().map(|s| s / paths as f64).collect()
}

mod art;
mod diffusion;
mod flame_colours;
mod lattice;
mod lines;
mod physics;
mod robustness;
