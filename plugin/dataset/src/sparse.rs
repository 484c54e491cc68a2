//! Sparse VDB trees (OpenVDB and NanoVDB alike) made dense over the active region, so channels share one
//! lattice and the fire samples a flat array.

use super::Loaded;
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
pub struct Leaf {
    pub origin: [i32; 3],
    pub values: Vec<f32>,
    pub mask: [u64; 8],
}

/// A constant cube of `size`³ voxels at `origin`.
pub struct Tile {
    pub origin: [i32; 3],
    pub size: i32,
    pub value: f32,
    pub active: bool,
}

/// One grid: its map, background, tiles and leaves.
pub struct Tree {
    pub transform: Transform,
    pub background: f32,
    pub tiles: Vec<Tile>,
    pub leaves: Vec<Leaf>,
}

impl Tree {
    /// Keeps `tile` unless it is inactive and holds the background: such a tile changes nothing, and every
    /// empty slot of every node is one (tens of thousands in a 256³ fire, more than the reader's other memory).
    pub fn add_tile(&mut self, tile: Tile) {
        if tile.counts(self.background) {
            self.tiles.push(tile);
        }
    }
}

impl Tile {
    /// Whether the tile changes a tree of `background`: it is active or holds another value.
    pub fn counts(&self, background: f32) -> bool {
        self.active || self.value.to_bits() != background.to_bits()
    }
}

/// Where a tree's leaf values come from while the dense grid is filled: called once per leaf, in order.
pub trait LeafValues: Send {
    /// Leaf `leaf`'s 512 values (z fastest).
    fn values<'a>(&'a mut self, leaf: &'a Leaf) -> Result<&'a [f32], Error>;
}

/// Leaves decoded with the tree (their `values`).
pub struct InLeaves;

impl LeafValues for InLeaves {
    fn values<'a>(&'a mut self, leaf: &'a Leaf) -> Result<&'a [f32], Error> {
        Ok(&leaf.values)
    }
}

pub fn bit(m: &[u64], i: usize) -> bool {
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
pub fn missing_grid<'a>(file: &str, name: &str, have: impl Iterator<Item = &'a str>) -> Error {
    let have: Vec<String> = have.map(|g| format!("'{g}'")).collect();
    Error::format(
        file,
        "grid table",
        format!("a grid named '{name}'"),
        format!("grids {}", have.join(", ")),
    )
}

use crate::grid::BRICK;

/// The error of a part of `file`'s grids (`what`, `bytes` of it) past the memory budget `max_bytes`.
fn over_budget(file: &str, max_bytes: u64) -> impl Fn(String, u64) -> Error + '_ {
    move |what, bytes| Error::TooLarge {
        file: file.to_string(),
        what,
        bytes,
        cap: max_bytes,
    }
}

/// The union box of a dataset's trees (index space, inclusive) and the offset of its first sample in its 8³ brick:
/// bricks aligned as the file's leaves are (multiples of 8 in its index space).
struct BrickBox {
    lo: [i64; 3],
    hi: [i64; 3],
    off: [usize; 3],
}

impl BrickBox {
    /// The bricks of a voxel range [a, b] (index space), clipped to the box: per axis, the first and last.
    fn bricks_of(&self, a: [i64; 3], b: [i64; 3]) -> Option<([usize; 3], [usize; 3])> {
        let (lo, hi, off) = (self.lo, self.hi, self.off);
        let a = [0, 1, 2].map(|k| a[k].max(lo[k]));
        let b = [0, 1, 2].map(|k| b[k].min(hi[k]));
        if (0..3).any(|k| a[k] > b[k]) {
            return None;
        }
        Some((
            [0, 1, 2].map(|k| ((a[k] - lo[k]) as usize + off[k]) / BRICK),
            [0, 1, 2].map(|k| ((b[k] - lo[k]) as usize + off[k]) / BRICK),
        ))
    }

    /// The voxels [a, b] of brick `c` inside the box.
    fn voxels(&self, c: [usize; 3]) -> ([i64; 3], [i64; 3]) {
        let (lo, hi, off) = (self.lo, self.hi, self.off);
        let a = [0, 1, 2].map(|k| (lo[k] + (BRICK * c[k]) as i64 - off[k] as i64).max(lo[k]));
        let b = [0, 1, 2]
            .map(|k| (lo[k] + (BRICK * c[k] + BRICK - 1) as i64 - off[k] as i64).min(hi[k]));
        (a, b)
    }
}

