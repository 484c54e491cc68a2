//! `firemedium physics`: the physics core's quantities at given conditions, as a table or JSON.
//!
//! JSON fields (stable names, documented in the README):
//! `temperature_k`, `fuel`, `soot_fraction`, `alpha`, `pressure_pa`, `humidity`, `co2_ppm` (the inputs);
//! `wavelengths`: one object per wavelength with `wavelength_nm` (vacuum), `blackbody` (W·m⁻²·sr⁻¹·nm⁻¹),
//! `soot_kappa` (m⁻¹), `air_index_minus_one` (n − 1);
//! `blackbody_xyz` {X, Y, Z} (CIE 1931, Y in cd/m², 380–780 nm), `blackbody_chromaticity` {x, y},
//! `blackbody_srgb_linear` {r, g, b} (linear sRGB, D65, same scale as XYZ).

use clap::Args;
use firemedium::Error;
use firemedium_core::{blackbody, ciddor, cie, soot};
use serde::Serialize;

#[derive(Debug, Args)]
// (Negative numbers are values: `--temperature -5` is refused by its range, not taken for a flag.)
#[command(allow_negative_numbers = true)]
pub struct PhysicsArgs {
    /// Gas temperature, K.
    #[arg(long, value_name = "K", default_value_t = 1500.0)]
    temperature: f64,
    /// Vacuum wavelengths, nm, comma-separated.
    #[arg(
        long,
        value_name = "NM,...",
        value_delimiter = ',',
        default_value = "450,550,650"
    )]
    wavelengths: Vec<f64>,
    /// Soot optical constants: propane or acetylene (Dalzell & Sarofim 1969).
    #[arg(long, default_value = "propane")]
    fuel: String,
    /// Soot volume fraction f_v (m³ of soot per m³), 0–1.
    #[arg(long, value_name = "FV", default_value_t = 1e-6)]
    soot_fraction: f64,
    /// Soot exponent α: 1.39 (Hottel, λ in µm) or 1 (Rayleigh, λ in m).
    #[arg(long, default_value_t = soot::HOTTEL_ALPHA)]
    alpha: f64,
    /// Air pressure, Pa (for the index of air).
    #[arg(long, value_name = "PA", default_value_t = 101_325.0)]
    pressure: f64,
    /// Relative humidity of the air, fraction 0–1.
    #[arg(long, value_name = "H", default_value_t = 0.0)]
    humidity: f64,
    /// CO₂ mole fraction of the air, ppm.
    #[arg(long, value_name = "PPM", default_value_t = 450.0)]
    co2: f64,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Report {
    temperature_k: f64,
    fuel: String,
    soot_fraction: f64,
    alpha: f64,
    pressure_pa: f64,
    humidity: f64,
    co2_ppm: f64,
    wavelengths: Vec<AtWavelength>,
    blackbody_xyz: Xyz,
    blackbody_chromaticity: Chromaticity,
    blackbody_srgb_linear: Rgb,
}

#[derive(Debug, Serialize)]
struct AtWavelength {
    wavelength_nm: f64,
    blackbody: f64,
    soot_kappa: f64,
    air_index_minus_one: f64,
}

#[derive(Debug, Serialize)]
#[allow(non_snake_case)]
struct Xyz {
    X: f64,
    Y: f64,
    Z: f64,
}

#[derive(Debug, Serialize)]
struct Chromaticity {
    x: f64,
    y: f64,
}

#[derive(Debug, Serialize)]
struct Rgb {
    r: f64,
    g: f64,
    b: f64,
}

/// Checks `value` lies in [lo, hi] and is finite; the message names the flag, the value and the range.
fn check(flag: &str, value: f64, lo: f64, hi: f64, what: &str) -> Result<f64, Error> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(Error::value(format!(
            "--{flag} {value}: expected {what} from {lo} to {hi}"
        )))
    }
}

