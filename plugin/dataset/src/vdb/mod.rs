//! OpenVDB (`.vdb`) reader for float grids of the standard 5-4-3 tree, full or half precision, with blosc,
//! zip or no compression, active-mask coding, tiles, and the grid transform. Written from the file format
//! (OpenVDB `io/Archive`, `io/Compression`, `tree/{RootNode,InternalNode,LeafNode}`), checked against files
//! written by OpenVDB 12 (tests/data/valid/vdb).
//!
//! The sparse tree is made dense over the bounding box of the active voxels and tiles of the requested grids
//! (their union, so channels share one lattice): every voxel holds what OpenVDB's `getValue` returns there
//! (stored values of leaves and tiles, active or not, else the background). OpenVDB's integer index is the
//! voxel centre, so index box [a, b] spans medium space T(a − ½) … T(b + ½), T the grid's affine map.
//!
//! Supported maps: uniform and non-uniform scale, with or without translation, translation, and axis-aligned
//! affine maps. Rotated or perspective maps are an error (give the rotation in the scene instead).

use super::compress::{blosc, half_to_f32, zlib};
use super::cursor::{Bytes, Cursor};
use super::sparse::{bit, densify, missing_grid, Leaf, LeafValues, Tile, Transform, Tree};
use super::Loaded;
use crate::Error;
use glam::DVec3;

const MAGIC: i64 = 0x5644_4220;
const COMPRESS_ZIP: u32 = 0x1;
const COMPRESS_ACTIVE_MASK: u32 = 0x2;
const COMPRESS_BLOSC: u32 = 0x4;

/// A grid's entry in the file's table of contents.
#[derive(Debug, Clone, PartialEq)]
pub struct GridInfo {
    /// Grid name (OpenVDB's unique-name suffix removed).
    pub name: String,
    /// Tree type, e.g. `Tree_float_5_4_3` (without `_HalfFloat`).
    pub tree_type: String,
    /// Stored as half floats.
    pub half: bool,
    grid_pos: u64,
    block_pos: u64,
    instance_parent: String,
}

impl GridInfo {
    /// Whether the grid has its own tree (not an instance of another grid).
    pub fn instance_parent_is_empty(&self) -> bool {
        self.instance_parent.is_empty()
    }
}

/// The file's header facts and grid table.
#[derive(Debug, Clone, PartialEq)]
pub struct Header {
    /// File format version (e.g. 224).
    pub file_version: u32,
    /// Library version (major, minor) that wrote it.
    pub library: (u32, u32),
    /// The grids in file order.
    pub grids: Vec<GridInfo>,
    /// The file metadata's `creator` string (what wrote the file), when it has one.
    pub creator: Option<String>,
}

fn string<'a>(c: &mut Cursor<'a>, what: &str) -> Result<String, Error> {
    let len = c.u32(&format!("the length of {what}"))?;
    if len as usize > c.remaining() || len > 1 << 20 {
        c.pos -= 4;
        return Err(c.err(
            format!("the length of {what} (at most the rest of the file)"),
            len,
        ));
    }
    Ok(String::from_utf8_lossy(c.bytes(len as usize, what)?).into_owned())
}

/// Skips a metadata table (OpenVDB `MetaMap`): every value carries its byte size, so unknown types (such as
/// Mantaflow's `__delayedload`) are skipped safely.
fn skip_metadata(c: &mut Cursor, whose: &str) -> Result<(), Error> {
    metadata_string(c, whose, "").map(|_| ())
}

/// Reads a metadata table as [`skip_metadata`] does, returning the string entry named `wanted`, if any.
fn metadata_string(c: &mut Cursor, whose: &str, wanted: &str) -> Result<Option<String>, Error> {
    let count = c.u32(&format!("the {whose} metadata count"))?;
    if count as usize > c.remaining() {
        c.pos -= 4;
        return Err(c.err(
            format!("a {whose} metadata count that fits the file"),
            count,
        ));
    }
    let mut found = None;
    for _ in 0..count {
        let name = string(c, "a metadata name")?;
        let ty = string(c, "a metadata type")?;
        let size = c.u32("a metadata size")?;
        if !wanted.is_empty() && name == wanted && ty == "string" && size <= 1 << 16 {
            found = Some(
                String::from_utf8_lossy(c.bytes(size as usize, "a metadata value")?).into_owned(),
            );
        } else {
            c.skip(size as usize, "a metadata value")?;
        }
    }
    Ok(found)
}

