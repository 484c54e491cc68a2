//! `firemedium tonemap IN.exr -o OUT.png`: the visual-adaptation tone mapping (`crate::tonemap`) of an absolute
//! render, with the observer's adaptation and white point as options.

use clap::Args;
use firemedium::imageio;
use firemedium::tonemap::{self, Adapt, Operator, Options, White, WhiteArg};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct TonemapArgs {
    /// The absolute render (EXR, linear sRGB in cd/m²-scaled units, as `render` writes).
    input: PathBuf,
    /// The PNG to write.
    #[arg(short, long)]
    output: PathBuf,
    /// naka-rushton (cone responses, P&P §3.8), exposure (linear + sRGB curve) or reinhard (2002 global).
    #[arg(long, default_value = "naka-rushton", value_parser = ["naka-rushton", "exposure", "reinhard"])]
    operator: String,
    /// What the eye is adapted to: image (from the image itself), night, indoor, day, or a luminance in cd/m².
    #[arg(long, default_value = "image", value_parser = tonemap::parse_adapt, allow_negative_numbers = true)]
    adapt: Adapt,
    /// The white (von Kries): fire (the render's hottest temperature; D65 if it records none), d65, a
    /// temperature (1800K) or a chromaticity (0.3127,0.3290).
    #[arg(long, default_value = "fire", value_parser = tonemap::parse_white)]
    white: WhiteArg,
    /// Exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f64,
    /// Bits per channel of the PNG: 8 or 16.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u8).range(8..=16))]
    bits: u8,
}

pub fn run(a: &TonemapArgs) -> Result<String, (u8, String)> {
    if a.bits != 8 && a.bits != 16 {
        return Err((2, format!("--bits {}: expected 8 or 16", a.bits)));
    }
    if !a.exposure.is_finite() || a.exposure.abs() > 100.0 {
        return Err((
            2,
            format!("--exposure {}: expected stops within ±100", a.exposure),
        ));
    }
    let img = imageio::read(&a.input, false).map_err(|e| (1, e))?;
    let (white, from) = match a.white {
        WhiteArg::Given(w) => (w, "given"),
        WhiteArg::Fire => match imageio::read_fire_temperature(&a.input).map_err(|e| (1, e))? {
            Some(t) => (White::Blackbody(t), "the render's fire"),
            None => (White::D65, "none recorded: D65"),
        },
    };
    let o = Options {
        operator: match a.operator.as_str() {
            "exposure" => Operator::Exposure,
            "reinhard" => Operator::Reinhard,
            _ => Operator::NakaRushton,
        },
        white,
        adapt: a.adapt,
        stops: a.exposure,
    };
    let xyz = tonemap::srgb_to_xyz(&img.px);
    let px = tonemap::map(&xyz, &o);
    imageio::write_png(&a.output, img.w, img.h, &px, a.bits == 16).map_err(|e| (1, e))?;
    let white_text = match white {
        White::D65 => "D65".to_string(),
        White::Blackbody(t) => format!("blackbody {t:.0} K"),
        White::Chromaticity(x, y) => format!("x,y {x:.4},{y:.4}"),
    };
    Ok(format!(
        "wrote {} ({}×{}, {}-bit; {}, adapted to {}, white {white_text} ({from}), {:+} stops)\n",
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
