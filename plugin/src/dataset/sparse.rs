//! Sparse VDB trees (OpenVDB and NanoVDB alike) made dense over the active region, so channels share one
//! lattice and the fire samples a flat array.

use super::{alloc_grid, Loaded};
use crate::Error;
use glam::DVec3;

/// Axis-aligned index → medium map of a grid: p = scale ∘ ijk + translation (integer index = voxel centre).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Per-axis voxel size.
    pub scale: DVec3,
    /// Medium-space position of index (0, 0, 0).
    pub translation: DVec3,
}

/// An 8³ leaf: origin, 512 values (z fastest within the leaf: offset x·64 + y·8 + z; empty when a
/// [`LeafValues`] source decodes them while the grid is made dense), active mask.
pub(crate) struct Leaf {
    pub origin: [i32; 3],
    pub values: Vec<f32>,
    pub mask: [u64; 8],
}

/// A constant cube of `size`³ voxels at `origin`.
pub(crate) struct Tile {
    pub origin: [i32; 3],
    pub size: i32,
    pub value: f32,
    pub active: bool,
}

/// One grid: its map, background, tiles and leaves.
pub(crate) struct Tree {
    pub transform: Transform,
    pub background: f32,
    pub tiles: Vec<Tile>,
    pub leaves: Vec<Leaf>,
}

/// Where a tree's leaf values come from while the dense grid is filled: called once per leaf, in order.
pub(crate) trait LeafValues: Send {
    /// Leaf `leaf`'s 512 values (z fastest).
    fn values<'a>(&'a mut self, leaf: &'a Leaf) -> Result<&'a [f32], Error>;
}

/// Leaves decoded with the tree (their `values`).
pub(crate) struct InLeaves;

impl LeafValues for InLeaves {
    fn values<'a>(&'a mut self, leaf: &'a Leaf) -> Result<&'a [f32], Error> {
        Ok(&leaf.values)
    }
}

pub(crate) fn bit(m: &[u64], i: usize) -> bool {
    m[i >> 6] >> (i & 63) & 1 == 1
}

fn leaf_voxel(o: [i32; 3], i: usize) -> [i64; 3] {
    [
        o[0] as i64 + (i >> 6) as i64,
        o[1] as i64 + ((i >> 3) & 7) as i64,
        o[2] as i64 + (i & 7) as i64,
    ]
}

/// Index box [min, max] of the active voxels and tiles, or `None` when nothing is active.
fn active_bbox(t: &Tree) -> Option<([i64; 3], [i64; 3])> {
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    let mut grow = |a: [i64; 3], b: [i64; 3]| {
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
    };
    for tile in t.tiles.iter().filter(|t| t.active) {
        let o = tile.origin.map(|v| v as i64);
        grow(o, o.map(|v| v + tile.size as i64 - 1));
    }
    for leaf in &t.leaves {
        // The mask's words are x slabs, its bits y·8 + z: the active x range from the non-zero words, y from
        // the bytes of their union, z from the bits of the union of those bytes.
        let mut xs = (0..8).filter(|&x| leaf.mask[x] != 0);
        let (Some(x0), Some(x1)) = (xs.clone().next(), xs.next_back()) else {
            continue;
        };
        let union = leaf.mask.iter().fold(0u64, |a, &w| a | w);
        let mut ys = (0..8).filter(|&y| (union >> (8 * y)) & 0xff != 0);
        let (y0, y1) = (ys.clone().next().unwrap_or(0), ys.next_back().unwrap_or(0));
        let zbits = (0..8).fold(0u64, |a, y| a | (union >> (8 * y)) & 0xff);
        let (z0, z1) = (
            zbits.trailing_zeros() as i64,
            63 - zbits.leading_zeros() as i64,
        );
        let o = leaf.origin.map(|v| v as i64);
        grow(
            [o[0] + x0 as i64, o[1] + y0 as i64, o[2] + z0],
            [o[0] + x1 as i64, o[1] + y1 as i64, o[2] + z1],
        );
    }
    (lo[0] <= hi[0]).then_some((lo, hi))
}

/// The error for a grid name a file does not hold, listing the names it does.
pub(crate) fn missing_grid<'a>(
    file: &str,
    name: &str,
    have: impl Iterator<Item = &'a str>,
) -> Error {
    let have: Vec<String> = have.map(|g| format!("'{g}'")).collect();
    Error::format(
        file,
        "grid table",
        format!("a grid named '{name}'"),
        format!("grids {}", have.join(", ")),
    )
}