/// The union of `trees`' active boxes (index space, inclusive), refused when their transforms differ (channels
/// share one lattice) or none holds an active voxel.
fn shared_box<S>(file: &str, trees: &[(&str, Tree, S)]) -> Result<([i64; 3], [i64; 3]), Error> {
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
    for (_, t, _) in trees {
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
    Ok((lo, hi))
}

/// Which bricks vary and which hold constants, and the constants' classes: a brick a leaf touches varies; one
/// under tiles alone is constant in every grid (its values a class, shared by every brick of the same values).
#[allow(clippy::type_complexity)]
fn constant_bricks<S>(
    trees: &[(&str, Tree, S)],
    bx: &BrickBox,
) -> (
    std::collections::HashSet<[usize; 3]>,
    Vec<Vec<f32>>,
    std::collections::HashMap<[usize; 3], u32>,
) {
    // Bricks a leaf touches hold varying values. Bricks under tiles alone are constant in every grid — each
    // grid's tile value there (the smallest tile covering it: tiles are written largest first), or its
    // background — and bricks with the same values share one block of storage (`Topology::share`). A tile
    // that covers a brick only in part (not OpenVDB's alignment) makes it vary.
    let mut varied: std::collections::HashSet<[usize; 3]> = Default::default();
    for (_, t, _) in trees {
        for leaf in &t.leaves {
            let o = leaf.origin.map(|v| v as i64);
            if let Some((ba, bb)) = bx.bricks_of(o, o.map(|v| v + 7)) {
                for z in ba[2]..=bb[2] {
                    for y in ba[1]..=bb[1] {
                        for x in ba[0]..=bb[0] {
                            varied.insert([x, y, z]);
                        }
                    }
                }
            }
        }
    }
    let backgrounds: Vec<f32> = trees.iter().map(|t| t.1.background).collect();
    let mut constant: std::collections::HashMap<[usize; 3], Vec<f32>> = Default::default();
    for (n, (_, t, _)) in trees.iter().enumerate() {
        for tile in written_tiles(t) {
            let o = tile.origin.map(|v| v as i64);
            let e = o.map(|v| v + tile.size as i64 - 1);
            let Some((ba, bb)) = bx.bricks_of(o, e) else {
                continue;
            };
            for z in ba[2]..=bb[2] {
                for y in ba[1]..=bb[1] {
                    for x in ba[0]..=bb[0] {
                        let c = [x, y, z];
                        if varied.contains(&c) {
                            continue;
                        }
                        let (va, vb) = bx.voxels(c);
                        if (0..3).all(|k| o[k] <= va[k] && vb[k] <= e[k]) {
                            constant.entry(c).or_insert_with(|| backgrounds.clone())[n] =
                                tile.value;
                        } else {
                            constant.remove(&c);
                            varied.insert(c);
                        }
                    }
                }
            }
        }
    }
    // One class per distinct tuple of values (by their bits).
    let mut classes: std::collections::HashMap<Vec<u32>, u32> = Default::default();
    let mut class_values: Vec<Vec<f32>> = Vec::new();
    let class_of: std::collections::HashMap<[usize; 3], u32> = constant
        .iter()
        .map(|(c, v)| {
            let key: Vec<u32> = v.iter().map(|x| x.to_bits()).collect();
            let id = *classes.entry(key).or_insert_with(|| {
                class_values.push(v.clone());
                class_values.len() as u32 - 1
            });
            (*c, id)
        })
        .collect();
    (varied, class_values, class_of)
}

/// Stores `trees` as 8³ bricks over the union of their active boxes, one topology for all: a brick is stored
/// where some tree has a leaf or a tile other than its background; every voxel holds the tree's value there (leaf
/// values, active or not, over tile values, over the background), as a dense grid over the box would — but
/// memory follows the leaves, not the box (a fire and a far-away second copy cost two fires and a brick table).
pub fn densify<S: LeafValues>(
    file: &str,
    trees: Vec<(&str, Tree, S)>,
    max_bytes: u64,
) -> Result<Vec<Loaded>, Error> {
    use crate::grid::{Grid, Topology};
    let (lo, hi) = shared_box(file, &trees)?;
    let first = &trees[0].1;
    let extent = [0, 1, 2].map(|k| (hi[k] - lo[k] + 1) as u64);
    let dims = extent.map(|e| usize::try_from(e).unwrap_or(usize::MAX));
    let tr = first.transform;
    let to_medium = |v: [f64; 3]| DVec3::from_array(v) * tr.scale + tr.translation;
    let p0 = to_medium([0, 1, 2].map(|k| lo[k] as f64 - 0.5));
    let p1 = to_medium([0, 1, 2].map(|k| hi[k] as f64 + 0.5));
    let too_large = over_budget(file, max_bytes);
    let table = table_within(file, dims, max_bytes)?;
    // The bricks on the file's leaves' alignment (sample 0 of the box at lo mod 8 in its brick).
    let bx = BrickBox {
        lo,
        hi,
        off: lo.map(|v| v.rem_euclid(BRICK as i64) as usize),
    };
    let (off, bricks_of, brick_voxels) = (bx.off, |a, b| bx.bricks_of(a, b), |c| bx.voxels(c));
    // Every tile's and leaf's range, as the trees hold them.
    let ranges = || {
        trees.iter().flat_map(|(_, t, _)| {
            let tiles = written_tiles(t).into_iter().map(|tile| {
                let o = tile.origin.map(|v| v as i64);
                (o, o.map(|v| v + tile.size as i64 - 1))
            });
            let leaves = t.leaves.iter().map(|leaf| {
                let o = leaf.origin.map(|v| v as i64);
                (o, o.map(|v| v + 7))
            });
            tiles.chain(leaves)
        })
    };
    // The list of covered bricks, counted before it is made: a brick a leaf touches is stored (2 KB per grid,
    // checked below), a brick under tiles alone costs its bookkeeping (a tile may cover a whole box: a count
    // beyond the budget is refused here, before any brick is visited).
    let listed: u64 = ranges()
        .filter_map(|(a, b)| bricks_of(a, b))
        .map(|(ba, bb)| (0..3).map(|k| (bb[k] - ba[k] + 1) as u64).product::<u64>())
        .fold(0, u64::saturating_add);
    let per_listed = 128 + 4 * trees.len() as u64;
    if listed.saturating_mul(per_listed) > max_bytes {
        return Err(too_large(
            format!(
                "the table of {listed} bricks of 8³ (a {}×{}×{} box)",
                dims[0], dims[1], dims[2]
            ),
            listed.saturating_mul(per_listed),
        ));
    }
    let (varied, class_values, class_of) = constant_bricks(&trees, &bx);
    let mut list: Vec<[usize; 3]> = crate::alloc::with_capacity(listed as usize)
        .ok_or_else(|| too_large("the brick list".to_string(), listed.saturating_mul(24)))?;
    for (ba, bb) in ranges().filter_map(|(a, b)| bricks_of(a, b)) {
        for z in ba[2]..=bb[2] {
            for y in ba[1]..=bb[1] {
                for x in ba[0]..=bb[0] {
                    list.push([x, y, z]);
                }
            }
        }
    }
    // (Time and memory follow the bricks listed, not the box.)
    let topo = Topology::from_bricks(dims, off, list)
        .and_then(|t| t.share(|b| class_of.get(&b).copied()))
        .ok_or_else(|| too_large("the brick table".to_string(), table))?;
    // A representative brick of each class, to write its shared block.
    let mut class_brick = vec![None; class_values.len()];
    for (c, &id) in &class_of {
        class_brick[id as usize].get_or_insert(*c);
    }
    let per = (topo.values_len() as u64).saturating_mul(4);
    let all = per
        .saturating_mul(trees.len() as u64)
        .saturating_add(topo.bytes() as u64);
    if all > max_bytes {
        return Err(too_large(
            format!(
                "{} grids of {} blocks of 8³ f32 and their brick table (a {}×{}×{} box)",
                trees.len(),
                topo.blocks_stored(),
                dims[0],
                dims[1],
                dims[2]
            ),
            all,
        ));
    }
    let topo = std::sync::Arc::new(topo);
    // One grid per tree, filled in parallel (each leaf's values decoded as it is placed).
    let trees: Vec<_> = trees.into_iter().enumerate().collect();
    super::par_map(trees, |(n, (_, t, mut source))| {
        let mut g = Grid::filled(topo.clone(), t.background).ok_or_else(|| {
            too_large(
                format!(
                    "{} blocks of 8³ f32 (the allocator refused them)",
                    topo.blocks_stored()
                ),
                per,
            )
        })?;
        let put = |g: &mut Grid, p: [i64; 3], v: f32| {
            let q = [0, 1, 2].map(|k| p[k] - lo[k]);
            if (0..3).all(|k| q[k] >= 0 && (q[k] as usize) < dims[k]) {
                g.set(q[0] as usize, q[1] as usize, q[2] as usize, v);
            }
        };
        // Constant bricks: their class's block, once.
        for (values, c) in class_values.iter().zip(&class_brick) {
            if let Some(block) = c.and_then(|c| g.brick_values_mut(c)) {
                block.fill(values[n]);
            }
        }
        // Tiles over the bricks that vary, voxel by voxel (the rest are the blocks above).
        for tile in written_tiles(&t) {
            let o = tile.origin.map(|v| v as i64);
            let e = o.map(|v| v + tile.size as i64 - 1);
            let Some((ba, bb)) = bricks_of(o, e) else {
                continue;
            };
            for bz in ba[2]..=bb[2] {
                for by in ba[1]..=bb[1] {
                    for bx in ba[0]..=bb[0] {
                        if !varied.contains(&[bx, by, bz]) {
                            continue;
                        }
                        let (va, vb) = brick_voxels([bx, by, bz]);
                        let a = [0, 1, 2].map(|k| o[k].max(va[k]));
                        let b = [0, 1, 2].map(|k| e[k].min(vb[k]));
                        for z in a[2]..=b[2] {
                            for y in a[1]..=b[1] {
                                for x in a[0]..=b[0] {
                                    put(&mut g, [x, y, z], tile.value);
                                }
                            }
                        }
                    }
                }
            }
        }
        for leaf in &t.leaves {
            let values = source.values(leaf)?;
            let o = leaf.origin.map(|v| v as i64);
            let whole: Option<&[f32; 512]> = values.try_into().ok();
            // A whole leaf inside the box is one brick (the bricks are aligned as the leaves): its values
            // transposed into place (the leaf is z fastest, the brick x fastest), no per-voxel lookups.
            if let (true, Some(values)) =
                ((0..3).all(|k| o[k] >= lo[k] && o[k] + 7 <= hi[k]), whole)
            {
                let q = [0, 1, 2].map(|k| (o[k] - lo[k]) as usize);
                if let Some(brick) = g.brick_mut(q) {
                    for (i, &v) in values.iter().enumerate() {
                        brick[(i >> 6) + 8 * ((i >> 3) & 7) + 64 * (i & 7)] = v;
                    }
                    continue;
                }
            }
            for (i, &v) in values.iter().enumerate() {
                put(&mut g, leaf_voxel(leaf.origin, i), v);
            }
        }
        Ok(Loaded {
            dims,
            data: Vec::new(),
            bricks: Some(g),
            bounds: Some([p0, p1]),
        })
    })
    .into_iter()
    .collect()
}

/// The tiles a tree writes over its background, largest first: every tile of another value, and a background
/// tile only where it lies inside a larger tile of another value (which it then overwrites) — elsewhere it
/// changes nothing, and storing it would store the empty space between leaves (OpenVDB's internal nodes hold
/// thousands of such inactive tiles).
fn written_tiles(t: &Tree) -> Vec<&Tile> {
    let mut tiles: Vec<&Tile> = t.tiles.iter().collect();
    tiles.sort_by_key(|t| -t.size);
    let is_bg = |tile: &Tile| tile.value.to_bits() == t.background.to_bits();
    let inside = |a: &Tile, b: &Tile| {
        b.size > a.size
            && (0..3).all(|k| {
                let (a0, b0) = (a.origin[k] as i64, b.origin[k] as i64);
                a0 >= b0 && a0 + a.size as i64 <= b0 + b.size as i64
            })
    };
    // The valued tiles by the cells of their own size they overlap (one, or up to eight when a file's origin is
    // not aligned): a background tile inside one overlaps a cell of that size holding it. Every node's empty
    // slot is a tile, so a file of many nodes holds millions; matching each against every valued tile was
    // quadratic (an 11 MB mutant ran for minutes).
    let cell = |o: [i32; 3], size: i32| o.map(|v| (v as i64).div_euclid(size.max(1) as i64));
    let mut cells: std::collections::HashMap<(i32, [i64; 3]), Vec<&Tile>> = Default::default();
    for &v in tiles.iter().filter(|tile| !is_bg(tile)) {
        let (lo, hi) = (
            cell(v.origin, v.size),
            cell(v.origin.map(|c| c.saturating_add(v.size - 1)), v.size),
        );
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    cells.entry((v.size, [x, y, z])).or_default().push(v);
                }
            }
        }
    }
    let sizes: std::collections::BTreeSet<i32> = cells.keys().map(|k| k.0).collect();
    tiles
        .into_iter()
        .filter(|tile| {
            !is_bg(tile)
                || sizes.iter().filter(|&&s| s > tile.size).any(|&s| {
                    cells
                        .get(&(s, cell(tile.origin, s)))
                        .is_some_and(|vs| vs.iter().any(|v| inside(tile, v)))
                })
        })
        .collect()
}

