//! A small deterministic generator (SplitMix64) for per-ray random numbers: each ray carries a seed, so results
//! do not depend on threads, batch sizes or call order.

/// SplitMix64 (Steele, Lea & Flood 2014).
#[derive(Debug, Clone)]
pub struct Rng(u64, Option<f64>);

impl Rng {
    /// A stream from `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x5851_F42D_4C95_7F2D, None)
    }
    /// The stream from `seed` whose first uniform number is `first` (a host's own sample, in [0, 1)) instead of
    /// the stream's: the next ones are the stream's own from its start.
    pub fn starting(seed: u64, first: Option<f64>) -> Rng {
        Rng(seed ^ 0x5851_F42D_4C95_7F2D, first)
    }
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        if let Some(u) = self.1.take() {
            return u;
        }
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_given_first_number_comes_first_then_the_stream() {
        let mut own = Rng::new(9);
        let mut given = Rng::starting(9, Some(0.25));
        assert_eq!(given.next_f64(), 0.25);
        for _ in 0..4 {
            assert_eq!(given.next_f64(), own.next_f64());
        }
        let (mut a, mut b) = (Rng::new(3), Rng::starting(3, None));
        assert_eq!(a.next_f64(), b.next_f64());
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut r = Rng::new(1);
        let n = 100_000;
        let s: f64 = (0..n)
            .map(|_| r.next_f64())
            .inspect(|&x| assert!((0.0..1.0).contains(&x)))
            .sum();
        // Mean 1/2, σ of the mean = 1/√(12 n) ≈ 9.1e-4: within 4σ.
        assert!((s / n as f64 - 0.5).abs() < 4.0 * (1.0 / (12.0 * n as f64)).sqrt());
        assert_ne!(Rng::new(1).next_u64(), Rng::new(2).next_u64());
    }
}
