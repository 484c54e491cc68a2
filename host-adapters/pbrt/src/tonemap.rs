//! Visual adaptation: what an observer sees of an absolute image (Pegoraro & Parker 2006 §3.8; the thesis's
//! eq. 4.5), as a post-process from XYZ in cd/m² to display sRGB.
//!
//! Naka–Rushton (the default), per pixel:
//!
//! ```text
//!     LMS = diag(1 / LMS_w) · M · XYZ                 (von Kries: the white W, Y_W = 1, becomes D65)
//!     R_c = LMS_c / (LMS_c + σ_c · 2^(−stops))        (Naka–Rushton cone response, c = L, M, S)
//!     display = sRGB(M⁻¹ · R)                         (R = 1 is the display white, R = ½ mid-grey)
//! ```
//!
//! M is Hunt–Pointer–Estévez normalised to D65 (M · XYZ_D65 = (1, 1, 1)), so after von Kries a pixel of the
//! white's chromaticity at luminance Y has L = M = S = Y. σ is the paper's (§3.8) "average of the LMS cone
//! response values throughout the image" — one value for all three cones, taken from the scene as it arrives,
//! before von Kries (the paper's order: the white point adapts the signal, the response adapts to the scene; a σ
//! per cone from the balanced signal would cancel the white balance, every `--white` giving the same picture) —
//! or one adaptation luminance in cd/m² (`night`, `indoor`, `day` or a number): a grey at that luminance maps to
//! R = ½. The white W is the blackbody at the fire's hottest
//! temperature (the thesis; a render records it in its EXR), a given temperature, a given chromaticity, or D65
//! (no von Kries). A flame much brighter than σ saturates every cone towards 1 — near white, as at night; with σ
//! near the flame's own luminance the cones stay in their proportional range and the orange shows, as in
//! daylight (the paper's Figure 3).
//!
//! The thesis's other choices, for comparison, take the same white: `exposure` (linear, the 99th percentile of
//! luminance to 1, or the adaptation luminance to 0.18, times 2^stops, clipped) and Reinhard et al.'s 2002 global
//! operator (key 0.18 · 2^stops over the log-average luminance or the adaptation luminance; L_d = L (1 + L /
//! L_white²) / (1 + L) with L_white the largest scaled luminance; colour ratios kept).
//!
//! Every operator is monotone in the input luminance (M⁻¹'s Y row is non-negative), maps black to black and stays
//! finite for any finite input (σ of an all-black image falls back to 1 cd/m²).

use firemedium_core::{blackbody, cie};
use glam::DVec3;

/// Adaptation luminances (cd/m²) of the named surroundings.
pub const NIGHT: f64 = 1.0;
pub const INDOOR: f64 = 100.0;
pub const DAY: f64 = 1.0e4;

/// The tone-mapping operator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Operator {
    NakaRushton,
    Exposure,
    Reinhard,
    /// Sobotka's AgX display transform (Blender 4's default view), by Wrensch's fit.
    Agx,
    /// The ACES filmic curve, by Narkowicz's fit.
    Aces,
}

impl Operator {
    /// The name `--operator` takes.
    pub fn name(self) -> &'static str {
        match self {
            Operator::NakaRushton => "naka-rushton",
            Operator::Exposure => "exposure",
            Operator::Reinhard => "reinhard",
            Operator::Agx => "agx",
            Operator::Aces => "aces",
        }
    }
}

