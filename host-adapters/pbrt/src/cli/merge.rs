//! `firemedium merge TILE.exr… -o FRAME.exr`: the tiles of one render (`render --cropwindow` / `--pixelbounds`,
//! each an EXR whose data window sits in the film's display window) assembled into the full frame. Refused: tiles
//! of different films, scenes, frames, sample counts or seeds (the render record each EXR carries), tiles that overlap,
//! and a set that leaves pixels out. Pixels carry their own seeds, so the merged frame equals the full render's
//! pixels bit for bit.

use clap::Args;
use firemedium::imageio;
use firemedium::Error;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The tiles (EXR), in any order.
    #[arg(required = true)]
    tiles: Vec<PathBuf>,
    /// The frame to write (EXR; a PNG preview is not written).
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// The memory budget in GB the images' sizes are checked against before their pixels are read
    /// (default: half the machine's memory).
    #[arg(long, value_name = "GB", value_parser = crate::args::parse_gb)]
    max_memory: Option<f64>,
}

pub fn run(a: &MergeArgs) -> firemedium::Result<String> {
    // (Before the tiles are read and assembled: their work must not end in "cannot write".)
    firemedium::imageio::check_writable(&a.output)?;
    let budget = crate::args::budget(a.max_memory);
    // The first tile's film, attributes and name: every other tile must match them.
    let mut frame: Option<(imageio::Window, imageio::Meta, &PathBuf)> = None;
    let mut rgb: Vec<[f32; 3]> = Vec::new();
    let mut owner: Vec<u32> = Vec::new();
    let mut fire_t = None;
    // The tiles' render times, summed into the frame's record.
    let mut seconds = 0.0;
    // Channels beside R, G, B (AOVs, a spectral or gbuffer film's): the first tile's names, every tile's the
    // same; per pixel their values.
    let mut extra: Option<(Vec<String>, Vec<f32>)> = None;
    for (k, path) in a.tiles.iter().enumerate() {
        let (win, meta) = imageio::read_meta(path)?;
        // A tile an interrupted render wrote (its record says so) is not merged into a finished-looking frame.
        if let Some((_, v)) = meta
            .iter()
            .find(|(k, _)| k == "complete")
            .filter(|(_, v)| v != "true")
        {
            return Err(Error::input(format!(
                    "{}: the tile's record says complete={v}: its render was interrupted (render the tile again)",
                    path.display()
                ),
            ));
        }
        seconds += meta
            .iter()
            .find(|(k, _)| k == imageio::RENDER_SECONDS)
            .and_then(|(_, v)| v.parse::<f64>().ok())
            .unwrap_or(0.0);
        match &frame {
            None => {
                let (w, h) = win.full;
                let n = w.checked_mul(h).filter(|&n| n > 0).ok_or_else(|| {
                    Error::file(path.display(), format!("a film of {w}×{h} pixels"))
                })?;
                firemedium::budget::check(
                    &format!("{}: the merged {w}×{h} frame", path.display()),
                    n as u64,
                    16,
                    budget,
                )?;
                let file = path.display().to_string();
                rgb = imageio::filled_vec(&file, n, [0.0; 3])?;
                owner = imageio::filled_vec(&file, n, 0)?;
                frame = Some((win, meta.clone(), path));
            }
            Some((first, first_meta, first_path)) => {
                if first.full != win.full {
                    return Err(Error::input(format!(
                        "{}: a film of {}×{} pixels, {} one of {}×{}: tiles of different renders",
                        path.display(),
                        win.full.0,
                        win.full.1,
                        first_path.display(),
                        first.full.0,
                        first.full.1
                    )));
                }
                if let Some(differs) = imageio::record_differences(first_meta, &meta) {
                    return Err(Error::input(format!(
                            "{}: not a tile of the render {} is a tile of ({differs}): tiles of different renders",
                            path.display(),
                            first_path.display(),
                        ),
                    ));
                }
            }
        }
        let img = imageio::read_within(path, false, budget)?;
        let (fw, fh) = win.full;
        if win.origin.0 + img.w > fw || win.origin.1 + img.h > fh {
            return Err(Error::input(format!(
                "{}: {}×{} pixels at ({}, {}) reach past the {fw}×{fh} film",
                path.display(),
                img.w,
                img.h,
                win.origin.0,
                win.origin.1
            )));
        }
        let (names, values) = imageio::read_extra_channels(path, budget)?;
        // The pixels as the tile's render wrote them (a tile from before the record held a checksum: as read).
        if let Some((_, want)) = meta.iter().find(|(k, _)| k == imageio::PIXELS_KEY) {
            let got = imageio::pixels_checksum(&img.px, &names, &values, false);
            if got != *want {
                return Err(Error::input(format!(
                        "{}: its pixels' checksum {got} is not the {want} its render recorded: the file was changed or damaged after it was written (render the tile again)",
                        path.display()
                    ),
                ));
            }
        }
        let nk = names.len();
        match &mut extra {
            None => {
                let n = fw * fh;
                firemedium::budget::check(
                    &format!(
                        "{}: the merged frame's {nk} further channels",
                        path.display()
                    ),
                    (n as u64).saturating_mul(nk as u64),
                    4,
                    budget,
                )?;
                let values = imageio::filled_vec(&path.display().to_string(), n * nk, 0.0)?;
                extra = Some((names, values));
            }
            Some((first, _)) if *first != names => {
                return Err(Error::input(format!(
                    "{}: channels {} beside R, G, B, {} has {}: tiles of different renders",
                    path.display(),
                    names.join(" "),
                    a.tiles[0].display(),
                    first.join(" ")
                )));
            }
            Some(_) => {}
        }
        let merged = &mut extra.as_mut().expect("set above").1;
        for y in 0..img.h {
            for x in 0..img.w {
                let i = win.origin.0 + x + fw * (win.origin.1 + y);
                let j = x + img.w * y;
                merged[i * nk..(i + 1) * nk].copy_from_slice(&values[j * nk..(j + 1) * nk]);
                if owner[i] != 0 {
                    return Err(Error::input(format!(
                        "{} overlaps {} at pixel ({}, {})",
                        path.display(),
                        a.tiles[owner[i] as usize - 1].display(),
                        win.origin.0 + x,
                        win.origin.1 + y
                    )));
                }
                owner[i] = k as u32 + 1;
                rgb[i] = img.px[x + img.w * y];
            }
        }
        if fire_t.is_none() {
            fire_t = imageio::read_fire_temperature(path)?;
        }
    }
    let Some((win, mut meta, _)) = frame else {
        return Err(Error::value("no tiles"));
    };
    for (k, v) in meta.iter_mut() {
        if k == imageio::RENDER_SECONDS {
            *v = format!("{seconds:.6}");
        }
    }
    let (fw, _) = win.full;
    if let Some(i) = owner.iter().position(|&o| o == 0) {
        return Err(Error::input(format!(
            "the tiles leave pixel ({}, {}) of the {}×{} film out ({} of its pixels)",
            i % fw,
            i / fw,
            win.full.0,
            win.full.1,
            owner.iter().filter(|&&o| o == 0).count()
        )));
    }
    let full = imageio::Window {
        origin: (0, 0),
        full: win.full,
    };
    match extra {
        Some((names, values)) if !names.is_empty() => imageio::write_channels_exr(
            &a.output, win.full.0, win.full.1, &rgb, &names, &values, fire_t, false, full, &meta,
        ),
        _ => imageio::write_exr_as(
            &a.output, win.full.0, win.full.1, &rgb, fire_t, false, full, &meta,
        ),
    }?;
    Ok(format!(
        "merged {} tiles into {} ({}×{})\n",
        a.tiles.len(),
        a.output.display(),
        win.full.0,
        win.full.1
    ))
}
