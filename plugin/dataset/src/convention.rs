//! What a simulator's file means: which grid is the smoke (soot), which the temperature and in what unit, which
//! the flame and which the velocity — from the grids' names —, and, from the data where the names do not say it,
//! which way is up, where the flame is, and a soot scale that makes a simulator's arbitrary density a flame in its
//! smoke rather than an opaque body. Every choice carries the sentence that says why: `firemedium scene` prints them
//! and writes them into its scene; a fire medium that names no `source` makes the same choices and says them in
//! its notes.
//!
//! The rules (docs/guide/your-vdb.md says them for users):
//! - **Names.** EmberGen: `smoke`, `temperature` and `flames`/`fuel`. Blender's Mantaflow cache: `density` and
//!   `flame` with `shadow`, a `velocity` vector grid or no `temperature` (its `temperature` is Mantaflow's heat,
//!   not kelvin: the flame grid is read as Cycles does). Houdini Pyro: `density` with `vel`, `flame` or `heat`.
//!   NanoVDB files with `density`: pbrt-v4's. Anything else with a temperature: a generic density + temperature.
//! - **Temperature unit**, from the grid's peak (its 99.9th percentile over the voxels it fills, so a stray voxel
//!   does not decide): at or above 500, kelvin (never scaled again; above 5 000 K a warning); from 50 to 500, kelvin
//!   too cool to glow (a warning: either a cold smoke or another unit); below 50, a simulator's relative
//!   temperature, `temperaturescale` = min(5 000 K, 1 500 K / peak) — Houdini's Pyro shader's 1 → 5 000 K unless
//!   that puts the flame above 1 500 K, what a fire's luminous soot reaches. A flame intensity (0–1: Blender's
//!   `flame`, or a file's only heat grid) is 1 000 K at its edge to 1 500 K at 1 (`flameignition` 1,
//!   `flamemax` 1.5), where it is above zero.
//! - **Up**: flames rise. The heat's centroid lies below the smoke's, and the hottest gas below the merely warm;
//!   the axis (and its sign) along which both separate most is up. When no axis stands out, or two do about
//!   equally, the tool's own convention decides (Blender, the generator, the thesis and generic files: +z;
//!   Houdini, EmberGen and pbrt-v4's nanovdb: +y), and a tie is said as a warning.
//! - **Soot**: a density whose peak is at most 1e-4 is a soot volume fraction already (a flame's is 1e-8–1e-5):
//!   `sootscale` 1. Otherwise the scale makes the thickest line of sight across the fire (along either horizontal
//!   axis) one optical depth at 550 nm: the flame shows through its own smoke, and the smoke is seen.

use crate::grid::Grid;
use crate::{Error, GridEntry};
use glam::DVec3;

/// A temperature's peak at or above which a grid is kelvin.
pub const KELVIN_PEAK: f64 = 500.0;
/// A relative temperature's peak below this; kelvin at or above [`KELVIN_PEAK`]; between, kelvin too cool to glow.
pub const RELATIVE_PEAK: f64 = 50.0;
/// The temperature a relative grid's peak is mapped to, at most (K): what a fire's luminous soot reaches (pool
/// fires' luminous zones radiate at 1 100–1 400 K; the generator's campfire peaks at 1 390 K). Hotter, the flame
/// renders white.
pub const FLAME_KELVIN: f64 = 1500.0;
/// A flame intensity's (0–1) temperatures, in 1000 K, as the `blender` source's `flameignition` and `flamemax`
/// take them: 1 000 K at its edge to [`FLAME_KELVIN`] at its peak. (Cycles' own 1.5 and 3.0 put the flame above
/// any hydrocarbon's adiabatic flame temperature, ~2 250 K, and render it white.)
pub const FLAME_RANGE: (f64, f64) = (1.0, FLAME_KELVIN / 1000.0);
/// Kelvin per unit of Houdini's temperature field: its Pyro shader's blackbody maps 1 to 5000 K by default.
pub const HOUDINI_KELVIN: f64 = 5000.0;
/// Above this (K, after any scale) a temperature is beyond any flame: a warning.
pub const HOTTEST_FLAME: f64 = 5000.0;
/// A density peak at or below which the density is a soot volume fraction already.
pub const VOLUME_FRACTION_PEAK: f64 = 1e-4;
/// The optical depth at 550 nm of the thickest horizontal line of sight, for a simulator's density.
pub const SMOKE_DEPTH: f64 = 1.0;

