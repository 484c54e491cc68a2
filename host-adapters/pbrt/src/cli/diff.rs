//! `firemedium diff A.exr B.exr`: whether two EXRs hold the same render — every channel of every pixel equal bit
//! for bit, the same place on the same film, and the same render record but for its render time (the one line two
//! renders of a scene differ in). Exit 0 when they do, 1 with the first difference when they do not: a farm's
//! merged frames checked against a local render, or a re-render against the frame it replaces.

use clap::Args;
use firemedium::imageio;
use firemedium::Error;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct DiffArgs {
    /// The first EXR.
    a: PathBuf,
    /// The second EXR.
    b: PathBuf,
    /// The memory budget in GB the images' sizes are checked against before their pixels are read
    /// (default: half the machine's memory).
    #[arg(long, value_name = "GB", value_parser = crate::args::parse_gb)]
    max_memory: Option<f64>,
    /// Compare the pixels alone, not the render records (two builds whose records say different things, the
    /// same image expected).
    #[arg(long)]
    pixels: bool,
}

pub fn run(a: &DiffArgs) -> firemedium::Result<String> {
    let (pa, pb) = (&a.a, &a.b);
    let (wa, ma) = imageio::read_meta(pa)?;
    let (wb, mb) = imageio::read_meta(pb)?;
    if wa != wb {
        return Err(Error::input(format!(
            "{} lies at {:?} on a {:?} film, {} at {:?} on a {:?} film",
            pa.display(),
            wa.origin,
            wa.full,
            pb.display(),
            wb.origin,
            wb.full
        )));
    }
    if let Some(differs) = imageio::record_differences(&ma, &mb).filter(|_| !a.pixels) {
        return Err(Error::input(format!(
            "{} and {} are records of different renders: {differs}",
            pa.display(),
            pb.display(),
        )));
    }
    let budget = crate::args::budget(a.max_memory);
    let (ia, ib) = (
        imageio::read_within(pa, false, budget)?,
        imageio::read_within(pb, false, budget)?,
    );
    let (na, va) = imageio::read_extra_channels(pa, budget)?;
    let (nb, vb) = imageio::read_extra_channels(pb, budget)?;
    if (ia.w, ia.h) != (ib.w, ib.h) || na != nb {
        return Err(Error::input(format!(
            "{}: {}×{} pixels, R G B {}; {}: {}×{}, R G B {}",
            pa.display(),
            ia.w,
            ia.h,
            na.join(" "),
            pb.display(),
            ib.w,
            ib.h,
            nb.join(" ")
        )));
    }
    let names: Vec<&str> = ["R", "G", "B"]
        .into_iter()
        .chain(na.iter().map(String::as_str))
        .collect();
    let k = na.len();
    let value = |px: &[[f32; 3]], extra: &[f32], i: usize, c: usize| {
        if c < 3 {
            px[i][c]
        } else {
            extra[i * k + c - 3]
        }
    };
    let (mut first, mut count) = (None, 0usize);
    for i in 0..ia.w * ia.h {
        let mut differs = false;
        for c in 0..names.len() {
            let (x, y) = (value(&ia.px, &va, i, c), value(&ib.px, &vb, i, c));
            if x.to_bits() != y.to_bits() {
                differs = true;
                first.get_or_insert((i, c, x, y));
            }
        }
        count += differs as usize;
    }
    if let Some((i, c, x, y)) = first {
        return Err(Error::input(format!(
            "{} and {} differ in {count} of {} pixels; first at ({}, {}) {}: {x} vs {y}",
            pa.display(),
            pb.display(),
            ia.w * ia.h,
            i % ia.w,
            i / ia.w,
            names[c]
        )));
    }
    Ok(format!(
        "{} and {}: the same render ({}×{} pixels, {} channels, bit for bit)\n",
        pa.display(),
        pb.display(),
        ia.w,
        ia.h,
        names.len()
    ))
}