/// The bytes of a `dims` lattice's brick table, or the error naming them when they exceed `max_bytes`.
fn table_within(file: &str, dims: [usize; 3], max_bytes: u64) -> Result<u64, Error> {
    let table = crate::grid::Topology::table_bytes(dims).unwrap_or(u64::MAX);
    if table > max_bytes {
        return Err(Error::TooLarge {
            file: file.to_string(),
            what: format!(
                "the brick table of a {}×{}×{} grid",
                dims[0], dims[1], dims[2]
            ),
            bytes: table,
            cap: max_bytes,
        });
    }
    Ok(table)
}

/// A replay of a file's voxel writes: calls its argument with (voxel, value) for each, in file order.
pub type VoxelWrites<'a> = dyn Fn(&mut dyn FnMut([usize; 3], f32)) -> Result<(), Error> + 'a;

/// A grid of `dims` bricked as a file is read, never dense: `visit` replays the file's voxel writes (`put(voxel,
/// value)`, in file order, a later write winning) and is run twice — once to list the bricks a value other than
/// `background` touches, once to fill them. Voxels never written hold `background` (every empty brick reads
/// it). Memory: the stored bricks and their table, checked against `max_bytes` before anything is allocated.
pub fn brick_as_read(
    file: &str,
    dims: [usize; 3],
    background: f32,
    max_bytes: u64,
    visit: &VoxelWrites,
) -> Result<Loaded, Error> {
    use crate::grid::{Grid, Topology};
    let too_large = over_budget(file, max_bytes);
    let table = table_within(file, dims, max_bytes)?;
    // The bricks a voxel other than the background is written to (every empty brick reads the background):
    // a 1000³ grid of background 1 and no voxels is its background, not 4 GB of ones.
    let topo = {
        let mut list: Vec<[usize; 3]> = Vec::new();
        let mut last = [usize::MAX; 3];
        let mut refused = false;
        visit(&mut |v, x| {
            let b = v.map(|c| c / BRICK);
            if x != background && b != last && !refused {
                last = b;
                if list.len() == list.capacity() && list.try_reserve(list.len().max(64)).is_err() {
                    refused = true;
                    return;
                }
                list.push(b);
            }
        })?;
        if refused {
            return Err(too_large("the list of bricks".to_string(), u64::MAX));
        }
        Topology::from_bricks(dims, [0; 3], list)
    }
    .ok_or_else(|| too_large("the brick table".to_string(), table))?;
    let bytes = (topo.values_len() as u64)
        .saturating_mul(4)
        .saturating_add(topo.bytes() as u64);
    if bytes > max_bytes {
        return Err(too_large(
            format!(
                "{} bricks of 8³ f32 (a {}×{}×{} grid) and their table",
                topo.active_bricks(),
                dims[0],
                dims[1],
                dims[2]
            ),
            bytes,
        ));
    }
    let mut g = Grid::filled(std::sync::Arc::new(topo), background).ok_or_else(|| {
        too_large(
            "the grid's bricks (the allocator refused them)".to_string(),
            bytes,
        )
    })?;
    visit(&mut |[i, j, k], x| {
        g.set(i, j, k, x);
    })?;
    Ok(Loaded {
        dims,
        data: Vec::new(),
        bricks: Some(g),
        bounds: None,
    })
}
