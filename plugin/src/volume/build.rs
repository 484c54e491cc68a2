//! Building a fire volume: the parameters read once, the dataset read, its channels found, the coefficient
//! tables, the majorants, the optional layers the scene asks for, the march's accelerator — each part of
//! [`FireVolume`] made here, within the memory budget and the thread budget.

use super::*;

impl FireVolume {
    /// Builds a fire volume from a parameter list (the `dataset` and `volume` tables, docs/reference/params.md): the
    /// parameters are read and checked first ([`Settings`]), then the dataset is loaded, then the coefficient
    /// tables, the march lattice, the majorant bricks and (if asked for) the refraction field are built.
    pub fn new(list: &[Param]) -> Result<FireVolume, Error> {
        Self::new_in(list, &HostContext::default())
    }

    /// As [`new`](Self::new), in a host's context (its threads, memory budget, frame and shutter), which stands
    /// where the scene does not set the same itself.
    pub fn new_in(list: &[Param], ctx: &HostContext) -> Result<FireVolume, Error> {
        Self::new_unlocated(list, ctx).map_err(|e| e.located(crate::params::location_in(list)))
    }

    pub(super) fn new_unlocated(list: &[Param], ctx: &HostContext) -> Result<FireVolume, Error> {
        let start = Instant::now();
        let list = &*looks::expand(list);
        let comps = settings::components();
        let r = ParamReader::new("volume", list, &comps);
        r.check_names()?;
        march::check_simd()?;
        // (The look was expanded into the list above; reading it checks its name.)
        r.string("look")?;
        let set = Settings::read(&r, list, ctx)?;
        let threads = match ctx.threads {
            Some(n) if !r.list_has("threads") => n,
            _ => r.int("threads")? as usize,
        };
        let budget = HostContext::float(&r, "maxbytes", ctx.max_bytes.map(|b| b as f64))? as u64;
        crate::par::with_budget(threads, || {
            // Every parameter read and checked before a file is opened.
            let request = crate::dataset::params::read(&r, set.mode == Mode::Pbrt, ctx)?;
            r.finish()?;
            let loaded = request.load()?;
            let mut v = Self::build(set, loaded, budget, start)?;
            v.report.set_threads(threads);
            Ok(v)
        })
    }

