//! Progressive rendering: the image in passes over all of its pixels, each pass a run of every pixel's next
//! samples — the same samples, in the same order, as a render of all of them at once, so the image is the same
//! bit for bit — with an estimate of its error after each pass, and, when asked, adaptive sampling to a noise
//! threshold and a time limit.
//!
//! **The estimate.** Each pixel keeps its samples' luminance in two interleaved halves (even and odd sample
//! indices); their difference is an unbiased estimate of the pixel mean's error: with n_A and n_B samples,
//! E[(Y_A − Y_B)²] = σ²(1/n_A + 1/n_B), so e = (Y_A − Y_B)² n_A n_B / n² estimates Var(Y) = σ²/n. The image's
//! relative RMSE estimate is √(Σ e / Σ Y²), the relative RMSE of `firemedium compare` against a reference
//! (√mean((a − r)²) / √mean(r²)) with the reference's place taken by the render itself. That holds for
//! independent samples; a low-discrepancy sampler's (pbrt-v4's default `zsobol`, stratified, Halton, Sobol)
//! halves are not independent — each is a worse-spread set than the whole, and the whole's error falls faster
//! than 1/√n: the halves overstate its error 1.6–4.7× on the campfire at 4–256 spp. So some pixels take a
//! **twin**: the same number of samples again under an independent randomization of the sampler (another seed).
//! A pixel and its twin are two independent estimates of its value with the same n, so d = (M − M')²/2
//! estimates the pixel mean's error without bias, and the sampler's gain — by how much the halves overstate —
//! is G = Σ d/π / Σ e/π over the twins, which scales every pixel's e. The gain differs from pixel to pixel (a
//! flame's smooth light gains more from low discrepancy than a surface's) and the image's error is the bright
//! pixels', so the twins are chosen after the first pass (two samples) with probability π ∝ ½ Y²/ΣY² + ½ 1/N —
//! by the pixel's level, a defensive mix with uniform, about max(256, N/32) of them, Horvitz–Thompson weights
//! 1/π; by their level and not by their halves' difference, which would pick the pixels whose first samples
//! happened to differ most and so understate the gain 2–4×. A twin catches up with its pixel's samples in the
//! pass after it is chosen. Twins cost about 3 % more camera samples (a small image's up to 2×); their samples
//! never enter the image; with `independent` samples there are none (the halves are independent already).
//!
//! **Adaptive sampling.** The film is cut into blocks of 8 × 8 pixels (on the full film, so a tile of a farm's
//! render cuts the same blocks as the whole frame's where it can); a block, not a pixel, because one pixel's two
//! halves are too few to say. Once every pixel has 8 samples, each block's relative variance per sample r (its
//! estimated relMSE, the mean of g e / (Y² + 0.01 Ȳ²) over its pixels, with Ȳ the image's mean luminance — the dark pixels' errors weighed
//! against the image's level, as relMSE weighs them —, times its samples) and its cost per sample c (the seconds
//! its pixels took) say how many samples it should have: the image's relMSE, the blocks' mean of r / n, reaches T²
//! at the least time when n ∝ √(r / c) (a Lagrange multiplier: a cheap noisy block — the floor beside the fire —
//! takes more, an expensive one — a thick flame — fewer), and no block is left above (2T)². After each pass the
//! multiplier that meets T² with the samples the blocks already have is found, and a block that has its share
//! stops. (A threshold on each block's own error, n ∝ r, spends the samples on the blocks whose error is largest,
//! not where a sample lowers the image's error most for its time: it measured 0.8–1.2× uniform sampling at equal
//! relMSE.) The render stops when every block has, when `--spp` samples are reached, or after the pass that
//! crosses the time limit.

use super::*;
use adapt::adapt;
use sums::{choose_twins, gain, gain_relative, slot_of, sums, Px, Sums, Twin};

mod adapt;
mod sums;

