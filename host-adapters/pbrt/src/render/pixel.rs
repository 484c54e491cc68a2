//! Where a pixel's samples fall on the film, the numbers each sample's path draws, and what a sample weighs:
//! pbrt-v4's samplers (`src/pbrt/samplers.h`) and its pixel filters by filter importance sampling
//! (`src/pbrt/filters.h`).
//!
//! **Samples.** A path draws its numbers from a [`Samples`] stream, dimension after dimension (the pixel
//! position first, then the lens, then the integrator's). `independent` draws them at random. `stratified`
//! places the pixel position in `xs` × `ys` strata taken in a per-pixel random order (jittered, or at the
//! strata's centres), the rest at random. The low-discrepancy samplers give the first [`LD_DIMENSIONS`]
//! dimensions from a (0, 2)-sequence in base 2 — the first two dimensions of Sobol's sequence — one pair of
//! dimensions at a time, each pair with its own random permutation of the pixel's sample indices and its own
//! Owen scrambling (Burley 2020's hash-based nested uniform scrambling, pbrt-v4's `FastOwenScrambler`): pbrt-v4's
//! `paddedsobol` (`pmj02bn` renders so too: the same per-pixel stratification). `zsobol`, pbrt-v4's default, runs
//! one Owen-scrambled (0, 2)-sequence over the whole film with the pixels in Morton order and the base-4 digits of
//! each index permuted per dimension (Ahmed & Wonka 2020): a pixel's samples are an aligned block of it, so
//! stratified as `paddedsobol`'s, and neighbouring pixels' samples stratify each other (`sobol` renders as
//! `zsobol`). `halton` gives dimension d < 16 the radical inverse in the d-th prime of the permuted index, its digits
//! scrambled per dimension (the rest at random). Their measured convergence rates are in docs/results/log.md (`convergence` tests).
//!
//! **Filters.** A pixel sample u ∈ [0, 1)² becomes a film offset p = F⁻¹(u) from the pixel's centre, drawn from the
//! filter f itself: `box` and `triangle` exactly (weight 1), `gaussian`, `mitchell` and `sinc` (Lanczos) from
//! a piecewise-constant table of |f| (32 cells per unit of radius, as pbrt-v4's `FilterSampler`) with weight
//! f(p) / pdf(p). The pixel's value is Σ w L / Σ w (pbrt-v4's `RGBFilm`).

use super::distrib::Distribution2D;
use firemedium_core::rng::Rng;

/// How many leading dimensions of a path the low-discrepancy samplers give (the rest are random).
pub const LD_DIMENSIONS: u32 = 64;

/// How sample `s` of a pixel draws its numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sampler {
    /// Uniform random numbers (pbrt-v4's `independent`).
    Independent,
    /// `xs` × `ys` strata of the pixel position, visited in a per-pixel random order; jittered within the stratum
    /// or at its centre.
    Stratified { xs: usize, ys: usize, jitter: bool },
    /// Owen-scrambled Sobol (0, 2)-sequence pairs, padded (pbrt-v4's `paddedsobol`).
    PaddedSobol,
    /// Scrambled radical inverses in the primes.
    Halton,
    /// pbrt-v4's `zsobol` (its default; Ahmed & Wonka 2020): one Owen-scrambled Sobol (0, 2)-sequence over the
    /// whole film, pixels in Morton order, the base-4 digits of each sample's index randomly permuted per
    /// dimension so neighbouring pixels' samples decorrelate. `log2_spp` and `digits` (base-4 digits of the
    /// index) come from the film with [`Sampler::for_film`], `seed` from the render.
    ZSobol {
        log2_spp: u32,
        digits: u32,
        seed: u64,
    },
}

/// The numbers one sample of one pixel draws, dimension by dimension.
#[derive(Debug, Clone)]
pub struct Samples {
    rng: Rng,
    sampler: Sampler,
    /// The pixel's hash, its Morton code (x, y interleaved), the sample's index and the pixel's sample count.
    pixel: u64,
    morton: u64,
    index: u64,
    spp: u64,
    dim: u32,
    /// The sample's time in the shutter (frames; 0 unless the camera drew one): every medium lookup of the
    /// sample's path is at this time.
    pub time: f64,
}

impl Samples {
    /// A key unique to the sample's pixel (its Morton code).
    pub fn pixel_key(&self) -> u64 {
        self.morton
    }
}