    /// `budget`: the volume's memory budget (`maxbytes`); what it derives beyond its grids must fit in what the
    /// grids leave of it.
    pub(super) fn build(
        mut set: Settings,
        loaded: crate::dataset::params::Loaded,
        budget: u64,
        start: Instant,
    ) -> Result<FireVolume, Error> {
        let crate::dataset::params::Loaded {
            ds,
            lescale,
            emission_grid,
            motion,
            scatter_color,
            reaction,
            embers,
            tool,
            chosen,
        } = loaded;
        let spare = budget.saturating_sub(ds.bytes() as u64);
        let channel = |name: &str| ds.channels().iter().position(|c| c.name == name);
        let density = channel("density").unwrap_or(0);
        let temperature = channel("temperature");
        // ---- what the dataset's conventions chose, and the soot scale a simulator's density needs
        let mut said = chosen;
        said.extend(settle_soot(
            &mut set,
            &ds,
            (density, temperature),
            tool,
            spare,
        )?);
        if let Some(t) = temperature {
            let st = ds.channels()[t].stats;
            if st.max as f64 > crate::dataset::convention::HOTTEST_FLAME {
                said.push(format!("the temperature reaches {:.0} K (its grid mapped to {:.0}–{:.0} K), beyond any flame (above {:.0} K): is the grid already in kelvin and scaled again (temperaturescale), or in another unit (temperatureremap [a b ka kb])?", st.max, st.min, st.max, crate::dataset::convention::HOTTEST_FLAME));
            }
        }
        // ---- coefficients
        let Optics {
            co,
            mut tables,
            thick,
            spare,
        } = optics(
            &set,
            &ds,
            temperature,
            (emission_grid, reaction),
            spare,
            &mut said,
        )?;
        let mut notes = said;

        // ---- the march lattice, for a volume that marches in f32 lanes over a trilinear dataset (kept below
        // only if the lanes are built): made before the majorants, because it gathers its grids' brick ranges
        // as it copies them.
        let brick = majorant_brick(set.brick, ds.topology());
        let Marched {
            lattice,
            deferred,
            known,
            refused,
        } = march_lattice(
            &set,
            &ds,
            &co,
            (density, temperature, lescale),
            brick,
            spare,
        );
        notes.extend(refused);
        let lanes_wanted = set.lanes_wanted();
        let basis = set.basis;
        let c = basis.channels();

        // ---- majorants
        let (majorant, brick_sigma, brick_empty) = majorants(
            &ds,
            &co,
            (density, temperature, lescale, emission_grid),
            (brick, c),
            known,
            &mut tables,
        )?;
        let nb = brick_sigma.len();
        let bounds = (&majorant, &brick_sigma[..], &brick_empty[..]);
        let blur = motion.map(|m| blur_layer(m, &ds, bounds, &mut tables));

        // ---- embers
        let embers = embers
            .map(|ef| ember_layer((&set.emission, set.ember), &basis, &ef, spare, &mut tables))
            .transpose()?;

        // ---- refraction
        let step = set.stepsize * ds.voxel_size().min_element();
        // (What the budget leaves after the grids and the lattice; the layer takes its tables' bytes off.)
        let left = spare.saturating_sub(lattice.as_ref().map_or(0, |(l, _)| l.bytes() as u64));
        let refraction = set
            .refraction
            .as_ref()
            .map(|rs| refraction_layer(rs, &ds, temperature, step, left, &mut tables))
            .transpose()?;

        // The largest value a lookup can return, from the bricks' ranges (for the lane march's range check).
        let max = |ch: usize| (0..nb).map(|b| majorant.max(b, ch)).fold(0f32, f32::max) as f64;
        let (dmax, lesmax) = (max(density), lescale.map_or(1.0, max));
        // The largest emitting density: d · Lescale, or the emission grid itself.
        let dlmax = if emission_grid { lesmax } else { dmax * lesmax };
        let nmax: Vec<f64> = co.species.iter().map(|sp| max(sp.ch())).collect();
        let (clip_box, margin) = clip_box(set.mode, &ds);
        let scatter_color = scatter_color.map(|k| (k, scatter_weights(&basis)));
        let (physical_colour, point_model) = point_model(
            (&set.emission, set.sigma_s.as_ref()),
            [
                !co.species.is_empty(),
                thick.is_some(),
                scatter_color.is_some(),
                set.diffusion.is_some(),
                refraction.is_some(),
                embers.is_some(),
            ],
        );
        let mut vol = FireVolume {
            grids: parts::Grids::new(
                ds,
                (density, temperature, lescale),
                emission_grid,
                co.species,
            ),
            model: parts::Model::new(
                (basis, set.mode),
                (co.a, co.a_t, co.s, co.j, co.t_emit),
                (physical_colour, scatter_color),
                set.g,
                point_model,
            ),
            bounds: parts::Bounds::new(majorant, (brick_sigma, brick_empty), clip_box, margin),
            layers: parts::Layers::new(blur, embers, refraction, thick),
            estimator: parts::Estimator::new(set.integrator, step, set.step_tau, set.cutoff),
            report: parts::Report::new(tables, co.source, notes),
            capped: CapCounter::default(),
            #[cfg(test)]
            fault: set.fault,
        };
        if lanes_wanted {
            vol.attach_lanes((dmax, dlmax, &nmax), step, lattice, deferred);
        }
        if let Some(res) = set
            .diffusion
            .filter(|_| vol.model.s().iter().any(|&v| v > 0.0))
        {
            vol.attach_diffusion(res, spare)?;
        }
        let reserved = vol.estimator.lattice().reserved();
        vol.report
            .finish(spare, reserved, start.elapsed().as_secs_f64());
        Ok(vol)
    }

