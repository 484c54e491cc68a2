//! Art direction (scales, tint, colour ramps), emission and scatter colour grids, the reaction shell's blue core.

use super::*;

/// Art direction beside the physics: each control changes what it says and nothing else.
#[test]
fn smokescale_firescale_tint_and_remap_do_what_they_say() {
    let p = DVec3::splat(0.5);
    let coef = |extra: Vec<Param>| {
        let v = slab_volume(
            2e-6,
            1600.0,
            [vec![Param::floats("sigma_s", &[5.0])], extra].concat(),
        );
        let c = v.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        v.coefficients(p, &mut sa, &mut ss, &mut j);
        (sa, ss, j)
    };
    let (sa, ss, j) = coef(vec![]);
    assert!(sa.iter().chain(&ss).chain(&j).all(|&x| x > 0.0));
    // smokescale 0: no absorption, no scattering, the same emission.
    let (sa0, ss0, j0) = coef(vec![Param::float("smokescale", 0.0)]);
    assert!(sa0.iter().chain(&ss0).all(|&x| x == 0.0));
    assert_eq!(j0, j);
    // smokescale 0.5: half of both, exactly.
    let (sah, ssh, _) = coef(vec![Param::float("smokescale", 0.5)]);
    for c in 0..sa.len() {
        assert!((sah[c] / sa[c] - 0.5).abs() < 1e-12 && (ssh[c] / ss[c] - 0.5).abs() < 1e-12);
    }
    // firescale 2: twice the emission, the same absorption; given with intensity: refused.
    let (sa2, _, j2) = coef(vec![Param::float("firescale", 2.0)]);
    assert_eq!(sa2, sa);
    for c in 0..j.len() {
        assert!((j2[c] / j[c] - 2.0).abs() < 1e-12, "{} {}", j2[c], j[c]);
    }
    let both = FireVolume::new(&thesis_bins(vec![
        Param::floats("density", &[1e-6]),
        Param::floats("temperature", &[1500.0]),
        Param::float("firescale", 2.0),
        Param::float("intensity", 2.0),
    ]));
    assert!(both.unwrap_err().to_string().contains("firescale"));
    // tint black: no emission; tint white (rgb 1 1 1): the blackbody's, to the rgb spectrum's flatness.
    let (sat, _, jt) = coef(vec![Param::rgb("tint", [0.0, 0.0, 0.0])]);
    assert!(jt.iter().all(|&x| x == 0.0));
    assert_eq!(sat, sa);
    let (_, _, jw) = coef(vec![Param::rgb("tint", [1.0, 1.0, 1.0])]);
    for c in 0..j.len() {
        assert!(
            (jw[c] / j[c] - 1.0).abs() < 1e-3,
            "bin {c}: {} vs {}",
            jw[c],
            j[c]
        );
    }
    // A red tint keeps the red end and darkens the blue.
    let (_, _, jr) = coef(vec![Param::rgb("tint", [1.0, 0.2, 0.2])]);
    let last = j.len() - 1;
    assert!(
        jr[last] / j[last] > 0.8 && jr[0] / j[0] < 0.4,
        "{} {}",
        jr[last] / j[last],
        jr[0] / j[0]
    );
    // temperatureremap a b ka kb is the scale and offset it stands for, bit for bit; with them, refused.
    let remap = coef(vec![Param::floats(
        "temperatureremap",
        &[0.0, 2000.0, 1000.0, 2000.0],
    )]);
    let scaled = coef(vec![
        Param::float("temperaturescale", 0.5),
        Param::float("temperatureoffset", -2000.0),
    ]);
    assert_eq!(remap, scaled);
    for bad in [
        vec![
            Param::floats("temperatureremap", &[0.0, 1.0, 1000.0, 2000.0]),
            Param::float("temperaturescale", 2.0),
        ],
        vec![Param::floats(
            "temperatureremap",
            &[1.0, 1.0, 1000.0, 2000.0],
        )],
        vec![Param::floats(
            "temperatureremap",
            &[0.0, 1.0, 2000.0, 1000.0],
        )],
        vec![Param::floats("temperatureremap", &[0.0, 1.0, 2000.0])],
    ] {
        let r = FireVolume::new(&thesis_bins(
            [
                vec![
                    Param::floats("density", &[1e-6]),
                    Param::floats("temperature", &[1500.0]),
                ],
                bad,
            ]
            .concat(),
        ));
        assert!(r.unwrap_err().to_string().contains("temperatureremap"));
    }
}