/// The tools whose conventions are known (the `source` presets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tool {
    /// Density and temperature in kelvin (the generator, the thesis's files, a generic file).
    Kelvin,
    /// pbrt-v4's nanovdb: density and temperature in kelvin.
    Pbrt,
    /// Blender's Mantaflow cache: the flame grid is the fire's temperature, as Cycles maps it.
    Blender,
    /// Houdini Pyro: density, a relative temperature (or heat), flame, vel.
    Houdini,
    /// EmberGen: smoke, temperature, flames, fuel.
    EmberGen,
}

impl Tool {
    /// The `source` parameter's name for it.
    pub fn name(self) -> &'static str {
        match self {
            Tool::Kelvin => "kelvin",
            Tool::Pbrt => "pbrt",
            Tool::Blender => "blender",
            Tool::Houdini => "houdini",
            Tool::EmberGen => "embergen",
        }
    }
    /// Its up axis, which breaks a tie the data leaves.
    pub fn up(self) -> Up {
        match self {
            Tool::Houdini | Tool::EmberGen | Tool::Pbrt => Up {
                axis: 1,
                down: false,
            },
            Tool::Kelvin | Tool::Blender => Up {
                axis: 2,
                down: false,
            },
        }
    }
    fn label(self) -> &'static str {
        match self {
            Tool::Kelvin => "a generic density + temperature file",
            Tool::Pbrt => "pbrt-v4's nanovdb",
            Tool::Blender => "Blender's Mantaflow cache",
            Tool::Houdini => "Houdini Pyro",
            Tool::EmberGen => "EmberGen",
        }
    }
}

/// A signed axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Up {
    /// 0, 1, 2: x, y, z.
    pub axis: usize,
    /// Whether up is the axis's negative direction.
    pub down: bool,
}

impl Up {
    /// The unit vector.
    pub fn vector(self) -> DVec3 {
        let mut v = DVec3::ZERO;
        v[self.axis] = if self.down { -1.0 } else { 1.0 };
        v
    }
    /// `+x`, `-y`, … (as `--up` takes it).
    pub fn name(self) -> String {
        format!(
            "{}{}",
            if self.down { '-' } else { '+' },
            ['x', 'y', 'z'][self.axis]
        )
    }
    /// `x`, `+y`, `-z` …; `None` for anything else.
    pub fn parse(s: &str) -> Option<Up> {
        let (down, a) = match s.as_bytes() {
            [b'-', a] => (true, *a),
            [b'+', a] | [a] => (false, *a),
            _ => return None,
        };
        let axis = match a.to_ascii_lowercase() {
            b'x' => 0,
            b'y' => 1,
            b'z' => 2,
            _ => return None,
        };
        Some(Up { axis, down })
    }
}

/// A choice and the sentence that says why it was made.
#[derive(Debug, Clone, PartialEq)]
pub struct Choice<T> {
    pub value: T,
    pub why: String,
}

fn choice<T>(value: T, why: impl Into<String>) -> Choice<T> {
    Choice {
        value,
        why: why.into(),
    }
}

/// What a heat grid holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeatKind {
    /// A temperature (kelvin or relative: [`Unit`] says which, from the data).
    Temperature,
    /// A flame intensity 0–1: 1000 K · (1 + 0.5 · flame) where flame > 0 ([`FLAME_RANGE`]).
    Flame,
}

/// The grids a file's names choose.
#[derive(Debug, Clone, PartialEq)]
pub struct Names {
    pub tool: Choice<Tool>,
    /// The smoke: the soot's density.
    pub smoke: Choice<String>,
    /// The grid the fire's temperature comes from, and what it holds.
    pub heat: Choice<(String, HeatKind)>,
    /// A flame grid not used as the heat (said, not read).
    pub flame: Option<Choice<String>>,
    /// A velocity grid (a vector grid; read for motion blur when the shutter opens).
    pub velocity: Option<Choice<String>>,
}