/// AgX (T. Sobotka, 2022) as B. Wrensch's minimal fit ("Minimal AgX Implementation", 2023): linear sRGB through
/// the inset matrix, log2 over [−12.47393, 4.026069] EV normalised to [0, 1], a 6th-order polynomial fit of the
/// default contrast sigmoid, the outset matrix, then display-encoded to linear (γ 2.2). Mid-grey 0.18 lands at
/// 0.497 encoded; values 16× mid-grey and above reach the top; bright saturated colours go towards white along
/// their hue rather than clipping per channel.
fn agx(rgb: DVec3) -> DVec3 {
    use glam::DMat3;
    let inset = DMat3::from_cols(
        DVec3::new(0.842479062253094, 0.0423282422610123, 0.0423756549057051),
        DVec3::new(0.0784335999999992, 0.878468636469772, 0.0784336),
        DVec3::new(0.0792237451477643, 0.0791661274605434, 0.879142973793104),
    );
    let outset = DMat3::from_cols(
        DVec3::new(1.19687900512017, -0.0528968517574562, -0.0529716355144438),
        DVec3::new(-0.0980208811401368, 1.15190312990417, -0.0980434501171241),
        DVec3::new(-0.0990297440797205, -0.0989611768448433, 1.15107367264116),
    );
    const MIN_EV: f64 = -12.47393;
    const MAX_EV: f64 = 4.026069;
    let v = inset * rgb.max(DVec3::ZERO);
    let x = v.to_array().map(|c| {
        let e = if c > 0.0 { c.log2() } else { MIN_EV };
        let x = (e.clamp(MIN_EV, MAX_EV) - MIN_EV) / (MAX_EV - MIN_EV);
        let (x2, x4) = (x * x, x * x * x * x);
        15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x
            - 0.00232
    });
    (outset * DVec3::from(x)).max(DVec3::ZERO).powf(2.2)
}

/// The ACES filmic curve as K. Narkowicz's fit ("ACES Filmic Tone Mapping Curve", 2016), per channel:
/// x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14), with his 0.6 pre-exposure; mid-grey 0.18 lands at 0.109 linear.
fn aces(rgb: DVec3) -> DVec3 {
    let x = rgb.max(DVec3::ZERO) * 0.6;
    (x * (x * 2.51 + 0.03)) / (x * (x * 2.43 + 0.59) + 0.14)
}

/// The white the observer is adapted to (von Kries).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum White {
    /// D65: no chromatic adaptation.
    D65,
    /// A blackbody at this temperature (K).
    Blackbody(f64),
    /// This CIE 1931 chromaticity (x, y).
    Chromaticity(f64, f64),
}

/// Where the adaptation state comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Adapt {
    /// From the image (Naka–Rushton: mean LMS per cone; exposure: 99th percentile; Reinhard: log-average).
    Image,
    /// A luminance in cd/m².
    Luminance(f64),
}

/// All choices of a tone mapping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    pub operator: Operator,
    pub white: White,
    pub adapt: Adapt,
    /// Exposure in stops (a factor 2^stops on the input).
    pub stops: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            operator: Operator::NakaRushton,
            white: White::D65,
            adapt: Adapt::Image,
            stops: 0.0,
        }
    }
}

/// Parses `night`, `indoor`, `day`, `image` or a luminance in cd/m².
pub fn parse_adapt(s: &str) -> Result<Adapt, crate::Error> {
    match s {
        "image" => Ok(Adapt::Image),
        "night" => Ok(Adapt::Luminance(NIGHT)),
        "indoor" => Ok(Adapt::Luminance(INDOOR)),
        "day" => Ok(Adapt::Luminance(DAY)),
        _ => match s.parse::<f64>() {
            Ok(v) if v > 0.0 && v.is_finite() => Ok(Adapt::Luminance(v)),
            _ => Err(crate::Error::value(format!(
                "'{s}': expected image, night ({NIGHT} cd/m²), indoor ({INDOOR}), day ({DAY}) or a luminance \
                 in cd/m² > 0"
            ))),
        },
    }
}

/// What `--white` names: `fire` (the render's hottest temperature) or a [`White`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WhiteArg {
    Fire,
    Given(White),
}