/// How a render spends its samples and whom it tells after each pass.
#[derive(Default, Clone, Copy)]
pub struct Progressive<'a> {
    /// Sample adaptively until the image's estimated relative error (relMSE's root) is below this, each block of
    /// pixels taking its share (see the module; `--noise-threshold`).
    pub noise_threshold: Option<f64>,
    /// Stop after the pass that ends past this many seconds of rendering (`--time-limit`).
    pub time_limit: Option<f64>,
    /// Called after each pass.
    pub on_pass: Option<&'a (dyn Fn(&Pass) + Sync)>,
    /// Tally where the paths' time and light go ([`super::profile`]; `--profile`).
    pub profile: bool,
}

impl Progressive<'_> {
    /// How far a render is beyond its samples' share, after a pass `seconds` in with `estimate`: an adaptive
    /// render's way to its threshold ((T / estimate)²: the error falls as 1/√samples) or a time limit's share.
    fn ahead(&self, estimate: Option<f64>, seconds: f64) -> f64 {
        let mut ahead = 0.0f64;
        if let (Some(t), Some(e)) = (self.noise_threshold, estimate) {
            ahead = ahead.max((t / e).powi(2).min(1.0));
        }
        if let Some(limit) = self.time_limit {
            ahead = ahead.max((seconds / limit).min(1.0));
        }
        ahead
    }
}

impl std::fmt::Debug for Progressive<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Progressive")
            .field("noise_threshold", &self.noise_threshold)
            .field("time_limit", &self.time_limit)
            .field("on_pass", &self.on_pass.is_some())
            .field("profile", &self.profile)
            .finish()
    }
}

/// What a pass leaves: when, how many samples so far, and the image's estimated error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pass {
    /// 1 for the first pass.
    pub index: usize,
    /// Seconds since the render began.
    pub seconds: f64,
    /// Camera samples taken so far (all pixels).
    pub samples: u64,
    /// Samples per pixel so far, the most any pixel has.
    pub spp: usize,
    /// The image's estimated relative RMSE (see the module); `None` before every pixel has two samples.
    pub rel_rmse_estimate: Option<f64>,
    /// Pixels still sampling.
    pub active_pixels: usize,
}

/// Why the render stopped sampling.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Stop {
    /// Every pixel took the scene's samples per pixel.
    #[default]
    Spp,
    /// The image's estimated error is below the noise threshold: every block has its share of samples.
    NoiseThreshold,
    /// The time limit passed.
    TimeLimit,
    /// A signal asked the render to stop.
    Interrupted,
}

impl Stop {
    /// What a user reads.
    pub fn describe(self) -> &'static str {
        match self {
            Stop::Spp => "the samples per pixel reached",
            Stop::NoiseThreshold => "the noise threshold reached",
            Stop::TimeLimit => "the time limit reached",
            Stop::Interrupted => "interrupted",
        }
    }
}

/// How far the render is, for a progress bar: the pass, its tiles done of its tiles, and the share of the
/// scene's samples taken (an adaptive render ends early, below 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    pub pass: usize,
    pub tiles_done: usize,
    pub tiles: usize,
    pub fraction: f64,
}

/// The first pass's samples per pixel, and the most a pass takes.
const FIRST_PASS: usize = 2;
const MAX_PASS: usize = 64;

/// What a pixel keeps beside its sums when the film asks for more than the beauty: the spectral film's bins, the
/// gbuffer's and the AOVs' sums.
#[derive(Debug, Clone)]
struct Extra {
    spectrum: Vec<f64>,
    gpixel: film::GPixel,
    apixel: accum::Pixel,
}

impl Extra {
    /// A pixel's extras before its first sample.
    fn new(scene: &scene::Scene) -> Extra {
        let bins = if scene.spectral.is_some() {
            scene.bins.n()
        } else {
            0
        };
        Extra {
            spectrum: vec![0.0; bins],
            gpixel: film::GPixel::default(),
            apixel: accum::Pixel::default(),
        }
    }
}