impl Sampler {
    /// The stream of sample `s` of `spp` in the pixel hashed `pixel` at film position `xy`, its random part from
    /// `rng`.
    pub fn samples(&self, s: usize, spp: usize, pixel: u64, xy: (u32, u32), rng: Rng) -> Samples {
        Samples {
            rng,
            sampler: *self,
            pixel,
            morton: morton2(xy.0, xy.1),
            index: s as u64,
            spp: spp.max(1) as u64,
            dim: 0,
            time: 0.0,
        }
    }

    /// The sampler for a film of `res` pixels (the full film, not a crop: a cropped render draws the full
    /// render's numbers) with `spp` samples per pixel and the render's seed. Only `zsobol` depends on them.
    pub fn for_film(&self, res: (usize, usize), spp: usize, seed: u64) -> Sampler {
        match self {
            Sampler::ZSobol { .. } => {
                let log2_spp = spp.max(1).next_power_of_two().trailing_zeros();
                let side = res.0.max(res.1).max(1).next_power_of_two().trailing_zeros();
                Sampler::ZSobol {
                    log2_spp,
                    digits: side + log2_spp.div_ceil(2),
                    seed,
                }
            }
            s => *s,
        }
    }
}

/// Bits of x and y interleaved (x in the even bits), 32 bits of each.
fn morton2(x: u32, y: u32) -> u64 {
    let spread = |v: u32| {
        let mut v = v as u64;
        v = (v | (v << 16)) & 0x0000_FFFF_0000_FFFF;
        v = (v | (v << 8)) & 0x00FF_00FF_00FF_00FF;
        v = (v | (v << 4)) & 0x0F0F_0F0F_0F0F_0F0F;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    spread(x) | (spread(y) << 1)
}

/// pbrt-v4's `MixBits` (a 64-bit finaliser).
fn mix_bits(mut v: u64) -> u64 {
    v ^= v >> 31;
    v = v.wrapping_mul(0x7fb5_d329_728e_a185);
    v ^= v >> 27;
    v = v.wrapping_mul(0x81da_def4_bc2d_d44d);
    v ^ (v >> 33)
}

/// The 24 permutations of (0, 1, 2, 3), in lexicographic order.
const PERMUTATIONS4: [[u8; 4]; 24] = {
    let mut out = [[0u8; 4]; 24];
    let mut n = 0;
    let mut a = 0;
    while a < 4 {
        let mut b = 0;
        while b < 4 {
            let mut c = 0;
            while c < 4 {
                let d = 6 - a - b - c;
                if a != b && a != c && b != c {
                    out[n] = [a as u8, b as u8, c as u8, d as u8];
                    n += 1;
                }
                c += 1;
            }
            b += 1;
        }
        a += 1;
    }
    out
};

/// The index into the film-wide Sobol sequence of Morton-ordered sample `morton_index` in dimension `dim`:
/// pbrt-v4's `ZSobolSampler::GetSampleIndex`. Each base-4 digit is permuted by one of the 24 permutations, chosen
/// by a hash of the digits above it and the dimension (a random nested permutation: the points of a pixel stay
/// a scrambled aligned block — a (0, m, 2)-net — while pixels and dimensions decorrelate); with an odd
/// log₂ spp the last digit is binary and flipped by a hashed bit.
fn zsobol_index(morton_index: u64, dim: u64, log2_spp: u32, digits: u32) -> u64 {
    let odd = log2_spp & 1 == 1;
    let last = u32::from(odd);
    let mut index = 0u64;
    for i in (last..digits).rev() {
        let shift = 2 * i - u32::from(odd);
        let digit = (morton_index.checked_shr(shift).unwrap_or(0) & 3) as usize;
        let higher = morton_index.checked_shr(shift + 2).unwrap_or(0);
        let p = ((mix_bits(higher ^ 0x5555_5555u64.wrapping_mul(dim)) >> 24) % 24) as usize;
        index |= (PERMUTATIONS4[p][digit] as u64)
            .checked_shl(shift)
            .unwrap_or(0);
    }
    if odd {
        let digit = morton_index & 1;
        index |= digit ^ (mix_bits((morton_index >> 1) ^ 0x5555_5555u64.wrapping_mul(dim)) & 1);
    }
    index
}

impl Samples {
    /// Random numbers only (paths traced outside a pixel's samples).
    pub fn random(rng: Rng) -> Samples {
        Sampler::Independent.samples(0, 1, 0, (0, 0), rng)
    }

    /// The next number in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        let d = self.dim;
        self.dim = self.dim.saturating_add(1);
        match self.sampler {
            Sampler::Independent => self.rng.next_f64(),
            Sampler::Stratified { xs, ys, jitter } if d < 2 => {
                let n = (xs * ys).max(1);
                let k = permute(self.index as usize % n, n, self.pixel);
                let (cell, count) = if d == 0 {
                    (k % xs.max(1), xs)
                } else {
                    (k / xs.max(1), ys)
                };
                let off = if jitter { self.rng.next_f64() } else { 0.5 };
                (cell as f64 + off) / count.max(1) as f64
            }
            Sampler::Stratified { .. } => self.rng.next_f64(),
            _ if d >= LD_DIMENSIONS => self.rng.next_f64(),
            // (A prime used twice would tie two dimensions to the same digits: Halton stops at its primes.)
            Sampler::Halton if d as usize >= PRIMES.len() => self.rng.next_f64(),
            Sampler::PaddedSobol => {
                // Pair d/2: its own permutation of the pixel's sample indices and its own scrambling per axis.
                let pair = hash2(self.pixel, (d / 2) as u64);
                let i = permute_u64(self.index, self.spp, pair);
                let v = if d % 2 == 0 { sobol0(i) } else { sobol1(i) };
                to_unit(owen_scramble(v, hash2(pair, (d % 2) as u64) as u32))
            }
            Sampler::ZSobol {
                log2_spp,
                digits,
                seed,
            } => {
                // Pair d/2 is pbrt-v4's Get2D at dimension 2·(d/2 + 1): one index per pair, its two axes Sobol's
                // first two dimensions, each Owen-scrambled by half of a hash of the dimension and the seed.
                let dimension = 2 * (d as u64 / 2 + 1);
                // (Shifts past 64 bits, from absurd sample counts, keep the low bits: wrong but finite.)
                let low = 1u64.checked_shl(log2_spp).map_or(u64::MAX, |v| v - 1);
                let morton_index =
                    self.morton.checked_shl(log2_spp).unwrap_or(0) | (self.index & low);
                let i = zsobol_index(morton_index, dimension, log2_spp, digits);
                let bits = hash2(seed, dimension);
                let v = if d % 2 == 0 { sobol0(i) } else { sobol1(i) };
                let scramble = if d % 2 == 0 {
                    bits as u32
                } else {
                    (bits >> 32) as u32
                };
                to_unit(owen_scramble(v, scramble))
            }
            Sampler::Halton => {
                // One index permutation for all dimensions (the points are the sequence's, jointly), digits
                // scrambled per dimension.
                let i = permute_u64(self.index, self.spp, self.pixel);
                let h = hash2(self.pixel, d as u64);
                scrambled_radical_inverse(PRIMES[d as usize], i, h)
            }
        }
    }

    /// 64 random bits (seeds handed to the plugin: never from the low-discrepancy part).
    pub fn next_u64(&mut self) -> u64 {
        self.rng.next_u64()
    }
}

