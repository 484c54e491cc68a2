//! The parameter tables of the voxel dataset and fire volume components (docs/reference/params.md is generated from
//! them).

use super::{Integrator, Mode};
use crate::params::choice;
use crate::params::{row as p, Choice, Component, ParamType as T, Range};

/// The voxel dataset component.
pub static DATASET: Component = Component {
    name: "dataset",
    doc: "Voxel grids from files (OpenVDB, NanoVDB, the thesis's ASCII and raw formats) or inline arrays (pbrt-v4 `uniformgrid`). Only the grids the fire uses are loaded.",
    params: &[
        p("filename", T::String, "", "", Range::Path, "File holding the grids (.vdb, .nvdb; any format). A `####` or `%04d` in the name takes `frame`."),
        p("dataset", T::String, "", "", Range::Path, "The fire scene's name for `filename` (`MakeNamedMedium \"f\" \"string type\" \"fire\" \"string dataset\" \"flame.vdb\"`)."),
        p("densityfile", T::String, "", "", Range::Path, "File of the density grid, when grids come in separate files (thesis formats)."),
        p("temperaturefile", T::String, "", "", Range::Path, "File of the temperature grid, when grids come in separate files."),
        p("format", T::String, "", "", Range::Choices(<Option<crate::dataset::Format> as Choice>::NAMES), "File format; empty: from the extension."),
        p("densitygrid", T::String, "density", "", Range::Any, "Name of the density grid in a VDB/NanoVDB file."),
        p("temperaturegrid", T::String, "temperature", "", Range::Any, "Name of the temperature grid; empty for none (no emission from temperature)."),
        p("gridname", T::String, "", "", Range::Any, "pbrt-v4's nanovdb name for densitygrid (give one of the two)."),
        p("temperaturename", T::String, "", "", Range::Any, "pbrt-v4's nanovdb name for temperaturegrid (give one of the two)."),
        p("species", T::String, "", "", Range::Any, "Element symbols of species grids (Na, Li, K, Ca, Sr, Ba, Cu); each grid is named by its symbol and holds the element's free atoms. Ca, Sr, Ba and Cu also carry the bands of the hydroxides (and Ba's and Cu's oxides) they form in a flame, at the share a gas flame holds them in: their flame-test colours."),
        p("speciesfiles", T::String, "", "", Range::Path, "Files of the species grids, one per symbol, when not in `filename`."),
        p("speciesscale", T::Float, "1", "m⁻³ per unit", Range::Between(0.0, 1e40), "Multiplier turning species grid values into number densities (one value, or one per species)."),
        p("order", T::String, "x", "", Range::Choices(<crate::dataset::AxisOrder as Choice>::NAMES), "Dense ASCII value order: x fastest (the thesis text) or z fastest (its shader code)."),
        p("rawcoords", T::String, "thesis", "", Range::Choices(<crate::dataset::RawCoords as Choice>::NAMES), "Raw coordinates: 1-based x z y (the thesis's shader) or 0-based x y z."),
        p("rawvalue", T::String, "red", "", Range::Choices(<crate::dataset::RawValue as Choice>::NAMES), "Raw value: r/256 or max(r, g, b)/256."),
        p("rawdims", T::Integer, "256 256 256", "voxels", Range::Between(1.0, 1048576.0), "Dims of a headerless raw file."),
        p("nonfinite", T::String, "error", "", Range::Choices(<crate::dataset::Policy as Choice>::NAMES), "NaN or infinite values: refuse the file, or replace by 0 (counted)."),
        p("negative", T::String, "error", "", Range::Choices(<crate::dataset::Policy as Choice>::NAMES), "Negative density, temperature or species values: refuse, or replace by 0."),
        p("maxbytes", T::Float, "8589934592", "bytes", Range::Above(0.0), "The volume's memory budget, checked before allocating: a file's grids share it (refused beyond it), the march lattice is built only within what they leave (else the march reads the grids in place: the same image, slower), and the fire light must fit in what remains."),
        p("frame", T::Integer, "", "", Range::Between(-1e9, 1e9), "Frame number substituted into a patterned file name."),
        p("interpolation", T::String, "trilinear", "", Range::Choices(<crate::grid::Interpolation as Choice>::NAMES), "Lookup between voxel centres."),
        p("p0", T::Point3, "", "medium units", Range::Any, "Lower corner of the grid's box (inline grids, formats without a transform; default 0,0,0)."),
        p("p1", T::Point3, "", "medium units", Range::Any, "Upper corner (default 1,1,1)."),
        p("nx", T::Integer, "1", "voxels", Range::Between(1.0, 1048576.0), "Inline grid resolution along x (pbrt-v4 uniformgrid)."),
        p("ny", T::Integer, "1", "voxels", Range::Between(1.0, 1048576.0), "Inline grid resolution along y."),
        p("nz", T::Integer, "1", "voxels", Range::Between(1.0, 1048576.0), "Inline grid resolution along z."),
        p("density", T::Float, "", "", Range::Any, "Inline density values, nx·ny·nz, x fastest (pbrt-v4 uniformgrid)."),
        p("temperature", T::Float, "", "K before mapping", Range::Any, "Inline temperature values, nx·ny·nz."),
        p("temperaturescale", T::Float, "1", "", Range::Between(0.0, 1e9), "T = (t − temperatureoffset) · temperaturescale (pbrt-v4)."),
        p("temperatureoffset", T::Float, "0", "", Range::Between(-1e9, 1e9), "Subtracted from grid temperatures before scaling (pbrt-v4)."),
        p("temperaturecutoff", T::Float, "", "", Range::Between(-1e9, 1e9), "pbrt-v4 nanovdb's name for temperatureoffset."),
        p("source", T::String, "auto", "", Range::Choices(<crate::dataset::params::Tool as Choice>::NAMES), "Where the grids come from. auto: found from an OpenVDB/NanoVDB file's grid names and data (docs/guide/your-vdb.md: which grid is the smoke, which the temperature and in what unit — kelvin from a peak of 500, a relative temperature below 50 —, Blender's flame grid as 1000 K at its edge to 1500 K at 1 unless flameignition and flamemax are given), said in the volume's notes; kelvin otherwise. kelvin (and pbrt): density and temperature in K (our gen, the thesis's files, pbrt-v4's nanovdb). blender: a Mantaflow domain cache; the fire's temperature is its flame grid as Cycles maps it, 1000 K · (flameignition + flame · (flamemax − flameignition)) where flame > 0, else none. houdini: Pyro's density and relative temperature (else heat), × 5000 K (the Pyro shader's blackbody default: 1 → 5000 K) or less, so that its peak is at most 1500 K (what a fire's luminous soot reaches); temperaturescale or temperatureremap replace that. embergen: smoke (else density) and temperature in K. densitygrid and temperaturegrid, when given, name other grids."),
        p("scattercolorgrid", T::String, "", "", Range::Any, "A colour grid that tints the scattering per voxel (Houdini's `Cd`: a vec3s grid, or its components name.x/.y/.z): the albedo of what scatters, r, g, b clamped to [0, 1] (spectral bins: the smooth rgb→spectrum fits of the three primaries, normalised to sum to 1). Extinction is kept: what a colour does not scatter is absorbed."),
        p("flameignition", T::Float, "1.5", "1000 K", Range::Between(0.0, 100.0), "source blender: the domain's flame Ignition (Blender's default 1.5)."),
        p("flamemax", T::Float, "3", "1000 K", Range::Between(0.0, 100.0), "source blender: the domain's flame Maximum (Blender's default 3.0)."),
        p("temperatureremap", T::Float, "", "", Range::Any, "Art direction: a b ka kb maps the grid's values a..b linearly onto ka..kb kelvin (instead of temperaturescale and temperatureoffset)."),
        p("reactiongrid", T::String, "", "", Range::Any, "The blue core: a grid of the reaction zone's heat release rate (W/m³) — a `reaction` grid of `gen`, or a simulator's; the zone emits `chemiluminescence` of it as the CH* (431 nm) and C₂* Swan (473, 516, 563 nm) bands, isotropically, absorbing nothing. Physical mode."),
        p("chemiluminescence", T::Float, "1e-4", "", Range::Between(0.0, 1.0), "The fraction of the heat release the reaction zone emits as CH* and C₂* light (with reactiongrid; ~1e-5–1e-4 in hydrocarbon flames, Hardalupas & Orain 2004)."),
        p("emissiongrid", T::String, "", "", Range::Any, "A grid the fire's emission follows instead of the soot density (Houdini's or Blender's flame, heat, burn; Arnold's emission channel): j = e · σ_a(λ, per unit density) · B(T), e in the density's units (a soot volume fraction once sootscale applies: a flame grid of 0–1 wants a firescale near the soot fraction, ~1e-6). Not the density: emission no longer equals absorption times Planck (Kirchhoff)."),
        p("embers", T::String, "", "", Range::Path, "A particle file of embers (PLY — ascii or binary — or CSV with a header row; a `####` or `%04d` takes `frame`): per particle a position, radius (or pscale, width) and temperature (K, at age 0), and optionally a velocity (medium units per second) and an age (s). Each is rendered as an opaque grey sphere of radiance emberemissivity · B(T) (× intensity), T from its age and the ray's time — burning its char in the air (emberoxygen) and cooling by radiation and convection —, moving with its velocity while the shutter is open, and sampled by the fire light. Physical mode."),
        p("velocitygrid", T::String, "", "", Range::Any, "Velocity for motion blur: one name — a vector grid (Houdini `vel`, Mantaflow `velocity`, EmberGen) or the float grids name.x, name.y, name.z — or three float grids' names; `auto`: the first of vel, v, velocity the file holds (OpenVDB). Read only while the shutter is open."),
        p("velocityscale", T::Float, "1", "", Range::Between(-1e6, 1e6), "Multiplier of the velocity grid's values (medium units per second after it)."),
        p("fps", T::Float, "24", "frames/s", Range::Between(1e-6, 1e6), "Frames per second: the shutter is in frames, velocities per second (1: velocities per frame)."),
        p("shutteropen", T::Float, "0", "frames", Range::Between(-1e6, 1e6), "When the shutter opens, relative to the time of the grids (pbrt-v4's camera `shutteropen`; the pbrt host passes its camera's)."),
        p("shutterclose", T::Float, "0", "frames", Range::Between(-1e6, 1e6), "When it closes; equal to shutteropen: no motion blur (velocity is not read)."),
    ],
};

