//! pbrt-v4 fidelity, end to end: scenes written for pbrt-v4 render at pbrt-v4's own pixel values (its film,
//! its light normalisation, its grid media's peak-normalised blackbody), checked against numbers measured by
//! running pbrt-v4 itself (`tests/data/pbrt-v4-measured/`) and against closed forms from its definitions.

use crate::common::image;
use crate::common::render;

use image::{luminance, read_exr};
use render::{data, mean_rgb, out_dir, read_text, render, run_render, y_of};
use std::path::{Path, PathBuf};

mod film;
mod media;
mod scenes;

/// The slab scenes' two regions, inside their edges: the grid's box [0, 1] (x) × [0, 1] (z) and the light's
/// quad [1.2, 2.2] × [0, 1], seen from (1.1, −20, 0.5) looking along +y on a 64 × 32 film 4 × 2 units wide (16
/// pixels per unit; pbrt's camera space is left-handed, so world x grows to the left: pixel i is x = 3.1 − i/16).
const BOX: ((usize, usize), (usize, usize)) = ((36, 48), (10, 22));
const LIGHT: ((usize, usize), (usize, usize)) = ((16, 29), (10, 22));