/// Reads the header and the grid table.
pub fn read_header(file: &str, bytes: &[u8]) -> Result<Header, Error> {
    read_header_from(file, Bytes::Slice(bytes))
}

/// [`read_header`] from bytes in memory or an open file (whose grids are skipped, not read).
pub fn read_header_from(file: &str, src: Bytes) -> Result<Header, Error> {
    let mut c = Cursor::over(file, src);
    let magic = c.i64("the OpenVDB magic number")?;
    if magic != MAGIC {
        return Err(Error::format(
            file,
            "byte 0",
            "the OpenVDB magic number 0x56444220 (' BDV')",
            format!("{magic:#x}"),
        ));
    }
    let file_version = c.u32("the file version")?;
    if !(222..=300).contains(&file_version) {
        return Err(Error::Unsupported {
            file: file.to_string(),
            what: format!("OpenVDB file version {file_version}"),
            hint: "versions 222 and later (OpenVDB 3 onward) are read; re-save the file with a current OpenVDB".into(),
        });
    }
    let library = (
        c.u32("the library major version")?,
        c.u32("the library minor version")?,
    );
    let has_offsets = c.u8("the grid-offsets flag")?;
    if has_offsets != 1 {
        return Err(Error::Unsupported {
            file: file.to_string(),
            what: "a file without grid offsets".into(),
            hint: "re-save it with OpenVDB's default settings".into(),
        });
    }
    c.skip(36, "the file UUID")?;
    let creator = metadata_string(&mut c, "file", "creator")?;
    let count = c.i32("the grid count")?;
    if count < 0 || count as usize > c.remaining() {
        c.pos -= 4;
        return Err(c.err("a grid count that fits the file", count));
    }
    let mut grids = Vec::with_capacity(count as usize);
    for _ in 0..count {
        let unique = string(&mut c, "a grid name")?;
        let name = unique.split('\u{1e}').next().unwrap_or("").to_string();
        let ty = string(&mut c, "a grid type")?;
        let (tree_type, half) = match ty.strip_suffix("_HalfFloat") {
            Some(t) => (t.to_string(), true),
            None => (ty, false),
        };
        let instance_parent = string(&mut c, "an instance parent name")?;
        let grid_pos = c.i64("the grid offset")?;
        let block_pos = c.i64("the data-block offset")?;
        let end_pos = c.i64("the grid end offset")?;
        // Each descriptor is followed by its grid; the next descriptor starts at this grid's end.
        let ordered = (c.pos as i64) <= grid_pos && grid_pos <= block_pos && block_pos <= end_pos;
        if !ordered || end_pos as u64 > c.len() as u64 {
            return Err(Error::format(
                file,
                format!("grid '{name}' descriptor"),
                format!("offsets ordered after the descriptor (byte {}) and within the file of {} bytes", c.pos, c.len()),
                format!("grid {grid_pos}, blocks {block_pos}, end {end_pos}"),
            ));
        }
        grids.push(GridInfo {
            name,
            tree_type,
            half,
            grid_pos: grid_pos as u64,
            block_pos: block_pos as u64,
            instance_parent,
        });
        c.seek(end_pos as u64, "the next grid descriptor")?;
    }
    Ok(Header {
        file_version,
        library,
        grids,
        creator,
    })
}

fn vec3d(c: &mut Cursor, what: &str) -> Result<DVec3, Error> {
    Ok(DVec3::new(c.f64(what)?, c.f64(what)?, c.f64(what)?))
}