/// The fire volume component.
pub static VOLUME: Component = Component {
    name: "volume",
    doc: "Soot absorption and blackbody emission (Pegoraro & Parker 2006 eq. 5–6), atomic lines (eq. 7–12), optional scattering, integrated along rays (eq. 1–3).",
    params: &[
        p("mode", T::String, "physical", "", Range::Choices(<Mode as Choice>::NAMES), "physical: the paper's fire; pbrt: pbrt-v4 uniformgrid/nanovdb semantics (σ spectra × density, peak-normalised blackbody × Lescale above 100 K)."),
        p("look", T::String, "", "", Range::Choices(&super::looks::CHOICES), "A named set of this table's parameters, each overridden by the scene's own: candle (smokescale 0.3), campfire (sootscatter 2e6, g 0.6: soot aggregates' albedo ≈ 0.2), gasburner (sootscale 0.02, smokescale 0, a blue colorramp with physical 0: art direction for the reaction zone's chemiluminescence), explosion (fuel acetylene, smokescale 3, sootscatter 2e6, g 0.6)."),
        p("multiplescattering", T::String, "pathtraced", "", Range::Choices(<Scattering as Choice>::NAMES), "How the smoke scatters: pathtraced — the host samples scattering events (every light, unbiased); diffusion — the fire's own light in its smoke solved once by the diffusion equation on a coarse grid (Stam & Fiume §5) and added to the emission: no scattering events and no noise from them, other lights not scattered; within 10 % of path tracing from an optical thickness of 1 to 100 at albedo 0.9 on the default grid and step (the march samples it at least twice per cell and at most one optical depth per step; docs/results/log.md, \"Multiple scattering by diffusion\")."),
        p("diffusionresolution", T::Integer, "32", "cells", Range::Between(2.0, 256.0), "Cells of the diffusion grid along the box's longest side."),
        p("linecolour", T::String, "ownwavelength", "", Range::Choices(<LineColour as Choice>::NAMES), "How spectral bins carry an atomic line's light. ownwavelength: shared between its bin and a neighbour (energy kept, absorption alike) so that the film sees the line at its own wavelength's luminance — exact — and colour (chromaticity within 0.003), where a bin's mean gives Ca 422.7 nm −41 % and Na D +8 % with the default bins; binmean: in its bin alone, each bin the mean spectral radiance over it (the paper's; radiometry per bin, the colour of the bin). rgb mode projects lines at their own wavelengths either way."),
        p("lineshape", T::String, "voigt", "", Range::Choices(<LineShape as Choice>::NAMES), "Atomic lines' shape: voigt — Doppler and collisional broadening, integrated wavelength by wavelength across each line that can become optically thick in this fire (the curve of growth: a thick line saturates to the blackbody only over its true width); box — the paper's φ = 1/bin width, right while the lines are thin and up to ~100× too bright where they are not."),
        p("linebroadening", T::Float, "0.08", "cm⁻¹", Range::Between(0.0, 100.0), "Collisional full width at half maximum of every atomic line at 2500 K and 1 atm (∝ T^-0.7): an estimate for flame gases (Na D's Voigt damping 0.5; 0.4–0.8 measured in flames)."),
        p("fuel", T::String, "propane", "", Range::Choices(<Fuel as Choice>::NAMES), "Soot optical constants (Dalzell & Sarofim 1969), or `fuelnk`."),
        p("fuelnk", T::Float, "", "nm, 1, 1", Range::Any, "Custom soot optical constants: (λ nm, n, k) triples, λ increasing."),
        p("alpha", T::Float, "1.39", "", Range::Between(0.0, 4.0), "Soot exponent: 1.39 (Hottel, λ in µm) or 1 (Rayleigh, λ in m); 0 with constant n, k is a grey absorber."),
        p("sootscale", T::Float, "", "volume fraction per unit density", Range::Between(0.0, 1.0), "Soot volume fraction f_v = sootscale · density. Unset: 1 for inline grids, the thesis's formats and an OpenVDB/NanoVDB density that peaks at most 1e-4 (a volume fraction already); for a simulator's density (a larger peak), the scale that makes the thickest horizontal line of sight across the fire one optical depth at 550 nm (the flame seen through its smoke), said in the volume's notes."),
        p("intensity", T::Float, "1", "", Range::Between(0.0, 1e12), "Artistic multiplier on emission; 1 is physical."),
        p("firescale", T::Float, "1", "", Range::Between(0.0, 1e12), "The fire's emission times this, its absorption kept (Arnold's and Houdini's name for intensity; give one of the two). Not 1: emission no longer equals absorption times Planck (Kirchhoff)."),
        p("smokescale", T::Float, "1", "", Range::Between(0.0, 1e12), "The smoke's absorption and scattering times this, the fire's emission kept: 0 leaves a fire without smoke. Not 1: emission no longer equals absorption times Planck (Kirchhoff)."),
        p("colorramp", T::Float, "", "", Range::Any, "Art direction: keys T r g b (kelvin, increasing; linear sRGB) of the fire's colour over temperature, replacing the blackbody's chromaticity and keeping its luminance (linear between keys in the render's channels, the end keys' beyond)."),
        p("physical", T::Float, "0", "", Range::Between(0.0, 1.0), "With a colorramp (and only with one): 1 the physical colour, 0 the ramp's, between a blend of the two (V-Ray's \"physically based\")."),
        p("tint", T::Spectrum, "", "", Range::Any, "The soot's emission times this spectrum (rgb: a colour, as pbrt-v4's unbounded spectra; or a constant, or (λ nm, value) pairs); species lines are not tinted. Not white: the fire's colour is no longer the blackbody's."),
        p("sigma_a", T::Spectrum, "1", "m⁻¹ per unit density", Range::Any, "pbrt mode: absorption spectrum (× scale × density)."),
        p("sigma_s", T::Spectrum, "", "m⁻¹ per unit density", Range::Any, "Scattering: σ_s = sigma_s · density (pbrt mode: × scale). Unset: 0 in physical mode (the low-albedo fire of the paper), 1 in pbrt mode (pbrt-v4's default)."),
        p("scale", T::Float, "1", "", Range::Between(0.0, 1e12), "pbrt mode: multiplier on sigma_a and sigma_s."),
        p("g", T::Float, "0", "", Range::Between(-0.999, 0.999), "Henyey–Greenstein asymmetry (eq. 4)."),
        p("Lescale", T::Float, "1", "", Range::Between(0.0, 1e30), "pbrt mode: emission scale (one value), or nx·ny·nz values for inline grids."),
        p("Le", T::Spectrum, "", "", Range::Any, "pbrt mode: constant emission spectrum (uniformgrid without temperature)."),
        p("colormode", T::String, "spectral", "", Range::Choices(<ColourSpace as Choice>::NAMES), "spectral: bins of W·m⁻²·sr⁻¹·nm⁻¹; rgb: three CIE XYZ bands (Y in cd/m²), the thesis's speed path."),
        p("bins", T::Integer, "32", "", Range::Between(1.0, 4096.0), "Spectral bins."),
        p("lambdamin", T::Float, "400", "nm", Range::Between(200.0, 2000.0), "Lower end of the spectral bins."),
        p("lambdamax", T::Float, "780", "nm", Range::Between(200.0, 2000.0), "Upper end of the spectral bins (CIE ȳ continues to 780 nm: on a soot flame 700 leaves out about 0.4 % of the luminance, 780 keeps it)."),
        p("stepsize", T::Float, "0.5", "voxels", Range::Between(1e-4, 1e9), "March step, in voxels (the paper's half voxel); from 1e-4 (a step count per ray that still ends)."),
        p("integrator", T::String, "", "", Range::Choices(<Option<Integrator> as Choice>::NAMES), "march: fixed steps, eq. 3 (a step thicker than steptau split in sub-steps); ratio/delta: unbiased tracking over the majorant bricks (ratio: pbrt-v4's own estimator). Unset: march."),
        p("steptau", T::Float, "", "", Range::Between(1e-6, 1e30), "march: the largest optical depth of one step, at its midpoint; a thicker step is split into sub-steps of at most this depth (at most 4096). Unset: 0.1 in pbrt mode; 1 with multiplescattering diffusion (whose scattered light rises over a diffusion length from the smoke's surface); otherwise never."),
        p("brick", T::Integer, "8", "voxels", Range::Between(1.0, 4096.0), "Majorant brick edge (the march jumps over bricks holding nothing; the tracking integrators sample against each brick's bound)."),
        p("lattice", T::String, "auto", "", Range::Choices(<Lattice as Choice>::NAMES), "The copy of the grids the f32 march reads: dense over the box, or a padded copy per brick holding data (memory follows the data); auto: for a `fire`, dense while it costs at most 4× the grids' storage, else bricks, and for a fire that scatters (its host tracks it) built when a ray first marches; for pbrt-v4's own grid media (`nanovdb`, `uniformgrid`), none: they read their grids in place, as pbrt-v4 does, in about its memory; off: no copy, the march reads the grids' stored bricks in place (the same image to the bit, a slower march, least memory; also what a volume does when the budget leaves no room for the copy). The fire light's coarse copy keeps a lattice of its own whatever this says: it is made to fit in the caches."),
        p("precision", T::String, "f32", "", Range::Choices(<Precision as Choice>::NAMES), "Per-sample arithmetic of the march: f32 in vector lanes (about 2× faster; within 1e-6 of f64 on the campfire), falling back to f64 when a product could leave f32's range; f64: always f64."),
        p("threads", T::Integer, "0", "", Range::Between(0.0, 4096.0), "Threads the build may use (tables, lattice, reading and densifying grids); 0: every core. A host passes its own thread count."),
        p("cutoff", T::Float, "1e-6", "", Range::Between(0.0, 1.0), "march: stop when every channel's transmittance is below this."),
        p("refraction", T::Bool, "false", "", Range::Any, "Bend rays through the hot gas (P&P §3.7): an index field from temperature (Ciddor), curved rays by the ray equation. Off: nothing is baked."),
        p("refractionintegrator", T::String, "verlet", "", Range::Choices(<RefractionIntegrator as Choice>::NAMES), "verlet: one symplectic step per march step, n and ∇n looked up at the medium's sample point (fast); rk4: adaptive RK4 with step doubling, steps ending at the grid's planes (the accurate reference, ~3× slower)."),
        p("refractionscale", T::Float, "1", "", Range::Between(0.0, 1e6), "Exaggeration of (n − 1), as the paper's Figure 2."),
        p("refractionwavelength", T::Float, "550", "nm", Range::Between(200.0, 2000.0), "Vacuum wavelength the index is computed at (one for all channels)."),
        p("emberemissivity", T::Float, "0.9", "", Range::Between(1e-6, 1.0), "Emissivity of the embers' char (grey; 0.85–0.95 for char, Incropera's table of total emissivities)."),
        p("emberdensity", T::Float, "250", "kg/m³", Range::Between(1e-3, 1e5), "Apparent density of the embers (softwood char 200–300 kg/m³): with emberheatcapacity and the radius, how fast an ember cools."),
        p("emberheatcapacity", T::Float, "1200", "J/(kg·K)", Range::Between(1.0, 1e5), "Specific heat of the embers' char (1.0–1.5 kJ/(kg·K) at 600–1200 K, Gupta, Yang & Kozinski 2003)."),
        p("emberoxygen", T::Float, "0.233", "", Range::Between(0.0, 1.0), "Oxygen mass fraction of the air the embers fly in (air: 0.233): their char burns in it — wood char's kinetics (Anca-Couce et al. 2012) in series with the oxygen's diffusion to the surface, its carbon burning to CO₂ (12.3 MJ per kg of oxygen) — against radiation and convection, so a 1 mm spark glows near 1100 K for seconds, a 3 mm one cannot stay lit, and a cold or tiny one goes out; 0: the embers only cool by radiation."),
        p("ambienttemperature", T::Float, "293.15", "K", Range::Between(1.0, 1e4), "Temperature of the air around the fire; colder voxels (0 K where a simulation holds no data) count as ambient."),
        p("pressure", T::Float, "101325", "Pa", Range::Between(1.0, 1e7), "Air pressure (index of refraction)."),
        p("humidity", T::Float, "0", "", Range::Between(0.0, 1.0), "Relative humidity of the air, 0–1 (index of refraction)."),
        p("co2", T::Float, "450", "ppm", Range::Between(0.0, 1e6), "CO₂ mole fraction of the air (index of refraction)."),
        p("sootscatter", T::Float, "", "m⁻¹ per unit volume fraction", Range::Between(0.0, 1e12), "The soot aggregates' scattering: σ_s = sootscatter · f_v (f_v = sootscale · density), so that it follows the soot whatever unit a simulator's density is in (the looks' scattering: 2e6, an albedo ≈ 0.2 at 550 nm). Physical mode; one of this and sigma_s."),
    ],
};