    /// The march's lanes (σ per unit density in f32 lanes; the largest density, emitting density and species'
    /// values a lookup can return, for their range check) and, with them, the lattice they march (built, or
    /// deferred to the first ray) — neither without the other.
    fn attach_lanes(
        &mut self,
        (dmax, dlmax, nmax): (f64, f64, &[f64]),
        step: f64,
        lattice: Option<(lattice::Lattice, f64)>,
        deferred: Option<lattice::Plan>,
    ) {
        let vol = self;
        let t3 = Instant::now();
        vol.estimator
            .set_lanes(lanes::LaneTables::build(vol, dmax, dlmax, nmax, step));
        if let Some(lt) = vol.estimator.lanes() {
            vol.report.push(TableReport {
                name: "march lanes (σ per unit density; the tables are shared)".into(),
                bytes: lt.bytes(),
                seconds: t3.elapsed().as_secs_f64(),
            });
            if let Some((lat, seconds)) = lattice {
                vol.report.push(TableReport {
                    name: match lat.bricks() {
                        None => "march lattice (grids interleaved and padded; their brick ranges)"
                            .into(),
                        Some(t) => format!(
                            "march lattice (grids interleaved, a padded copy per brick: {} copies)",
                            t.active_bricks()
                        ),
                    },
                    bytes: lat.bytes(),
                    seconds,
                });
                vol.estimator.set_lattice(lattice::Slot::ready(lat));
            }
            if let Some(plan) = deferred {
                vol.report.push(TableReport {
                    name: plan.describe(),
                    bytes: 0,
                    seconds: 0.0,
                });
                vol.estimator.set_lattice(lattice::Slot::deferred(plan));
            }
        }
    }

    /// Diffusion's scattered light, solved on a grid of `res` cells along the box's longest side, within what
    /// `spare` leaves after the tables.
    fn attach_diffusion(&mut self, res: usize, spare: u64) -> Result<(), Error> {
        let vol = self;
        let t5 = Instant::now();
        // The solve's peak: three cell arrays per channel, five per solving thread.
        let cells = {
            let size = vol.bounds.clip_box()[1] - vol.bounds.clip_box()[0];
            let h = size.max_element() / res.clamp(1, diffusion::MAX_RESOLUTION) as f64;
            [0, 1, 2]
                .map(|k| ((size[k] / h).ceil() as u64).max(1))
                .iter()
                .product::<u64>()
        };
        let need = cells * (vol.channels() as u64 * 28 + 40 * crate::par::threads(16) as u64);
        let left = spare.saturating_sub(vol.report.table_bytes());
        if need > left {
            return Err(Error::invalid(
                "volume",
                "diffusionresolution",
                format!("{res} ({cells} cells, {need} bytes to solve)"),
                format!("a grid within the memory budget's {left} bytes left"),
            ));
        }
        let df = diffusion::Diffusion::build(vol, res, vol.model.g())?;
        // The march samples the scattered light at least twice per diffusion cell.
        vol.estimator.shorten_step(0.5 * df.cell());
        vol.report.push(TableReport {
            name: format!("diffusion ({} iterations)", df.iterations()),
            bytes: df.bytes(),
            seconds: t5.elapsed().as_secs_f64(),
        });
        vol.layers.set_diffusion(df);
        Ok(())
    }
}

/// The hottest temperature a volume takes, K: far past any flame (the notes warn above 5000 K), and where the
/// tables and the march's f32 sums stay finite.
const MAX_TEMPERATURE: f64 = 1e9;

/// The march's lattice and what its copying found: built now, planned for the first ray that marches (a fire
/// that scatters), or neither; the grids' brick ranges it gathered (the majorants' start).
struct Marched {
    lattice: Option<(lattice::Lattice, f64)>,
    deferred: Option<lattice::Plan>,
    known: Vec<Option<crate::majorant::Ranges>>,
    /// A lattice the budget refused, as the note that says so: the march reads the grids in place.
    refused: Option<String>,
}