pub fn run(args: &PhysicsArgs) -> firemedium::Result<String> {
    let t = check(
        "temperature",
        args.temperature,
        0.0,
        1e6,
        "a temperature in K",
    )?;
    let fv = check(
        "soot-fraction",
        args.soot_fraction,
        0.0,
        1.0,
        "a volume fraction",
    )?;
    let alpha = check("alpha", args.alpha, 0.1, 4.0, "an exponent")?;
    let p = check("pressure", args.pressure, 1.0, 1e7, "a pressure in Pa")?;
    let h = check(
        "humidity",
        args.humidity,
        0.0,
        1.0,
        "a relative humidity fraction",
    )?;
    let co2 = check("co2", args.co2, 0.0, 1e6, "a CO2 mole fraction in ppm")?;
    if args.wavelengths.is_empty() {
        return Err(Error::value(
            "--wavelengths: expected at least one wavelength in nm",
        ));
    }
    for &l in &args.wavelengths {
        check("wavelengths", l, 200.0, 20_000.0, "wavelengths in nm")?;
    }
    let optics =
        soot::SootOptics::for_fuel(&args.fuel).map_err(|e| Error::value(format!("--fuel: {e}")))?;
    let air = ciddor::Air {
        temperature_k: t,
        pressure_pa: p,
        relative_humidity: h,
        co2_ppm: co2,
    };

    let wavelengths = args
        .wavelengths
        .iter()
        .map(|&l| AtWavelength {
            wavelength_nm: l,
            blackbody: blackbody::spectral_radiance(t, l),
            soot_kappa: optics.kappa(l, fv, alpha),
            air_index_minus_one: ciddor::refractivity(l, &air),
        })
        .collect();
    let xyz = cie::spectrum_to_xyz(|l| blackbody::spectral_radiance(t, l));
    let (cx, cy) = cie::chromaticity(xyz);
    let rgb = cie::xyz_to_linear_srgb(xyz);
    let report = Report {
        temperature_k: t,
        fuel: args.fuel.to_ascii_lowercase(),
        soot_fraction: fv,
        alpha,
        pressure_pa: p,
        humidity: h,
        co2_ppm: co2,
        wavelengths,
        blackbody_xyz: Xyz {
            X: xyz.x,
            Y: xyz.y,
            Z: xyz.z,
        },
        blackbody_chromaticity: Chromaticity { x: cx, y: cy },
        blackbody_srgb_linear: Rgb {
            r: rgb.x,
            g: rgb.y,
            b: rgb.z,
        },
    };
    if args.json {
        serde_json::to_string_pretty(&report)
            .map(|s| s + "\n")
            .map_err(|e| Error::input(format!("JSON output failed: {e}")))
    } else {
        Ok(table(&report))
    }
}

fn table(r: &Report) -> String {
    let mut s = format!(
        "T = {} K, {} soot f_v = {:e} (alpha {}), air {} Pa, RH {}, CO2 {} ppm\n\n",
        r.temperature_k, r.fuel, r.soot_fraction, r.alpha, r.pressure_pa, r.humidity, r.co2_ppm
    );
    s += &format!(
        "{:>12} {:>22} {:>16} {:>16}\n",
        "lambda (nm)", "B (W/m^2/sr/nm)", "kappa (1/m)", "n - 1"
    );
    for w in &r.wavelengths {
        s += &format!(
            "{:>12} {:>22.6e} {:>16.6e} {:>16.6e}\n",
            w.wavelength_nm, w.blackbody, w.soot_kappa, w.air_index_minus_one
        );
    }
    s += &format!(
        "\nblackbody XYZ = ({:.6e}, {:.6e}, {:.6e}) (Y in cd/m^2), xy = ({:.4}, {:.4})\n",
        r.blackbody_xyz.X,
        r.blackbody_xyz.Y,
        r.blackbody_xyz.Z,
        r.blackbody_chromaticity.x,
        r.blackbody_chromaticity.y
    );
    s += &format!(
        "blackbody linear sRGB = ({:.6e}, {:.6e}, {:.6e})\n",
        r.blackbody_srgb_linear.r, r.blackbody_srgb_linear.g, r.blackbody_srgb_linear.b
    );
    s
}
