//! Atomic lines: thick sodium against line by line, line reversal, rgb against spectral lines, a line's own colour in the light, and the tables' budget.

use super::*;

#[test]
fn thick_sodium_follows_the_line_by_line_curve_of_growth() {
    // Na D (589.16 and 589.76 nm, in the 580–590 nm bin; D1's wing reaches into 590–600) at 2000 K through 1 m
    // at N·L from 1e14 to 1e20 m⁻² (the 1e16–1e20 m⁻³ over 1 cm–1 m: only N·L matters in a homogeneous
    // slab): the Voigt model within 1 % of a line-by-line integration in both bins' radiance and transmittance
    // deficit 1 − T. The paper's box is right while thin and far too bright once thick.
    let dir = std::env::temp_dir().join(format!("firemedium-voigt-{}", std::process::id()));
    let t = 2000.0;
    for n in [1e14, 1e16, 1e18, 1e20] {
        let voigt = sodium_slab(&dir, n, t, 0.0, vec![]);
        let boxed = sodium_slab(&dir, n, t, 0.0, vec![Param::string("lineshape", "box")]);
        let (l, tr) = run(&voigt, &ray_x(0));
        let (lb, _) = run(&boxed, &ray_x(0));
        for (bin, lo) in [(18, 580.0), (19, 590.0)] {
            let (want_l, want_t) = sodium_line_by_line(n, t, 1.0, lo);
            let rel_l = l[bin] / want_l - 1.0;
            let rel_a = (1.0 - tr[bin]) / (1.0 - want_t) - 1.0;
            eprintln!(
                "N·L {n:e} bin {bin}: LBL L {want_l:.4e} T {want_t:.6}; voigt {:.4e} ({rel_l:+.2e}), 1−T {rel_a:+.2e}; box {:.4e} ({:.2}×)",
                l[bin],
                lb[bin],
                lb[bin] / want_l
            );
            // (Bin 19 holds only D1's wing: 1 % of a thin line's light, which f32 tables hold to 1e-3.)
            let tol = if bin == 19 && n < 1e16 { 0.03 } else { 0.01 };
            assert!(
                rel_l.abs() < tol,
                "N·L {n:e} bin {bin}: L {} vs {want_l}",
                l[bin]
            );
            assert!(
                rel_a.abs() < tol,
                "N·L {n:e} bin {bin}: T {} vs {want_t}",
                tr[bin]
            );
        }
        if n >= 1e18 {
            assert!(lb[18] > 5.0 * l[18], "box {} vs {}", lb[18], l[18]);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn cold_sodium_in_front_of_hot_reverses_the_line_as_line_by_line() {
    // Self-reversal: 0.5 m of sodium at 1200 K in front of 0.5 m at 2200 K, 1e18 m⁻³. Per wavelength the cold
    // layer absorbs the hot layer's line core and emits little: L(λ) = B₁(1 − T₁(λ)) + T₁(λ) B₂(1 − T₂(λ)),
    // integrated over the 580–590 nm bin on a 2e-5 nm grid (the Voigt widths and populations at each layer's
    // temperature) — the nodes' transfer within 1 %. The box model cannot see the reversal: it absorbs the
    // hot line with the cold line's bin-mean σ, far too little where the line is thick and too much in the
    // wings.
    let dir = std::env::temp_dir().join(format!("firemedium-reversal-{}", std::process::id()));
    let (t1, t2, n) = (1200.0, 2200.0, 1e18);
    let (k1, k2) = (sodium_d_kappa(t1), sodium_d_kappa(t2));
    let steps = 500_000;
    let h = 10.0 / steps as f64;
    let (mut want_l, mut want_t) = (0.0, 0.0);
    for i in 0..steps {
        let lam = 580.0 + (i as f64 + 0.5) * h;
        let (tr1, tr2) = ((-0.5 * n * k1(lam)).exp(), (-0.5 * n * k2(lam)).exp());
        want_l += (spectral_radiance(t1, lam) * (1.0 - tr1)
            + tr1 * spectral_radiance(t2, lam) * (1.0 - tr2))
            * h
            / 10.0;
        want_t += tr1 * tr2 * h / 10.0;
    }
    let v = sodium_layers(&dir, n, [t1, t2], 0.0, vec![]);
    let (l, t) = run(&v, &ray_x(0));
    let (hot, _) = run(&sodium_slab(&dir, n, t2, 0.0, vec![]), &ray_x(0));
    let boxed = sodium_layers(
        &dir,
        n,
        [t1, t2],
        0.0,
        vec![Param::string("lineshape", "box")],
    );
    let (lb, _) = run(&boxed, &ray_x(0));
    std::fs::remove_dir_all(&dir).ok();
    assert!(
        (l[18] / want_l - 1.0).abs() < 0.01 && ((1.0 - t[18]) / (1.0 - want_t) - 1.0).abs() < 0.01,
        "L {} vs {want_l}, T {} vs {want_t} (box {})",
        l[18],
        t[18],
        lb[18]
    );
    // The cold layer takes most of the hot line's light (a metre of hot sodium alone is far brighter), and the
    // box misses the reversal by a wide margin.
    assert!(l[18] < 0.6 * hot[18], "{} vs hot alone {}", l[18], hot[18]);
    assert!(lb[18] > 2.0 * want_l, "box {} vs {want_l}", lb[18]);
}

#[test]
fn rgb_lines_agree_with_spectral_lines() {
    // The same thick sodium slab (2000 K, 1e18 m⁻³ over 1 m, and with soot) in 30 spectral bins and in rgb: both
    // see line light at its own wavelength's colour (spectral: `linecolour "ownwavelength"`, the default),
    // within 1 % (as bin means — `binmean` — the spectral bins gave 580–590 nm's mean ȳ, 0.815 against
    // ȳ(589.3 nm) = 0.77: 6 % apart).
    let dir = std::env::temp_dir().join(format!("firemedium-rgblines-{}", std::process::id()));
    for fv in [0.0, 1e-7] {
        let own = vec![Param::string("linecolour", "ownwavelength")];
        let spectral = sodium_slab(&dir, 1e18, 2000.0, fv, own);
        let rgb = sodium_slab(
            &dir,
            1e18,
            2000.0,
            fv,
            vec![Param::string("colormode", "rgb")],
        );
        let (ls, _) = run(&spectral, &ray_x(0));
        let (lr, _) = run(&rgb, &ray_x(0));
        let xyz = spectral.channel_xyz();
        let ys: f64 = ls.iter().zip(&xyz).map(|(l, w)| l * w.y).sum();
        let yr = lr[1] * rgb.channel_xyz()[1].y;
        eprintln!(
            "fv {fv:e}: Y spectral {ys:.5e}, rgb {yr:.5e} ({:+.3})",
            yr / ys - 1.0
        );
        assert!(
            ys > 0.0 && (yr / ys - 1.0).abs() < 0.01,
            "fv {fv:e}: rgb Y {yr} vs spectral {ys}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn line_light_takes_its_own_wavelengths_colour() {
    // Na D at 2000 K through 1 m, thin to thick: the film's XYZ from the 30 bins (Σ L_c w_c) against 683 ∫ L(λ)
    // x̄ȳz̄(λ) dλ line by line (570–610 nm on a 4e-5 nm grid). Shared with a neighbour bin (the default), the
    // luminance is within 1 % and the chromaticity within 0.004; as bin means it is +7 % and 0.04 off while
    // thin.
    let dir = std::env::temp_dir().join(format!("firemedium-linecolour-{}", std::process::id()));
    let t = 2000.0;
    let kappa = sodium_d_kappa(t);
    let xy = |v: DVec3| (v.x / v.element_sum(), v.y / v.element_sum());
    for n in [1e14, 1e17, 1e20] {
        let steps = 1_000_000;
        let h = 40.0 / steps as f64;
        let mut want = DVec3::ZERO;
        for i in 0..steps {
            let lam = 570.0 + (i as f64 + 0.5) * h;
            let l = spectral_radiance(t, lam) * -(-n * kappa(lam)).exp_m1();
            want += crate::cie::cmf(lam) * (683.0 * l * h);
        }
        for (colour, tol_y, tol_xy) in [("ownwavelength", 0.01, 0.004), ("binmean", 1.0, 1.0)] {
            let v = sodium_slab(&dir, n, t, 0.0, vec![Param::string("linecolour", colour)]);
            let (l, _) = run(&v, &ray_x(0));
            let got: DVec3 = l.iter().zip(v.channel_xyz()).map(|(l, w)| w * *l).sum();
            let (dy, (gx, gy), (wx, wy)) = (got.y / want.y - 1.0, xy(got), xy(want));
            let dxy = ((gx - wx).powi(2) + (gy - wy).powi(2)).sqrt();
            eprintln!("N·L {n:e} {colour}: Y {dy:+.4}, xy ({gx:.4}, {gy:.4}) vs ({wx:.4}, {wy:.4}): {dxy:.4}");
            assert!(
                dy.abs() < tol_y && dxy < tol_xy,
                "{colour} N·L {n:e}: Y {dy:+}, xy {dxy}"
            );
            if colour == "binmean" && n < 1e15 {
                // The error the split removes (the regression this test guards).
                assert!(dy > 0.05 && dxy > 0.02, "bin means: Y {dy:+}, xy {dxy}");
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn thick_line_tables_beyond_the_memory_budget_are_an_error_before_they_are_built() {
    // Two thick D lines at 2000 K want ~1.9 MB of tables: 1 MB beyond the temperature tables' share of the budget
    // refuses them by name, with the way out.
    let dir = std::env::temp_dir().join(format!("firemedium-linebudget-{}", std::process::id()));
    let list = |maxbytes: f64| {
        let extra = vec![Param::float("maxbytes", maxbytes)];
        sodium_params(&dir, 1e18, [2000.0; 2], 0.0, extra)
    };
    let tables = super::super::tables::bytes_for(2000.0, 30, 1, false) as f64;
    let e = FireVolume::new(&list(tables + 1e6))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("lineshape") && e.contains("\"box\"") && e.contains("MB"),
        "{e}"
    );
    assert!(FireVolume::new(&list(1e8)).is_ok());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_dense_sodium_slab_holds_its_wings_and_kirchhoff() {
    // Na D at 2000 K through 1 m at N·L 1e22–1e25 m⁻², where the collisional wings are thick tens of nm out:
    // each of the eight bins 550–630 nm against the line-by-line integration of the D lines — radiance and
    // absorption within 1 % of the bin's Planck mean plus 1 % of the reference (and so Kirchhoff: an opaque
    // bin emits B). Measured: every bin within 2.2 % of its reference from 1e23 (0.1 % at 1e24–1e25); at 1e22 the
    // bins 30–40 nm out, at 1−T 1.3 %, −33 % of their little light (0.4 % of B). With windows fixed at ±20 nm
    // (before): at 1e24 the bins 560–570 and 610–620 nm, 92 % and 90 % opaque, rendered 89 % and 99 % too dark.
    let dir = std::env::temp_dir().join(format!("firemedium-wings-{}", std::process::id()));
    let t = 2000.0;
    for n in [1e22, 1e24, 1e25] {
        let v = sodium_slab(&dir, n, t, 0.0, vec![]);
        let (l, tr) = run(&v, &ray_x(0));
        for bin in 15..23 {
            let lo = 400.0 + 10.0 * bin as f64;
            let (want_l, want_t) = sodium_line_by_line(n, t, 1.0, lo);
            let planck = (0..100)
                .map(|i| crate::blackbody::spectral_radiance(t, lo + 0.1 * (i as f64 + 0.5)))
                .sum::<f64>()
                / 100.0;
            let (dl, da) = (l[bin] - want_l, (1.0 - tr[bin]) - (1.0 - want_t));
            assert!(
                dl.abs() < 0.01 * planck + 0.01 * want_l && da.abs() < 0.01 + 0.01 * (1.0 - want_t),
                "N·L {n:e} bin {bin}: L {} vs {want_l} (B {planck}), 1−T {} vs {}",
                l[bin],
                1.0 - tr[bin],
                1.0 - want_t
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