/// The grids `entries` (of `file`, NanoVDB when `nanovdb`) name: the tool whose conventions they follow and which
/// grid plays each part. An error when no grid can be the smoke or when none carries heat (no temperature, heat
/// or flame: nothing would glow), naming the file's grids.
pub fn names(file: &str, entries: &[GridEntry], nanovdb: bool) -> Result<Names, Error> {
    let has = |n: &str| entries.iter().any(|g| g.name == n);
    let float = |n: &str| entries.iter().any(|g| g.name == n && g.loadable);
    let vector = |n: &str| entries.iter().any(|g| g.name == n && !g.loadable);
    let first = |names: &[&str]| names.iter().find(|n| float(n)).map(|n| n.to_string());
    let listed = || {
        entries
            .iter()
            .map(|g| format!("'{}' ({})", g.name, g.kind))
            .collect::<Vec<_>>()
            .join(", ")
    };
    if !entries.iter().any(|g| g.loadable) {
        return Err(Error::invalid(
            "dataset",
            "densitygrid",
            format!("'{file}' holds {}", listed()),
            "a float grid (density, temperature, …): with no float grid the file is not a fire dataset",
        ));
    }
    let flame_grid = first(&["flame", "flames", "fire", "burn"]);
    let (tool, why) = if float("smoke") && float("temperature") && (has("flames") || has("fuel")) {
        (
            Tool::EmberGen,
            "smoke, temperature and flames/fuel are EmberGen's grids",
        )
    } else if float("density")
        && float("flame")
        && (has("shadow") || vector("velocity") || !has("temperature"))
    {
        (Tool::Blender, "density and flame beside shadow, a velocity vector grid or no temperature: a Mantaflow domain cache")
    } else if float("density")
        && (has("vel") || float("flame") || float("heat"))
        && (float("temperature") || float("heat"))
    {
        (
            Tool::Houdini,
            "density and temperature/heat beside vel or flame are Houdini Pyro's grids",
        )
    } else if nanovdb && float("density") {
        (
            Tool::Pbrt,
            "a NanoVDB file with a density grid: pbrt-v4's nanovdb convention",
        )
    } else {
        (Tool::Kelvin, "no simulator's grid names")
    };
    let smoke_names: &[&str] = if tool == Tool::EmberGen {
        &["smoke", "density"]
    } else {
        &["density", "smoke", "soot"]
    };
    let smoke = first(smoke_names).ok_or_else(|| {
        Error::invalid(
            "dataset",
            "densitygrid",
            format!("'{file}' holds {}", listed()),
            format!(
                "a smoke density grid named {} (or name one with \"string densitygrid\")",
                smoke_names.join(", ")
            ),
        )
    })?;
    let smoke = choice(
        smoke.clone(),
        format!("'{smoke}' is the smoke: the soot's density"),
    );
    let temperature = first(&["temperature", "heat", "temp"]);
    let heat = match (tool, &temperature, &flame_grid) {
        (Tool::Blender, _, Some(f)) => Some(choice(
            (f.clone(), HeatKind::Flame),
            format!(
                "'{f}' is the fire's temperature, as Cycles reads a Mantaflow cache{}",
                if has("temperature") { " ('temperature' is Mantaflow's heat, not kelvin: not read)" } else { "" }
            ),
        )),
        (_, Some(t), _) => Some(choice(
            (t.clone(), HeatKind::Temperature),
            format!("'{t}' is the temperature"),
        )),
        (_, None, Some(f)) => Some(choice(
            (f.clone(), HeatKind::Flame),
            format!("no temperature grid: '{f}' is the fire's temperature, read as Cycles reads a Mantaflow flame grid"),
        )),
        (_, None, None) => None,
    };
    let Some(heat) = heat else {
        return Err(Error::invalid(
            "dataset",
            "temperaturegrid",
            format!("'{file}' holds {}", listed()),
            "a grid with the fire's heat — temperature, heat, temp, flame, flames, fire or burn — for a fire to glow (or name one with \"string temperaturegrid\"); a smoke-only file renders as smoke with \"string temperaturegrid\" \"\"",
        ));
    };
    let flame = flame_grid.filter(|f| *f != heat.value.0).map(|f| {
        choice(
            f.clone(),
            format!("'{f}' is the flame; the temperature carries its heat, so it is not read"),
        )
    });
    let velocity = ["vel", "velocity", "v"]
        .iter()
        .find(|n| vector(n))
        .map(|v| {
            choice(
                v.to_string(),
                format!("'{v}' is the velocity: read for motion blur when the shutter opens"),
            )
        });
    Ok(Names {
        tool: choice(tool, format!("{}: {why}", tool.label())),
        smoke,
        heat,
        flame,
        velocity,
    })
}

