//! The fire light's parameter table (docs/reference/params.md is generated from it with the dataset's and the volume's).

use crate::params::{row as p, Choice, Component, ParamType as T, Range};

/// The fire light component (created from a fire volume; docs/reference/params.md).
pub static LIGHT: Component = Component {
    name: "light",
    doc: "The fire as a light (Selle's piecewise-constant 3D pdf over emitting voxels), created from a fire volume: its parameters are the volume's plus these.",
    params: &[p(
        "weighting",
        T::String,
        "power",
        "",
        Range::Choices(<super::Weighting as Choice>::NAMES),
        "Voxel weights: power, ∫ j dλ over the bins; luminance, Σ j Y; or escaping, power times the share that leaves the fire (e^{−τ} to the grid's edge along the axes, from the bricks' mean extinction; at least 5 %). Power measured 0.4–0.7 % lower error than luminance on the default scene (docs/results/log.md).",
    ),
    p(
        "cell",
        T::Integer,
        "8",
        "voxels",
        Range::Between(1.0, 8.0),
        "Voxels per side of the pdf's cells, 1, 2, 4 or 8: the light picks a cell by its emission and a point uniform in it, and the density of a direction walks cells, not voxels (docs/results/log.md, the fire light at production scale).",
    ),
    p(
        "linestep",
        T::Float,
        "0",
        "voxels",
        Range::Between(0.0, 1e6),
        "The march step of the fire's emission along a sampled direction (next-event estimation); 0: the fire's longest side over 16, 32 or 64 steps — with lineblock 0, the coarsest whose line (through a copy or the fire's voxels) stays within 0.5 % of the volume's march on 1024 of the light's rays (their lines over their directions' densities, and within 1 % in their plain sum), 64 if none does; with lineblock given, 64. Never shorter than the volume's own step (then it is the volume's march).",
    ),
    p(
        "linecorrection",
        T::Float,
        "0",
        "",
        Range::Between(0.0, 1.0),
        "The probability of correcting a coarse line estimate by the volume's own march (the difference over the probability: unbiased against it); 0: the coarse march alone.",
    ),
    p(
        "lineblock",
        T::Integer,
        "0",
        "voxels",
        Range::Between(0.0, 8.0),
        "The blocks of the copy of the fire the coarse line marches through (density their mean, temperature the one that emits their mean: a copy that stays in the caches): 2, 4 or 8 voxels per side; 1, the fire's own voxels; 0, the coarsest copy no coarser than the step whose line stays within 0.5 % of the volume's march on 1024 of the light's rays (their lines over their directions' densities, and within 1 % in their plain sum) (checked when the light is built). Volumes with species, emission or Lescale grids, motion blur, refraction, diffusion, thick lines or embers march their own voxels.",
    ),
    p(
        "linechannels",
        T::Integer,
        "0",
        "channels",
        Range::Between(0.0, 1e6),
        "How many of the spectral bins the coarse line marches, the others following from them (transmittance exactly from the column of soot, radiance by interpolation in 1/λ of the logarithm of its ratio to a slab of that soot at the fire's hottest temperature): 0, 8 bins where the line's X, Y and Z stay within 0.2 % of every bin's on 1024 of the light's rays (checked when the light is built), else all; 2 to 32, that many; at least the volume's bins, all of them. Only a soot fire's bins (no species' lines, no emission or Lescale grid, and as lineblock's list); rgb marches its 3.",
    )],
};
