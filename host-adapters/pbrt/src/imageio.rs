//! Image files in and out.
//!
//! In: images for `imagemap` textures, `infinite` light maps and `compare`/`tonemap`: EXR (linear) and PNG
//! (8/16-bit, sRGB-encoded unless told otherwise), looked up bilinearly with pbrt-v4's conventions (pixel
//! centres at (i + ½)/res, row 0 at the top, `repeat`/`clamp`/`black` wrapping).
//!
//! Out: the film as a linear float EXR (with the fire's hottest temperature as an attribute), display pixels as
//! an 8/16-bit sRGB PNG; every file is written to a temporary name beside it and renamed into place.

use std::path::{Path, PathBuf};

/// Linear RGB pixels, row-major, row 0 at the top.
#[derive(Debug, Clone)]
pub struct RgbImage {
    pub w: usize,
    pub h: usize,
    pub px: Vec<[f32; 3]>,
}

/// Out-of-range lookups.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Clamp,
    Black,
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads an EXR or PNG; `srgb` decodes 8/16-bit PNG values with the sRGB curve (pbrt's default encoding).
/// Its pixels must fit in the default memory budget ([`crate::budget`]).
pub fn read(path: &Path, srgb: bool) -> Result<RgbImage, crate::Error> {
    read_within(path, srgb, crate::budget::default_bytes())
}

/// As [`read`], with the image's size checked against `budget` bytes from its header, before its pixels are
/// read (a 373-byte EXR may claim 100 000² pixels).
pub fn read_within(path: &Path, srgb: bool, budget: u64) -> Result<RgbImage, crate::Error> {
    let file = path.display().to_string();
    let kind = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("exr") => ImageKind::Exr,
        Some("png") => ImageKind::Png,
        _ => return Err(crate::Error::file(file, "images must be .exr or .png")),
    };
    // (A device or FIFO named as an image would never end or block: only regular files, read to their length.)
    let len = std::fs::metadata(path)
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.len())
        .ok_or_else(|| {
            crate::Error::file(
                &file,
                "cannot read: not a regular file (missing, a directory, device or FIFO)",
            )
        })?;
    crate::budget::check(&format!("{file}: the file"), len, 1, budget)?;
    let bytes = firemedium_pbrt_parser::read_regular_file(path)
        .map_err(|e| crate::Error::file(&file, format!("cannot read: {e}")))?;
    decode(&file, &bytes, kind, srgb, budget)
}

/// An EXR's channels other than R, G and B (a spectral film's buckets, a gbuffer's, the AOVs): their names in
/// the file's (alphabetical) order, and per pixel their values in that order (`names.len()` per pixel), the
/// layout [`write_channels_exr`] takes. Its pixels must fit in `budget` bytes, checked from the header.
pub fn read_extra_channels(
    path: &Path,
    budget: u64,
) -> Result<(Vec<String>, Vec<f32>), crate::Error> {
    use exr::prelude::*;
    let file = path.display().to_string();
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| crate::Error::file(&file, format!("cannot read EXR: {e}")))?;
    for h in &meta.headers {
        let n = (h.layer_size.width() as u64).saturating_mul(h.layer_size.height() as u64);
        crate::budget::check(
            &format!(
                "{file}: {} channels of a {}×{} image",
                h.channels.list.len(),
                h.layer_size.width(),
                h.layer_size.height()
            ),
            n.saturating_mul(h.channels.list.len() as u64),
            8,
            budget,
        )?;
    }
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| crate::Error::file(&file, format!("cannot read EXR: {e}")))?;
    let extra: Vec<&AnyChannel<FlatSamples>> = img
        .layer_data
        .channel_data
        .list
        .iter()
        .filter(|c| !["R", "G", "B"].contains(&c.name.to_string().as_str()))
        .collect();
    let n = img.layer_data.size.area();
    let k = extra.len();
    let mut values = filled_vec(&file, n * k, 0f32)?;
    for (j, c) in extra.iter().enumerate() {
        for (i, v) in c.sample_data.values_as_f32().enumerate().take(n) {
            values[i * k + j] = v;
        }
    }
    Ok((extra.iter().map(|c| c.name.to_string()).collect(), values))
}

