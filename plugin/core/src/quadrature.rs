//! Fixed-order Gauss–Legendre quadrature, for integrals over wavelength (bin averages, band integrals).
//!
//! Eight nodes per panel integrate polynomials up to degree 15 exactly; smooth spectra such as Planck's law
//! converge to machine precision with a handful of panels per decade.

/// Nodes (on [-1, 1]) and weights of the 8-point Gauss–Legendre rule (Abramowitz & Stegun, table 25.4).
const GL8: [(f64, f64); 8] = [
    (-0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
    (-0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (-0.525_532_409_916_329_0, 0.313_706_645_877_887_3),
    (-0.183_434_642_495_649_8, 0.362_683_783_378_362_0),
    (0.183_434_642_495_649_8, 0.362_683_783_378_362_0),
    (0.525_532_409_916_329_0, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// ∫ₐᵇ f(x) dx with `panels` equal panels of the 8-point Gauss–Legendre rule (`panels` ≥ 1).
pub fn gauss_legendre(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
    let panels = panels.max(1);
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * h;
        let half = 0.5 * h;
        sum += GL8.iter().map(|&(x, w)| w * f(mid + half * x)).sum::<f64>() * half;
    }
    sum
}

/// The nodes and weights of [`gauss_legendre`] over [a, b]: Σ w·f(x) is the same integral (for integrands
/// evaluated once and reused, e.g. across the rows of a temperature table).
pub fn gauss_legendre_nodes(a: f64, b: f64, panels: usize) -> Vec<(f64, f64)> {
    let panels = panels.max(1);
    let h = (b - a) / panels as f64;
    let half = 0.5 * h;
    (0..panels)
        .flat_map(|p| {
            let mid = a + (p as f64 + 0.5) * h;
            GL8.iter().map(move |&(x, w)| (mid + half * x, w * half))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_give_the_same_integral() {
        let f = |x: f64| (x * 0.3).exp() / (1.0 + x * x);
        let by_nodes: f64 = gauss_legendre_nodes(400.0, 410.0, 4)
            .iter()
            .map(|&(x, w)| w * f(x))
            .sum();
        let direct = gauss_legendre(f, 400.0, 410.0, 4);
        assert!(
            (by_nodes - direct).abs() <= 1e-14 * direct.abs(),
            "{by_nodes} vs {direct}"
        );
    }

    #[test]
    fn exact_for_degree_15() {
        // ∫₀¹ x¹⁵ dx = 1/16 exactly for an 8-point rule on one panel.
        let v = gauss_legendre(|x| x.powi(15), 0.0, 1.0, 1);
        assert!((v - 1.0 / 16.0).abs() < 1e-15, "{v}");
        let w: f64 = GL8.iter().map(|p| p.1).sum();
        assert!((w - 2.0).abs() < 1e-15);
    }

    #[test]
    fn converges_on_smooth_function() {
        // ∫₀^π sin = 2.
        let v = gauss_legendre(f64::sin, 0.0, std::f64::consts::PI, 4);
        assert!((v - 2.0).abs() < 1e-14, "{v}");
    }
}