/// A temperature grid's unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Unit {
    /// Kelvin, as the grid holds it.
    Kelvin,
    /// A relative temperature: T = t · kelvin_per_unit.
    Relative { kelvin_per_unit: f64 },
    /// A flame intensity: [`FLAME_RANGE`] where it is above zero.
    Flame,
}

/// A temperature grid's unit from its peak (see the module docs), and a warning when the data is odd.
pub fn unit(grid: &str, kind: HeatKind, peak: f64) -> (Choice<Unit>, Option<String>) {
    if kind == HeatKind::Flame {
        let (a, b) = FLAME_RANGE;
        return (choice(Unit::Flame, format!("'{grid}' is a flame intensity (peak {peak:.3}): {:.0} K at its edge to {:.0} K at 1, a fire's luminous soot (Cycles' 1 500–3 000 K renders it white)", a * 1000.0, b * 1000.0)), None);
    }
    if !(peak > 0.0) {
        return (
            choice(Unit::Kelvin, format!("'{grid}' is zero everywhere")),
            Some(format!(
                "the temperature grid '{grid}' is zero everywhere: the fire will not glow"
            )),
        );
    }
    if peak >= KELVIN_PEAK {
        let warn = (peak > HOTTEST_FLAME).then(|| {
            format!("the temperature grid '{grid}' reaches {peak:.0} K, beyond any flame (above {HOTTEST_FLAME:.0} K): if it is not in kelvin, map it with \"float temperatureremap\" [a b ka kb]")
        });
        return (
            choice(
                Unit::Kelvin,
                format!(
                    "'{grid}' peaks at {peak:.0}: kelvin (a flame is 1 000–2 500 K), read as it is"
                ),
            ),
            warn,
        );
    }
    if peak >= RELATIVE_PEAK {
        return (
            choice(Unit::Kelvin, format!("'{grid}' peaks at {peak:.1}: read as kelvin")),
            Some(format!("the temperature grid '{grid}' peaks at {peak:.1}: as kelvin too cool to glow (a flame is over 1 000 K), too large for a simulator's relative temperature (0 to ~3): a cold smoke, or a unit of its own — map it with \"float temperaturescale\" or \"float temperatureremap\" [a b ka kb]")),
        );
    }
    let k = HOUDINI_KELVIN.min(FLAME_KELVIN / peak);
    let why = if k == HOUDINI_KELVIN {
        format!("'{grid}' peaks at {peak:.3}: a relative temperature, {HOUDINI_KELVIN:.0} K per unit (Houdini's Pyro shader's default), its peak {:.0} K", peak * k)
    } else {
        format!("'{grid}' peaks at {peak:.3}: a relative temperature, its peak at {FLAME_KELVIN:.0} K (what a fire's luminous soot reaches; Houdini's shader's {HOUDINI_KELVIN:.0} K per unit would make it {:.0} K): {k:.2} K per unit", peak * HOUDINI_KELVIN)
    };
    (choice(Unit::Relative { kelvin_per_unit: k }, why), None)
}