/// An empty vector with room for `n` values, or an error naming `file` and the bytes when the machine has not
/// got them (never an abort).
fn fallible_vec<T>(file: &str, n: usize) -> Result<Vec<T>, crate::Error> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        crate::Error::file(
            file,
            format!(
                "{} bytes for its pixels: more than this machine can give",
                n.saturating_mul(std::mem::size_of::<T>())
            ),
        )
    })?;
    Ok(v)
}

/// `n` copies of `v`, or an error naming `file` when the machine has not got the bytes (never an abort).
pub fn filled_vec<T: Clone>(file: &str, n: usize, v: T) -> Result<Vec<T>, crate::Error> {
    let mut out = fallible_vec(file, n)?;
    out.resize(n, v);
    Ok(out)
}

/// The image formats [`decode`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImageKind {
    Exr,
    Png,
}

/// Decodes an image held in memory (`file` names it in errors). Its pixels must fit in `budget` bytes, checked
/// from the header before they are allocated; NaN and infinite EXR values are refused.
pub fn decode(
    file: &str,
    bytes: &[u8],
    kind: ImageKind,
    srgb: bool,
    budget: u64,
) -> Result<RgbImage, crate::Error> {
    let fits = |w: usize, h: usize| {
        crate::budget::check(
            &format!("{file}: a {w}×{h} image"),
            (w as u64).saturating_mul(h as u64),
            std::mem::size_of::<[f32; 3]>() as u64,
            budget,
        )
    };
    match kind {
        ImageKind::Exr => {
            use exr::prelude::*;
            let meta = exr::meta::MetaData::read_from_buffered(bytes, false)
                .map_err(|e| crate::Error::file(file, format!("cannot read EXR: {e}")))?;
            let mut most = 0usize;
            for h in &meta.headers {
                let size = h.layer_size;
                fits(size.width(), size.height())?;
                most = most.max(size.width().saturating_mul(size.height()));
            }
            // The pixels' storage reserved here, fallibly, for the largest layer (a 600 KB file may claim 30 000²
            // pixels, 10.8 GB: within a budget of half a large machine, it aborted the process when allocated
            // infallibly); the reader's callback then only sizes it.
            let pixels = std::cell::RefCell::new(Some(fallible_vec::<[f32; 3]>(file, most)?));
            let img = read()
                .no_deep_data()
                .largest_resolution_level()
                .rgba_channels(
                    |res, _| {
                        let mut v = pixels.borrow_mut().take().unwrap_or_default();
                        v.resize(res.width() * res.height(), [0f32; 3]);
                        (res.width(), v)
                    },
                    |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                        px[pos.x() + *w * pos.y()] = [r, g, b]
                    },
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(std::io::Cursor::new(bytes))
                .map_err(|e| crate::Error::file(file, format!("cannot read EXR: {e}")))?;
            let (w, px) = img.layer_data.channel_data.pixels;
            let h = px.len().checked_div(w).unwrap_or(0);
            if px.iter().any(|p| p.iter().any(|c| !c.is_finite())) {
                return Err(crate::Error::file(
                    file,
                    "the image holds NaN or infinite values",
                ));
            }
            Ok(RgbImage { w, h, px })
        }
        ImageKind::Png => {
            let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
            dec.set_transformations(png::Transformations::EXPAND);
            let mut r = dec
                .read_info()
                .map_err(|e| crate::Error::file(file, format!("not a PNG: {e}")))?;
            {
                let info = r.info();
                fits(info.width as usize, info.height as usize)?;
            }
            let n = r
                .output_buffer_size()
                .ok_or_else(|| crate::Error::file(file, "PNG too large"))?;
            let mut buf = fallible_vec::<u8>(file, n)?;
            buf.resize(n, 0);
            let info = r
                .next_frame(&mut buf)
                .map_err(|e| crate::Error::file(file, format!("corrupt PNG: {e}")))?;
            let (w, h) = (info.width as usize, info.height as usize);
            let chans = info.color_type.samples();
            let sixteen = info.bit_depth == png::BitDepth::Sixteen;
            let value = |i: usize| -> f32 {
                let v = if sixteen {
                    u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]]) as f32 / 65535.0
                } else {
                    buf[i] as f32 / 255.0
                };
                if srgb {
                    srgb_to_linear(v)
                } else {
                    v
                }
            };
            let mut px = fallible_vec::<[f32; 3]>(file, w * h)?;
            px.extend((0..w * h).map(|p| {
                let b = p * chans;
                match chans {
                    1 | 2 => [value(b); 3],
                    _ => [value(b), value(b + 1), value(b + 2)],
                }
            }));
            Ok(RgbImage { w, h, px })
        }
    }
}