/// Renders the scene in passes (see the module) with `spp` samples per pixel at most; `progress` is told of
/// every tile finished.
pub fn render_progressive(
    scene: &scene::Scene,
    seed: u64,
    opts: &Progressive<'_>,
    progress: &(dyn Fn(Progress) + Sync),
) -> (Image, Stats) {
    let start = std::time::Instant::now();
    // The pixels rendered: the film's pixel bounds (all of it, unless cropped), in full-film coordinates.
    let [x0, x1, y0, y1] = scene.bounds;
    let (w, h) = (x1 - x0, y1 - y0);
    let integ = integrator::Integrator {
        scene,
        mask: scene.bins.mask(),
        fire_samples: Default::default(),
        failures: Default::default(),
        profile: opts.profile.then(Default::default),
    };
    let (tw, th) = (w.div_ceil(TILE), h.div_ceil(TILE));
    let ntiles = tw * th;
    // Dealt out by stride: rayon splits the list into one contiguous run per thread, so with the tiles in row
    // order the threads would march far-apart parts of the scene at once (and of a fire's grids, which do not
    // fit the shared cache); dealt out, thread j takes tiles j, j + k, j + 2k, … and the threads stay side by
    // side. (Pixels carry their index: the order changes no value.)
    let k = rayon::current_num_threads().max(1);
    let dealt: Vec<usize> = (0..k).flat_map(|j| (j..ntiles).step_by(k)).collect();
    let sampler = scene.sampler.for_film(scene.res, scene.spp, seed);
    // The twins' randomization (see the module); none for independent samples, whose halves are independent.
    let twin_seed = hash(seed, 0x7417_u64, 0, 0);
    let twin_sampler = scene.sampler.for_film(scene.res, scene.spp, twin_seed);
    let twins_wanted = !matches!(scene.sampler, pixel::Sampler::Independent);
    let gspace = scene.gbuffer.map(|g| GSpace::new(scene, g.world));
    // AOVs of the visible surface need the integrator to report it.
    let aov_surface = scene
        .aovs
        .iter()
        .any(|a| matches!(a, Aov::Depth | Aov::Albedo | Aov::Normal));
    let extra = scene.spectral.is_some() || gspace.is_some() || !scene.aovs.is_empty();
    // Each tile's pixels in a run of TILE² slots (row by row inside the tile; the edge tiles' spare slots idle).
    let slots = TILE * TILE;
    let mut px = vec![Px::default(); ntiles * slots];
    // The twins, by slot (chosen after the first pass).
    let mut twins: Vec<Twin> = Vec::new();
    let mut ex: Vec<Extra> = if extra {
        vec![Extra::new(scene); ntiles * slots]
    } else {
        Vec::new()
    };
    let sampling = Sampling {
        scene,
        integ: &integ,
        sampler: &sampler,
        twin_sampler: &twin_sampler,
        seed,
        twin_seed,
        gspace: gspace.as_ref(),
        aov_surface,
        tw,
        w,
        origin: (x0, y0),
    };
    let total_work = (w * h * scene.spp).max(1) as f64;
    let work = AtomicUsize::new(0);
    // The progress a pass's end can say beyond the samples' share: an adaptive render's way to its threshold
    // ((T / estimate)²: the error falls as 1/√samples) or a time limit's share of the time (f64 bits).
    let floor = std::sync::atomic::AtomicU64::new(0f64.to_bits());
    let (mut s0, mut len) = (0usize, FIRST_PASS.min(scene.spp));
    let mut pass = 0;
    let mut stop = Stop::Spp;
    let mut estimate;
    let mut twin_samples = 0u64;
    let mut complete = true;
    loop {
        pass += 1;
        let s1 = (s0 + len).min(scene.spp);
        let done = AtomicUsize::new(0);
        let mut rows = rows_to_sample(&mut px, &mut ex, &mut twins, extra, &dealt, (tw, h));
        let items = rows.len().max(1);
        let (stopped, taken_by_twins) = rows
            .par_iter_mut()
            .map(|(t, r, pxs, exs, tws)| {
                let (cut, taken, twins) = sampling.row((*t, *r), pxs, exs, tws, s0..s1);
                let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                let so_far = work.fetch_add(taken, Ordering::Relaxed) + taken;
                progress(Progress {
                    pass,
                    tiles_done: n * ntiles / items,
                    tiles: ntiles,
                    fraction: (so_far as f64 / total_work)
                        .max(f64::from_bits(floor.load(Ordering::Relaxed)))
                        .min(1.0),
                });
                (cut, twins)
            })
            .reduce(|| (false, 0), |a, b| (a.0 || b.0, a.1 + b.1));
        twin_samples += taken_by_twins;
        drop(rows);
        s0 = s1;
        // The estimate, and the blocks that may stop.
        let Sums {
            e: sum_e,
            y2: sum_y2,
            y: sum_y,
            counted,
            all,
        } = sums(&px, (w, h), tw);
        if pass == 1 && twins_wanted && all && sum_y2 > 0.0 && s0 < scene.spp {
            twins = choose_twins(&px, (w, h), tw, seed, sum_y2);
        }
        let g = gain(&px, &twins);
        estimate = (all && counted > 0 && sum_y2 > 0.0).then(|| (g * sum_e / sum_y2).sqrt());
        if let Some(threshold) = opts.noise_threshold.filter(|_| all && counted > 0) {
            let mean_y = sum_y / counted as f64;
            let g_rel = gain_relative(&px, &twins, 0.01 * mean_y * mean_y);
            adapt(
                &mut px,
                (w, h),
                (x0, y0),
                tw,
                (threshold, g_rel, scene.spp),
                mean_y,
            );
        }
        let samples: u64 = px.iter().map(|p| p.n() as u64).sum();
        // (The edge tiles' spare slots are never sampled, never done: counted apart.)
        let spare = ntiles * slots - w * h;
        let active_pixels = px.iter().filter(|p| !p.done()).count() - spare;
        let seconds = start.elapsed().as_secs_f64();
        floor.fetch_max(opts.ahead(estimate, seconds).to_bits(), Ordering::Relaxed);
        if let Some(f) = opts.on_pass {
            f(&Pass {
                index: pass,
                seconds,
                samples,
                spp: s0,
                rel_rmse_estimate: estimate,
                active_pixels,
            });
        }
        if stopped || interrupted() {
            stop = Stop::Interrupted;
            complete = false;
            break;
        }
        if s0 >= scene.spp {
            break;
        }
        if active_pixels == 0 {
            stop = Stop::NoiseThreshold;
            break;
        }
        // The next pass: as many samples as so far (up to MAX_PASS), so the samples double from pass to pass (2,
        // 4, 8, …: even steps on a log-log curve, whole powers of two for the Sobol' sampler); with a threshold a
        // quarter of the samples so far, at least 4 (a block is checked after each pass: doubling would overshoot
        // its need by up to 2×).
        len = if opts.noise_threshold.is_some() {
            (s0 / 4).clamp(4, MAX_PASS)
        } else {
            s0.clamp(1, MAX_PASS)
        };
        if let Some(limit) = opts.time_limit {
            if seconds >= limit {
                stop = Stop::TimeLimit;
                break;
            }
            // The next pass no longer than the time left, at this render's pace per pixel sample.
            let per = seconds / samples.max(1) as f64;
            let fits = ((limit - seconds) / (per * active_pixels.max(1) as f64)).floor();
            len = len.min((fits as usize).max(1));
        }
    }
    drop(twins);
    // (The sums are given back as they are read: gone before the image's second copy.)
    let (xyz, extra, camera_rays) = pixels(scene, (px, ex), gspace.is_some(), (w, h), tw);
    let rgb = linear_srgb(&xyz);
    let stats = Stats {
        seconds: start.elapsed().as_secs_f64(),
        camera_rays,
        fire_light_samples: integ.fire_samples.into_inner(),
        plugin_failures: integ.failures.into_report(),
        passes: pass,
        rel_rmse_estimate: estimate,
        stop,
        twin_samples,
        profile: integ.profile.as_ref().map(|p| p.report()),
    };
    (
        Image {
            w,
            h,
            rgb,
            xyz,
            complete,
            origin: (x0, y0),
            full: scene.res,
            extra,
            meta: Vec::new(),
        },
        stats,
    )
}

