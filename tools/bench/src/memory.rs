//! `firemedium bench memory`: the two rooms pbrt-v4's memory was measured on — a scattering fire (albedo 0.8)
//! lighting its room, and an absorbing fire lighting its room through the fire light — over a pbrt-v4 `nanovdb`
//! medium, rendered by `firemedium render` (a child process loading the cdylib, as a user runs it), in rounds
//! that alternate the rooms and the march's copy of the grids (`lattice` as the medium's default, and `dense`).
//! Each render's peak RSS stands beside pbrt-v4's own, measured on the same rooms over the 256-voxel campfire
//! written as NanoVDB (pbrt-v4 is not installable here: its figures are constants, measured beside this renderer).

use crate::fire_light::{room_scene, Fire};
use crate::user_path::{render, Rendered, Scratch};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct MemoryArgs {
    /// The fire, read by pbrt-v4's `nanovdb` medium: pbrt-v4's figures are for the 256-voxel campfire as a `.nvdb`
    /// (OpenVDB's `nanovdb_convert` of the one generated here); default: that campfire as OpenVDB (`.vdb`), generated
    /// once into the temp directory.
    #[arg(long)]
    dataset: Option<PathBuf>,
    /// Samples per pixel of every render.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    spp: u32,
    /// Rounds: each round renders every room and lattice once, in turn; a row shows every round's figure.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    rounds: u32,
    /// The film's resolution WxH instead of the rooms' own (320×180 and 320×240; pbrt-v4's figures are for those).
    #[arg(long, value_name = "WxH")]
    resolution: Option<String>,
}

/// pbrt-v4's peak RSS on each room over the 256-voxel campfire as `.nvdb`, measured beside this renderer, as
/// `/usr/bin/time -f %M` gives it: 42 000 and 44 000 KiB (what docs/results writes as 42 and 44 MB, beside this
/// renderer's figures read the same way), here in MB of 10⁶ bytes as `render --stats` prints its own.
const PBRT_V4_MB: [f64; 2] = [42_000.0 * 1.024e-3, 44_000.0 * 1.024e-3];

/// A room: its name, the fire in it, its `volpath` depth and film height (320 wide).
struct Room {
    name: &'static str,
    fire: Fire,
    maxdepth: u32,
    height: u32,
}

const ROOMS: [Room; 2] = [
    Room {
        name: "a scattering fire (albedo 0.8, `Lescale` 3) lighting its room, maxdepth 10",
        fire: Fire::NanoVdb {
            albedo: 0.8,
            lescale: 3.0,
        },
        maxdepth: 10,
        height: 180,
    },
    Room {
        name:
            "an absorbing fire (`Lescale` 1) lighting its room through the fire light, maxdepth 5",
        fire: Fire::NanoVdb {
            albedo: 0.0,
            lescale: 1.0,
        },
        maxdepth: 5,
        height: 240,
    },
];

/// The `lattice` settings compared: the medium's default, and the copy asked for.
const LATTICES: [Option<&str>; 2] = [None, Some("dense")];

/// The room's scene over `dataset`, with `lattice` on its medium when given.
fn scene(room: &Room, dataset: &std::path::Path, lattice: Option<&str>) -> String {
    let s = room_scene(dataset, room.fire, room.maxdepth).replacen(
        "\"integer yresolution\" 240",
        &format!("\"integer yresolution\" {}", room.height),
        1,
    );
    match lattice {
        Some(l) => s.replacen(
            "\"float Lescale\"",
            &format!("\"string lattice\" \"{l}\" \"float Lescale\""),
            1,
        ),
        None => s,
    }
}

/// The range of `xs` as "a–b" (one value alone), with `digits` decimals.
fn range(xs: &[f64], digits: usize) -> String {
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if format!("{lo:.digits$}") == format!("{hi:.digits$}") {
        format!("{lo:.digits$}")
    } else {
        format!("{lo:.digits$}–{hi:.digits$}")
    }
}