impl RgbImage {
    fn texel(&self, x: i64, y: i64, wrap: Wrap) -> [f32; 3] {
        let (w, h) = (self.w as i64, self.h as i64);
        let (x, y) = match wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
            Wrap::Black => {
                if x < 0 || y < 0 || x >= w || y >= h {
                    return [0.0; 3];
                }
                (x, y)
            }
        };
        self.px[(x + w * y) as usize]
    }

    /// Bilinear lookup at (s, t) in [0, 1]², t = 0 at the top row.
    pub fn bilerp(&self, s: f32, t: f32, wrap: Wrap) -> [f32; 3] {
        if self.w == 0 || self.h == 0 || !(s.is_finite() && t.is_finite()) {
            return [0.0; 3];
        }
        let (x, y) = (s * self.w as f32 - 0.5, t * self.h as f32 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let mut out = [0f32; 3];
        for (dx, dy, wgt) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let p = self.texel(x0 + dx, y0 + dy, wrap);
            for c in 0..3 {
                out[c] += wgt * p[c];
            }
        }
        out
    }
}

/// The longest file name, in bytes, a file system holds (Linux's NAME_MAX, and that of ext4, xfs, btrfs, NTFS).
pub const NAME_MAX: usize = 255;

/// The temporary file [`write_atomic`] writes before renaming it to `path`: `NAME.tmp-PID.EXT` beside it, or —
/// when that name would not fit a file system's 255 bytes — `.firemedium-PID.tmp`, so that a legal output name
/// always has a temporary that fits.
fn temporary_of(path: &Path) -> PathBuf {
    let tmp = path.with_extension(format!(
        "tmp-{}.{}",
        std::process::id(),
        path.extension().and_then(|e| e.to_str()).unwrap_or("out")
    ));
    match tmp.file_name() {
        Some(n) if n.len() <= NAME_MAX => tmp,
        _ => path.with_file_name(format!(".firemedium-{}.tmp", std::process::id())),
    }
}

/// Whether `path` can be written, checked before the work that fills it: its name fits a file system (255
/// bytes), it is not a folder, and its folder exists and takes a new file (a probe created and removed). The
/// error names the file and why.
pub fn check_writable(path: &Path) -> Result<(), crate::Error> {
    let shown = path.display();
    let name = path
        .file_name()
        .ok_or_else(|| crate::Error::file(&shown, "names no file (it ends in a folder)"))?;
    if name.len() > NAME_MAX {
        return Err(crate::Error::file(
            &shown,
            format!(
                "its name is {} bytes, longer than the {NAME_MAX} a file system's file name holds",
                name.len()
            ),
        ));
    }
    if path.is_dir() {
        return Err(crate::Error::file(&shown, "is a folder"));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(crate::Error::file(
            &shown,
            format!("its folder {} does not exist", dir.display()),
        ));
    }
    let probe = temporary_of(path);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|e| crate::Error::file(&shown, format!("cannot be written: {e}")))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Writes `bytes` to `path` atomically: a temporary file beside it ([`temporary_of`]), then a rename.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), crate::Error>,
) -> Result<(), crate::Error> {
    let tmp = temporary_of(path);
    remove_stale_temporaries(path);
    write(&tmp).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })?;
    std::fs::rename(&tmp, path)
        .map_err(|e| crate::Error::file(path.display(), format!("cannot rename into place: {e}")))
}