/// A grid's peak: the 99.9th percentile of the positive values its stored voxels hold (0 when it holds none).
pub fn peak(grid: &Grid) -> f64 {
    let max = grid.stats().max;
    if !(max > 0.0) || !max.is_finite() {
        return 0.0;
    }
    const BINS: usize = 4096;
    let mut hist = [0u64; BINS];
    let values = grid.values();
    let scale = BINS as f32 / max;
    grid.topology().for_each_stored_voxel(|_, n| {
        let v = values[n];
        if v > 0.0 {
            hist[((v * scale) as usize).min(BINS - 1)] += 1;
        }
    });
    let total: u64 = hist.iter().sum();
    let want = (total as f64 * 0.999).ceil() as u64;
    let mut seen = 0;
    for (b, &c) in hist.iter().enumerate() {
        seen += c;
        if seen >= want {
            return (b + 1) as f64 / BINS as f64 * max as f64;
        }
    }
    max as f64
}

/// The data's evidence for up: the smoke's and the warm gas's centroids against the hottest gas's, per axis, in
/// units of the data's extent along it; and the box of the glowing gas (where the light is), in samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Evidence {
    pub score: [f64; 3],
    /// Samples [lo, hi] of the glowing voxels; `None` when none glow.
    pub glow_box: Option<[[usize; 3]; 2]>,
}

/// Gathers [`Evidence`] from the smoke and heat grids (one lattice): the heat threshold `hot` (the grid's units)
/// splits the hottest gas (at or above it) from the warm (a fifth of it up to it); the glowing gas is where the
/// smoke emits at 550 nm at least a thousandth of the brightest voxel's (Planck's e^(−hc/λkT) times the density,
/// the heat in kelvin by `kelvin`; none when it has no heat).
pub fn evidence(smoke: &Grid, heat: &Grid, hot: f32, kelvin: &dyn Fn(f32) -> f64) -> Evidence {
    let dims = smoke.dims();
    let (sv, hv) = (smoke.values(), heat.values());
    let same = std::sync::Arc::ptr_eq(smoke.topology(), heat.topology());
    let each = |f: &mut dyn FnMut([usize; 3], f32, f32)| {
        if same {
            smoke
                .topology()
                .for_each_stored_voxel(|p, n| f(p, sv[n], hv[n]));
        } else {
            heat.topology().for_each_stored_voxel(|p, n| {
                f(p, smoke.at(p[0] as i64, p[1] as i64, p[2] as i64), hv[n])
            });
        }
    };
    // hc/(λk) at 550 nm, K.
    const X550: f64 = 0.014387769 / 550e-9;
    let glow = |d: f32, h: f32| {
        let t = kelvin(h);
        if d > 0.0 && t > 0.0 {
            d as f64 * (-X550 / t).exp()
        } else {
            0.0
        }
    };
    // Weight and first moment (per axis) of the smoke, the warm gas and the hot gas; the brightest glow.
    let mut acc = [[0f64; 4]; 3];
    let mut brightest = 0f64;
    each(&mut |p, d, h| {
        let mut add = |w: f64, i: usize| {
            if w > 0.0 {
                acc[i][0] += w;
                for a in 0..3 {
                    acc[i][1 + a] += w * p[a] as f64;
                }
            }
        };
        add(d as f64, 0);
        if h >= hot {
            add((h - hot) as f64 + 1e-3 * hot as f64, 2);
        } else if h >= 0.2 * hot {
            add(h as f64, 1);
        }
        brightest = brightest.max(glow(d, h));
    });
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    if brightest > 0.0 {
        each(&mut |p, d, h| {
            if glow(d, h) >= 1e-3 * brightest {
                for a in 0..3 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
        });
    }
    let centroid = |i: usize| -> Option<DVec3> {
        (acc[i][0] > 0.0).then(|| DVec3::new(acc[i][1], acc[i][2], acc[i][3]) / acc[i][0])
    };
    let extent = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
    let mut score = [0.0; 3];
    if let Some(h) = centroid(2) {
        for other in [centroid(0), centroid(1)].into_iter().flatten() {
            let d = (other - h) / extent;
            for a in 0..3 {
                score[a] += d[a];
            }
        }
    }
    Evidence {
        score,
        glow_box: (lo[0] != usize::MAX).then_some([lo, hi]),
    }
}

impl Unit {
    /// Kelvin of a grid value `t` in this unit.
    pub fn kelvin(self, t: f32) -> f64 {
        match self {
            Unit::Kelvin => t as f64,
            Unit::Relative { kelvin_per_unit } => t as f64 * kelvin_per_unit,
            Unit::Flame => {
                let (a, b) = FLAME_RANGE;
                if t > 0.0 {
                    1000.0 * (a + t as f64 * (b - a))
                } else {
                    0.0
                }
            }
        }
    }
}

/// Up from the [`Evidence`], the tool's convention breaking a tie; a warning when two axes are candidates.
pub fn up(ev: &Evidence, tool: Tool) -> (Choice<Up>, Option<String>) {
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| ev.score[b].abs().total_cmp(&ev.score[a].abs()));
    let signed = |a: usize| Up {
        axis: a,
        down: ev.score[a] < 0.0,
    };
    let (best, second) = (order[0], order[1]);
    let tie = tool.up();
    let said = |a: usize| format!("{} ({:.2})", signed(a).name(), ev.score[a].abs());
    if ev.score[best].abs() < 0.02 {
        return (
            choice(tie, format!("the data does not show which way its flame rises (its heat and smoke share one centre): {}'s convention, {}", tool.label(), tie.name())),
            None,
        );
    }
    if ev.score[second].abs() > 0.5 * ev.score[best].abs() {
        let pick = if tie.axis == second {
            signed(second)
        } else {
            signed(best)
        };
        let warn = format!(
            "two candidate up axes, {} and {} (the smoke's and the warm gas's rise above the hottest gas, in extents): {} taken{}; give --up to choose",
            said(best),
            said(second),
            pick.name(),
            if tie.axis == second || tie.axis == best { format!(" ({}'s convention breaks the tie)", tool.label()) } else { String::new() },
        );
        return (
            choice(
                pick,
                format!(
                    "{} of two candidates, {} and {}",
                    pick.name(),
                    said(best),
                    said(second)
                ),
            ),
            Some(warn),
        );
    }
    let u = signed(best);
    (
        choice(u, format!("{}: the smoke and the warm gas lie {:.2} of the data's extent above the hottest gas along it (flames rise; next {})", u.name(), ev.score[best].abs(), said(second))),
        None,
    )
}