/// Parses `fire`, `d65`, a temperature (`1800` or `1800K`, 300–1e5 K) or a chromaticity `x,y`.
pub fn parse_white(s: &str) -> Result<WhiteArg, crate::Error> {
    let bad = || {
        crate::Error::value(format!(
            "'{s}': expected fire, d65, a temperature in K (300–100000, e.g. 1800K) or a chromaticity x,y \
             (e.g. 0.3127,0.3290)"
        ))
    };
    let lower = s.to_ascii_lowercase();
    match lower.as_str() {
        "fire" => return Ok(WhiteArg::Fire),
        "d65" => return Ok(WhiteArg::Given(White::D65)),
        _ => {}
    }
    if let Some((x, y)) = lower.split_once(',') {
        let (x, y) = (
            x.trim().parse::<f64>().map_err(|_| bad())?,
            y.trim().parse::<f64>().map_err(|_| bad())?,
        );
        if !(x > 0.0 && y > 0.0 && x + y < 1.0) {
            return Err(bad());
        }
        return Ok(WhiteArg::Given(White::Chromaticity(x, y)));
    }
    let t = lower
        .strip_suffix('k')
        .unwrap_or(&lower)
        .parse::<f64>()
        .map_err(|_| bad())?;
    if !(300.0..=1e5).contains(&t) {
        return Err(bad());
    }
    Ok(WhiteArg::Given(White::Blackbody(t)))
}

/// The white's XYZ with Y = 1.
pub fn white_xyz(w: White) -> DVec3 {
    let xyz = match w {
        White::D65 => return cie_d65(),
        White::Blackbody(t) => cie::spectrum_to_xyz(|nm| blackbody::spectral_radiance(t, nm)),
        White::Chromaticity(x, y) => DVec3::new(x / y, 1.0, (1.0 - x - y) / y),
    };
    if xyz.y > 0.0 && xyz.is_finite() {
        xyz / xyz.y
    } else {
        cie_d65()
    }
}

/// D65 with Y = 1 (the white of sRGB and of the HPE normalisation).
fn cie_d65() -> DVec3 {
    DVec3::new(0.95047, 1.0, 1.08883)
}