/// The lattice the f32 lanes march over a trilinear dataset (its `density`, `temperature` and the further grids
/// the march reads: `lescale`, the species'), dense or bricked by `set.lattice`, within `spare` bytes.
fn march_lattice(
    set: &Settings,
    ds: &Dataset,
    co: &coefficients::Coefficients,
    (density, temperature, lescale): (usize, Option<usize>, Option<usize>),
    brick: usize,
    spare: u64,
) -> Marched {
    let mut lattice = None;
    let mut deferred = None;
    let mut refused = None;
    let mut known = vec![None; ds.channels().len()];
    if set.lanes_wanted() && ds.interpolation() == crate::grid::Interpolation::Trilinear {
        let t4 = Instant::now();
        let ch = ds.channels();
        let extra: Vec<usize> = lescale
            .iter()
            .copied()
            .chain(co.species.iter().map(|sp| sp.ch()))
            .collect();
        let grids: Vec<&crate::grid::Grid> = extra.iter().map(|&k| &ch[k].grid).collect();
        // Dense over the box while it costs at most four times what its grids store (512 values per block:
        // constant tiles share blocks, as the brick layout's copies of their interiors do), else a copy per
        // brick holding data (a fire far from its copy in a big box, a file of constant tiles).
        let per_grid = (ds.topology().blocks_stored() as u64 + 1) * 4 * 512;
        let copied = per_grid * (2 + grids.len() as u64 - temperature.is_none() as u64);
        let dense_fits = lattice::Lattice::padded(ds.dims()).is_some_and(|p| {
            let voxels = p.iter().map(|&n| n as u64).product::<u64>();
            voxels.saturating_mul(4 * (2 + grids.len() as u64)) <= copied.saturating_mul(4)
        });
        // pbrt-v4's own grid media read their grids in place, as pbrt-v4 does: a scene written for pbrt-v4
        // renders in about pbrt-v4's memory unless it asks for the copy.
        let mut dense = match set.lattice {
            params::Lattice::Dense => Some(true),
            params::Lattice::Bricks => Some(false),
            params::Lattice::Off => None,
            params::Lattice::Auto if set.mode == Mode::Pbrt => None,
            params::Lattice::Auto => Some(dense_fits),
        };
        let (d, t) = (&ch[density].grid, temperature.map(|k| &ch[k].grid));
        // A fire that scatters is tracked by its host: its lattice waits for the first ray that marches.
        let scatters = set.diffusion.is_none() && co.s.iter().any(|&v| v > 0.0);
        let channels = (density, temperature, extra.clone());
        // A copy beyond the budget is not tried (nor planned): the march reads the grids in place, and says so.
        let plan = dense.map(|d| lattice::Plan::new(d, channels, ds, brick, spare));
        if let Some(bytes) = plan
            .as_ref()
            .map(lattice::Plan::bytes)
            .filter(|&b| b > spare && b < u64::MAX)
        {
            refused = Some(format!(
                "the march's copy of the grids ({:.1} MB) does not fit the memory budget's {:.1} MB left after them: the march reads the grids in place (the same image, a slower march; raise the budget, maxbytes or --max-memory, to keep the copy)",
                bytes as f64 / 1e6,
                spare as f64 / 1e6
            ));
            dense = None;
        }
        deferred =
            plan.filter(|_| dense.is_some() && scatters && set.lattice == params::Lattice::Auto);
        match dense.filter(|_| deferred.is_none()) {
            Some(true) => {
                if let Some((lat, ranges)) = lattice::Lattice::build(d, t, &grids, brick, spare) {
                    let order = std::iter::once(density).chain(temperature).chain(extra);
                    for (k, r) in order.zip(ranges) {
                        if known[k].is_none() {
                            known[k] = Some(r);
                        }
                    }
                    lattice = Some((lat, t4.elapsed().as_secs_f64()));
                }
            }
            Some(false) => {
                lattice = lattice::Lattice::build_bricks(d, t, &grids, spare)
                    .map(|lat| (lat, t4.elapsed().as_secs_f64()));
            }
            None => {}
        }
    }
    Marched {
        lattice,
        deferred,
        known,
        refused,
    }
}

/// What the build makes of the fire's optics: its coefficients (the soot's, the species', the blue core's), their
/// tables' reports, the thick lines' model, and the budget left after the tables.
struct Optics {
    co: coefficients::Coefficients,
    tables: Vec<TableReport>,
    thick: Option<lines::ThickLines>,
    spare: u64,
}

