//! The error metrics of DESIGN.md, the same everywhere (`compare`, the benchmarks, the tests): relative RMSE
//! and relMSE of an image against a reference, over luminance.

/// Luminance Y of linear sRGB (the Y row of the sRGB → XYZ matrix, IEC 61966-2-1), relative to the pixel values.
pub fn luminance(p: [f32; 3]) -> f64 {
    0.2126729 * p[0] as f64 + 0.7151522 * p[1] as f64 + 0.0721750 * p[2] as f64
}

/// The error metrics of DESIGN.md, of image `a` against the reference `r` (the same pixels): relative RMSE
/// √mean((a − r)²) / √mean(r²), and relMSE mean((a − r)² / (r² + 0.01·mean(r)²)). (Until session 5 the RMSE
/// was divided by mean(r) instead, smaller by √mean(r²)/mean(r): 4.59 on the perf workload's image, 4.62 on
/// error-vs-time's — a compact fire on black.)
pub fn errors(a: &[f64], r: &[f64]) -> (f64, f64) {
    let n = r.len().max(1) as f64;
    let mean = r.iter().sum::<f64>() / n;
    let ms = r.iter().map(|y| y * y).sum::<f64>() / n;
    let mse = a.iter().zip(r).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / n;
    // (A pixel equal to the reference adds 0, also where the reference is black everywhere.)
    let rel_mse = a
        .iter()
        .zip(r)
        .map(|(x, y)| match (x - y).powi(2) {
            0.0 => 0.0,
            d2 => d2 / (y * y + 0.01 * mean * mean),
        })
        .sum::<f64>()
        / n;
    (if ms > 0.0 { (mse / ms).sqrt() } else { 0.0 }, rel_mse)
}

/// [`errors`] of `a` against a reference that is the mean of two independent renders `half` (`r` = their
/// mean), with the reference's own noise taken out: per pixel E[(a − r)²] = MSE(a) + Var(r), and (h₁ − h₂)²/4
/// estimates Var(r) without bias, so both sums lose it (floored at 0). Against a reference a few times less
/// noisy than the image, the raw error counts the reference's noise as the image's.
pub fn errors_debiased(a: &[f64], r: &[f64], half: [&[f64]; 2]) -> (f64, f64) {
    let n = r.len().max(1) as f64;
    let mean = r.iter().sum::<f64>() / n;
    let ms = r.iter().map(|y| y * y).sum::<f64>() / n;
    let var = |k: usize| (half[0][k] - half[1][k]).powi(2) / 4.0;
    let mse = (0..r.len())
        .map(|k| (a[k] - r[k]).powi(2) - var(k))
        .sum::<f64>()
        / n;
    let rel_mse = (0..r.len())
        .map(|k| ((a[k] - r[k]).powi(2) - var(k)) / (r[k] * r[k] + 0.01 * mean * mean))
        .sum::<f64>()
        / n;
    (
        if ms > 0.0 {
            (mse.max(0.0) / ms).sqrt()
        } else {
            0.0
        },
        rel_mse.max(0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_references_noise_is_taken_out() {
        // Halves (1, 3.2) and (1.2, 2.8): r = (1.1, 3), Var(r) ≈ ((0.2)², (0.4)²)/4 = (0.01, 0.04). An image
        // a = (1.3, 3.3): (a − r)² = (0.04, 0.09), less the reference's (0.03, 0.05): mean 0.04; mean r² =
        // (1.21 + 9)/2 = 5.105. relMSE: ε = 0.01·2.05² = 0.042025.
        let (h1, h2) = ([1.0, 3.2], [1.2, 2.8]);
        let (rmse, rel) = errors_debiased(&[1.3, 3.3], &[1.1, 3.0], [&h1, &h2]);
        assert!((rmse - (0.04f64 / 5.105).sqrt()).abs() < 1e-12, "{rmse}");
        let eps = 0.01 * 2.05f64.powi(2);
        let want = (0.03 / (1.21 + eps) + 0.05 / (9.0 + eps)) / 2.0;
        assert!((rel - want).abs() < 1e-12, "{rel} vs {want}");
        // An image as close as the reference's own noise: no error left (not negative).
        assert_eq!(
            errors_debiased(&[1.1, 3.0], &[1.1, 3.0], [&h1, &h2]),
            (0.0, 0.0)
        );
        // Identical halves (no noise): the raw errors.
        let same = [1.1, 3.0];
        let raw = errors(&[1.3, 3.3], &same);
        let deb = errors_debiased(&[1.3, 3.3], &same, [&same, &same]);
        assert!((raw.0 - deb.0).abs() < 1e-15 && (raw.1 - deb.1).abs() < 1e-15);
    }

    #[test]
    fn relative_rmse_and_relmse_are_designs() {
        // r = (1, 3, 0), a = (1, 3.1, 0.2): mean (a − r)² = 0.05/3, mean r² = 10/3, so rel. RMSE = √0.005;
        // relMSE = (0.01/(9 + ε) + 0.04/ε) / 3 with ε = 0.01·mean(r)² = 0.01·(4/3)².
        let (rmse, rel) = errors(&[1.0, 3.1, 0.2], &[1.0, 3.0, 0.0]);
        assert!((rmse - 0.005f64.sqrt()).abs() < 1e-15, "{rmse}");
        let eps = 0.01 * (4.0f64 / 3.0).powi(2);
        let want = (0.01 / (9.0 + eps) + 0.04 / eps) / 3.0;
        assert!((rel - want).abs() < 1e-12, "{rel} vs {want}");
        assert_eq!(errors(&[0.0, 0.0], &[0.0, 0.0]), (0.0, 0.0));
        assert_eq!(errors(&[1.0, 0.0], &[0.0, 0.0]).1, f64::INFINITY);
    }

    #[test]
    fn luminance_is_the_srgb_y_row() {
        // A grey's luminance is its value (the row sums to 1); pure green holds 71.5 % of white's.
        assert!((luminance([0.5, 0.5, 0.5]) - 0.5).abs() < 1e-7);
        assert!((luminance([0.0, 1.0, 0.0]) - 0.7151522).abs() < 1e-12);
    }
}
