//! `firemedium tonemap IN.exr -o OUT.png`: the visual-adaptation tone mapping (`crate::tonemap`) of an absolute
//! render, with the observer's adaptation and white point as options.

use clap::Args;
use firemedium::imageio;
use firemedium::tonemap::{self, Adapt, Operator, Options, White, WhiteArg};
use firemedium::Error;
use std::path::PathBuf;

#[derive(Debug, Args)]
// (Negative numbers are values: `--temperature -5` is refused by its range, not taken for a flag.)
#[command(allow_negative_numbers = true)]
pub struct TonemapArgs {
    /// The absolute render (EXR, linear sRGB in cd/m²-scaled units, as `render` writes).
    input: PathBuf,
    /// The PNG to write.
    #[arg(short, long)]
    output: PathBuf,
    /// naka-rushton (cone responses, P&P §3.8), exposure (linear + sRGB curve), reinhard (2002 global), agx
    /// (Sobotka's display transform: a soft shoulder towards white along each hue) or aces (the ACES filmic curve).
    #[arg(long, default_value = "naka-rushton", value_parser = ["naka-rushton", "exposure", "reinhard", "agx", "aces"])]
    operator: String,
    /// What the eye is adapted to: image (from the image itself), night, indoor, day, or a luminance in cd/m².
    #[arg(long, default_value = "image", value_parser = tonemap::parse_adapt, allow_negative_numbers = true)]
    adapt: Adapt,
    /// The white (von Kries): d65 (the display's: the fire's colour kept), fire (the render's hottest
    /// temperature, D65 if it records none: an eye adapted to the fire alone), a temperature (1800K) or a
    /// chromaticity (0.3127,0.3290).
    #[arg(long, default_value = "d65", value_parser = tonemap::parse_white)]
    white: WhiteArg,
    /// Exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f64,
    /// Bits per channel of the PNG: 8 or 16.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u8).range(8..=16))]
    bits: u8,
    /// The memory budget in GB the images' sizes are checked against before their pixels are read
    /// (default: half the machine's memory).
    #[arg(long, value_name = "GB", value_parser = crate::args::parse_gb)]
    max_memory: Option<f64>,
}

pub fn run(a: &TonemapArgs) -> firemedium::Result<String> {
    if a.bits != 8 && a.bits != 16 {
        return Err(Error::value(format!("--bits {}: expected 8 or 16", a.bits)));
    }
    if !a.exposure.is_finite() || a.exposure.abs() > 100.0 {
        return Err(Error::value(format!(
            "--exposure {}: expected stops within ±100",
            a.exposure
        )));
    }
    let budget = crate::args::budget(a.max_memory);
    firemedium::imageio::check_writable(&a.output)?;
    let img = imageio::read_within(&a.input, false, budget)?;
    // (The map's working copies: XYZ in f64 and the display's values, per pixel.)
    firemedium::budget::check(
        &format!(
            "{}: tone mapping {}×{} pixels",
            a.input.display(),
            img.w,
            img.h
        ),
        (img.w as u64).saturating_mul(img.h as u64),
        48,
        budget,
    )?;
    let (white, from) = match a.white {
        WhiteArg::Given(w) => (w, "given"),
        WhiteArg::Fire => match imageio::read_fire_temperature(&a.input)? {
            Some(t) => (White::Blackbody(t), "the render's fire"),
            None => (White::D65, "none recorded: D65"),
        },
    };
    let o = Options {
        operator: match a.operator.as_str() {
            "exposure" => Operator::Exposure,
            "reinhard" => Operator::Reinhard,
            "agx" => Operator::Agx,
            "aces" => Operator::Aces,
            _ => Operator::NakaRushton,
        },
        white,
        adapt: a.adapt,
        stops: a.exposure,
    };
    // An EXR in ACEScg (`render --colorspace acescg`, as its record says) comes back to linear Rec.709 first.
    let mut img = img;
    let acescg = imageio::read_meta(&a.input).is_ok_and(|(_, meta)| {
        meta.iter()
            .any(|(k, v)| k == imageio::COLORSPACE_KEY && v == "acescg")
    });
    if acescg {
        let m = imageio::SRGB_TO_ACESCG.map(|r| r.map(f64::from));
        let inv = glam::DMat3::from_cols_array_2d(&m).transpose().inverse();
        for p in img.px.iter_mut() {
            let v = inv * glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            *p = [v.x as f32, v.y as f32, v.z as f32];
        }
    }
    let xyz = tonemap::srgb_to_xyz(&img.px);
    let px = tonemap::map(&xyz, &o);
    imageio::write_png(&a.output, img.w, img.h, px.iter().copied(), a.bits == 16)?;
    // How much of the flame the display flattens: of the pixels where the render's `fire` AOV (the fire seen from
    // the camera) is at least 5 % of its 99th percentile, those with a channel at the display's top (8-bit 250 and
    // above: clipped, or saturated so that steps of the input no longer show).
    let (names, extra) = imageio::read_extra_channels(&a.input, budget)?;
    let clipped = ["fire.R", "fire.G", "fire.B"]
        .map(|n| names.iter().position(|m| m == n))
        .iter()
        .all(Option::is_some)
        .then(|| {
            let k = names.len();
            let at = |n: &str| names.iter().position(|m| m == n).unwrap_or(0);
            let (r, g, b) = (at("fire.R"), at("fire.G"), at("fire.B"));
            let lum: Vec<f64> = (0..img.w * img.h)
                .map(|i| {
                    let v = |c: usize| extra[i * k + c] as f64;
                    0.2126 * v(r) + 0.7152 * v(g) + 0.0722 * v(b)
                })
                .collect();
            let mut sorted = lum.clone();
            sorted.sort_by(f64::total_cmp);
            let p99 = sorted[((sorted.len() - 1) as f64 * 0.99) as usize];
            let flame: Vec<usize> = (0..lum.len())
                .filter(|&i| p99 > 0.0 && lum[i] >= 0.05 * p99)
                .collect();
            let top = 249.5 / 255.0;
            let n = flame
                .iter()
                .filter(|&&i| px[i].iter().any(|&c| imageio::srgb_encode(c) >= top))
                .count();
            (n, flame.len())
        });
    let white_text = match white {
        White::D65 => "D65".to_string(),
        White::Blackbody(t) => format!("blackbody {t:.0} K"),
        White::Chromaticity(x, y) => format!("x,y {x:.4},{y:.4}"),
    };
    let clip_text = match clipped {
        Some((n, of)) if of > 0 => format!(
            "; flame pixels at the top: {n} of {of} ({:.1} %)",
            100.0 * n as f64 / of as f64
        ),
        _ => String::new(),
    };
    Ok(format!(
        "wrote {} ({}×{}, {}-bit; {}, adapted to {}, white {white_text} ({from}), {:+} stops{clip_text})\n",
        a.output.display(),
        img.w,
        img.h,
        a.bits,
        a.operator,
        match a.adapt {
            Adapt::Image => "the image".to_string(),
            Adapt::Luminance(l) => format!("{l} cd/m²"),
        },
        a.exposure
    ))
}