/// Removes the temporaries of `path` (`NAME.tmp-PID.EXT`) that a killed writer left behind: those whose process
/// no longer runs (Linux: no `/proc/PID`). A write that is killed cannot clean up after itself; the next write of
/// the same file does.
fn remove_stale_temporaries(path: &Path) {
    let (Some(dir), Some(stem)) = (path.parent(), path.file_stem().and_then(|s| s.to_str())) else {
        return;
    };
    if !Path::new("/proc/self").exists() {
        return;
    }
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let prefix = format!("{stem}.tmp-");
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(&prefix)) else {
            continue;
        };
        let pid = rest.split('.').next().unwrap_or("");
        if pid.parse::<u32>().is_ok() && !Path::new("/proc").join(pid).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The EXR attribute that records the hottest temperature (K) of the scene's fire media: the tone mapper's
/// default white (`firemedium tonemap --white fire`).
pub const FIRE_TEMPERATURE_ATTRIBUTE: &str = "firemediumFireTemperature";

/// Writes `w` × `h` linear RGB pixels (row-major) as an RGB float EXR (with the fire temperature, if any, as an
/// attribute).
pub fn write_exr(
    path: &Path,
    w: usize,
    h: usize,
    rgb: &[[f32; 3]],
    fire_temperature: Option<f64>,
) -> Result<(), crate::Error> {
    let window = Window {
        origin: (0, 0),
        full: (w, h),
    };
    write_exr_as(path, w, h, rgb, fire_temperature, false, window, &[])
}

/// Writes linear RGB plus the channels `names` (a spectral film's buckets `S0.<centre>nm`, a gbuffer's
/// `Albedo.R`, `Px`, …), `values` holding each pixel's channels in turn.
#[allow(clippy::too_many_arguments)]
pub fn write_channels_exr(
    path: &Path,
    w: usize,
    h: usize,
    rgb: &[[f32; 3]],
    names: &[String],
    values: &[f32],
    fire_temperature: Option<f64>,
    fp16: bool,
    window: Window,
    meta: &[(String, String)],
) -> Result<(), crate::Error> {
    use exr::prelude::*;
    let nb = names.len();
    let samples = |v: Vec<f32>| {
        if fp16 {
            FlatSamples::F16(v.into_iter().map(f16::from_f32).collect())
        } else {
            FlatSamples::F32(v)
        }
    };
    let mut list: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
        .iter()
        .enumerate()
        .map(|(c, name)| AnyChannel::new(*name, samples(rgb.iter().map(|p| p[c]).collect())))
        .collect();
    for (k, name) in names.iter().enumerate() {
        list.push(AnyChannel::new(
            name.as_str(),
            samples(
                (0..w * h)
                    .map(|i| values.get(i * nb + k).copied().unwrap_or(0.0))
                    .collect(),
            ),
        ));
    }
    write_atomic(path, |tmp| {
        let mut layer = Layer::new(
            (w, h),
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(list.into()),
        );
        let pos = |v: usize| i32::try_from(v).unwrap_or(i32::MAX);
        layer.attributes.layer_position = Vec2(pos(window.origin.0), pos(window.origin.1));
        let mut image = Image::from_layer(layer);
        image.attributes.display_window =
            IntegerBounds::new(Vec2(0, 0), Vec2(window.full.0.max(1), window.full.1.max(1)));
        let meta = with_checksum(meta, pixels_checksum(rgb, names, values, fp16));
        image.attributes.chromaticities = Some(chromaticities(&meta));
        record_attribute(&mut image.attributes.other, &meta, fire_temperature);
        image
            .write()
            .non_parallel()
            .to_file(tmp)
            .map_err(|e| crate::Error::file(path.display(), format!("cannot write EXR: {e}")))
    })
}