/// The fire's optics from its settings and dataset (`temperature`'s channel, an emission grid, the reaction's
/// channel) within `spare` bytes; what a user should hear about its species added to `said`.
fn optics(
    set: &Settings,
    ds: &Dataset,
    temperature: Option<usize>,
    (emission_grid, reaction): (bool, Option<usize>),
    spare: u64,
    said: &mut Vec<String>,
) -> Result<Optics, Error> {
    let basis = &set.basis;
    let c = basis.channels();
    let t_max = temperature
        .map(|i| ds.channels()[i].stats.max as f64)
        .unwrap_or(0.0)
        .max(0.0);
    // Temperatures past any the model holds (Planck's and the soot's tables, f32 sums) are refused, not left to
    // overflow into NaN far down the line.
    if t_max > MAX_TEMPERATURE {
        return Err(Error::invalid(
            "dataset",
            "temperature",
            format!("{t_max:e} K (its grid's hottest voxel, after any mapping)"),
            format!("temperatures from 0 to {MAX_TEMPERATURE:e} K (check temperaturescale and the grid's unit)"),
        ));
    }
    // ---- what a user should hear about its species (at its hottest; 2000 K without a temperature grid)
    if let Emission::Physical { species, .. } = &set.emission {
        let range = match basis.mode() {
            ColorMode::Spectral(g) => (g.min_nm(), g.max_nm()),
            ColorMode::Rgb => (380.0, 780.0),
        };
        let hot = if temperature.is_some() {
            t_max.max(1000.0)
        } else {
            2000.0
        };
        said.extend(notes::species(species, hot, range));
    }
    // The temperature tables' bytes, counted against what the grids leave of the budget before any is built.
    let n_species = match &set.emission {
        Emission::Physical { species, .. } => species.len(),
        Emission::Pbrt { .. } => 0,
    };
    let rgb = matches!(basis.mode(), ColorMode::Rgb);
    let need = tables::bytes_for(t_max, c, n_species, rgb);
    if need > spare {
        return Err(Error::TooLarge {
            file: ds
                .channels()
                .first()
                .map_or_else(String::new, |ch| ch.report.file.clone()),
            what: format!(
                "the temperature tables ({c} channels up to {t_max:.0} K: the soot's, {n_species} species' σ and j, and their range maxima)"
            ),
            bytes: need,
            cap: spare,
        });
    }
    // (What the rest of the build may take: the grids' and the tables' share of the budget set aside.)
    let spare = spare - need;
    let mut tables = Vec::new();
    let mut thick = None;
    let mut co = match &set.emission {
        Emission::Physical {
            optics,
            alpha,
            sootscale,
            intensity,
            smokescale,
            tint,
            ramp,
            species,
        } => {
            // Lines that can be thick leave the tables for the line model (`lines`).
            let mut thin = species.clone();
            if set.voigt && !species.is_empty() {
                let t0 = Instant::now();
                let sigma_s = set.sigma_s.as_ref();
                let continuum = |l: f64| {
                    let k = optics.kappa(l, 1.0, *alpha) * sootscale;
                    [
                        smokescale * k,
                        smokescale * sigma_s.map_or(0.0, |f| f(l)),
                        intensity * k * tint.as_ref().map_or(1.0, |f| f(l)),
                    ]
                };
                let t_range = temperature
                    .map(|i| {
                        let st = &ds.channels()[i].stats;
                        [st.min as f64, st.max as f64]
                    })
                    .unwrap_or([0.0, 0.0]);
                let inp = lines::Input {
                    species,
                    ds,
                    basis,
                    broadening: set.linebroadening,
                    intensity: *intensity,
                    continuum: &continuum,
                    t_range,
                    budget: spare,
                };
                let marks = lines::select(&inp);
                thick = lines::ThickLines::new(&inp, &marks, t_max)?;
                for ((_, e, _), m) in thin.iter_mut().zip(&marks) {
                    let keep: Vec<bool> = m.iter().map(|x| !x).collect();
                    let lines = e.lines().to_vec();
                    *e = e.with_lines(&|l| {
                        lines
                            .iter()
                            .zip(&keep)
                            .any(|(x, &k)| k && x.lambda_nm == l.lambda_nm)
                    });
                }
                if let Some(tl) = &thick {
                    tables.push(TableReport {
                        name: format!("thick lines ({} wavelengths across them)", tl.nodes()),
                        bytes: tl.bytes(),
                        seconds: t0.elapsed().as_secs_f64(),
                    });
                }
            }
            let mut co = coefficients::physical(
                basis,
                optics,
                (*alpha, *sootscale, *intensity),
                (*smokescale, tint.as_ref(), ramp.as_ref()),
                &thin,
                set.sigma_s.as_ref(),
                ds,
                t_max,
                &mut tables,
            );
            // (The light's power counts every line.)
            if let Some(src) = &mut co.source {
                src.set_elements(species.iter().map(|(_, full, _)| full.clone()));
            }
            co
        }
        Emission::Pbrt {
            scale,
            sigma_a,
            le_scale,
            le,
        } => coefficients::pbrt(
            basis,
            *scale,
            sigma_a,
            *le_scale,
            le.as_ref(),
            set.sigma_s.as_ref(),
            temperature.is_some(),
            t_max,
            &mut tables,
        )?,
    };
    // (The fire light's full-spectrum power assumes emission follows the soot: with an emission grid it reports
    // its power over the bins.)
    if emission_grid {
        co.source = None;
    }
    // The blue core: the reaction zone's chemiluminescence, a channel that emits (yield · heat release / 4π
    // times the CH*/C₂* band spectrum, per channel) and absorbs nothing — the species' machinery, with
    // tables that do not depend on temperature.
    if let Some(ch) = reaction {
        let shape = basis.emit(&firemedium_core::chemiluminescence::spectrum);
        let zeros = vec![0.0; c];
        co.species.push(SpeciesChannel::new(
            ch,
            set.chemiluminescence / (4.0 * std::f64::consts::PI),
            tables::TTable::build(0.0, c, &|_| zeros.clone()),
            tables::TTable::build(0.0, c, &|_| shape.clone()),
        ));
        // (The light's full-spectrum power: the soot's and atoms' over the spectrum, the blue core's over the
        // bins, which hold its bands whole.)
        if let Some(src) = co.source.as_mut() {
            // (Its spectrum integrates to 1: one unit emits the channel's scale, W m⁻³ sr⁻¹.)
            src.set_reaction(ch, set.chemiluminescence / (4.0 * std::f64::consts::PI));
        }
    }
    if co.a.iter().chain(&co.s).any(|v| !v.is_finite() || *v < 0.0) {
        return Err(Error::invalid(
            "volume",
            "sigma_a/sigma_s",
            format!("{:?} {:?}", co.a, co.s),
            "finite, non-negative coefficients",
        ));
    }
    Ok(Optics {
        co,
        tables,
        thick,
        spare,
    })
}