/// The largest ∫ density ds (density · m) along a lattice line of each axis, over the smoke grid with samples
/// `voxel` m apart; `None` when the sums would pass `cap` bytes. The sums follow the data: per stored brick, its
/// 8 × 8 lines along each axis are summed, then added into a map of the lines that hold data.
pub fn columns(smoke: &Grid, voxel: DVec3, cap: u64) -> Option<[f64; 3]> {
    use std::collections::HashMap;
    let topo = smoke.topology();
    if column_bytes(topo.active_bricks()) > cap {
        return None;
    }
    let values = smoke.values();
    let dims = smoke.dims();
    let mut sums: [HashMap<u64, f64>; 3] = Default::default();
    let mut partial = [[0f64; 64]; 3];
    let mut keys = [[u64::MAX; 64]; 3];
    topo.for_each_slot(|b, slot| {
        let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
        for p in &mut partial {
            p.fill(0.0);
        }
        for k in &mut keys {
            k.fill(u64::MAX);
        }
        for z in span[2].0..span[2].1 {
            for y in span[1].0..span[1].1 {
                for x in span[0].0..span[0].1 {
                    let p = [x, y, z];
                    let v = values[slot * 512 + topo_local(topo, p)].max(0.0) as f64;
                    for (along, (u, w)) in [(1, 2), (0, 2), (0, 1)].into_iter().enumerate() {
                        let l = (p[u] % 8) + 8 * (p[w] % 8);
                        partial[along][l] += v;
                        keys[along][l] = p[u] as u64 + dims[u] as u64 * p[w] as u64;
                    }
                }
            }
        }
        for along in 0..3 {
            for l in 0..64 {
                if keys[along][l] != u64::MAX {
                    *sums[along].entry(keys[along][l]).or_insert(0.0) += partial[along][l];
                }
            }
        }
    });
    Some([0, 1, 2].map(|a| sums[a].values().copied().fold(0.0, f64::max) * voxel[a]))
}