/// A 32-bit fraction to [0, 1) in f64.
fn to_unit(v: u32) -> f64 {
    v as f64 * (1.0 / 4_294_967_296.0)
}

/// SplitMix64's finaliser over two words.
fn hash2(a: u64, b: u64) -> u64 {
    let mut z = a ^ b.wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(17);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Sobol's first dimension (van der Corput in base 2), as 32 bits.
fn sobol0(i: u64) -> u32 {
    (i as u32).reverse_bits()
}

/// Sobol's second dimension (primitive polynomial x + 1, m₁ = 1: direction numbers v_k = v_{k−1} ⊕ (v_{k−1} ≫ 1)).
fn sobol1(i: u64) -> u32 {
    let (mut v, mut x, mut i) = (1u32 << 31, 0u32, i as u32);
    while i != 0 {
        if i & 1 != 0 {
            x ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    x
}

/// Nested uniform (Owen) scrambling of a 32-bit fraction: Burley's hash, bits affected only by higher ones.
fn owen_scramble(v: u32, seed: u32) -> u32 {
    let mut v = v.reverse_bits();
    v ^= v.wrapping_mul(0x3d20_adea);
    v = v.wrapping_add(seed);
    v = v.wrapping_mul((seed >> 16) | 1);
    v ^= v.wrapping_mul(0x0552_6c56);
    v ^= v.wrapping_mul(0x53a2_2864);
    v.reverse_bits()
}

/// The first primes, one base per Halton dimension.
const PRIMES: [u64; 16] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53];

/// The radical inverse of `i` in base `b`, each digit position shifted by its own random offset mod b (a random
/// digit shift keyed by `seed` and the position: every digit, and so the value, uniformly distributed — a
/// permutation family that is not uniform on 0..b biased renders by 2 %).
fn scrambled_radical_inverse(b: u64, mut i: u64, seed: u64) -> f64 {
    let inv = 1.0 / b as f64;
    let (mut out, mut scale) = (0.0, inv);
    let mut k = 0u64;
    // Enough digits for f64, then the tail digits are scrambled too (of index 0) so the result is not on a grid.
    while scale > 1e-17 {
        let digit = i % b;
        let p = ((digit + hash2(seed, k) % b) % b) as f64;
        out += p * scale;
        scale *= inv;
        i /= b;
        k += 1;
    }
    out.min(1.0 - f64::EPSILON)
}

/// Element `i` of a random permutation of 0..n chosen by `seed`.
fn permute_u64(i: u64, n: u64, seed: u64) -> u64 {
    if n <= 1 {
        return 0;
    }
    if n > usize::MAX as u64 {
        return i % n;
    }
    permute((i % n) as usize, n as usize, seed) as u64
}

/// Element `i` of a random permutation of 0..n chosen by `seed` (a bijection: each stratum exactly once per n
/// samples). Cycle-walking over an invertible hash of the next power of two.
fn permute(i: usize, n: usize, seed: u64) -> usize {
    if n <= 1 {
        return 0;
    }
    let bits = usize::BITS - (n - 1).leading_zeros();
    let mask = (1u64 << bits) - 1;
    let mut x = i as u64;
    loop {
        // An invertible mix on `bits` bits: xor-shifts, odd multiplications and xors with the seed, all mod 2^bits.
        for round in 0..3u64 {
            x ^= (seed.rotate_left((round * 21) as u32)) & mask;
            x = x.wrapping_mul(0x9E37_79B9_7F4A_7C15 | 1) & mask;
            x ^= x >> (bits / 2).max(1);
        }
        if (x as usize) < n {
            return x as usize;
        }
    }
}

/// A pbrt-v4 pixel filter, ready to sample.
#[derive(Debug, Clone)]
pub enum Filter {
    /// Constant over [−r, r]² (pbrt-v4's default radius 0.5: the pixel).
    Box { radius: [f64; 2] },
    /// (r − |x|)(r − |y|) over [−r, r]².
    Triangle { radius: [f64; 2] },
    /// Gaussian, Mitchell–Netravali or Lanczos: sampled from a table of |f|.
    Tabulated(Table),
}

/// A filter tabulated for importance sampling: |f| on a grid over [−r, r]², drawn cell by cell.
#[derive(Debug, Clone)]
pub struct Table {
    radius: [f64; 2],
    f: fn(&Params, f64, f64) -> f64,
    params: Params,
    nx: usize,
    ny: usize,
    cells: Distribution2D,
}

/// The parameters of the tabulated filters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    pub radius: [f64; 2],
    /// Gaussian σ.
    pub sigma: f64,
    /// Mitchell's B and C.
    pub b: f64,
    pub c: f64,
    /// Lanczos τ.
    pub tau: f64,
}

fn gaussian(p: &Params, x: f64, y: f64) -> f64 {
    let g = |x: f64, s: f64| {
        (-x * x / (2.0 * s * s)).exp() / (2.0 * std::f64::consts::PI * s * s).sqrt()
    };
    let s = p.sigma;
    (g(x, s) - g(p.radius[0], s)).max(0.0) * (g(y, s) - g(p.radius[1], s)).max(0.0)
}

fn mitchell(p: &Params, x: f64, y: f64) -> f64 {
    let (b, c) = (p.b, p.c);
    let m = |x: f64| {
        let x = x.abs();
        if x <= 1.0 {
            ((12.0 - 9.0 * b - 6.0 * c) * x.powi(3)
                + (-18.0 + 12.0 * b + 6.0 * c) * x * x
                + (6.0 - 2.0 * b))
                / 6.0
        } else if x <= 2.0 {
            ((-b - 6.0 * c) * x.powi(3)
                + (6.0 * b + 30.0 * c) * x * x
                + (-12.0 * b - 48.0 * c) * x
                + (8.0 * b + 24.0 * c))
                / 6.0
        } else {
            0.0
        }
    };
    m(2.0 * x / p.radius[0]) * m(2.0 * y / p.radius[1])
}

fn lanczos(p: &Params, x: f64, y: f64) -> f64 {
    let sinc = |x: f64| {
        if x.abs() < 1e-5 {
            1.0
        } else {
            (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
        }
    };
    let w = |x: f64, r: f64| {
        if x.abs() > r {
            0.0
        } else {
            sinc(x) * sinc(x / p.tau)
        }
    };
    w(x, p.radius[0]) * w(y, p.radius[1])
}

impl Filter {
    /// The filter pbrt-v4 names `ty`, or `None` for a name it does not have.
    pub fn new(ty: &str, p: Params) -> Option<Filter> {
        let f: fn(&Params, f64, f64) -> f64 = match ty {
            "box" => return Some(Filter::Box { radius: p.radius }),
            "triangle" => return Some(Filter::Triangle { radius: p.radius }),
            "gaussian" => gaussian,
            "mitchell" => mitchell,
            "sinc" | "lanczos" => lanczos,
            _ => return None,
        };
        Some(Filter::Tabulated(Table::new(f, p)))
    }

    /// pbrt-v4's default radius of filter `ty` (per axis).
    pub fn default_radius(ty: &str) -> f64 {
        match ty {
            "gaussian" => 1.5,
            "mitchell" | "triangle" => 2.0,
            "sinc" | "lanczos" => 4.0,
            _ => 0.5,
        }
    }

    /// The film offset from the pixel centre for pixel sample `u`, and the sample's weight.
    pub fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        match self {
            Filter::Box { radius } => (
                [
                    (2.0 * u[0] - 1.0) * radius[0],
                    (2.0 * u[1] - 1.0) * radius[1],
                ],
                1.0,
            ),
            Filter::Triangle { radius } => {
                // The tent's inverse CDF on [−1, 1].
                let tent = |u: f64| {
                    if u < 0.5 {
                        -1.0 + (2.0 * u).sqrt()
                    } else {
                        1.0 - (2.0 - 2.0 * u).sqrt()
                    }
                };
                ([tent(u[0]) * radius[0], tent(u[1]) * radius[1]], 1.0)
            }
            Filter::Tabulated(t) => t.sample(u),
        }
    }
}

impl Table {
    fn new(f: fn(&Params, f64, f64) -> f64, params: Params) -> Table {
        let radius = params.radius;
        let nx = ((32.0 * radius[0]).ceil() as usize).clamp(1, 4096);
        let ny = ((32.0 * radius[1]).ceil() as usize).clamp(1, 4096);
        let (cw, ch) = (2.0 * radius[0] / nx as f64, 2.0 * radius[1] / ny as f64);
        let mut weights = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (
                    -radius[0] + (i as f64 + 0.5) * cw,
                    -radius[1] + (j as f64 + 0.5) * ch,
                );
                weights.push(f(&params, x, y).abs());
            }
        }
        Table {
            radius,
            f,
            params,
            nx,
            ny,
            cells: Distribution2D::new(&weights, nx),
        }
    }

    fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        let Some(c) = self.cells.sample(u) else {
            return ([0.0, 0.0], 1.0);
        };
        let (cw, ch) = (
            2.0 * self.radius[0] / self.nx as f64,
            2.0 * self.radius[1] / self.ny as f64,
        );
        let p = [
            -self.radius[0] + (c.x as f64 + c.fx) * cw,
            -self.radius[1] + (c.y as f64 + c.fy) * ch,
        ];
        // pdf(p) = P(cell) / its area; the weight f(p) / pdf(p), up to the constant ∫|f| that Σw L / Σw divides
        // out: f(p) / |f|(cell's centre).
        let centre = c.p * self.cells.total();
        let w = (self.f)(&self.params, p[0], p[1]) / centre.max(1e-300);
        (p, if w.is_finite() { w } else { 0.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(r: f64) -> Params {
        Params {
            radius: [r, r],
            sigma: 0.5,
            b: 1.0 / 3.0,
            c: 1.0 / 3.0,
            tau: 3.0,
        }
    }

    fn first_two(s: &Sampler, k: usize, spp: usize, pixel: u64) -> [f64; 2] {
        let mut st = s.samples(k, spp, pixel, (0, 0), Rng::new(k as u64));
        [st.next_f64(), st.next_f64()]
    }

    #[test]
    fn stratified_samples_cover_each_stratum_once() {
        let s = Sampler::Stratified {
            xs: 3,
            ys: 2,
            jitter: false,
        };
        let mut seen: Vec<[f64; 2]> = (0..6).map(|k| first_two(&s, k, 6, 77)).collect();
        seen.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut all = Vec::new();
        for i in 0..3 {
            for j in [0.25, 0.75] {
                all.push([(i as f64 + 0.5) / 3.0, j]);
            }
        }
        assert_eq!(seen, all);
        // One unjittered sample is the pixel centre.
        let c = Sampler::Stratified {
            xs: 1,
            ys: 1,
            jitter: false,
        };
        assert_eq!(first_two(&c, 0, 1, 5), [0.5, 0.5]);
        for n in [1, 2, 5, 16, 100] {
            let mut p: Vec<usize> = (0..n).map(|i| permute(i, n, 12345)).collect();
            p.sort();
            assert_eq!(p, (0..n).collect::<Vec<_>>());
        }
    }

    #[test]
    fn sobol_pairs_are_02_nets() {
        // Any 2^m consecutive points of the (0, 2)-sequence, scrambled and permuted within the pixel's 2^m
        // samples, put exactly one point in each elementary interval of area 2^-m (here: every 2^a × 2^(m−a) grid).
        // zsobol's pixel holds an aligned block of its film-wide sequence, so the same holds, odd or even log₂ spp.
        let is_net = |pts: &[[f64; 2]], m: u32| {
            (0..=m).all(|a| {
                let (nx, ny) = (1usize << a, 1usize << (m - a));
                let mut cells = vec![0; 1 << m];
                for p in pts {
                    cells[(p[0] * nx as f64) as usize + nx * (p[1] * ny as f64) as usize] += 1;
                }
                cells.iter().all(|&c| c == 1)
            })
        };
        for m in [5u32, 6] {
            let n = 1usize << m;
            let zsobol = Sampler::ZSobol {
                log2_spp: 0,
                digits: 0,
                seed: 0,
            }
            .for_film((40, 30), n, 17);
            for (sampler, xy) in [
                (Sampler::PaddedSobol, (0, 0)),
                (zsobol, (3, 7)),
                (zsobol, (39, 29)),
            ] {
                for dim_pair in [0u32, 5] {
                    let pts: Vec<[f64; 2]> = (0..n)
                        .map(|k| {
                            let mut st = sampler.samples(k, n, 99, xy, Rng::new(1));
                            for _ in 0..2 * dim_pair {
                                st.next_f64();
                            }
                            [st.next_f64(), st.next_f64()]
                        })
                        .collect();
                    assert!(is_net(&pts, m), "{sampler:?} {xy:?}: pair {dim_pair}");
                }
            }
        }
        // Across pixels (zsobol's purpose): one sample in each of a 16 × 16 block of pixels, together, is a net
        // too — neighbouring pixels' samples avoid each other. Padded Sobol's are independent per pixel.
        let zsobol = Sampler::ZSobol {
            log2_spp: 0,
            digits: 0,
            seed: 0,
        }
        .for_film((64, 64), 1, 5);
        for dim_pair in [0u32, 3] {
            let block = |sampler: Sampler| -> Vec<[f64; 2]> {
                (0..256u32)
                    .map(|p| {
                        let (x, y) = (16 + p % 16, 32 + p / 16);
                        let mut st = sampler.samples(
                            0,
                            1,
                            hash2(x as u64, y as u64),
                            (x, y),
                            Rng::new(p as u64),
                        );
                        for _ in 0..2 * dim_pair {
                            st.next_f64();
                        }
                        [st.next_f64(), st.next_f64()]
                    })
                    .collect()
            };
            assert!(is_net(&block(zsobol), 8), "zsobol, pair {dim_pair}");
            assert!(!is_net(&block(Sampler::PaddedSobol), 8));
        }
    }

    #[test]
    fn every_dimension_is_uniform() {
        // Unbiased renders need each dimension uniform over pixels and samples: its mean ½ and second moment ⅓
        // (4 000 pixels × 16 samples: σ of the mean ≈ 1.1e-3). A non-uniform digit scrambling put Halton's mean
        // off by 1e-2 and biased a render by 2 %.
        let zsobol = Sampler::ZSobol {
            log2_spp: 0,
            digits: 0,
            seed: 0,
        }
        .for_film((64, 63), 16, 9);
        for sampler in [
            Sampler::Independent,
            Sampler::PaddedSobol,
            Sampler::Halton,
            zsobol,
        ] {
            for d in [0usize, 1, 2, 3, 7, 15, 16, 40, 63, 64, 70] {
                let (mut m1, mut m2, mut n) = (0.0, 0.0, 0.0);
                for pixel in 0..4000u64 {
                    for k in 0..16 {
                        let mut st = sampler.samples(
                            k,
                            16,
                            hash2(pixel, 3),
                            ((pixel % 64) as u32, (pixel / 64) as u32),
                            Rng::new(pixel * 16 + k as u64),
                        );
                        let v = (0..=d).map(|_| st.next_f64()).last().unwrap();
                        m1 += v;
                        m2 += v * v;
                        n += 1.0;
                    }
                }
                let (m1, m2) = (m1 / n, m2 / n);
                assert!(
                    (m1 - 0.5).abs() < 5e-3 && (m2 - 1.0 / 3.0).abs() < 5e-3,
                    "{sampler:?} dimension {d}: mean {m1}, E[x²] {m2}"
                );
            }
        }
    }

    #[test]
    fn convergence() {
        // RMSE over 64 independent pixels (seeds) of the mean of N samples, N = 16 … 1024, fitted in log–log: the
        // slope is each sampler's convergence rate on a smooth integrand (a 2D Gaussian bump) and a discontinuous
        // one (a quarter disc's indicator). Theory: independent −0.5 on both; jittered strata −1 and −0.75;
        // Owen-scrambled (0, 2)-sequences −1.5 and −0.75; scrambled Halton ≈ −1 on smooth ones.
        let smooth = |x: f64, y: f64| (-((x - 0.4).powi(2) + (y - 0.6).powi(2)) * 8.0).exp();
        let disc = |x: f64, y: f64| if x * x + y * y < 0.6 { 1.0 } else { 0.0 };
        // Exact values by a fine midpoint grid.
        let exact = |f: &dyn Fn(f64, f64) -> f64| {
            let k = 2000;
            (0..k * k)
                .map(|i| {
                    f(
                        ((i % k) as f64 + 0.5) / k as f64,
                        ((i / k) as f64 + 0.5) / k as f64,
                    )
                })
                .sum::<f64>()
                / (k * k) as f64
        };
        let (es, ed) = (exact(&smooth), exact(&disc));
        let rate = |s: &dyn Fn(usize) -> Sampler, f: &dyn Fn(f64, f64) -> f64, e: f64| {
            let ns = [16usize, 64, 256, 1024];
            let mut pts = Vec::new();
            for &n in &ns {
                let mut se = 0.0;
                for pixel in 0..64u64 {
                    let sampler = s(n);
                    let mut sum = 0.0;
                    for k in 0..n {
                        let mut st = sampler.samples(
                            k,
                            n,
                            pixel * 7919 + 13,
                            ((pixel % 8) as u32, (pixel / 8) as u32),
                            Rng::new(pixel * 1000 + k as u64),
                        );
                        let (x, y) = (st.next_f64(), st.next_f64());
                        sum += f(x, y);
                    }
                    se += (sum / n as f64 - e).powi(2);
                }
                pts.push(((n as f64).ln(), (se / 64.0).sqrt().ln()));
            }
            let m = pts.len() as f64;
            let (sx, sy) = (
                pts.iter().map(|p| p.0).sum::<f64>(),
                pts.iter().map(|p| p.1).sum::<f64>(),
            );
            let sxx = pts.iter().map(|p| p.0 * p.0).sum::<f64>();
            let sxy = pts.iter().map(|p| p.0 * p.1).sum::<f64>();
            (m * sxy - sx * sy) / (m * sxx - sx * sx)
        };
        let strat = |n: usize| {
            let side = (n as f64).sqrt() as usize;
            Sampler::Stratified {
                xs: side,
                ys: side,
                jitter: true,
            }
        };
        // (name, the sampler for N samples, the smooth and the discontinuous rate's accepted range)
        type Case<'a> = (
            &'a str,
            &'a dyn Fn(usize) -> Sampler,
            (f64, f64),
            (f64, f64),
        );
        let zsobol = |n: usize| {
            Sampler::ZSobol {
                log2_spp: 0,
                digits: 0,
                seed: 0,
            }
            .for_film((8, 8), n, 3)
        };
        let cases: [Case; 5] = [
            (
                "independent",
                &|_| Sampler::Independent,
                (-0.6, -0.4),
                (-0.6, -0.4),
            ),
            ("stratified", &strat, (-1.15, -0.85), (-0.9, -0.6)),
            (
                "paddedsobol",
                &|_| Sampler::PaddedSobol,
                (-1.8, -1.3),
                (-0.95, -0.6),
            ),
            ("halton", &|_| Sampler::Halton, (-1.3, -0.8), (-0.95, -0.55)),
            ("zsobol", &zsobol, (-1.8, -1.3), (-0.95, -0.6)),
        ];
        for (name, s, want_smooth, want_disc) in cases {
            let (rs, rd) = (rate(s, &smooth, es), rate(s, &disc, ed));
            eprintln!("convergence: {name}: smooth {rs:.2}, discontinuous {rd:.2}");
            assert!(
                (want_smooth.0..want_smooth.1).contains(&rs),
                "{name}: smooth rate {rs}"
            );
            assert!(
                (want_disc.0..want_disc.1).contains(&rd),
                "{name}: discontinuous rate {rd}"
            );
        }
    }

    #[test]
    fn filter_samples_have_the_filters_mean_and_variance() {
        // E[w · x²] / E[w] over evenly spread u is the filter's second moment: box r = 0.5 → 1/12; triangle r = 2 →
        // r²/6 = 2/3; gaussian σ = 0.5 truncated at 1.5 → 0.2454 (of the truncated, shifted Gaussian); the
        // Mitchell filter's weights are negative in its lobes, and its mean weight is positive.
        // The filters are separable: along u₀ with u₁ fixed, the x offsets follow the x marginal.
        let n = 20_000;
        let moment = |f: &Filter| {
            let (mut sw, mut sx2, mut sx) = (0.0, 0.0, 0.0);
            for a in 0..n {
                let (p, w) = f.sample([(a as f64 + 0.5) / n as f64, 0.3]);
                sw += w;
                sx2 += w * p[0] * p[0];
                sx += w * p[0];
            }
            (sx2 / sw, sx / sw)
        };
        let cases: [(&str, f64, f64); 3] = [
            ("box", 0.5, 1.0 / 12.0),
            ("triangle", 2.0, 2.0 / 3.0),
            ("gaussian", 1.5, 0.0),
        ];
        for (ty, r, want) in cases {
            let f = Filter::new(ty, params(r)).unwrap();
            let (m2, m1) = moment(&f);
            assert!(m1.abs() < 1e-3, "{ty}: mean {m1}");
            let want = if ty == "gaussian" {
                // ∫ x² g̃ / ∫ g̃ with g̃ = max(0, g(x) − g(1.5)), by quadrature.
                let g = |x: f64| (-2.0 * x * x).exp() - (-2.0 * 2.25f64).exp();
                let k = 20_000;
                let (mut a, mut b) = (0.0, 0.0);
                for i in 0..k {
                    let x = -1.5 + 3.0 * (i as f64 + 0.5) / k as f64;
                    a += x * x * g(x);
                    b += g(x);
                }
                a / b
            } else {
                want
            };
            assert!(
                (m2 / want - 1.0).abs() < 2e-3,
                "{ty}: second moment {m2}, expected {want}"
            );
        }
        let m = Filter::new("mitchell", params(2.0)).unwrap();
        let ws: Vec<f64> = (0..n)
            .map(|a| m.sample([(a as f64 + 0.5) / n as f64, 0.5]).1)
            .collect();
        assert!(ws.iter().any(|&w| w < 0.0) && ws.iter().sum::<f64>() > 0.0);
        assert!(
            Filter::new("lanczos", params(4.0)).is_some()
                && Filter::new("cubic", params(1.0)).is_none()
        );
    }
}