fn read_transform(c: &mut Cursor, grid: &str) -> Result<Transform, Error> {
    let at = c.pos;
    let ty = string(c, "the transform's map type")?;
    let t = match ty.as_str() {
        "UniformScaleMap" | "ScaleMap" => {
            let scale = vec3d(c, "the map scale")?;
            c.skip(4 * 24, "the map's derived vectors")?;
            Transform {
                scale,
                translation: DVec3::ZERO,
            }
        }
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
            let translation = vec3d(c, "the map translation")?;
            let scale = vec3d(c, "the map scale")?;
            c.skip(4 * 24, "the map's derived vectors")?;
            Transform { scale, translation }
        }
        "TranslationMap" => Transform {
            scale: DVec3::ONE,
            translation: vec3d(c, "the map translation")?,
        },
        "AffineMap" => {
            let mut m = [0f64; 16];
            for v in m.iter_mut() {
                *v = c.f64("the affine matrix")?;
            }
            // Row-vector convention: p = ijk · M; translation in the last row.
            let off_diagonal = [m[1], m[2], m[4], m[6], m[8], m[9], m[3], m[7], m[11]];
            if off_diagonal.iter().any(|&v| v != 0.0) || m[15] != 1.0 {
                return Err(Error::Unsupported {
                    file: c.file.to_string(),
                    what: format!("grid '{grid}': a rotated, sheared or projective AffineMap"),
                    hint:
                        "only axis-aligned maps are read; put the rotation in the scene's transform"
                            .into(),
                });
            }
            Transform {
                scale: DVec3::new(m[0], m[5], m[10]),
                translation: DVec3::new(m[12], m[13], m[14]),
            }
        }
        other => {
            return Err(Error::Unsupported {
                file: c.file.to_string(),
                what: format!("grid '{grid}': map type '{other}' at byte {at}"),
                hint: "scale, scale-translate, translation and axis-aligned affine maps are read"
                    .into(),
            })
        }
    };
    if !(t.scale.is_finite() && t.translation.is_finite() && t.scale.cmpgt(DVec3::ZERO).all()) {
        return Err(Error::format(
            c.file,
            format!("byte {at} (grid '{grid}' transform)"),
            "a finite, positive voxel size and a finite translation",
            format!("scale {}, translation {}", t.scale, t.translation),
        ));
    }
    Ok(t)
}

/// Reading context of one grid.
struct Ctx {
    half: bool,
    compression: u32,
    background: f32,
    /// Values per voxel (1 for float grids, 3 for vector grids) and the one read (a vector grid's component).
    comps: usize,
    pick: usize,
}

/// One value of the grid's type (`comps` floats), its picked component kept.
fn value(c: &mut Cursor, ctx: &Ctx, what: &str) -> Result<f32, Error> {
    let mut v = 0.0;
    for k in 0..ctx.comps {
        let x = c.f32(what)?;
        if k == ctx.pick {
            v = x;
        }
    }
    Ok(v)
}

/// A grid's leaf buffers (after its topology): every leaf in tree order, its value mask again, then its
/// values, decoded one leaf at a time into `scratch` as the dense grid is filled.
struct Buffers<'a> {
    c: Cursor<'a>,
    ctx: Ctx,
    scratch: Vec<f32>,
}

impl LeafValues for Buffers<'_> {
    fn values<'s>(&'s mut self, _leaf: &'s Leaf) -> Result<&'s [f32], Error> {
        let m = mask(&mut self.c, 8, "a leaf's value mask")?;
        read_values(&mut self.c, &self.ctx, 512, &m, &mut self.scratch)?;
        Ok(&self.scratch)
    }
}

fn mask(c: &mut Cursor, words: usize, what: &str) -> Result<Vec<u64>, Error> {
    (0..words).map(|_| c.u64(what)).collect()
}