/// The colour ramp: at `physical` 1 the physical tables bit for bit; at 0 the ramp's colour at the emission's own
/// luminance; between, the blend.
#[test]
fn a_colour_ramp_replaces_the_chromaticity_and_keeps_the_luminance() {
    let p = DVec3::splat(0.5);
    let emission = |extra: Vec<Param>| {
        let v = slab_volume(2e-6, 1600.0, extra);
        let c = v.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        v.coefficients(p, &mut sa, &mut ss, &mut j);
        let xyz = v.channel_xyz();
        let y: f64 = j.iter().zip(&xyz).map(|(a, w)| a * w.y).sum();
        (sa, j, y, xyz)
    };
    // Blue below 1500 K, green above 1700 K: 1600 K is their mean.
    let ramp = Param::floats("colorramp", &[1500.0, 0.0, 0.0, 1.0, 1700.0, 0.0, 1.0, 0.0]);
    let (sa, j, y, xyz) = emission(vec![]);
    let (sa1, j1, _, _) = emission(vec![ramp.clone(), Param::float("physical", 1.0)]);
    assert_eq!(
        (sa1, j1),
        (sa.clone(), j.clone()),
        "physical 1 is the physics"
    );
    let (sa0, j0, y0, _) = emission(vec![ramp.clone()]);
    assert_eq!(sa0, sa, "the ramp leaves absorption alone");
    assert!((y0 / y - 1.0).abs() < 1e-5, "luminance kept: {y0} vs {y}");
    // Its colour: the mean of blue and green's spectra at the same luminance — no red end left.
    let last = j.len() - 1;
    assert!(
        j0[last] < 0.05 * j[last],
        "red end {} vs {}",
        j0[last],
        j[last]
    );
    let chroma = |j: &[f64]| {
        let s: glam::DVec3 = j.iter().zip(&xyz).map(|(a, w)| *w * *a).sum();
        (s.x / (s.x + s.y + s.z), s.y / (s.x + s.y + s.z))
    };
    let (x0, _) = chroma(&j0);
    let (xb, _) = chroma(&j);
    assert!(x0 < 0.3 && xb > 0.5, "ramp x {x0}, blackbody x {xb}");
    // A key's colour is an emitter's (the fit times D65, as pbrt-v4's RGBIlluminantSpectrum): one key of
    // linear sRGB (0, 0.6, 1) renders as that colour, to the bins' resolution.
    let (_, jc, _, _) = emission(vec![Param::floats("colorramp", &[1600.0, 0.0, 0.6, 1.0])]);
    let s: glam::DVec3 = jc.iter().zip(&xyz).map(|(a, w)| *w * *a).sum();
    let rgb = glam::DVec3::new(
        3.2404542 * s.x - 1.5371385 * s.y - 0.4985314 * s.z,
        -0.9692660 * s.x + 1.8760108 * s.y + 0.0415560 * s.z,
        0.0556434 * s.x - 0.2040259 * s.y + 1.0572252 * s.z,
    );
    let rgb = rgb / rgb.z;
    assert!(
        rgb.x.abs() < 0.03 && (rgb.y - 0.6).abs() < 0.03,
        "a (0, 0.6, 1) key renders as {rgb:?}"
    );
    // Half and half: the mean of the two, channel by channel.
    let (_, jh, _, _) = emission(vec![ramp.clone(), Param::float("physical", 0.5)]);
    for c in 0..j.len() {
        assert!(
            (jh[c] - 0.5 * (j[c] + j0[c])).abs() <= 1e-6 * j[c].max(j0[c]),
            "bin {c}"
        );
    }
    // Bad ramps and a lone `physical` are refused.
    for bad in [
        vec![Param::floats("colorramp", &[1500.0, 0.0, 0.0])],
        vec![Param::floats(
            "colorramp",
            &[1500.0, 0.0, 0.0, 1.0, 1400.0, 1.0, 0.0, 0.0],
        )],
        vec![Param::floats("colorramp", &[1500.0, -1.0, 0.0, 1.0])],
        vec![Param::float("physical", 0.5)],
    ] {
        let name = bad[0].name.clone();
        let r = FireVolume::new(&thesis_bins(
            [
                vec![
                    Param::floats("density", &[1e-6]),
                    Param::floats("temperature", &[1500.0]),
                ],
                bad,
            ]
            .concat(),
        ));
        assert!(r.unwrap_err().to_string().contains(&name));
    }
}