/// Test-only parameters: compiled into the plugin's own unit tests, never into the shipped library.
#[cfg(test)]
pub static FAULTS: Component = Component {
    name: "faults",
    doc: "Test-only fault injection (the plugin's unit tests).",
    params: &[p(
        "faultinjection",
        T::String,
        "",
        "",
        Range::Choices(&["", "create", "integrate"]),
        "Panic inside creation or integration, to test that no panic crosses the ABI.",
    )],
};

/// `precision`: the march's per-sample arithmetic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Precision {
    F32,
    F64,
}
choice!(Precision { Precision::F32 => "f32", Precision::F64 => "f64" });

/// `lattice`: the copy of the grids the f32 march reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Lattice {
    /// For a `fire`, dense while it costs at most 4× the grids' storage, else bricks; none for pbrt-v4's media.
    Auto,
    Dense,
    Bricks,
    /// No copy: the march reads the grids' stored bricks in place.
    Off,
}
choice!(Lattice { Lattice::Auto => "auto", Lattice::Dense => "dense", Lattice::Bricks => "bricks", Lattice::Off => "off" });

/// `lineshape`: atomic lines' profiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LineShape {
    Voigt,
    Box,
}
choice!(LineShape { LineShape::Voigt => "voigt", LineShape::Box => "box" });