/// OpenVDB `readCompressedValues`: `count` values of a node with value mask `value_mask`.
fn read_values(
    c: &mut Cursor,
    ctx: &Ctx,
    count: usize,
    value_mask: &[u64],
    out: &mut Vec<f32>,
) -> Result<(), Error> {
    let at = c.pos;
    let meta = c.u8("a node's value-coding byte")?;
    if meta > 6 {
        c.pos = at;
        return Err(c.err("a value-coding byte 0..6", meta));
    }
    let bg = ctx.background;
    let (mut inactive0, mut inactive1) = (if meta == 0 { bg } else { -bg }, bg);
    if meta == 2 || meta == 4 || meta == 5 {
        inactive0 = value(c, ctx, "an inactive value")?;
        if meta == 5 {
            inactive1 = value(c, ctx, "a second inactive value")?;
        }
    }
    let selection = if (3..=5).contains(&meta) {
        Some(mask(c, value_mask.len(), "a selection mask")?)
    } else {
        None
    };
    let masked = ctx.compression & COMPRESS_ACTIVE_MASK != 0 && meta != 6;
    let stored = if masked {
        value_mask.iter().map(|w| w.count_ones() as usize).sum()
    } else {
        count
    };
    let elem = if ctx.half { 2 } else { 4 };
    let nbytes = stored * elem * ctx.comps;
    // Half values: OpenVDB's HalfReader writes nothing at all for zero values (full floats still carry
    // an empty block).
    let raw = if ctx.half && stored == 0 {
        Vec::new()
    } else {
        block(c, ctx.compression, nbytes)?
    };
    // All stored values decoded at once (a loop over exact chunks, which compiles to plain loads), into `out`
    // (reused from leaf to leaf: no allocation per leaf).
    // (A vector grid's values are `comps` components each: the picked one is kept.)
    out.clear();
    let (k, n) = (ctx.pick, ctx.comps);
    if ctx.half {
        out.extend(
            raw.chunks_exact(2 * n)
                .map(|b| half_to_f32(u16::from_le_bytes([b[2 * k], b[2 * k + 1]]))),
        );
    } else {
        out.extend(
            raw.chunks_exact(4 * n)
                .map(|b| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])),
        );
    }
    if out.len() < stored.min(count) {
        return Err(c.err(
            format!("{stored} stored values"),
            format!("{} values", out.len()),
        ));
    }
    if !masked || stored == count {
        out.truncate(count);
        return Ok(());
    }
    // The stored (active) values spread to their places, inactive ones filled: from the back, in place.
    out.resize(count, 0.0);
    let mut k = stored;
    for i in (0..count).rev() {
        out[i] = if bit(value_mask, i) {
            k -= 1;
            out[k]
        } else if selection.as_ref().is_some_and(|s| bit(s, i)) {
            inactive1
        } else {
            inactive0
        };
    }
    Ok(())
}

/// One data block: raw, or an int64 size + blosc/zip data (a negative size means stored raw).
fn block(c: &mut Cursor, compression: u32, nbytes: usize) -> Result<Vec<u8>, Error> {
    if compression & (COMPRESS_BLOSC | COMPRESS_ZIP) == 0 {
        return Ok(c.bytes(nbytes, "uncompressed values")?.to_vec());
    }
    let at = c.pos;
    let size = c.i64("a compressed block size")?;
    if size <= 0 {
        let n = size.unsigned_abs() as usize;
        if n != nbytes {
            c.pos = at;
            return Err(c.err(
                format!("a stored block of {nbytes} bytes"),
                format!("{n} bytes"),
            ));
        }
        return Ok(c.bytes(n, "stored values")?.to_vec());
    }
    if size as usize > c.remaining() {
        c.pos = at;
        return Err(c.err(
            format!(
                "a compressed block that fits the file ({} bytes left)",
                c.remaining() - 8
            ),
            format!("{size} bytes (truncated)"),
        ));
    }
    let data = c.bytes(size as usize, "compressed values")?;
    let result = if compression & COMPRESS_BLOSC != 0 {
        blosc(data, nbytes)
    } else {
        zlib(data, nbytes)
    };
    result.map_err(|e| e.at(c.file, format!("byte {at}")))
}