/// An emission grid: the fire's emission follows it, not the soot. Pointed at the density grid it changes
/// nothing; a flame where there is no smoke emits without absorbing, and tracking finds that emission as the
/// march does.
#[test]
fn an_emission_grid_emits_where_it_says() {
    let n = 24usize;
    let (mut d, mut fl) = (vec![0f32; n * n * n], vec![0f32; n * n * n]);
    for i in 0..n * n * n {
        let c = [i % n, (i / n) % n, i / (n * n)].map(|k| (k as f64 + 0.5) / n as f64);
        let blob = |x: f64, amp: f64| {
            let r2 = (c[0] - x).powi(2) + (c[1] - 0.5).powi(2) + (c[2] - 0.5).powi(2);
            (amp * (-r2 / (2.0 * 0.08f64.powi(2))).exp()) as f32
        };
        d[i] = blob(0.3, 1e-6);
        fl[i] = blob(0.7, 2e-6);
    }
    let t = vec![1600f32; n * n * n];
    let bytes = crate::dataset::vdb::write(
        &[
            ("density", [n; 3], &d),
            ("temperature", [n; 3], &t),
            ("flame", [n; 3], &fl),
        ],
        DVec3::ZERO,
        DVec3::splat(1.0 / n as f64),
    );
    let file = std::env::temp_dir().join(format!("firemedium-emission-{}.vdb", std::process::id()));
    std::fs::write(&file, bytes).unwrap();
    let build = |extra: Vec<Param>| {
        let mut list = vec![Param::string("filename", &file.display().to_string())];
        list.extend(extra);
        FireVolume::new(&thesis_bins(list)).unwrap_or_else(|e| panic!("{e}"))
    };
    let plain = build(vec![]);
    let same = build(vec![Param::string("emissiongrid", "density")]);
    let flame = build(vec![Param::string("emissiongrid", "flame")]);
    let ratio = build(vec![
        Param::string("emissiongrid", "flame"),
        Param::string("integrator", "ratio"),
    ]);
    std::fs::remove_file(&file).unwrap();
    let c = plain.channels();
    let ray = |x: f64, seed: u64| Ray {
        o: DVec3::new(x, 0.5, -0.5),
        d: DVec3::Z,
        t0: 0.0,
        t1: 3.0,
        seed,
        first: None,
    };
    let run = |v: &FireVolume, r: &Ray| {
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        v.integrate(r, &mut l, &mut t);
        (l, t)
    };
    let sum = |x: &[f64]| x.iter().sum::<f64>();
    // The density as its own emission grid: the same radiance (to f32 lanes' rounding), the same transmittance.
    for x in [0.3, 0.5, 0.7] {
        let ((l0, t0), (l1, t1)) = (run(&plain, &ray(x, 1)), run(&same, &ray(x, 1)));
        assert_eq!(t0, t1);
        assert!(
            (sum(&l1) - sum(&l0)).abs() <= 1e-5 * sum(&l0).max(1e-30),
            "x {x}: {} vs {}",
            sum(&l1),
            sum(&l0)
        );
    }
    // Through the flame alone (no smoke): it emits, absorbing nothing; without the grid, nothing is there.
    let (lf, tf) = run(&flame, &ray(0.7, 1));
    let (lp, tp) = run(&plain, &ray(0.7, 1));
    // (The smoke's Gaussian tail, 5σ away, absorbs 2e-5 there and emits as little.)
    assert!(
        sum(&lf) > 0.0 && tf.iter().all(|&x| x > 0.9999),
        "{} {:?}",
        sum(&lf),
        &tf[..3]
    );
    assert!(sum(&lp) < 1e-3 * sum(&lf) && tp.iter().all(|&x| x > 0.9999));
    // Through the smoke alone: only the flame's far tail emits — absorption without emission.
    let (ls, ts) = run(&flame, &ray(0.3, 1));
    assert!(
        sum(&ls) < 1e-5 * sum(&lf) && ts[0] < 0.9,
        "{} {}",
        sum(&ls),
        ts[0]
    );
    // Ratio tracking through the smokeless flame: collisions over the floor majorant find its emission.
    let k = 4000;
    let (mut m, mut m2) = (0.0, 0.0);
    for s in 0..k {
        let v = sum(&run(&ratio, &ray(0.7, s)).0);
        m += v;
        m2 += v * v;
    }
    let mean = m / k as f64;
    let se = ((m2 / k as f64 - mean * mean) / k as f64).sqrt();
    assert!(
        (mean - sum(&lf)).abs() < 4.0 * se + 1e-3 * sum(&lf),
        "{mean} ± {se} vs {}",
        sum(&lf)
    );
}