/// `multiplescattering`: how the smoke scatters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scattering {
    PathTraced,
    Diffusion,
}
choice!(Scattering { Scattering::PathTraced => "pathtraced", Scattering::Diffusion => "diffusion" });

/// `refractionintegrator`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RefractionIntegrator {
    Verlet,
    Rk4,
}
choice!(RefractionIntegrator { RefractionIntegrator::Verlet => "verlet", RefractionIntegrator::Rk4 => "rk4" });

/// `colormode`: spectral bins or XYZ bands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ColourSpace {
    Spectral,
    Rgb,
}
choice!(ColourSpace { ColourSpace::Spectral => "spectral", ColourSpace::Rgb => "rgb" });

/// `linecolour`: how spectral bins carry an atomic line's light.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LineColour {
    OwnWavelength,
    BinMean,
}
choice!(LineColour { LineColour::OwnWavelength => "ownwavelength", LineColour::BinMean => "binmean" });

/// `fuel`: the soot's optical constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Fuel {
    Propane,
    Acetylene,
    /// `fuelnk`'s table.
    Custom,
}
choice!(Fuel { Fuel::Propane => "propane", Fuel::Acetylene => "acetylene", Fuel::Custom => "custom" });

choice!(Option<Integrator> {
    None => "",
    Some(Integrator::March) => "march",
    Some(Integrator::Ratio) => "ratio",
    Some(Integrator::Delta) => "delta",
});