fn read_internal(
    c: &mut Cursor,
    ctx: &Ctx,
    origin: [i32; 3],
    log2: u32,
    child_total: u32,
    tiles: &mut Vec<Tile>,
    leaves: &mut Vec<Leaf>,
) -> Result<(), Error> {
    let n = 1usize << (3 * log2);
    let words = n / 64;
    let child_mask = mask(c, words, "a child mask")?;
    let value_mask = mask(c, words, "a value mask")?;
    let mut values = Vec::new();
    read_values(c, ctx, n, &value_mask, &mut values)?;
    let dim = 1i32 << log2;
    let coord = |i: usize| {
        let i = i as i32;
        let (x, y, z) = (i >> (2 * log2), (i >> log2) & (dim - 1), i & (dim - 1));
        [
            origin[0].wrapping_add(x << child_total),
            origin[1].wrapping_add(y << child_total),
            origin[2].wrapping_add(z << child_total),
        ]
    };
    for (i, &v) in values.iter().enumerate() {
        let tile = Tile {
            origin: coord(i),
            size: 1 << child_total,
            value: v,
            active: bit(&value_mask, i),
        };
        if !bit(&child_mask, i) && tile.counts(ctx.background) {
            tiles.push(tile);
        }
    }
    for i in 0..n {
        if bit(&child_mask, i) {
            if child_total == 3 {
                let m = mask(c, 8, "a leaf's value mask")?;
                leaves.push(Leaf {
                    origin: coord(i),
                    values: Vec::new(),
                    mask: m.try_into().unwrap_or([0; 8]),
                });
            } else {
                read_internal(c, ctx, coord(i), 4, 3, tiles, leaves)?;
            }
        }
    }
    Ok(())
}

/// A grid's topology (tiles, leaf origins and masks) and where its leaf values are.
fn read_tree<'a>(
    file: &'a str,
    src: &Bytes<'a>,
    info: &GridInfo,
    pick: Option<usize>,
) -> Result<(Tree, Buffers<'a>), Error> {
    let name = &info.name;
    let want = if pick.is_some() {
        "Tree_vec3s_5_4_3"
    } else {
        "Tree_float_5_4_3"
    };
    if info.tree_type != want {
        return Err(Error::Unsupported {
            file: file.to_string(),
            what: format!("grid '{name}' of type {}", info.tree_type),
            hint: "float grids (Tree_float_5_4_3), and a vector grid's components (Tree_vec3s_5_4_3, asked for as \
                   name.x, name.y, name.z), full or half precision, are read"
                .into(),
        });
    }
    if !info.instance_parent.is_empty() {
        return Err(Error::Unsupported {
            file: file.to_string(),
            what: format!("grid '{name}' is an instance of '{}'", info.instance_parent),
            hint: "load the parent grid".into(),
        });
    }
    let mut c = Cursor::over(file, src.clone());
    c.seek(info.grid_pos, &format!("grid '{name}'"))?;
    let compression = c.u32("the grid's compression flags")?;
    if compression & !0x7 != 0 {
        c.pos -= 4;
        return Err(c.err(
            "compression flags made of ZIP (1), ACTIVE_MASK (2), BLOSC (4)",
            format!("{compression:#x}"),
        ));
    }
    skip_metadata(&mut c, &format!("grid '{name}'"))?;
    let transform = read_transform(&mut c, name)?;
    let buffers = c.i32("the buffer count")?;
    if buffers != 1 {
        c.pos -= 4;
        return Err(c.err("a buffer count of 1", buffers));
    }
    let mut ctx = Ctx {
        half: info.half,
        compression,
        background: 0.0,
        comps: if pick.is_some() { 3 } else { 1 },
        pick: pick.unwrap_or(0),
    };
    let background = value(&mut c, &ctx, "the background value")?;
    ctx.background = background;
    let (ntiles, nchildren) = (
        c.u32("the root tile count")?,
        c.u32("the root child count")?,
    );
    if (ntiles as usize + nchildren as usize) * 12 > c.remaining() {
        return Err(c.err(
            "root tile and child counts that fit the file",
            format!("{ntiles} tiles, {nchildren} children"),
        ));
    }
    let mut tiles = Vec::new();
    for _ in 0..ntiles {
        let origin = [
            c.i32("a tile origin")?,
            c.i32("a tile origin")?,
            c.i32("a tile origin")?,
        ];
        let value = value(&mut c, &ctx, "a tile value")?;
        let active = c.u8("a tile's active flag")? != 0;
        let tile = Tile {
            origin,
            size: 4096,
            value,
            active,
        };
        if tile.counts(background) {
            tiles.push(tile);
        }
    }
    let mut leaves = Vec::new();
    for _ in 0..nchildren {
        let origin = [
            c.i32("a node origin")?,
            c.i32("a node origin")?,
            c.i32("a node origin")?,
        ];
        read_internal(&mut c, &ctx, origin, 5, 7, &mut tiles, &mut leaves)?;
    }
    // (Grown by doubling, the lists would hold up to twice their leaves' headers while the grid is made dense:
    // 1.7 MB for a 256-voxel fire's 9 023 leaves, where they need 0.9.)
    leaves.shrink_to_fit();
    tiles.shrink_to_fit();
    // The buffers: read leaf by leaf as the grid is made dense.
    c.seek(info.block_pos, &format!("grid '{name}' data blocks"))?;
    Ok((
        Tree {
            transform,
            background,
            tiles,
            leaves,
        },
        Buffers {
            c,
            ctx,
            scratch: Vec::with_capacity(512),
        },
    ))
}