/// Where sample `p` sits within its brick's 512 values.
fn topo_local(topo: &crate::grid::Topology, p: [usize; 3]) -> usize {
    let off = topo.offset();
    let l = [0, 1, 2].map(|a| (p[a] + off[a]) % 8);
    l[0] + 8 * (l[1] + 8 * l[2])
}

/// The bytes [`columns`] needs, at most, for `bricks` stored bricks: 3 × 64 lines each, a map entry of about 32
/// bytes per line.
pub fn column_bytes(bricks: usize) -> u64 {
    (bricks as u64).saturating_mul(3 * 64 * 32)
}

/// The thickest line of sight across the fire, horizontally (along an axis other than `up`), from [`columns`].
pub fn thickest_across(columns: [f64; 3], up: Up) -> f64 {
    (0..3)
        .filter(|&a| a != up.axis)
        .map(|a| columns[a])
        .fold(0.0, f64::max)
}

/// The soot scale for a smoke grid whose peak is `peak` and whose thickest horizontal line of sight holds
/// `column` (density · m), with soot absorbing `kappa` m⁻¹ per unit volume fraction at 550 nm (see the module
/// docs).
pub fn soot_scale(grid: &str, peak: f64, column: f64, kappa: f64) -> Choice<f64> {
    if peak <= VOLUME_FRACTION_PEAK {
        return choice(1.0, format!("'{grid}' peaks at {peak:.3e}: a soot volume fraction already (a flame's is 1e-8 to 1e-5), sootscale 1"));
    }
    if !(column > 0.0 && kappa > 0.0) {
        return choice(1.0, format!("'{grid}' holds no smoke"));
    }
    let s = SMOKE_DEPTH / (kappa * column);
    choice(
        s,
        format!("'{grid}' peaks at {peak:.3}, not a volume fraction: sootscale {s:.3e} makes its thickest line of sight across the fire ({column:.3} density·m) {SMOKE_DEPTH} optical depth at 550 nm, its peak soot volume fraction {:.2e}", s * peak),
    )
}

/// Everything [`survey`] found in a file or a sequence of them.
#[derive(Debug, Clone, PartialEq)]
pub struct Reading {
    pub names: Names,
    pub unit: Choice<Unit>,
    pub up: Choice<Up>,
    pub soot: Choice<f64>,
    /// The medium-space box every frame's data lies in.
    pub bounds: [DVec3; 2],
    /// The medium-space box of every frame's glowing gas that holds smoke (where the light is); `None` when no
    /// voxel glows.
    pub flame: Option<[DVec3; 2]>,
    /// What a user should hear (odd data, a tie).
    pub warnings: Vec<String>,
}

/// The heat threshold of the hottest gas, in the grid's own units: 0.7 of a temperature's peak, 0.4 of a flame's
/// (1 200 K of 1 000–1 500 K).
pub fn hot_threshold(kind: HeatKind, peak: f64) -> f32 {
    (peak * if kind == HeatKind::Flame { 0.4 } else { 0.7 }) as f32
}