/// Makes `trees` dense over the union of their active boxes; every voxel holds the tree's value there
/// (leaf values, active or not, over tile values, over the background).
pub(crate) fn densify<S: LeafValues>(
    file: &str,
    trees: Vec<(&str, Tree, S)>,
    max_bytes: u64,
) -> Result<Vec<Loaded>, Error> {
    let (first_name, first) = (&trees[0].0, &trees[0].1);
    for (name, t, _) in &trees[1..] {
        if t.transform != first.transform {
            return Err(Error::format(
                file,
                format!("grid '{name}'"),
                format!(
                    "the transform of grid '{first_name}' (channels share one lattice): {:?}",
                    first.transform
                ),
                format!("{:?}", t.transform),
            ));
        }
    }
    let mut bbox: Option<([i64; 3], [i64; 3])> = None;
    for (_, t, _) in &trees {
        if let Some((a, b)) = active_bbox(t) {
            bbox = Some(match bbox {
                None => (a, b),
                Some((lo, hi)) => (
                    [0, 1, 2].map(|k| lo[k].min(a[k])),
                    [0, 1, 2].map(|k| hi[k].max(b[k])),
                ),
            });
        }
    }
    let Some((lo, hi)) = bbox else {
        let names: Vec<&str> = trees.iter().map(|t| t.0).collect();
        return Err(Error::format(
            file,
            format!("grid '{}'", names.join("', '")),
            "at least one active voxel",
            "an empty grid",
        ));
    };
    let extent = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as u64);
    let dims = extent.map(|e| usize::try_from(e).unwrap_or(usize::MAX));
    let tr = first.transform;
    let to_medium = |v: [f64; 3]| DVec3::from_array(v) * tr.scale + tr.translation;
    let p0 = to_medium([0, 1, 2].map(|k| lo[k] as f64 - 0.5));
    let p1 = to_medium([0, 1, 2].map(|k| hi[k] as f64 + 0.5));
    // One dense grid per tree, filled in parallel (each leaf's values decoded as it is placed). The cap covers
    // them all: each gets its share (three grids of 1 GB each passed a 1 GB cap one by one).
    let share = max_bytes / trees.len().max(1) as u64;
    super::par_map(trees, |(_, t, mut source)| {
        let mut data = alloc_grid(file, dims, share, t.background)?;
        let put = |data: &mut [f32], p: [i64; 3], v: f32| {
            let q = [0, 1, 2].map(|k| p[k] - lo[k]);
            if (0..3).all(|k| q[k] >= 0 && (q[k] as usize) < dims[k]) {
                data[q[0] as usize + dims[0] * (q[1] as usize + dims[1] * q[2] as usize)] = v;
            }
        };
        let mut tiles: Vec<&Tile> = t.tiles.iter().collect();
        tiles.sort_by_key(|t| -t.size);
        let max_tile = tiles.first().map_or(0, |t| t.size);
        for tile in tiles {
            let o = tile.origin.map(|v| v as i64);
            let a = [0, 1, 2].map(|k| o[k].max(lo[k]));
            let b = [0, 1, 2].map(|k| (o[k] + tile.size as i64 - 1).min(hi[k]));
            // (A tile of the background value changes nothing, unless a larger tile wrote over it first.)
            if tile.value.to_bits() == t.background.to_bits() && tile.size == max_tile {
                continue;
            }
            if (0..3).any(|k| a[k] > b[k]) {
                continue;
            }
            let q = [0, 1, 2].map(|k| (a[k] - lo[k]) as usize);
            let len = (b[0] - a[0] + 1) as usize;
            for z in 0..=(b[2] - a[2]) as usize {
                for y in 0..=(b[1] - a[1]) as usize {
                    let start = q[0] + dims[0] * (q[1] + y + dims[1] * (q[2] + z));
                    if let Some(row) = data.get_mut(start..start + len) {
                        row.fill(tile.value);
                    }
                }
            }
        }
        for leaf in &t.leaves {
            let o = leaf.origin.map(|v| v as i64);
            let values = source.values(leaf)?;
            let whole: Option<&[f32; 512]> = values.try_into().ok();
            if let (true, Some(values)) =
                ((0..3).all(|k| o[k] >= lo[k] && o[k] + 7 <= hi[k]), whole)
            {
                // The whole leaf inside the box (the common case): the grid's rows of 8 along x, each written
                // at once (the leaf is z fastest; reading it across is cheap, it is 2 KB), no per-voxel checks.
                let q = [0, 1, 2].map(|k| (o[k] - lo[k]) as usize);
                for z in 0..8 {
                    for y in 0..8 {
                        let start = q[0] + dims[0] * (q[1] + y + dims[1] * (q[2] + z));
                        let Some(row) = data.get_mut(start..start + 8) else {
                            continue;
                        };
                        for (x, d) in row.iter_mut().enumerate() {
                            *d = values[(x << 6) | (y << 3) | z];
                        }
                    }
                }
                continue;
            }
            for (i, &v) in values.iter().enumerate() {
                put(&mut data, leaf_voxel(leaf.origin, i), v);
            }
        }
        Ok(Loaded {
            dims,
            data,
            bounds: Some([p0, p1]),
        })
    })
    .into_iter()
    .collect()
}