/// Where an image lies on its full film: its first pixel's position, and the film's size (EXR's data window in its
/// display window).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    pub origin: (usize, usize),
    pub full: (usize, usize),
}

/// What a render was (name, value pairs: scene, frame, spp, seed).
pub type Meta = Vec<(String, String)>;

/// The render record's line holding a checksum of the pixels as stored (FNV-1a over each channel in the order of
/// their names — R, G, B and the further ones alike, as the EXR sorts them — its name, then its values as f32
/// bits, a half float as the f32 it reads back as): `merge` verifies each tile against it, so a flipped byte in a
/// tile is an error, not a pixel of −1.2e15 in the frame.
pub const PIXELS_KEY: &str = "pixels_fnv1a64";

/// The checksum of [`PIXELS_KEY`] over `rgb` and the channels `names` whose values `extra` holds per pixel in
/// turn, as stored.
pub fn pixels_checksum(rgb: &[[f32; 3]], names: &[String], extra: &[f32], fp16: bool) -> String {
    let stored = |v: f32| {
        if fp16 {
            exr::prelude::f16::from_f32(v).to_f32()
        } else {
            v
        }
    };
    let nk = names.len();
    let mut channels: Vec<(&str, usize)> =
        ["R", "G", "B"].iter().map(|n| (*n, usize::MAX)).collect();
    channels.extend(names.iter().enumerate().map(|(k, n)| (n.as_str(), k)));
    channels.sort_by(|a, b| a.0.cmp(b.0));
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for (name, k) in channels {
        eat(name.as_bytes());
        for (i, p) in rgb.iter().enumerate() {
            let v = match (name, k) {
                ("R", usize::MAX) => p[0],
                ("G", usize::MAX) => p[1],
                ("B", usize::MAX) => p[2],
                _ => extra.get(i * nk + k).copied().unwrap_or(0.0),
            };
            eat(&stored(v).to_bits().to_le_bytes());
        }
    }
    format!("{h:016x}")
}

/// `meta` with its [`PIXELS_KEY`] line set to the checksum of these pixels.
fn with_checksum(meta: &[(String, String)], sum: String) -> Meta {
    let mut m: Meta = meta
        .iter()
        .filter(|(k, _)| k != PIXELS_KEY)
        .cloned()
        .collect();
    if !meta.is_empty() {
        m.push((PIXELS_KEY.to_string(), sum));
    }
    m
}

/// The EXR attribute that holds a render's [`Meta`], one `name=value` per line. One attribute: the EXR writer
/// keeps attributes in a hash map, so several would be written in a different order by every process and the
/// same render would not give the same bytes.
pub const RENDER_ATTRIBUTE: &str = "firemediumRender";

/// The render record's line that holds the render's wall time (s): the one line in which two renders of the same
/// scene, seed and samples differ (`merge` sums it over the tiles).
pub const RENDER_SECONDS: &str = "render_seconds";

/// How two render records differ, the render time aside (the one line two renders of one scene differ in):
/// `None` when they are records of the same render, else the differing lines as `name a vs b`, `; `-separated.
pub fn record_differences(a: &[(String, String)], b: &[(String, String)]) -> Option<String> {
    let timeless = |m: &[(String, String)]| -> Meta {
        m.iter()
            .filter(|(k, _)| k != RENDER_SECONDS && k != PIXELS_KEY)
            .cloned()
            .collect()
    };
    let (a, b) = (timeless(a), timeless(b));
    if a == b {
        return None;
    }
    // Line by line by name (a line one record lacks is "(none)" there), in the first record's order.
    let get = |m: &Meta, k: &str| m.iter().find(|(n, _)| n == k).map(|(_, v)| v.clone());
    let mut names: Vec<&String> = a.iter().map(|(k, _)| k).collect();
    names.extend(
        b.iter()
            .map(|(k, _)| k)
            .filter(|k| !a.iter().any(|(n, _)| n == *k)),
    );
    let differs: Vec<String> = names
        .into_iter()
        .filter_map(|k| {
            let (x, y) = (get(&a, k), get(&b, k));
            (x != y).then(|| {
                let none = || "(none)".to_string();
                format!(
                    "{k} {} vs {}",
                    x.unwrap_or_else(none),
                    y.unwrap_or_else(none)
                )
            })
        })
        .collect();
    Some(if differs.is_empty() {
        format!("{} vs {} entries", a.len(), b.len())
    } else {
        differs.join("; ")
    })
}