/// The soot per unit density when the scene left `sootscale` unset and the density is a simulator's (what was
/// found, to be said), then the soot's scattering per unit density from `sootscatter`, per unit soot.
fn settle_soot(
    set: &mut Settings,
    ds: &Dataset,
    (density, temperature): (usize, Option<usize>),
    tool: crate::dataset::convention::Tool,
    spare: u64,
) -> Result<Option<String>, Error> {
    let mut said = None;
    if set.soot_auto {
        let kappa = match &set.emission {
            Emission::Physical { optics, alpha, .. } => optics.kappa(550.0, 1.0, *alpha),
            Emission::Pbrt { .. } => 0.0,
        };
        if let Some(s) = auto_soot(ds, density, temperature, tool, kappa, spare)? {
            said = Some(format!("sootscale: {}", s.why));
            if let Emission::Physical { sootscale, .. } = &mut set.emission {
                *sootscale = s.value;
            }
        }
    }
    if let (Some(k), Emission::Physical { sootscale, .. }) = (set.sootscatter, &set.emission) {
        let per_density = sootscale * k;
        set.sigma_s = Some(std::sync::Arc::new(move |_: f64| per_density));
    }
    Ok(said)
}

/// The soot scale for a file's density whose `sootscale` the scene left unset (`convention::soot_scale`, up from
/// the data with `tool`'s convention breaking a tie, the soot absorbing `kappa` m⁻¹ per unit volume fraction at
/// 550 nm); `None` for inline grids and single-grid formats (1 stands)
/// and for a density that is a volume fraction already.
fn auto_soot(
    ds: &Dataset,
    density: usize,
    temperature: Option<usize>,
    tool: crate::dataset::convention::Tool,
    kappa: f64,
    spare: u64,
) -> Result<Option<crate::dataset::convention::Choice<f64>>, Error> {
    use crate::dataset::convention;
    if !matches!(ds.format(), Format::Vdb | Format::NanoVdb) {
        return Ok(None);
    }
    let smoke = &ds.channels()[density];
    let peak = convention::peak(&smoke.grid);
    if peak <= convention::VOLUME_FRACTION_PEAK {
        return Ok(None);
    }
    let up = match temperature {
        Some(t) => {
            let heat = &ds.channels()[t].grid;
            let hot = convention::hot_threshold(
                convention::HeatKind::Temperature,
                convention::peak(heat),
            );
            let ev = convention::evidence(&smoke.grid, heat, hot, &|t| t as f64);
            convention::up(&ev, tool).0.value
        }
        None => tool.up(),
    };
    let cols = convention::columns(&smoke.grid, ds.voxel_size(), spare).ok_or_else(|| {
        Error::TooLarge {
            file: smoke.report.file.clone(),
            what: "the smoke's column sums (the soot scale of an unset sootscale)".into(),
            bytes: convention::column_bytes(ds.topology().active_bricks()),
            cap: spare,
        }
    })?;
    Ok(Some(convention::soot_scale(
        &smoke.name,
        peak,
        convention::thickest_across(cols, up),
        kappa,
    )))
}