/// The scatter colour grid (Houdini's `Cd`) tints what scatters and absorbs the rest: white changes nothing,
/// black removes scattering, red keeps the long wavelengths' — and σ_t never moves.
#[test]
fn a_scatter_colour_grid_tints_the_albedo_and_keeps_extinction() {
    let n = 8usize;
    let d = vec![2e-6f32; n * n * n];
    let t = vec![1500f32; n * n * n];
    let dir = std::env::temp_dir().join(format!("firemedium-cd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, rgb: [f32; 3]| {
        let [r, g, b] = rgb.map(|v| vec![v; n * n * n]);
        let bytes = crate::dataset::vdb::write_with_vectors(
            &[("density", [n; 3], &d), ("temperature", [n; 3], &t)],
            &[("Cd", [n; 3], [&r, &g, &b])],
            DVec3::ZERO,
            DVec3::splat(0.1),
        );
        let f = dir.join(format!("{name}.vdb"));
        std::fs::write(&f, bytes).unwrap();
        f
    };
    let coef = |file: &std::path::Path, cd: bool| {
        let mut list = vec![
            Param::string("filename", &file.display().to_string()),
            Param::floats("sigma_s", &[3.0]),
        ];
        if cd {
            list.push(Param::string("scattercolorgrid", "Cd"));
        }
        let v = FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}"));
        let c = v.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        v.coefficients(DVec3::splat(0.4), &mut sa, &mut ss, &mut j);
        (sa, ss, j)
    };
    let white = write("white", [1.0; 3]);
    let (sa0, ss0, j0) = coef(&white, false);
    assert!(ss0.iter().all(|&s| s > 0.0));
    let (sa, ss, j) = coef(&white, true);
    for c in 0..sa.len() {
        assert!(
            (sa[c] - sa0[c]).abs() <= 1e-12 * sa0[c],
            "bin {c}: white changes σ_a"
        );
        assert!(
            (ss[c] - ss0[c]).abs() <= 1e-12 * ss0[c],
            "bin {c}: white changes σ_s"
        );
    }
    assert_eq!(j, j0, "the colour never touches emission");
    let (sa, ss, _) = coef(&write("black", [0.0; 3]), true);
    for c in 0..sa.len() {
        assert_eq!(ss[c], 0.0);
        assert!(
            (sa[c] - (sa0[c] + ss0[c])).abs() <= 1e-12 * sa[c],
            "bin {c}: σ_t kept"
        );
    }
    let (sa, ss, _) = coef(&write("red", [1.0, 0.0, 0.0]), true);
    // (The default 32 bins over 400–780 nm: bin 21 holds 650 nm, bin 0 400 nm.)
    assert!(ss[21] > 0.9 * ss0[21] && ss[0] < 0.2 * ss0[0], "{ss:?}");
    for c in 0..sa.len() {
        assert!((sa[c] + ss[c] - sa0[c] - ss0[c]).abs() <= 1e-12 * (sa0[c] + ss0[c]));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The blue core (Selle): a thin spherical shell of reaction emits only its chemiluminescence, and a ray sees it
/// in proportion to its path through the shell — brightest towards grazing incidence, by Selle's chord-length
/// factor r/√(r² − b²) for a thin shell. The shell here is smooth (a Gaussian of heat release across the radius,
/// σ 1.5 voxels, so the grid samples it well); the reference is its analytic profile integrated along each ray
/// (and, thin-shell limit, the chord factor). Its light is the CH*/C₂* bands (blue), it absorbs nothing, and its
/// size is the yield times the heat release over 4π.
#[test]
fn a_reaction_shell_glows_blue_brightest_at_grazing() {
    let n = 96usize;
    let h = 0.01;
    let c = 0.48;
    let (rm, w) = (0.27, 0.015);
    let q = 1e6; // W/m³ of heat release at the shell's middle
    let profile = |r: f64| q * (-0.5 * ((r - rm) / w).powi(2)).exp();
    let mut react = vec![0f32; n * n * n];
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = DVec3::new(i as f64, j as f64, k as f64) * h + h / 2.0 - DVec3::splat(c);
                let v = profile(p.length());
                react[i + n * (j + n * k)] = if v > 1e-6 * q { v as f32 } else { 0.0 };
            }
        }
    }
    let zero = vec![0f32; n * n * n];
    let bytes = crate::dataset::vdb::write(
        &[("density", [n; 3], &zero), ("reaction", [n; 3], &react)],
        DVec3::ZERO,
        DVec3::splat(h),
    );
    let dir = std::env::temp_dir().join(format!("firemedium-bluecore-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("shell.vdb");
    std::fs::write(&file, bytes).unwrap();
    let v = FireVolume::new(&[
        Param::string("filename", &file.display().to_string()),
        Param::string("temperaturegrid", ""),
        Param::string("reactiongrid", "reaction"),
        Param::float("chemiluminescence", 1e-4),
        Param::float("stepsize", 0.25),
    ])
    .unwrap_or_else(|e| panic!("{e}"));
    std::fs::remove_dir_all(&dir).unwrap();
    // ∫ profile ds along the ray at impact parameter b (midpoints of 1e-5 m).
    let path = |b: f64| {
        let ds = 1e-5;
        (0..100_000)
            .map(|i| {
                let s = -0.5 + (i as f64 + 0.5) * ds;
                profile((s * s + b * b).sqrt())
            })
            .sum::<f64>()
            * ds
    };
    let total = |b: f64| {
        let ray = Ray {
            o: DVec3::new(-1.0, c + b, c),
            d: DVec3::X,
            t0: 0.0,
            t1: 5.0,
            seed: 3,
            first: None,
        };
        let (l, t) = run(&v, &ray);
        assert!(t.iter().all(|&x| x == 1.0), "the shell absorbs nothing");
        // (Radiance per nm over the render's bins: their widths sum it.)
        let width = (780.0 - 400.0) / l.len() as f64;
        (l.iter().sum::<f64>() * width, l)
    };
    // Absolute, through the centre: yield / 4π · ∫ q ds — the band spectrum lies inside 400–780 nm.
    let (l0, spectrum) = total(0.0);
    let want = 1e-4 / (4.0 * std::f64::consts::PI) * path(0.0);
    // (1.8 % measured: the grid's trilinear samples of a curved 1.5-voxel profile, between voxel centres.)
    assert!((l0 / want - 1.0).abs() < 0.03, "centre: {l0} vs {want}");
    // Blue: the CH* bin (431 nm) is the brightest, and nothing beyond the Swan bands (above 570 nm).
    let bin = |nm: f64| ((nm - 400.0) / (380.0 / spectrum.len() as f64)) as usize;
    let brightest = (0..spectrum.len())
        .max_by(|&a, &b| spectrum[a].total_cmp(&spectrum[b]))
        .unwrap();
    assert_eq!(brightest, bin(431.4));
    assert!(spectrum[bin(600.0)..]
        .iter()
        .all(|&x| x < 1e-6 * spectrum[brightest]));
    // Towards grazing: the profile's own path integral to 1 %, and Selle's chord factor r/√(r² − b²) while the
    // shell is thin against r − b.
    for b in [0.1, 0.2, 0.24] {
        let (l, _) = total(b);
        let got = l / l0;
        let want = path(b) / path(0.0);
        assert!((got / want - 1.0).abs() < 0.01, "b {b}: {got} vs {want}");
        if b <= 0.2 {
            let chord = rm / (rm * rm - b * b).sqrt();
            assert!(
                (got / chord - 1.0).abs() < 0.03,
                "b {b}: {got} vs chord factor {chord}"
            );
        }
    }
    assert!(path(0.24) / path(0.0) > 2.0);
}

/// A look's scattering is per unit of soot: on a simulator's density (a soot scale far from 1) the smoke keeps
/// the look's albedo, where a σ_s per unit density made it millions of times too thick (a Houdini plume with the
/// campfire look hit the collision cap on every ray).
#[test]
fn a_looks_scattering_follows_the_soot_whatever_the_densitys_unit() {
    let p = DVec3::splat(0.5);
    let coef = |d: f64, extra: Vec<Param>| {
        let v = slab_volume(d, 1600.0, extra);
        let c = v.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        v.coefficients(p, &mut sa, &mut ss, &mut j);
        (sa, ss)
    };
    let look = || Param::string("look", "campfire");
    // A volume fraction of 2e-6, as it is and as a simulator's density of 20 with sootscale 1e-7.
    let (sa, ss) = coef(2e-6, vec![look()]);
    let (sa_sim, ss_sim) = coef(20.0, vec![look(), Param::float("sootscale", 1e-7)]);
    for c in 0..sa.len() {
        assert!(
            (sa_sim[c] / sa[c] - 1.0).abs() < 1e-6,
            "absorption, bin {c}: {} against {}",
            sa_sim[c],
            sa[c]
        );
        assert!(
            (ss_sim[c] / ss[c] - 1.0).abs() < 1e-6,
            "scattering, bin {c}: {} against {}",
            ss_sim[c],
            ss[c]
        );
        // The look's albedo: σ_s = 2e6 · f_v against the soot's absorption.
        assert!(
            (ss[c] / (2e6 * 2e-6) - 1.0).abs() < 1e-6,
            "bin {c}: {}",
            ss[c]
        );
        let albedo = ss[c] / (sa[c] + ss[c]);
        assert!((0.05..0.4).contains(&albedo), "bin {c}: albedo {albedo}");
    }
    // The scene's own sigma_s (per unit density) replaces the look's; both given by the scene: refused.
    let (_, own) = coef(
        20.0,
        vec![
            look(),
            Param::float("sootscale", 1e-7),
            Param::floats("sigma_s", &[0.1]),
        ],
    );
    assert!(own.iter().all(|&v| (v - 2.0).abs() < 1e-12), "{own:?}");
    let both = FireVolume::new(&thesis_bins(vec![
        Param::floats("density", &[1e-6]),
        Param::floats("temperature", &[1500.0]),
        Param::float("sootscatter", 2e6),
        Param::floats("sigma_s", &[1.0]),
    ]));
    let Err(e) = both else {
        panic!("sootscatter with sigma_s is refused")
    };
    let e = e.to_string();
    assert!(e.contains("sootscatter") && e.contains("sigma_s"), "{e}");
}