/// The render record's line that holds the fire's hottest temperature (K), as [`FIRE_TEMPERATURE_ATTRIBUTE`]
/// does in an EXR without a record.
const FIRE_TEMPERATURE_KEY: &str = "fire_temperature";

fn meta_text(meta: &[(String, String)]) -> String {
    meta.iter()
        .map(|(k, v)| format!("{k}={}", v.replace('\n', " ")))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The EXR's one attribute of ours (see [`RENDER_ATTRIBUTE`]): the render record with the fire temperature as one
/// of its lines, or — without a record — the fire temperature as its own attribute.
/// The record's key naming the RGB channels' colour space (absent: linear Rec.709/sRGB).
pub const COLORSPACE_KEY: &str = "colorspace";

/// Linear Rec.709 (sRGB's primaries, D65) → ACEScg (AP1 primaries, the ACES white), with the Bradford adaptation:
/// the ACES project's matrix.
pub const SRGB_TO_ACESCG: [[f32; 3]; 3] = [
    [0.613_097_4, 0.339_523_1, 0.047_379_3],
    [0.070_193_7, 0.916_353_9, 0.013_452_4],
    [0.020_615_6, 0.109_569_7, 0.869_814_7],
];

/// The primaries and white the record names (`colorspace=acescg`: AP1 and the ACES white; else Rec.709 and D65),
/// written as the EXR's `chromaticities` so that a compositor reads the colours as meant.
fn chromaticities(meta: &[(String, String)]) -> exr::meta::attribute::Chromaticities {
    use exr::prelude::Vec2;
    let acescg = meta
        .iter()
        .any(|(k, v)| k == COLORSPACE_KEY && v == "acescg");
    let (r, g, b, w) = if acescg {
        (
            (0.713, 0.293),
            (0.165, 0.830),
            (0.128, 0.044),
            (0.32168, 0.33767),
        )
    } else {
        ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06), (0.3127, 0.3290))
    };
    exr::meta::attribute::Chromaticities {
        red: Vec2(r.0, r.1),
        green: Vec2(g.0, g.1),
        blue: Vec2(b.0, b.1),
        white: Vec2(w.0, w.1),
    }
}

/// An EXR text attribute holding `s` as its UTF-8 bytes — any text, where the exr crate's `Text::from` takes only
/// characters up to U+00FF and panics past them (a scene path in Chinese, a euro sign, an emoji). OpenEXR's text
/// attributes are byte strings; OpenEXR's own tools write and show UTF-8 so.
fn text_of(s: &str) -> exr::prelude::Text {
    exr::prelude::Text::from_slice_unchecked(s.as_bytes())
}

/// A text attribute's bytes as a string (UTF-8, any invalid byte replaced).
fn string_of(t: &exr::prelude::Text) -> String {
    String::from_utf8_lossy(t.bytes()).into_owned()
}

fn record_attribute(
    other: &mut std::collections::HashMap<exr::prelude::Text, exr::meta::attribute::AttributeValue>,
    meta: &[(String, String)],
    fire_temperature: Option<f64>,
) {
    use exr::prelude::*;
    if meta.is_empty() {
        if let Some(t) = fire_temperature {
            other.insert(
                Text::from(FIRE_TEMPERATURE_ATTRIBUTE),
                AttributeValue::F64(t),
            );
        }
        return;
    }
    let mut record = meta.to_vec();
    if let Some(t) = fire_temperature {
        record.push((FIRE_TEMPERATURE_KEY.to_string(), format!("{t:e}")));
    }
    other.insert(
        Text::from(RENDER_ATTRIBUTE),
        AttributeValue::Text(text_of(&meta_text(&record))),
    );
}