pub fn report(a: &MemoryArgs) -> Result<String, String> {
    let dataset = match &a.dataset {
        // (Absolute: the scenes are written elsewhere, and a scene's relative path is its own directory's.)
        Some(f) => std::fs::canonicalize(f).map_err(|e| format!("{}: {e}", f.display()))?,
        None => crate::perf::dataset(&std::env::temp_dir(), 256)?,
    };
    let dir = Scratch::new("memory")?;
    let spp = a.spp.to_string();
    let mut extra = vec!["--spp", spp.as_str(), "--threads", "2"];
    if let Some(r) = &a.resolution {
        extra.extend(["--resolution", r.as_str()]);
    }
    // runs[room][lattice]: one render per round, the rooms and lattices alternating within a round.
    let mut runs: Vec<Vec<Vec<Rendered>>> = vec![vec![Vec::new(); LATTICES.len()]; ROOMS.len()];
    for _ in 0..a.rounds {
        for (r, room) in ROOMS.iter().enumerate() {
            for (l, lattice) in LATTICES.iter().enumerate() {
                let name = format!("room{r}-{}", lattice.unwrap_or("default"));
                runs[r][l].push(render(
                    &dir.0,
                    &name,
                    &scene(room, &dataset, *lattice),
                    &extra,
                )?);
            }
        }
    }
    let mut out = format!(
        "dataset {} as pbrt-v4's `nanovdb` medium, `firemedium render --spp {} --threads 2{}` (a child process; the films 320×180 and 320×240 unless a resolution is given), {} alternating round(s); peak RSS in MB of 10⁶ bytes (`render --stats`); pbrt-v4's measured beside this renderer on these rooms over the 256-voxel campfire as `.nvdb` (`/usr/bin/time`: 42 000 and 44 000 KiB)\n\n",
        dataset.display(),
        a.spp,
        a.resolution
            .as_ref()
            .map_or(String::new(), |r| format!(" --resolution {r}")),
        a.rounds
    );
    out += "| room | `lattice` | peak RSS, MB | pbrt-v4, MB | peak / pbrt-v4 | load s | render s |\n|---|---|---|---|---|---|---|\n";
    for (r, room) in ROOMS.iter().enumerate() {
        for (l, lattice) in LATTICES.iter().enumerate() {
            let rs = &runs[r][l];
            let peak: Vec<f64> = rs.iter().map(|x| x.peak_mb).collect();
            let ratio: Vec<f64> = peak.iter().map(|m| m / PBRT_V4_MB[r]).collect();
            out += &format!(
                "| {} | {} | {} | {:.1} | {}× | {} | {} |\n",
                room.name,
                lattice.unwrap_or("auto (none: the grids read in place)"),
                range(&peak, 1),
                PBRT_V4_MB[r],
                range(&ratio, 2),
                range(&rs.iter().map(|x| x.load_s).collect::<Vec<_>>(), 3),
                range(&rs.iter().map(|x| x.render_s).collect::<Vec<_>>(), 3),
            );
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_room_asks_for_its_film_and_lattice() {
        let d = std::path::Path::new("/data/fire.nvdb");
        let s = scene(&ROOMS[0], d, Some("dense"));
        assert!(s.contains("\"integer xresolution\" 320 \"integer yresolution\" 180"));
        assert!(s.contains("\"string lattice\" \"dense\" \"float Lescale\" 3"));
        assert!(s.contains("\"integer maxdepth\" 10") && s.contains("\"string type\" \"nanovdb\""));
        let s = scene(&ROOMS[1], d, None);
        assert!(s.contains("\"integer yresolution\" 240") && !s.contains("lattice"));
        assert_eq!(range(&[1.04, 1.0], 1), "1.0");
        assert_eq!(range(&[54.61, 54.94, 54.4], 1), "54.4–54.9");
    }
}