/// The pixels' linear sRGB from their XYZ.
fn linear_srgb(xyz: &[DVec3]) -> Vec<[f32; 3]> {
    xyz.iter()
        .map(|v| cie::xyz_to_linear_srgb(*v).as_vec3().to_array())
        .collect()
}

/// A row of a tile: the tile, the row in it, its pixels, their extras and their twins.
type Row<'p> = (usize, usize, &'p mut [Px], &'p mut [Extra], &'p mut [Twin]);

/// A pass's work: every row of every tile (in the `dealt` order) that has a pixel still sampling — rows, not
/// tiles, so that a pass in which a few tiles are left keeps every thread busy. `extra`: whether pixels keep
/// extras; `twins` by slot; `tw` tiles across, `h` rows rendered.
fn rows_to_sample<'p>(
    px: &'p mut [Px],
    ex: &'p mut [Extra],
    twins: &'p mut [Twin],
    extra: bool,
    dealt: &[usize],
    (tw, h): (usize, usize),
) -> Vec<Row<'p>> {
    let slots = TILE * TILE;
    let mut by_tile: Vec<Option<(&mut [Px], &mut [Extra])>> = {
        let exs: Box<dyn Iterator<Item = &mut [Extra]>> = if extra {
            Box::new(ex.chunks_mut(slots))
        } else {
            Box::new(std::iter::repeat_with(|| &mut [][..]))
        };
        px.chunks_mut(slots).zip(exs).map(Some).collect()
    };
    // Each row's twins (a row is TILE consecutive slots).
    let mut twin_rows: Vec<&mut [Twin]> = Vec::with_capacity(by_tile.len() * TILE);
    let mut rest = twins;
    for row in 0..by_tile.len() * TILE {
        let end = rest.partition_point(|t| t.slot < (row + 1) * TILE);
        let (these, after) = rest.split_at_mut(end);
        twin_rows.push(these);
        rest = after;
    }
    let mut v = Vec::new();
    for &t in dealt {
        let Some((p, e)) = by_tile[t].take() else {
            continue;
        };
        let ex_rows: Box<dyn Iterator<Item = &mut [Extra]>> = if extra {
            Box::new(e.chunks_mut(TILE))
        } else {
            Box::new(std::iter::repeat_with(|| &mut [][..]))
        };
        for (r, (pr, er)) in p.chunks_mut(TILE).zip(ex_rows).enumerate() {
            if (t / tw) * TILE + r < h && pr.iter().any(|q| !q.done()) {
                v.push((t, r, pr, er, std::mem::take(&mut twin_rows[t * TILE + r])));
            }
        }
    }
    v
}

