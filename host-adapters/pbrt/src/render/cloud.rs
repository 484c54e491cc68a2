//! pbrt-v4's procedural `cloud` medium (`src/pbrt/media.h`, `CloudMedium::Density`): Perlin noise (Perlin's
//! improved noise, as pbrt-v4's `Noise`, with his permutation table) summed over five octaves, the lookup point
//! first perturbed by two octaves of the noise's gradient ("wispiness"), falling off with height:
//! d(p) = clamp((1 − y) 4.5 density Σ ½ⁱ⁺¹ N(1.99ⁱ p′), 0, 1) + 2 max(0, ½ − y), clamped to [0, 1].
//!
//! The renderer bakes d over the medium's bounds into a grid of [`BAKE`]³ cell-centred samples and renders it as
//! a pbrt grid medium through the plugin (pbrt-v4 evaluates d at every point; the grid, trilinear between
//! samples, smooths the finest octave, which carries 1/32 of the noise's amplitude).

use glam::DVec3;
use rayon::prelude::*;

/// Samples per axis of the baked grid.
pub const BAKE: usize = 128;

/// Ken Perlin's permutation of 0..256 (his reference implementation of improved noise, as pbrt-v4's `NoisePerm`).
const PERM: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

fn perm(i: usize) -> usize {
    PERM[i & 255] as usize
}

/// The gradient of lattice point (x, y, z) dotted with the offset (one of twelve edge directions, by hash).
fn grad(x: usize, y: usize, z: usize, d: DVec3) -> f64 {
    let h = perm(perm(perm(x) + y) + z) & 15;
    let u = if h < 8 || h == 12 || h == 13 {
        d.x
    } else {
        d.y
    };
    let v = if h < 4 || h == 12 || h == 13 {
        d.y
    } else {
        d.z
    };
    (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
}

/// Perlin's quintic fade 6t⁵ − 15t⁴ + 10t³.
fn fade(t: f64) -> f64 {
    t * t * t * (t * (6.0 * t - 15.0) + 10.0)
}

/// Perlin noise at `p` (0 at lattice points, within about [−1, 1]).
pub fn noise(p: DVec3) -> f64 {
    let f = p.floor();
    if !f.is_finite() {
        return 0.0;
    }
    let d = p - f;
    let (x, y, z) = (
        (f.x as i64 & 255) as usize,
        (f.y as i64 & 255) as usize,
        (f.z as i64 & 255) as usize,
    );
    let g = |dx: usize, dy: usize, dz: usize| {
        grad(
            x + dx,
            y + dy,
            z + dz,
            d - DVec3::new(dx as f64, dy as f64, dz as f64),
        )
    };
    let (wx, wy, wz) = (fade(d.x), fade(d.y), fade(d.z));
    let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
    let y0 = lerp(
        wy,
        lerp(wx, g(0, 0, 0), g(1, 0, 0)),
        lerp(wx, g(0, 1, 0), g(1, 1, 0)),
    );
    let y1 = lerp(
        wy,
        lerp(wx, g(0, 0, 1), g(1, 0, 1)),
        lerp(wx, g(0, 1, 1), g(1, 1, 1)),
    );
    lerp(wz, y0, y1)
}

/// The noise's gradient by forward differences of 0.01 (pbrt-v4's `DNoise`).
fn dnoise(p: DVec3) -> DVec3 {
    let (n, h) = (noise(p), 0.01);
    DVec3::new(
        noise(p + DVec3::X * h) - n,
        noise(p + DVec3::Y * h) - n,
        noise(p + DVec3::Z * h) - n,
    ) / h
}

/// The cloud's density at medium-space `p`.
pub fn density(p: DVec3, density: f64, wispiness: f64, frequency: f64) -> f64 {
    let mut pp = p * frequency;
    if wispiness > 0.0 {
        let (mut vomega, mut vlambda) = (0.05 * wispiness, 10.0);
        for _ in 0..2 {
            pp += dnoise(pp * vlambda) * vomega;
            vomega *= 0.5;
            vlambda *= 1.99;
        }
    }
    let (mut d, mut omega, mut lambda) = (0.0, 0.5, 1.0);
    for _ in 0..5 {
        d += omega * noise(pp * lambda);
        omega *= 0.5;
        lambda *= 1.99;
    }
    let d = ((1.0 - p.y) * 4.5 * density * d).clamp(0.0, 1.0) + 2.0 * (0.5 - p.y).max(0.0);
    d.clamp(0.0, 1.0)
}

/// The density at the [`BAKE`]³ cell centres of [p0, p1], x fastest.
pub fn bake(p0: DVec3, p1: DVec3, dens: f64, wispiness: f64, frequency: f64) -> Vec<f64> {
    let n = BAKE;
    (0..n * n * n)
        .into_par_iter()
        .map(|i| {
            let c = DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64);
            density(
                p0 + (p1 - p0) * ((c + 0.5) / n as f64),
                dens,
                wispiness,
                frequency,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perlin_noise_properties() {
        // Zero at every lattice point; continuous; within [−1, 1]; its mean over a large region near 0.
        for p in [
            DVec3::ZERO,
            DVec3::new(3.0, -7.0, 11.0),
            DVec3::new(255.0, 256.0, -1.0),
        ] {
            assert_eq!(noise(p), 0.0);
        }
        let p = DVec3::new(1.3, 2.7, -0.4);
        assert!((noise(p) - noise(p + DVec3::splat(1e-7))).abs() < 1e-5);
        let (mut sum, mut n) = (0.0, 0);
        for i in 0..20_000 {
            let q = DVec3::new(
                i as f64 * 0.731,
                i as f64 * 0.377 + 0.5,
                i as f64 * 0.113 + 0.25,
            );
            let v = noise(q);
            assert!(v.abs() <= 1.1, "{v}");
            sum += v;
            n += 1;
        }
        assert!((sum / n as f64).abs() < 0.02, "{}", sum / n as f64);
        // The table is a permutation.
        let mut seen = [false; 256];
        PERM.iter().for_each(|&v| seen[v as usize] = true);
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn the_cloud_thins_with_height() {
        // Below y = 0 the ground term saturates it; above y = 1 the (1 − y) factor empties it.
        assert_eq!(density(DVec3::new(0.3, -0.1, 0.7), 2.0, 1.0, 5.0), 1.0);
        assert_eq!(density(DVec3::new(0.3, 1.2, 0.7), 2.0, 1.0, 5.0), 0.0);
        let g = bake(DVec3::ZERO, DVec3::ONE, 2.0, 1.0, 5.0);
        assert_eq!(g.len(), BAKE * BAKE * BAKE);
        assert!(g.iter().all(|v| (0.0..=1.0).contains(v)));
        let layer = |j: usize| {
            (0..BAKE * BAKE)
                .map(|k| g[(k % BAKE) + BAKE * (j + BAKE * (k / BAKE))])
                .sum::<f64>()
        };
        assert!(layer(10) > layer(100), "{} vs {}", layer(10), layer(100));
    }
}