/// Reads `files` (one, or a sequence's frames, which must hold the same grids) as [`names`], [`unit`], [`up`]
/// (`up` given: taken) and [`soot_scale`] choose, over every frame: the peaks and the thickest line of sight are
/// the largest any frame has, the evidence for up their mean, the boxes their union. Only the smoke and heat grids
/// are read, one frame at a time, each within `opts.max_bytes`. `kappa`: the soot's absorption at 550 nm per unit
/// volume fraction.
pub fn survey(
    files: &[std::path::PathBuf],
    opts: &crate::LoadOptions,
    up_given: Option<Up>,
    kappa: f64,
) -> Result<Reading, Error> {
    let mut names_of: Option<(Names, String)> = None;
    let (mut smoke_peak, mut heat_peak) = (0f64, 0f64);
    let mut score = [0f64; 3];
    let mut cols = [0f64; 3];
    let mut bounds: Option<[DVec3; 2]> = None;
    let mut flame: Option<[DVec3; 2]> = None;
    let union = |a: Option<[DVec3; 2]>, b: [DVec3; 2]| {
        Some(a.map_or(b, |a| [a[0].min(b[0]), a[1].max(b[1])]))
    };
    // Two passes: the peaks first (the hot threshold follows the sequence's peak), then the evidence.
    for pass in 0..2 {
        for file in files {
            let label = file.display().to_string();
            let entries = crate::list_grids(file, opts)?;
            let nanovdb = crate::format_of(file, opts)? == crate::Format::NanoVdb;
            let n = names(&label, &entries, nanovdb)?;
            let (n, first) = match &names_of {
                None => {
                    names_of = Some((n.clone(), label.clone()));
                    (n, label.clone())
                }
                Some((m, first)) => (m.clone(), first.clone()),
            };
            for g in [&n.smoke.value, &n.heat.value.0] {
                if !entries.iter().any(|e| &e.name == g && e.loadable) {
                    return Err(Error::invalid(
                        "dataset",
                        "frames",
                        format!("'{label}' has no float grid '{g}'"),
                        format!("every frame to hold the grids the first, '{first}', holds"),
                    ));
                }
            }
            let sources = [
                crate::ChannelSource::new(&n.smoke.value, file),
                crate::ChannelSource::new(&n.heat.value.0, file),
            ];
            let ds = crate::Dataset::load(&sources, opts)?;
            let (smoke, heat) = (&ds.channels()[0].grid, &ds.channels()[1].grid);
            if pass == 0 {
                smoke_peak = smoke_peak.max(peak(smoke));
                heat_peak = heat_peak.max(peak(heat));
                bounds = union(bounds, ds.bounds());
                continue;
            }
            let unit = unit(&n.heat.value.0, n.heat.value.1, heat_peak).0.value;
            let hot = hot_threshold(n.heat.value.1, heat_peak);
            let ev = evidence(smoke, heat, hot, &|t| unit.kelvin(t));
            for a in 0..3 {
                score[a] += ev.score[a];
            }
            let voxel = ds.voxel_size();
            let c = columns(smoke, voxel, opts.max_bytes).ok_or_else(|| Error::TooLarge {
                file: label.clone(),
                what: "the smoke's column sums".into(),
                bytes: column_bytes(ds.topology().active_bricks()),
                cap: opts.max_bytes,
            })?;
            for a in 0..3 {
                cols[a] = cols[a].max(c[a]);
            }
            if let Some([lo, hi]) = ev.glow_box {
                let b0 = ds.bounds()[0];
                let at = |i: [usize; 3], d: usize| {
                    b0 + voxel * DVec3::new((i[0] + d) as f64, (i[1] + d) as f64, (i[2] + d) as f64)
                };
                flame = union(flame, [at(lo, 0), at(hi, 1)]);
            }
        }
    }
    let Some((names, _)) = names_of else {
        return Err(Error::invalid(
            "dataset",
            "files",
            "none",
            "one dataset file or more",
        ));
    };
    let mut warnings = Vec::new();
    let (unit, w) = unit(&names.heat.value.0, names.heat.value.1, heat_peak);
    warnings.extend(w);
    let up = match up_given {
        Some(u) => choice(u, format!("{}: given (--up)", u.name())),
        None => {
            let frames = files.len() as f64;
            let ev = Evidence {
                score: score.map(|s| s / frames),
                glow_box: None,
            };
            let (u, w) = up(&ev, names.tool.value);
            warnings.extend(w);
            u
        }
    };
    let soot = soot_scale(
        &names.smoke.value,
        smoke_peak,
        thickest_across(cols, up.value),
        kappa,
    );
    Ok(Reading {
        names,
        unit,
        up,
        soot,
        bounds: bounds.unwrap_or([DVec3::ZERO; 2]),
        flame,
        warnings,
    })
}
