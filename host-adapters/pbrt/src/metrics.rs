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

#[cfg(test)]
mod tests {
    use super::*;

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