/// The grid `name` names: a grid of that name, else — for `base.x`, `base.y`, `base.z` (Houdini's names for a
/// vector's components) — component 0, 1 or 2 of the vector grid `base`.
fn find_grid<'h>(header: &'h Header, name: &str) -> Option<(&'h GridInfo, Option<usize>)> {
    if let Some(g) = header.grids.iter().find(|g| g.name == name) {
        return Some((g, None));
    }
    let (base, axis) = name.rsplit_once('.')?;
    let pick = ["x", "y", "z"].iter().position(|&a| a == axis)?;
    // `auto`: the velocity under the names the tools write — Houdini's `vel`, `v`, Blender's and EmberGen's
    // `velocity` — as a vector grid or split into floats.
    if base == AUTO_VELOCITY && !header.grids.iter().any(|g| g.name == base) {
        return VELOCITY_NAMES
            .iter()
            .find_map(|b| find_grid(header, &format!("{b}.{axis}")));
    }
    let g = header
        .grids
        .iter()
        .find(|g| g.name == base && g.tree_type.starts_with("Tree_vec3s"))?;
    Some((g, Some(pick)))
}

/// The `velocitygrid` that finds the velocity under any of [`VELOCITY_NAMES`].
pub const AUTO_VELOCITY: &str = "auto";
/// The velocity's names in the tools' files, in the order `auto` tries them.
pub const VELOCITY_NAMES: [&str; 3] = ["vel", "v", "velocity"];

/// Reads the float grids `names` into bricks over the union of their active boxes. From a file, only their
/// descriptors and trees are read (the grids it does not name are skipped), their leaf values streamed as they
/// are placed.
pub fn read(file: &str, src: Bytes, names: &[&str], max_bytes: u64) -> Result<Vec<Loaded>, Error> {
    let header = read_header_from(file, src.clone())?;
    let mut infos = Vec::new();
    for &name in names {
        let Some((info, pick)) = find_grid(&header, name) else {
            // (A velocity's component may come from a vector grid: say so.)
            let wanted = match name.rsplit_once('.') {
                Some((AUTO_VELOCITY, "x" | "y" | "z")) => format!(
                    "{}' (a vector grid, or split into .x, .y, .z",
                    VELOCITY_NAMES.join("' or '")
                ),
                Some((base, "x" | "y" | "z")) => format!("{name}' or a vector grid '{base}"),
                _ => name.to_string(),
            };
            return Err(missing_grid(
                file,
                &wanted,
                header.grids.iter().map(|g| g.name.as_str()),
            ));
        };
        infos.push((name, info, pick));
    }
    // The grids' trees are independent byte ranges: decoded in parallel.
    let trees = super::par_map(infos, |(name, info, pick)| {
        read_tree(file, &src, info, pick).map(|(t, b)| (name, t, b))
    })
    .into_iter()
    .collect::<Result<Vec<_>, Error>>()?;
    densify(file, trees, max_bytes)
}

mod write;
pub use write::{
    write, write_sparse, write_sparse_vectors, write_sparse_vectors_by, write_tiled,
    write_with_vectors, VdbLeaf, VdbTile, VdbVector,
};

#[cfg(test)]
mod write_tests;