/// As [`write_exr`], in half floats when `fp16` (pbrt-v4's `savefp16`; values above 65 504 become infinite), and
/// placed at `window` on its film (a crop: the data window inside the display window).
#[allow(clippy::too_many_arguments)]
pub fn write_exr_as(
    path: &Path,
    w: usize,
    h: usize,
    rgb: &[[f32; 3]],
    fire_temperature: Option<f64>,
    fp16: bool,
    window: Window,
    meta: &[(String, String)],
) -> Result<(), crate::Error> {
    use exr::prelude::*;
    let meta = &with_checksum(meta, pixels_checksum(rgb, &[], &[], fp16));
    // The attribute, then one thread writes the blocks in order, so the same render gives the same bytes
    // (parallel writing put them in completion order; farms and caches compare files).
    macro_rules! write {
        ($pixel:expr) => {
            write_atomic(path, |tmp| {
                let channels =
                    SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| $pixel(rgb[x + w * y]));
                let mut image = Image::from_channels((w, h), channels);
                let pos = |v: usize| i32::try_from(v).unwrap_or(i32::MAX);
                image.layer_data.attributes.layer_position =
                    Vec2(pos(window.origin.0), pos(window.origin.1));
                image.attributes.display_window = IntegerBounds::new(
                    Vec2(0, 0),
                    Vec2(window.full.0.max(1), window.full.1.max(1)),
                );
                image.attributes.chromaticities = Some(chromaticities(meta));
                record_attribute(&mut image.attributes.other, meta, fire_temperature);
                image.write().non_parallel().to_file(tmp).map_err(|e| {
                    crate::Error::file(path.display(), format!("cannot write EXR: {e}"))
                })
            })
        };
    }
    if fp16 {
        write!(|p: [f32; 3]| (
            f16::from_f32(p[0]),
            f16::from_f32(p[1]),
            f16::from_f32(p[2])
        ))
    } else {
        write!(|p: [f32; 3]| (p[0], p[1], p[2]))
    }
}

/// What an EXR says about its render: where its pixels lie on the film (data window in display window) and its
/// [`Meta`] (scene, frame, spp, seed; empty for an EXR that did not come from `render`), sorted by name.
pub fn read_meta(path: &Path) -> Result<(Window, Meta), crate::Error> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| crate::Error::file(path.display(), format!("cannot read EXR: {e}")))?;
    let h = meta
        .headers
        .first()
        .ok_or_else(|| crate::Error::file(path.display(), "an EXR without a part"))?;
    let display = h.shared_attributes.display_window;
    let pos = h.own_attributes.layer_position;
    let at = |v: i32, what: &str| {
        usize::try_from(v).map_err(|_| {
            crate::Error::file(
                path.display(),
                format!("{what} {v}: expected a window inside the film (from 0)"),
            )
        })
    };
    if display.position.0 != 0 || display.position.1 != 0 {
        return Err(crate::Error::file(
            path.display(),
            format!(
                "display window at ({}, {}): expected one starting at (0, 0)",
                display.position.0, display.position.1
            ),
        ));
    }
    let window = Window {
        origin: (at(pos.0, "data window x")?, at(pos.1, "data window y")?),
        full: (display.size.0, display.size.1),
    };
    let key = exr::prelude::Text::from(RENDER_ATTRIBUTE);
    let text = match h
        .shared_attributes
        .other
        .get(&key)
        .or_else(|| h.own_attributes.other.get(&key))
    {
        Some(exr::meta::attribute::AttributeValue::Text(t)) => string_of(t),
        _ => String::new(),
    };
    let mut attrs: Meta = text
        .lines()
        .filter_map(|l| l.split_once('='))
        .filter(|(k, _)| *k != FIRE_TEMPERATURE_KEY)
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    attrs.sort();
    Ok((window, attrs))
}