/// The rendered pixels' values from their sums — Σ w L / Σ w, finished by the film's response —, the channels
/// beside the beauty (spectral buckets, the gbuffer's, the AOVs') with their names, and the camera rays taken.
///
/// The sums are read a row of tiles at a time from the last, and each row's memory given back once read (a
/// large film's sums are a mapping of their own, which shrinks in place), so the sums and the image they make
/// are not held whole together: the image's pages are touched as its rows are written.
#[allow(clippy::type_complexity)]
fn pixels(
    scene: &scene::Scene,
    (mut px, mut ex): (Vec<Px>, Vec<Extra>),
    gspace: bool,
    (w, h): (usize, usize),
    tw: usize,
) -> (Vec<DVec3>, Option<(Vec<String>, Vec<f32>)>, usize) {
    // Filled from the last pixel back and turned round at the end: its pages are touched as it grows.
    let mut xyz = Vec::with_capacity(w * h);
    let mut names: Option<Vec<String>> = match (&scene.spectral, scene.gbuffer) {
        (Some(b), _) => Some(
            b.centres()
                .iter()
                .map(|&l| spectral_channel_name(l))
                .collect(),
        ),
        (None, Some(_)) => Some(
            film::GBUFFER_CHANNELS
                .iter()
                .map(|s| s.to_string())
                .collect(),
        ),
        (None, None) => None,
    };
    if !scene.aovs.is_empty() {
        names
            .get_or_insert_with(Vec::new)
            .extend(aov::channel_names(&scene.aovs));
    }
    let nb = names.as_ref().map_or(0, |n| n.len());
    let mut buckets = vec![0f32; w * h * nb];
    let mut camera_rays = 0usize;
    let tile_row = tw * TILE * TILE;
    for ty in (0..h.div_ceil(TILE)).rev() {
        for (cy, cx) in (ty * TILE..h.min((ty + 1) * TILE))
            .rev()
            .flat_map(|cy| (0..w).rev().map(move |cx| (cy, cx)))
        {
            let i = slot_of(cx, cy, tw);
            let p = &px[i];
            let n = p.n() as f64;
            camera_rays += p.n() as usize;
            let weights = p.weights;
            // (n = spp for every pixel of a render that took them all: the value of a render in one pass.)
            xyz.push(if weights != 0.0 {
                scene.response.finish(p.sum * (n / weights)) / n
            } else {
                DVec3::ZERO
            });
            if nb == 0 {
                continue;
            }
            let e = &ex[i];
            let mut b = match &scene.spectral {
                Some(bk) if weights != 0.0 => {
                    let k = scene.response.imaging_ratio / weights;
                    let s: Vec<f64> = e.spectrum.iter().map(|v| v * k).collect();
                    bk.resample(&scene.bins, &s)
                }
                Some(bk) => vec![0.0; bk.n],
                None if gspace => e.gpixel.finish(weights).to_vec(),
                None => Vec::new(),
            };
            if !scene.aovs.is_empty() {
                b.extend(e.apixel.finish(scene, &scene.aovs, weights, p.n()));
            }
            let j = cx + w * cy;
            buckets[j * nb..(j + 1) * nb].copy_from_slice(&b);
        }
        px.truncate(ty * tile_row);
        px.shrink_to_fit();
        if !ex.is_empty() {
            ex.truncate(ty * tile_row);
            ex.shrink_to_fit();
        }
    }
    xyz.reverse();
    (xyz, names.map(|n| (n, buckets)), camera_rays)
}