/// The majorant bricks: each brick's grid ranges, its σ_t bound per channel (floored where an emission grid emits
/// without smoke, refused past an optical depth no fire has), and whether it is empty.
#[allow(clippy::type_complexity)]
fn majorants(
    ds: &Dataset,
    co: &coefficients::Coefficients,
    (density, temperature, lescale, emission_grid): (usize, Option<usize>, Option<usize>, bool),
    (brick, c): (usize, usize),
    known: Vec<Option<crate::majorant::Ranges>>,
    tables: &mut Vec<TableReport>,
) -> Result<(MajorantGrid, Vec<f64>, Vec<bool>), Error> {
    let t1 = Instant::now();
    let majorant = MajorantGrid::with_ranges(ds, brick, known);
    let mut brick_sigma = coefficients::brick_majorants(&majorant, co, density, temperature, c);
    // An emission grid emits where there may be no smoke: tracking's estimators add j/σ̄ at tentative
    // collisions, so σ̄ must not be 0 where j is not — a floor of one collision per voxel there.
    if let Some(e) = lescale.filter(|_| emission_grid) {
        let floor = 1.0 / ds.voxel_size().min_element();
        for (b, s) in brick_sigma.iter_mut().enumerate() {
            if majorant.max(b, e) > 0.0 {
                *s = s.max(floor);
            }
        }
    }
    let nb = brick_sigma.len();
    // An optical depth above 1e12 per voxel is no fire: a voxel value far outside the data's range, or a
    // scale far too large. Tracking through it would take ~1e12 collisions per voxel.
    let voxel = ds.voxel_size().max_element();
    if let Some((b, &sigma)) = brick_sigma
        .iter()
        .enumerate()
        .max_by(|x, y| x.1.total_cmp(y.1))
        .filter(|(_, &s)| !(s * voxel <= MAX_OPTICAL_DEPTH_PER_VOXEL))
    {
        let [cx, cy, _] = majorant.counts();
        let (i, j, k) = (b % cx, (b / cx) % cy, b / (cx * cy));
        return Err(Error::invalid(
            "volume",
            "extinction",
            format!("{sigma:.3e} m⁻¹ in brick ({i}, {j}, {k}) of {brick}³ voxels, an optical depth of {:.3e} per voxel", sigma * voxel),
            format!("at most {MAX_OPTICAL_DEPTH_PER_VOXEL:e} per voxel (a voxel value far outside the data's range, or sootscale, scale, sigma_a or sigma_s far too large?)"),
        ));
    }
    let emitter = lescale.filter(|_| emission_grid);
    let brick_empty: Vec<bool> = (0..nb)
        .map(|b| {
            majorant.max(b, density) <= 0.0
                && co.species.iter().all(|sp| majorant.max(b, sp.ch()) <= 0.0)
                && emitter.is_none_or(|e| majorant.max(b, e) <= 0.0)
        })
        .collect();
    tables.push(TableReport {
        name: format!("majorant bricks ({brick}³ voxels)"),
        bytes: majorant.bytes() + brick_sigma.len() * 8,
        seconds: t1.elapsed().as_secs_f64(),
    });
    Ok((majorant, brick_sigma, brick_empty))
}

/// The embers: the particles of `ef`, glowing by their temperature at the fire's `intensity` (a pbrt-v4 medium
/// has none), within what `spare` leaves after `tables`.
fn ember_layer(
    (emission, ember): (&Emission, crate::embers::Material),
    basis: &Basis,
    ef: &crate::dataset::params::EmberFile,
    spare: u64,
    tables: &mut Vec<TableReport>,
) -> Result<crate::embers::Embers, Error> {
    let Emission::Physical { intensity, .. } = emission else {
        return Err(Error::invalid(
            "dataset",
            "embers",
            format!("\"{}\" for a pbrt-v4 medium", ef.file),
            "a fire (\"string type\" \"fire\"): embers glow by their temperature",
        ));
    };
    let t6 = Instant::now();
    let nodes = basis.nodes();
    let g = vec![ember.emissivity * intensity; nodes.lambda.len()];
    let left = spare.saturating_sub(tables.iter().map(|t| t.bytes as u64).sum());
    let em = crate::embers::Embers::new(
        &ef.file,
        &ef.particles,
        ember,
        ef.shutter,
        ef.fps,
        &|t| basis.emit_planck(&nodes, &g, t),
        left,
    )?;
    tables.push(TableReport {
        name: format!("embers ({} particles and their grid)", em.len()),
        bytes: em.bytes(),
        seconds: t6.elapsed().as_secs_f64(),
    });
    Ok(em)
}