/// XYZ of linear-sRGB (D65) pixels.
pub fn srgb_to_xyz(px: &[[f32; 3]]) -> Vec<DVec3> {
    let m = cie::xyz_to_srgb_matrix().inverse();
    px.iter()
        .map(|p| m * DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect()
}

/// Tone-maps XYZ pixels (cd/m²) to display-linear sRGB in [0, 1].
pub fn map(xyz: &[DVec3], o: &Options) -> Vec<[f64; 3]> {
    let f = mapper(xyz, o);
    xyz.iter().map(|&p| f(p)).collect()
}

/// A pixel's display-linear sRGB in [0, 1] as [`map`] maps the pixels of `xyz`: what the operator takes from the
/// whole image (its mean, key or percentile) is taken here, once; then each pixel is mapped alone, so a writer
/// encodes it as it goes, with no image of mapped pixels beside its own bytes.
pub fn mapper(xyz: &[DVec3], o: &Options) -> Box<dyn Fn(DVec3) -> [f64; 3]> {
    // HPE rescaled so that D65 is exactly (1, 1, 1) (its 4-digit entries give D65 → (1, 0.99997, 0.99976)).
    let hpe = cie::xyz_to_lms_matrix();
    let m = glam::DMat3::from_diagonal(DVec3::ONE / (hpe * cie_d65())) * hpe;
    let m_inv = m.inverse();
    let to_srgb = cie::xyz_to_srgb_matrix();
    let gain = DVec3::ONE / (m * white_xyz(o.white));
    let k = 2f64.powf(o.stops);
    // Cone responses after von Kries, clipped at 0 (out-of-gamut negative lobes of M), and back to XYZ:
    // per pixel as it is mapped (an image of them beside the result would be the write's peak).
    let lms = move |p: DVec3| {
        let p = if p.is_finite() { p } else { DVec3::ZERO };
        (gain * (m * p)).max(DVec3::ZERO)
    };
    let adapted = move |p: DVec3| m_inv * lms(p);
    let clamp = move |c: DVec3| -> [f64; 3] {
        let c = c.clamp(DVec3::ZERO, DVec3::ONE);
        [c.x, c.y, c.z]
    };
    match o.operator {
        Operator::NakaRushton => {
            let sigma = match o.adapt {
                Adapt::Luminance(l) => DVec3::splat(l),
                Adapt::Image => {
                    // The mean cone response of the unbalanced scene (M · XYZ, clipped at 0 as above).
                    let n = xyz.len().max(1) as f64;
                    let sum = xyz
                        .iter()
                        .filter(|p| p.is_finite())
                        .map(|&p| (m * p).max(DVec3::ZERO))
                        .fold(DVec3::ZERO, |a, b| a + b);
                    let mean = (sum.x + sum.y + sum.z) / (3.0 * n);
                    DVec3::splat(if mean > 0.0 { mean } else { 1.0 })
                }
            } / k;
            Box::new(move |p| {
                let c = lms(p);
                let r = c / (c + sigma);
                clamp(to_srgb * (m_inv * r))
            })
        }
        Operator::Agx | Operator::Aces => {
            // The adaptation luminance to mid-grey 0.18, or the image's 99th percentile to 2 — a stop above
            // diffuse white: a fire's core in the curve's shoulder with its structure, the scene it lights in
            // the curve's middle (chosen by looking at the gallery); then the curve per pixel.
            let s = match o.adapt {
                Adapt::Luminance(l) => 0.18 / l,
                Adapt::Image => 2.0 / percentile(&luminances(xyz, adapted), 0.99).unwrap_or(1.0),
            } * k;
            let curve = if o.operator == Operator::Agx {
                agx
            } else {
                aces
            };
            Box::new(move |p| clamp(curve(to_srgb * (adapted(p) * s))))
        }
        Operator::Exposure | Operator::Reinhard => {
            // Work on the adapted XYZ (von Kries applied), keeping colour ratios.
            let ys = || luminances(xyz, adapted);
            let scale_of: Box<dyn Fn(f64) -> f64> = if o.operator == Operator::Exposure {
                let s = match o.adapt {
                    Adapt::Luminance(l) => 0.18 / l,
                    Adapt::Image => 1.0 / percentile(&ys(), 0.99).unwrap_or(1.0),
                } * k;
                Box::new(move |_| s)
            } else {
                let ys = ys();
                let key = match o.adapt {
                    Adapt::Luminance(l) => l,
                    Adapt::Image => {
                        let n = ys.len().max(1) as f64;
                        (ys.iter().map(|y| (1e-4 + y).ln()).sum::<f64>() / n).exp()
                    }
                };
                let a = 0.18 * k / key;
                let l_white = ys.iter().fold(0.0f64, |m, &y| m.max(a * y)).max(1e-12);
                Box::new(move |y: f64| {
                    if !(y > 0.0) {
                        return 0.0;
                    }
                    let l = a * y;
                    let ld = l * (1.0 + l / (l_white * l_white)) / (1.0 + l);
                    ld / y
                })
            };
            Box::new(move |p| {
                let a = adapted(p);
                clamp(to_srgb * (a * scale_of(a.y.max(0.0))))
            })
        }
    }
}

/// The adapted luminance of every pixel, at least 0 (what the image-keyed operators take their key from).
fn luminances(xyz: &[DVec3], adapted: impl Fn(DVec3) -> DVec3) -> Vec<f64> {
    xyz.iter().map(|&p| adapted(p).y.max(0.0)).collect()
}

/// The `q` quantile of the positive values, if any.
fn percentile(v: &[f64], q: f64) -> Option<f64> {
    let mut pos: Vec<f64> = v.iter().copied().filter(|y| *y > 0.0).collect();
    if pos.is_empty() {
        return None;
    }
    pos.sort_by(f64::total_cmp);
    Some(pos[((pos.len() - 1) as f64 * q) as usize])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imageio::srgb_encode;

    fn nr(white: White, adapt: Adapt) -> Options {
        Options {
            operator: Operator::NakaRushton,
            white,
            adapt,
            stops: 0.0,
        }
    }

    #[test]
    fn a_grey_at_the_adaptation_luminance_is_mid_grey() {
        // D65 grey of 250 cd/m², adapted to 250 cd/m² (and, as the only value, by the image's mean): R = ½ per
        // cone, display-linear ½ in every channel.
        let px = vec![cie_d65() * 250.0; 16];
        for adapt in [Adapt::Luminance(250.0), Adapt::Image] {
            let out = map(&px, &nr(White::D65, adapt));
            for c in out[0] {
                assert!((c - 0.5).abs() < 1e-3, "{adapt:?}: {:?}", out[0]);
            }
        }
        // One stop more exposure: R = 2/3.
        let o = Options {
            stops: 1.0,
            ..nr(White::D65, Adapt::Luminance(250.0))
        };
        let out = map(&px, &o);
        assert!((out[0][1] - 2.0 / 3.0).abs() < 1e-3, "{:?}", out[0]);
    }

    #[test]
    fn the_white_point_maps_to_neutral() {
        // A 1800 K blackbody pixel under von Kries to 1800 K is grey: r = g = b within 1/255 (8-bit PNG steps),
        // at several luminances; without adaptation (D65) the same pixel is orange.
        let white = White::Blackbody(1800.0);
        let xyz = white_xyz(white);
        for y in [1e-2, 1.0, 1e3, 1e6] {
            let out = map(&[xyz * y], &nr(white, Adapt::Luminance(100.0)))[0];
            let enc = out.map(srgb_encode);
            assert!(
                (enc[0] - enc[1]).abs() < 1.0 / 255.0 && (enc[1] - enc[2]).abs() < 1.0 / 255.0,
                "Y {y}: {enc:?}"
            );
        }
        let raw = map(&[xyz * 100.0], &nr(White::D65, Adapt::Luminance(100.0)))[0];
        assert!(raw[0] > 2.0 * raw[2], "{raw:?}");
        // A chromaticity white works the same way.
        let (x, y) = cie::chromaticity(xyz);
        let out = map(
            &[xyz * 100.0],
            &nr(White::Chromaticity(x, y), Adapt::Luminance(100.0)),
        )[0];
        assert!((out[0] - out[2]).abs() < 1e-4, "{out:?}");
    }

    #[test]
    fn adapted_to_the_image_the_white_still_matters_and_maps_to_neutral() {
        // A fire-lit image: a 1800 K flame pixel among dimmer ones of the same colour and a D65 grey. Adapted to
        // the image's own mean (the default), the white balance must not cancel: 1800 K and D65 whites give
        // different pictures, and under the 1800 K white the flame's colour is grey.
        let flame = white_xyz(White::Blackbody(1800.0));
        let px = vec![flame * 5e3, flame * 40.0, flame * 3.0, cie_d65() * 10.0];
        let warm = map(&px, &nr(White::Blackbody(1800.0), Adapt::Image));
        let d65 = map(&px, &nr(White::D65, Adapt::Image));
        for (i, (a, b)) in warm.iter().zip(&d65).enumerate() {
            if i < 3 {
                let enc = a.map(srgb_encode);
                assert!(
                    (enc[0] - enc[1]).abs() < 1.0 / 255.0 && (enc[1] - enc[2]).abs() < 1.0 / 255.0,
                    "pixel {i} under its own white: {enc:?}"
                );
                assert!(
                    b[0] > 0.0 && b[0] > 2.0 * b[2],
                    "pixel {i} under D65 is orange: {b:?}"
                );
            }
        }
    }

    #[test]
    fn monotone_finite_and_black_stays_black() {
        let colour = white_xyz(White::Blackbody(1500.0));
        for op in [
            Operator::NakaRushton,
            Operator::Exposure,
            Operator::Reinhard,
            Operator::Agx,
            Operator::Aces,
        ] {
            for adapt in [Adapt::Image, Adapt::Luminance(DAY)] {
                let o = Options {
                    operator: op,
                    white: White::Blackbody(2500.0),
                    adapt,
                    stops: 0.0,
                };
                // Luminance ladder 0, 1e-6 … 1e9 cd/m² of an orange pixel, in one image.
                let mut px = vec![DVec3::ZERO];
                px.extend((-6..=9).map(|e| colour * 10f64.powi(e)));
                let out = map(&px, &o);
                assert!(out.iter().flatten().all(|c| c.is_finite()), "{op:?}");
                assert_eq!(out[0], [0.0; 3], "{op:?}: black");
                let y = |c: [f64; 3]| 0.2126729 * c[0] + 0.7151522 * c[1] + 0.0721750 * c[2];
                for w in out.windows(2) {
                    assert!(y(w[1]) >= y(w[0]) - 1e-12, "{op:?} {adapt:?}: {out:?}");
                }
                // An all-black image is black, not NaN.
                let out = map(&[DVec3::ZERO; 4], &o);
                assert!(out.iter().flatten().all(|c| *c == 0.0), "{op:?}");
            }
        }
    }

    #[test]
    fn the_display_curves_keep_their_published_points() {
        // A D65 grey at the adaptation luminance is scene mid-grey 0.18: AgX puts it at 0.497 display-encoded
        // (Wrensch's polynomial at (log2 0.18 + 12.47393) / 16.5), ACES at 0.109 linear (Narkowicz's fit at
        // 0.6 · 0.18); both rise towards white and stay below it.
        let grey = |op: Operator, y: f64| {
            let o = Options {
                operator: op,
                white: White::D65,
                adapt: Adapt::Luminance(100.0),
                stops: 0.0,
            };
            map(&[cie_d65() * y], &o)[0]
        };
        let agx = grey(Operator::Agx, 100.0);
        for c in agx {
            assert!((c.powf(1.0 / 2.2) - 0.4967).abs() < 2e-3, "{agx:?}");
        }
        let aces = grey(Operator::Aces, 100.0);
        for c in aces {
            let x = 0.6 * 0.18;
            let want = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
            assert!((c - want).abs() < 1e-3, "{aces:?} vs {want}");
        }
        for op in [Operator::Agx, Operator::Aces] {
            let (lo, hi) = (grey(op, 1e3)[1], grey(op, 1e6)[1]);
            assert!(lo < hi && hi <= 1.0 && hi > 0.95, "{op:?}: {lo} {hi}");
        }
    }

    #[test]
    fn arguments_parse_and_bad_ones_explain() {
        assert_eq!(parse_adapt("night").ok(), Some(Adapt::Luminance(NIGHT)));
        assert_eq!(parse_adapt("250").ok(), Some(Adapt::Luminance(250.0)));
        assert!(parse_adapt("-3").unwrap_err().to_string().contains("cd/m²"));
        assert_eq!(parse_white("fire").ok(), Some(WhiteArg::Fire));
        assert_eq!(
            parse_white("1800K").ok(),
            Some(WhiteArg::Given(White::Blackbody(1800.0)))
        );
        assert_eq!(
            parse_white("0.3127,0.329").ok(),
            Some(WhiteArg::Given(White::Chromaticity(0.3127, 0.329)))
        );
        assert!(parse_white("5K")
            .unwrap_err()
            .to_string()
            .contains("300–100000"));
        assert!(parse_white("0.9,0.5").is_err());
        // D65 through the blackbody route: the white of 6504 K is within 0.003 of D65's chromaticity.
        let (x, y) = cie::chromaticity(white_xyz(White::Blackbody(6504.0)));
        assert!(
            (x - 0.3127).abs() < 0.01 && (y - 0.329).abs() < 0.01,
            "{x} {y}"
        );
    }
}