/// What every row of a pass shares: the scene, its integrator, the samplers and their seeds, what the film keeps
/// beside the beauty, and where the rendered pixels lie.
struct Sampling<'a> {
    scene: &'a scene::Scene,
    integ: &'a integrator::Integrator<'a>,
    sampler: &'a pixel::Sampler,
    twin_sampler: &'a pixel::Sampler,
    seed: u64,
    twin_seed: u64,
    gspace: Option<&'a GSpace>,
    aov_surface: bool,
    /// Tiles across, the rendered pixels' width and their origin on the full film.
    tw: usize,
    w: usize,
    origin: (usize, usize),
}

impl Sampling<'_> {
    /// Samples `range` of every pixel still sampling in row `r` of tile `t` (its pixels `pxs`, their extras
    /// `exs`), and its twins' (`tws`) catching up: whether a signal cut it short, the samples taken, the twins'
    /// samples.
    fn row(
        &self,
        (t, r): (usize, usize),
        pxs: &mut [Px],
        exs: &mut [Extra],
        tws: &mut [Twin],
        range: std::ops::Range<usize>,
    ) -> (bool, usize, u64) {
        let Sampling {
            scene,
            integ,
            sampler,
            twin_sampler,
            seed,
            twin_seed,
            gspace,
            aov_surface,
            tw,
            w,
            origin: (x0, y0),
        } = *self;
        let (s0, s1) = (range.start, range.end);
        let mut cut = false;
        let (mut taken, mut twins) = (0usize, 0u64);
        let (tx, ty) = (t % tw, t / tw);
        let cy = ty * TILE + r;
        for (i, cx) in (tx * TILE..((tx + 1) * TILE).min(w)).enumerate() {
            let slot = i;
            let p = &mut pxs[slot];
            if p.done() {
                continue;
            }
            let (x, y) = (x0 + cx, y0 + cy);
            let mut e = exs.get_mut(slot);
            // The pixel's strata order (stratified sampling), fixed by the seed and the pixel.
            let order = hash(seed, x as u64, y as u64, u64::MAX);
            let began = std::time::Instant::now();
            for s in s0..s1 {
                // Checked per sample: Ctrl-C ends a render whose pixels take long within a sample's time
                // (each pixel keeps the samples it finished: the image is whole).
                if interrupted() {
                    cut = true;
                    break;
                }
                let (mut rng, wt, (fx, fy), (o, d)) =
                    camera_sample(scene, sampler, seed, order, (x, y), s);
                let mut visible = None;
                let want = (gspace.is_some() || aov_surface).then_some(&mut visible);
                let mut split = aov::Split::default();
                let aovs = (!scene.aovs.is_empty()).then_some(&mut split);
                let l = integ.li_visible(o, d, &mut rng, want, aovs);
                // (A signal during the path cut it short: the sample is not one; the pixel keeps those
                // before it.)
                if interrupted() {
                    cut = true;
                    break;
                }
                let raw = scene.response.sensor_xyz(&scene.bins, &l);
                let sensor = scene.response.clamp_sample(raw);
                p.sum += sensor * wt;
                p.weights += wt;
                if s & 1 == 0 {
                    p.even_y += sensor.y * wt;
                    p.even_w += wt;
                }
                p.n_done += 1;
                taken += 1;
                if let Some(e) = e.as_deref_mut() {
                    if !scene.aovs.is_empty() {
                        // The beauty's clamp, as a factor every part shares.
                        let clamp = if sensor == raw { 1.0 } else { sensor.y / raw.y };
                        let clamp = if clamp.is_finite() { clamp } else { 0.0 };
                        e.apixel.add(scene, wt, l, &split, clamp, visible.as_ref());
                    }
                    if let (Some(g), Some(v)) = (&gspace, visible) {
                        e.gpixel.add(wt, &g.sample(scene, fx, fy, &v), sensor);
                    }
                    if scene.spectral.is_some() {
                        e.spectrum
                            .iter_mut()
                            .zip(l.0)
                            .for_each(|(a, v)| *a += v as f64 * wt);
                    }
                }
            }
            p.seconds += began.elapsed().as_secs_f32();
            if cut {
                break;
            }
            let first = t * TILE * TILE + r * TILE;
            if let Some(twin) = tws.iter_mut().find(|tw| tw.slot == first + slot) {
                // (A twin chosen after the first pass catches up with its pixel's samples first.)
                let from = if twin.w == 0.0 { 0 } else { s0 };
                let order = hash(twin_seed, x as u64, y as u64, u64::MAX);
                for s in from..s1 {
                    let (mut rng, wt, _, (o, d)) =
                        camera_sample(scene, twin_sampler, twin_seed, order, (x, y), s);
                    let l = integ.li_visible(o, d, &mut rng, None, None);
                    let sensor = scene
                        .response
                        .clamp_sample(scene.response.sensor_xyz(&scene.bins, &l));
                    twin.y += sensor.y * wt;
                    twin.w += wt;
                    twins += 1;
                }
            }
        }
        (cut, taken, twins)
    }
}