/// Refraction's index field, from the temperature grid (the index of air follows from it), within `left` bytes.
fn refraction_layer(
    rs: &super::settings::RefractionSettings,
    ds: &Dataset,
    temperature: Option<usize>,
    step: f64,
    spare: u64,
    tables: &mut Vec<TableReport>,
) -> Result<super::bent::Refraction, Error> {
    let left = spare.saturating_sub(tables.iter().map(|t| t.bytes as u64).sum());
    let t_ch = temperature.ok_or_else(|| {
        Error::invalid(
            "volume",
            "refraction",
            "true without a temperature grid",
            "a temperature grid (the index of air follows from it)",
        )
    })?;
    let t2 = Instant::now();
    let rf = super::bent::Refraction::build(
        &ds.channels()[t_ch].grid,
        ds.bounds(),
        &rs.air,
        (rs.wavelength, rs.scale),
        rs.rk4,
        step,
        ds.voxel_size().min_element(),
        left,
    )
    .map_err(|bytes| Error::TooLarge {
        file: "refraction".into(),
        what: "the index field (16 bytes per voxel around the voxels hotter than ambient)".into(),
        bytes,
        cap: left,
    })?;
    tables.push(TableReport {
        name: "refraction index field".into(),
        bytes: rf.bytes(),
        seconds: t2.elapsed().as_secs_f64(),
    });
    Ok(rf)
}

/// Whether the fire's colour is the physics' (no tint, no colour ramp short of `physical` 1), and the point
/// query's model: the closed forms, or what they cannot express — `layers` says which of the fire's layers are
/// on (species, thick lines, a scatter colour grid, diffusion, refraction, embers); the first such layer, or art
/// direction, names the refusal.
fn point_model(
    (emission, sigma_s): (&Emission, Option<&super::settings::SpectrumFn>),
    layers: [bool; 6],
) -> (bool, point::PointModel) {
    let physical_colour = match emission {
        Emission::Physical { tint, ramp, .. } => {
            tint.is_none() && ramp.as_ref().is_none_or(|r| r.physical >= 1.0)
        }
        _ => true,
    };
    let names = [
        "atomic lines or the blue core",
        "optically thick atomic lines",
        "a scatter colour grid",
        "diffusion",
        "refraction",
        "embers",
    ];
    let refused = layers
        .iter()
        .zip(names)
        .find(|(on, _)| **on)
        .map(|(_, why)| why)
        .or((!physical_colour).then_some("art direction (a tint or a colour ramp)"))
        .map(str::to_string);
    (
        physical_colour,
        point::PointModel::new(emission, sigma_s, refused),
    )
}

/// The box a ray is clipped to, and its margin in voxels: pbrt-v4's nanovdb medium shifts its grid's box by half a
/// voxel (its samples at the voxels' corners).
fn clip_box(mode: Mode, ds: &Dataset) -> ([DVec3; 2], f64) {
    let [b0, b1] = ds.bounds();
    if mode == Mode::Pbrt && ds.format() == Format::NanoVdb {
        let half = ds.voxel_size() * 0.5;
        ([b0 + half, b1 + half], 0.5)
    } else {
        ([b0, b1], 0.0)
    }
}

/// Motion blur's majorants, widened by how far the velocity carries the fire in the shutter.
fn blur_layer(
    m: crate::dataset::params::Motion,
    ds: &Dataset,
    (majorant, brick_sigma, brick_empty): (&MajorantGrid, &[f64], &[bool]),
    tables: &mut Vec<TableReport>,
) -> motion::Blur {
    let t5 = Instant::now();
    let b = motion::Blur::new(m, ds, majorant, brick_sigma, brick_empty);
    tables.push(TableReport {
        name: format!(
            "motion blur (majorants widened by {:.4} medium units)",
            b.reach()
        ),
        bytes: b.bytes(),
        seconds: t5.elapsed().as_secs_f64(),
    });
    b
}