/// The fire temperature an EXR records (see [`write_exr`]), if any.
pub fn read_fire_temperature(path: &Path) -> Result<Option<f64>, crate::Error> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| crate::Error::file(path.display(), format!("cannot read EXR: {e}")))?;
    // (Written as an image attribute; a reader may file an unknown attribute under the layer's.)
    let key = exr::prelude::Text::from(FIRE_TEMPERATURE_ATTRIBUTE);
    let record = exr::prelude::Text::from(RENDER_ATTRIBUTE);
    Ok(meta.headers.first().and_then(|h| {
        let get = |k| {
            h.shared_attributes
                .other
                .get(k)
                .or_else(|| h.own_attributes.other.get(k))
        };
        let t = match (get(&key), get(&record)) {
            (Some(exr::meta::attribute::AttributeValue::F64(t)), _) => Some(*t),
            (_, Some(exr::meta::attribute::AttributeValue::Text(r))) => {
                string_of(r).lines().find_map(|l| {
                    l.strip_prefix(FIRE_TEMPERATURE_KEY)?
                        .strip_prefix('=')?
                        .parse()
                        .ok()
                })
            }
            _ => None,
        };
        t.filter(|t: &f64| t.is_finite() && *t > 0.0)
    }))
}

/// The sRGB transfer curve of a display-linear value in [0, 1].
pub fn srgb_encode(c: f64) -> f64 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Writes display-linear pixels as an sRGB-encoded PNG, 8 or 16 bits per channel, atomically.
pub fn write_png(
    path: &Path,
    w: usize,
    h: usize,
    px: impl Iterator<Item = [f64; 3]>,
    sixteen: bool,
) -> Result<(), crate::Error> {
    let data: Vec<u8> = if sixteen {
        px.flat_map(|p| p.map(|c| (srgb_encode(c) * 65535.0 + 0.5) as u16))
            .flat_map(|v| v.to_be_bytes())
            .collect()
    } else {
        px.flat_map(|p| p.map(|c| (srgb_encode(c) * 255.0 + 0.5) as u8))
            .collect()
    };
    write_png_bytes(path, w, h, &data, sixteen)
}

/// Writes encoded RGB bytes (8-bit, or 16-bit big-endian) as a PNG, atomically.
pub fn write_png_bytes(
    path: &Path,
    w: usize,
    h: usize,
    data: &[u8],
    sixteen: bool,
) -> Result<(), crate::Error> {
    write_atomic(path, |tmp| {
        // (Messages name the file the user asked for, not the temporary one beside it.)
        let f = std::fs::File::create(tmp)
            .map_err(|e| crate::Error::file(path.display(), format!("cannot write: {e}")))?;
        let mut e = png::Encoder::new(std::io::BufWriter::new(f), w as u32, h as u32);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(if sixteen {
            png::BitDepth::Sixteen
        } else {
            png::BitDepth::Eight
        });
        let mut wr = e
            .write_header()
            .map_err(|e| crate::Error::file(path.display(), format!("{e}")))?;
        wr.write_image_data(data)
            .map_err(|e| crate::Error::file(path.display(), format!("{e}")))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_and_wrapping() {
        let img = RgbImage {
            w: 2,
            h: 1,
            px: vec![[0.0; 3], [1.0; 3]],
        };
        assert_eq!(img.bilerp(0.25, 0.5, Wrap::Clamp)[0], 0.0);
        assert_eq!(img.bilerp(0.5, 0.5, Wrap::Clamp)[0], 0.5);
        assert_eq!(img.bilerp(0.0, 0.5, Wrap::Repeat)[0], 0.5);
        assert_eq!(img.bilerp(1.0, 0.5, Wrap::Black)[0], 0.5);
    }
}