/// Sample `s` of pixel `(x, y)` (its strata `order`) under `sampler` randomized by `seed`: the path's sample
/// stream, the pixel filter's weight (pbrt-v4's RGBFilm: the pixel is Σ w L / Σ w), the film position and the
/// camera ray. The time in the shutter is drawn after the film position, before the lens (pbrt-v4's camera
/// sample), and only when a medium blurs by its velocity.
fn camera_sample(
    scene: &super::scene::Scene,
    sampler: &pixel::Sampler,
    seed: u64,
    order: u64,
    (x, y): (usize, usize),
    s: usize,
) -> (pixel::Samples, f64, (f64, f64), (glam::Vec3A, glam::Vec3A)) {
    let rng = Rng::new(hash(seed, x as u64, y as u64, s as u64));
    let mut rng = sampler.samples(s, scene.spp, order, (x as u32, y as u32), rng);
    let mut u = [rng.next_f64(), rng.next_f64()];
    if !scene.pixel_jitter {
        u = [0.5, 0.5];
    }
    let (off, wt) = scene.filter.sample(u);
    let (fx, fy) = (x as f64 + 0.5 + off[0], y as f64 + 0.5 + off[1]);
    if let Some([open, close]) = scene.shutter {
        rng.time = open + (close - open) * rng.next_f64();
    }
    let ray = camera_ray(scene, fx, fy, &mut rng);
    (rng, wt, (fx, fy), ray)
}

#[cfg(test)]
mod tests {
    use super::sums::DONE;
    use super::*;

    #[test]
    fn a_pixels_sums_are_pbrt_v4s_size_and_its_halves_the_totals_split() {
        assert_eq!(std::mem::size_of::<Px>(), 56);
        // Samples 1, 3 (even indices 0, 2) and 2, 5 (odd), weights 1 and ½: the halves' means 2 and 4 ⅓.
        let mut p = Px::default();
        for (s, (y, w)) in [(1.0, 1.0), (2.0, 1.0), (3.0, 0.5), (5.0, 0.5)]
            .into_iter()
            .enumerate()
        {
            p.sum.y += y * w;
            p.weights += w;
            if s % 2 == 0 {
                p.even_y += y * w;
                p.even_w += w;
            }
            p.n_done += 1;
        }
        let (y, e) = p.estimate().expect("two samples");
        let (a, b) = ((1.0 + 1.5) / 1.5, (2.0 + 2.5) / 1.5);
        assert!((y - 7.0 / 3.0).abs() < 1e-15, "{y}");
        assert!((e - (a - b) * (a - b) * 4.0 / 16.0).abs() < 1e-15, "{e}");
        assert!(!p.done() && p.n() == 4);
        p.n_done |= DONE;
        assert!(p.done() && p.n() == 4);
    }

    #[test]
    fn each_row_samples_with_its_own_twins_and_only_those() {
        // 40 × 37 pixels (3 × 3 tiles, the edge ones cut), every pixel luminance 1 with two samples: the twins
        // come out by slot, and a pass's rows — dealt out of order, the stopped ones left out — each hold the
        // twins of their own pixels, every twin of a sampled row once.
        let (w, h) = (40usize, 37usize);
        let tw = w.div_ceil(TILE);
        let ntiles = tw * h.div_ceil(TILE);
        let mut px = vec![Px::default(); ntiles * TILE * TILE];
        for cy in 0..h {
            for cx in 0..w {
                let p = &mut px[slot_of(cx, cy, tw)];
                (p.sum, p.weights, p.n_done) = (DVec3::ONE * 2.0, 2.0, 2);
                (p.even_y, p.even_w) = (1.0, 1.0);
            }
        }
        let mut twins = choose_twins(&px, (w, h), tw, 7, (w * h) as f64);
        // K = 256 of 1 480 pixels, each with π = K/N: about 256 twins.
        assert!((200..320).contains(&twins.len()), "{}", twins.len());
        assert!(twins.windows(2).all(|t| t[0].slot < t[1].slot));
        assert!(twins.iter().all(|t| (t.p - 256.0 / 1480.0).abs() < 1e-12));
        // Tile 4's rows stop.
        px[4 * TILE * TILE..5 * TILE * TILE]
            .iter_mut()
            .for_each(|p| p.n_done |= DONE);
        let chosen: Vec<usize> = twins.iter().map(|t| t.slot).collect();
        let dealt: Vec<usize> = (0..ntiles).rev().collect();
        let mut ex = Vec::new();
        let rows = rows_to_sample(&mut px, &mut ex, &mut twins, false, &dealt, (tw, h));
        let mut seen = Vec::new();
        for (t, r, pxs, _, tws) in &rows {
            assert_eq!(pxs.len(), TILE);
            let first = t * TILE * TILE + r * TILE;
            assert!(tws.iter().all(|x| (first..first + TILE).contains(&x.slot)));
            seen.extend(tws.iter().map(|x| x.slot));
        }
        seen.sort_unstable();
        let tile4 = 4 * TILE * TILE..5 * TILE * TILE;
        let want: Vec<usize> = chosen.into_iter().filter(|s| !tile4.contains(s)).collect();
        assert_eq!(seen, want);
        assert_eq!(rows.len(), 37 * 3 - TILE, "every rendered row but tile 4's");
    }
}
