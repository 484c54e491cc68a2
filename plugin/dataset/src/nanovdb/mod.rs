//! NanoVDB (`.nvdb`) reader for float grids, uncompressed or ZIP (zlib), as pbrt-v4's `nanovdb` medium reads
//! them. Written from NanoVDB 32.x's file and memory layout (`NanoVDB.h`, `io/IO.h`) and checked against
//! files written by NanoVDB's own tools (tests/data/valid/nvdb):
//!
//! - file: segments of { header "NanoVDB0", version u32, grid count u16, codec u16 }, then per grid a
//!   176-byte metadata record and its name, then the grids' buffers (for ZIP: u64 size + zlib stream);
//! - grid buffer: GridData (672 bytes: name at 40, map at 296 with the f64 matrix at 384 and translation at
//!   528, class and type at 632/636), TreeData (node offsets, counts), root (64-byte header, 32-byte tiles),
//!   upper 32³ nodes, lower 16³ nodes and 8³ leaves, children addressed by byte offsets from their parent.
//!
//! Every offset is checked to land on a node of the right level inside the buffer before it is followed. An
//! uncompressed grid is not held whole: the nodes before its leaves are read, then its leaves' masks, and their
//! values go from the file to the grid's bricks as it is filled (a 256-voxel fire's two grids, 38 MB of file,
//! peaked at 102 MB read whole); a ZIP grid is inflated twice as it is read, its values going from the stream to
//! the bricks ([`zip`]).

use super::compress::zlib;
#[cfg(feature = "zip")]
mod zip;
use super::cursor::{Bytes, Cursor};
use super::sparse::{
    bit, densify, missing_grid, InLeaves, Leaf, LeafValues, Tile, Transform, Tree,
};
use super::Loaded;
use crate::Error;
use glam::DVec3;

const FILE_MAGICS: [&[u8; 8]; 2] = [b"NanoVDB0", b"NanoVDB1"];
const META_BYTES: usize = 176;
const GRID_BYTES: usize = 672;
const UPPER: (usize, usize) = (8256, 32 * 32 * 32); // table offset, entries
const LOWER: (usize, usize) = (1088, 16 * 16 * 16);
const LEAF_BYTES: usize = 96 + 512 * 4;

struct GridEntry {
    name: String,
    grid_type: u32,
    codec: u16,
    grid_size: u64,
    file_size: u64,
    offset: usize,
}

/// Names and types of every grid in the file, with where its buffer starts.
fn table(file: &str, src: Bytes) -> Result<Vec<GridEntry>, Error> {
    let mut c = Cursor::over(file, src);
    let mut out = Vec::new();
    while c.remaining() > 0 {
        let at = c.pos;
        let magic: [u8; 8] = c
            .bytes(8, "the NanoVDB magic")?
            .try_into()
            .unwrap_or([0; 8]);
        if !FILE_MAGICS.iter().any(|m| **m == magic) {
            c.pos = at;
            return Err(c.err(
                "the NanoVDB magic 'NanoVDB0'",
                format!("{:?}", String::from_utf8_lossy(&magic)),
            ));
        }
        let version = c.u32("the NanoVDB version")?;
        if version >> 21 != 32 {
            return Err(Error::Unsupported {
                file: file.to_string(),
                what: format!(
                    "NanoVDB version {}.{}.{}",
                    version >> 21,
                    (version >> 10) & 0x7ff,
                    version & 0x3ff
                ),
                hint: "NanoVDB 32.x files are read".into(),
            });
        }
        let count = c.u16("the grid count")? as usize;
        let codec = c.u16("the codec")?;
        let mut metas = Vec::with_capacity(count);
        for _ in 0..count {
            let m = c.pos;
            let grid_size = c.u64("the grid size")?;
            let file_size = c.u64("the grid's size in the file")?;
            c.skip(16, "name key and voxel count")?;
            let grid_type = c.u32("the grid type")?;
            c.skip(4 + 48 + 24 + 24, "class and bounding boxes")?;
            let name_size = c.u32("the name size")? as usize;
            c.seek(
                (m + META_BYTES) as u64,
                "the grid name after its 176-byte record",
            )?;
            let raw = c.bytes(name_size, "the grid name")?;
            let name = String::from_utf8_lossy(raw)
                .trim_end_matches('\0')
                .to_string();
            metas.push((name, grid_type, grid_size, file_size));
        }
        for (name, grid_type, grid_size, file_size) in metas {
            let offset = c.pos;
            c.skip(
                usize::try_from(file_size).unwrap_or(usize::MAX),
                &format!("grid '{name}'"),
            )?;
            out.push(GridEntry {
                name,
                grid_type,
                codec,
                grid_size,
                file_size,
                offset,
            });
        }
    }
    Ok(out)
}

/// Names of the grids in the file and whether each is a float grid.
pub fn grid_names(file: &str, src: Bytes) -> Result<Vec<(String, bool)>, Error> {
    Ok(table(file, src)?
        .into_iter()
        .map(|g| (g.name, g.grid_type == 1))
        .collect())
}

/// The grid's uncompressed buffer (from a file, its bytes alone are read).
fn buffer(file: &str, src: &Bytes, g: &GridEntry, max_bytes: u64) -> Result<Vec<u8>, Error> {
    if g.grid_size.max(g.file_size) > max_bytes {
        return Err(Error::TooLarge {
            file: file.to_string(),
            what: format!("grid '{}'", g.name),
            bytes: g.grid_size,
            cap: max_bytes,
        });
    }
    // (`table` checked that the grid's bytes lie within the file.)
    let body = src.read(file, g.offset as u64, g.file_size as usize)?;
    match g.codec {
        0 if g.grid_size == g.file_size => Ok(body.into_owned()),
        0 => Err(Error::format(
            file,
            format!("grid '{}'", g.name),
            format!("{} bytes of uncompressed grid", g.grid_size),
            format!("{} bytes", g.file_size),
        )),
        1 => {
            let mut c = Cursor::new(file, &body);
            let size = c.u64("the compressed size")?;
            if size > c.remaining() as u64 {
                return Err(Error::format(
                    file,
                    format!("byte {} (grid '{}')", g.offset, g.name),
                    format!("a zlib stream within the grid's {} bytes", g.file_size),
                    format!("{size} bytes"),
                ));
            }
            zlib(&body[8..8 + size as usize], g.grid_size as usize)
                .map_err(|e| e.at(file, format!("byte {} (grid '{}')", g.offset + 8, g.name)))
        }
        other => Err(Error::Unsupported {
            file: file.to_string(),
            what: format!("grid '{}' compressed with codec {other}", g.name),
            hint: "uncompressed (0) and ZIP (1) NanoVDB files are read".into(),
        }),
    }
}

/// A grid's map (its voxel size and translation), read at the grid's header: axis-aligned, finite, positive.
fn map(c: &mut Cursor, file: &str, name: &str) -> Result<Transform, Error> {
    let at_grid = |what: &str| format!("grid '{name}' {what}");
    c.seek(384, &at_grid("map"))?;
    let mut m = [0f64; 9];
    for v in m.iter_mut() {
        *v = c.f64("the map matrix")?;
    }
    c.seek(528, &at_grid("map translation"))?; // after the inverse matrix
    let translation = DVec3::new(
        c.f64("the map translation")?,
        c.f64("the map translation")?,
        c.f64("the map translation")?,
    );
    if [m[1], m[2], m[3], m[5], m[6], m[7]]
        .iter()
        .any(|&v| v != 0.0)
    {
        return Err(Error::Unsupported {
            file: file.to_string(),
            what: at_grid("has a rotated map"),
            hint: "only axis-aligned maps are read; put the rotation in the scene".into(),
        });
    }
    let transform = Transform {
        scale: DVec3::new(m[0], m[4], m[8]),
        translation,
    };
    if !(transform.scale.is_finite()
        && transform.scale.cmpgt(DVec3::ZERO).all()
        && translation.is_finite())
    {
        return Err(Error::format(
            file,
            at_grid("map"),
            "a finite positive voxel size and finite translation",
            format!("{transform:?}"),
        ));
    }
    Ok(transform)
}

/// Where a grid's leaves are read from while its tree is parsed.
enum LeafBytes<'a> {
    /// The whole grid in memory (a ZIP grid, decompressed): masks and values from it.
    Buffer,
    /// The file, the grid starting at byte `at`: the masks are read now, the values as the grid is filled
    /// ([`FileLeaves`]).
    File { src: Bytes<'a>, at: usize },
    /// Each leaf's mask by its index among the grid's leaves (a ZIP grid's, found as it was inflated): the values
    /// are read as the grid is filled.
    #[cfg_attr(not(feature = "zip"), allow(dead_code))]
    Masks(&'a [[u64; 8]]),
}

/// Parses one float grid into a tree: `buf` holds the grid from its start, at least up to its leaves (all of it
/// for [`LeafBytes::Buffer`]), `grid_len` is the grid's size. With the leaves in the file, their values stay
/// there: the second value says where each leaf's start (in the tree's leaf order, file offsets).
fn tree(
    file: &str,
    name: &str,
    buf: &[u8],
    grid_len: usize,
    leaf_bytes: LeafBytes,
) -> Result<(Tree, Vec<usize>), Error> {
    let mut c = Cursor::new(file, buf);
    let at_grid = |what: &str| format!("grid '{name}' {what}");
    let transform = map(&mut c, file, name)?;
    let tree = GRID_BYTES;
    c.seek(tree as u64, &at_grid("tree"))?;
    let (off, counts) = tree_header(&mut c)?;
    let counts = counts.map(|n| n as usize);
    let base = |level: usize| (tree as u64).saturating_add(off[level]);
    let strides = [LEAF_BYTES, LOWER.0 + 8 * LOWER.1, UPPER.0 + 8 * UPPER.1];
    for level in 0..3 {
        let end = base(level)
            .saturating_add((counts[level] as u64).saturating_mul(strides[level] as u64));
        // (The leaves may lie beyond `buf`, in the file; the other nodes are read from it.)
        let within = if level == 0 { grid_len } else { buf.len() };
        if end > within as u64 {
            return Err(Error::format(
                file,
                at_grid("tree"),
                format!(
                    "{} level-{level} nodes within the {within}-byte grid",
                    counts[level],
                ),
                format!("nodes ending at byte {end}"),
            ));
        }
    }
    // Each node is some parent's child once: a tree. A file whose offsets point twice at one node (a DAG: 817
    // bytes of 32 768 upper entries onto one lower node onto one leaf claimed 134 M leaves) is refused at the
    // second reference, before anything is expanded. (At most a bit per node the file holds.)
    let seen = std::cell::RefCell::new([
        vec![false; counts[0]],
        vec![false; counts[1]],
        vec![false; counts[2]],
    ]);
    // Index of the node of `level` at byte `addr`, checked, and claimed.
    let node = |level: usize, addr: i128| -> Result<usize, Error> {
        let rel = addr - base(level) as i128;
        let stride = strides[level] as i128;
        if rel < 0 || rel % stride != 0 || rel / stride >= counts[level] as i128 {
            return Err(Error::format(
                file,
                at_grid("tree"),
                format!(
                    "a child offset onto one of the {} level-{level} nodes",
                    counts[level]
                ),
                format!("byte {addr}"),
            ));
        }
        let idx = (rel / stride) as usize;
        if std::mem::replace(&mut seen.borrow_mut()[level][idx], true) {
            return Err(Error::format(
                file,
                at_grid("tree"),
                "each node the child of one parent (a tree)",
                format!("level-{level} node {idx} (byte {addr}) referenced a second time"),
            ));
        }
        Ok(idx)
    };
    let root = base(3) as usize;
    c.seek(root as u64 + 24, &at_grid("root"))?;
    let table_size = c.u32("the root table size")? as usize;
    let background = c.f32("the background")?;
    if table_size.saturating_mul(32) > buf.len().saturating_sub(root + 64) {
        return Err(Error::format(
            file,
            at_grid("root"),
            "a root table that fits the grid",
            format!("{table_size} tiles"),
        ));
    }
    let mut t = Tree {
        transform,
        background,
        tiles: Vec::new(),
        leaves: Vec::new(),
    };
    let mut uppers = Vec::new();
    let mut keys = std::collections::HashSet::new();
    for i in 0..table_size {
        c.pos = root + 64 + 32 * i;
        let key = c.u64("a root key")?;
        if !keys.insert(key) {
            return Err(Error::format(
                file,
                at_grid("root"),
                "each root key once",
                format!("key {key:#x} repeated at entry {i}"),
            ));
        }
        let child = c.i64("a root child offset")?;
        let state = c.u32("a root tile state")?;
        let value = c.f32("a root tile value")?;
        let mask21 = (1u64 << 21) - 1;
        let k = |s: u32| (((key >> s) & mask21) as u32).wrapping_shl(12) as i32;
        let origin = [k(42), k(21), k(0)];
        if child == 0 {
            t.add_tile(Tile {
                origin,
                size: 4096,
                value,
                active: state != 0,
            });
        } else {
            uppers.push((origin, node(2, root as i128 + child as i128)?));
        }
    }
    let mut lowers = Vec::new();
    let mut leaves = Vec::new();
    // Internal nodes: origin + child index → (tiles, children), for both levels.
    let mut internal = |level: usize,
                        idx: usize,
                        origin: [i32; 3],
                        log2: u32,
                        child_total: u32,
                        out: &mut Vec<([i32; 3], usize)>|
     -> Result<(), Error> {
        let (table_off, n) = if level == 2 { UPPER } else { LOWER };
        let start = base(level) as usize + idx * strides[level];
        let words = n / 64;
        let mut cc = Cursor::new(file, buf);
        cc.pos = start + 32;
        let value_mask: Vec<u64> = (0..words)
            .map(|_| cc.u64("a value mask"))
            .collect::<Result<_, _>>()?;
        let child_mask: Vec<u64> = (0..words)
            .map(|_| cc.u64("a child mask"))
            .collect::<Result<_, _>>()?;
        let dim = 1i32 << log2;
        for i in 0..n {
            cc.pos = start + table_off + 8 * i;
            let entry = cc.i64("a node table entry")?;
            let ii = i as i32;
            let o = [
                origin[0].wrapping_add((ii >> (2 * log2)) << child_total),
                origin[1].wrapping_add(((ii >> log2) & (dim - 1)) << child_total),
                origin[2].wrapping_add((ii & (dim - 1)) << child_total),
            ];
            if bit(&child_mask, i) {
                out.push((o, node(level - 1, start as i128 + entry as i128)?));
            } else {
                let value = f32::from_le_bytes((entry as u64 as u32).to_le_bytes());
                t.add_tile(Tile {
                    origin: o,
                    size: 1 << child_total,
                    value,
                    active: bit(&value_mask, i),
                });
            }
        }
        Ok(())
    };
    for (origin, idx) in uppers {
        internal(2, idx, origin, 5, 7, &mut lowers)?;
    }
    for (origin, idx) in lowers {
        internal(1, idx, origin, 4, 3, &mut leaves)?;
    }
    let starts = read_leaves(
        file,
        name,
        (c, leaf_bytes),
        base(0) as usize,
        leaves,
        &mut t,
    )?;
    Ok((t, starts))
}

/// Reads the leaves `leaves` (origin, index among the grid's leaves, which start at byte `first`) into `t`: from
/// the buffer `c` reads, or their masks from the file (a window reading ahead) with their values left there —
/// then where each leaf's values start in the file, in order.
fn read_leaves(
    file: &str,
    name: &str,
    (c, leaf_bytes): (Cursor, LeafBytes),
    first: usize,
    leaves: Vec<([i32; 3], usize)>,
    t: &mut Tree,
) -> Result<Vec<usize>, Error> {
    let (mut lc, shift, in_file, masks) = match leaf_bytes {
        LeafBytes::Buffer => (c, 0, false, None),
        LeafBytes::File { src, at } => (Cursor::over(file, src), at, true, None),
        LeafBytes::Masks(m) => (c, 0, true, Some(m)),
    };
    // (Sized once: the list's leaves are checked to lie in the grid, and doubling would hold up to twice them.)
    let mut starts = Vec::new();
    let n = leaves.len();
    t.leaves
        .try_reserve_exact(n)
        .map_err(|_| too_many(file, name))?;
    if in_file {
        starts
            .try_reserve_exact(n)
            .map_err(|_| too_many(file, name))?;
    }
    for (origin, idx) in leaves {
        let start = shift + first + idx * LEAF_BYTES;
        let mask = match masks {
            Some(m) => *m
                .get(idx)
                .ok_or_else(|| lc.err("a leaf among those counted", format!("leaf {idx}")))?,
            None => {
                lc.pos = start + 16;
                let mut mask = [0u64; 8];
                for w in mask.iter_mut() {
                    *w = lc.u64("a leaf mask")?;
                }
                mask
            }
        };
        let values = if in_file {
            starts.push(start + 96);
            Vec::new()
        } else {
            lc.pos = start + 96;
            (0..512)
                .map(|_| lc.f32("a leaf value"))
                .collect::<Result<Vec<_>, _>>()?
        };
        t.leaves.push(Leaf {
            origin,
            values,
            mask,
        });
    }
    Ok(starts)
}

/// The refusal of a tree whose leaf list the allocator cannot hold.
fn too_many(file: &str, name: &str) -> Error {
    Error::Io {
        file: file.to_string(),
        message: format!("grid '{name}': more leaves than this machine can hold"),
    }
}

/// A grid's leaf values read from the file as the grid is filled, leaf by leaf (an uncompressed grid's values go
/// from the file to their bricks: the grid is never held twice).
struct FileLeaves<'a> {
    c: Cursor<'a>,
    /// Each leaf's values' file offset, in the tree's leaf order.
    starts: Vec<usize>,
    next: usize,
    scratch: Vec<f32>,
}

impl LeafValues for FileLeaves<'_> {
    fn values<'s>(&'s mut self, _leaf: &'s Leaf) -> Result<&'s [f32], Error> {
        let Some(&start) = self.starts.get(self.next) else {
            return Err(self.c.err("as many leaves as the tree holds", "another"));
        };
        self.next += 1;
        self.c.pos = start;
        let raw = self.c.bytes(512 * 4, "a leaf's values")?;
        self.scratch.clear();
        self.scratch.extend(
            raw.chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
        Ok(&self.scratch)
    }
}

/// Reads the float grids `names` and makes them dense over the union of their active boxes.
pub fn read(file: &str, src: Bytes, names: &[&str], max_bytes: u64) -> Result<Vec<Loaded>, Error> {
    let entries = table(file, src.clone())?;
    let mut trees = Vec::new();
    for &name in names {
        let Some(g) = entries.iter().find(|g| g.name == name) else {
            return Err(missing_grid(
                file,
                name,
                entries.iter().map(|g| g.name.as_str()),
            ));
        };
        if g.grid_type != 1 {
            return Err(Error::Unsupported {
                file: file.to_string(),
                what: format!("grid '{name}' of NanoVDB type {}", g.grid_type),
                hint: "float grids (type 1) are read".into(),
            });
        }
        // An uncompressed grid's leaves are read from the file as the grid is filled; a ZIP grid is
        // decompressed whole.
        let streamed = match g.codec {
            0 if g.grid_size == g.file_size => leaves_start(file, &src, g)?,
            _ => None,
        };
        #[cfg(feature = "zip")]
        if streamed.is_none() && g.codec == 1 {
            if let Some((t, z)) = zip::tree_and_leaves(file, &src, g, name, max_bytes)? {
                trees.push((name, t, Leaves::Zip(z)));
                continue;
            }
        }
        let (t, from) = match streamed {
            Some(head) => {
                let head = src.read(file, g.offset as u64, head)?;
                let at = LeafBytes::File {
                    src: src.clone(),
                    at: g.offset,
                };
                let (t, starts) = tree(file, name, &head, g.grid_size as usize, at)?;
                let leaves = FileLeaves {
                    c: Cursor::over(file, src.clone()),
                    starts,
                    next: 0,
                    scratch: Vec::with_capacity(512),
                };
                (t, Leaves::File(leaves))
            }
            None => {
                let buf = buffer(file, &src, g, max_bytes)?;
                let (t, _) = tree(file, name, &buf, buf.len(), LeafBytes::Buffer)?;
                (t, Leaves::Tree(InLeaves))
            }
        };
        trees.push((name, t, from));
    }
    densify(file, trees, max_bytes)
}

/// The tree's header at `c`: its four levels' node offsets (from the tree; leaves first, root last) and the
/// leaf, lower- and upper-node counts.
fn tree_header(c: &mut Cursor) -> Result<([u64; 4], [u32; 3]), Error> {
    let mut off = [0u64; 4];
    for o in off.iter_mut() {
        *o = c.u64("a node offset")?;
    }
    let counts = [
        c.u32("the leaf count")?,
        c.u32("the lower-node count")?,
        c.u32("the upper-node count")?,
    ];
    Ok((off, counts))
}

/// Where the leaves start in uncompressed grid `g`, when every other node lies before them (NanoVDB's layout:
/// grid, tree, root, upper and lower nodes, leaves): what must be read before its values. `None` for another
/// layout (the grid is then read whole).
fn leaves_start(file: &str, src: &Bytes, g: &GridEntry) -> Result<Option<usize>, Error> {
    if (g.grid_size as usize) < HEAD {
        return Ok(None);
    }
    leaves_start_in(file, &src.read(file, g.offset as u64, HEAD)?, g.grid_size)
}

/// The grid's bytes up to its tree's node counts (its first [`HEAD`]).
const HEAD: usize = GRID_BYTES + 32 + 12;

/// [`leaves_start`] from the grid's first [`HEAD`] bytes, `bytes`, for a grid of `grid_size` bytes.
fn leaves_start_in(file: &str, bytes: &[u8], grid_size: u64) -> Result<Option<usize>, Error> {
    let mut c = Cursor::new(file, bytes);
    c.pos = GRID_BYTES;
    let (off, counts) = tree_header(&mut c)?;
    let counts = counts.map(u64::from);
    let strides = [LOWER.0 + 8 * LOWER.1, UPPER.0 + 8 * UPPER.1].map(|s| s as u64);
    let leaves = off[0];
    let before = off[3] < leaves
        && (1..3)
            .all(|l| off[l].saturating_add(counts[l].saturating_mul(strides[l - 1])) <= leaves);
    let start = (GRID_BYTES as u64).saturating_add(leaves);
    Ok((before && counts[0] > 0 && start <= grid_size).then_some(start as usize))
}

/// A grid's leaf values: decoded with its tree, or read from the file as it is filled.
enum Leaves<'a> {
    Tree(InLeaves),
    File(FileLeaves<'a>),
    #[cfg(feature = "zip")]
    Zip(zip::ZipLeaves<'a>),
}

impl LeafValues for Leaves<'_> {
    fn values<'s>(&'s mut self, leaf: &'s Leaf) -> Result<&'s [f32], Error> {
        match self {
            Leaves::Tree(t) => t.values(leaf),
            Leaves::File(f) => f.values(leaf),
            #[cfg(feature = "zip")]
            Leaves::Zip(z) => z.values(leaf),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u64_at(b: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
    }

    /// The repository's plume (NanoVDB's own tools wrote it, uncompressed): its path and bytes.
    fn plume() -> (&'static str, Vec<u8>) {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tests/data/valid/nvdb/plume48.nvdb"
        );
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
        (path, bytes)
    }

    #[test]
    fn an_uncompressed_grids_values_come_from_the_file_as_they_are_read() {
        // The plume's density: the nodes before its leaves are all that is read first, its leaves' values come
        // leaf by leaf from the file, the same values as the whole buffer gives; a grid whose lower nodes lie
        // after its leaves is read whole.
        let (path, bytes) = plume();
        let src = Bytes::Slice(&bytes);
        let grids = table(path, src.clone()).unwrap();
        let g = grids.iter().find(|g| g.name == "density").unwrap();
        let head = leaves_start(path, &src, g)
            .unwrap()
            .expect("NanoVDB's layout");
        let leaves = GRID_BYTES + u64_at(&bytes, g.offset + GRID_BYTES) as usize;
        assert_eq!(head, leaves);
        let whole = &bytes[g.offset..g.offset + g.grid_size as usize];
        let (buffered, _) = tree(path, "density", whole, whole.len(), LeafBytes::Buffer).unwrap();
        let at = LeafBytes::File {
            src: src.clone(),
            at: g.offset,
        };
        let (streamed, starts) = tree(path, "density", &whole[..head], whole.len(), at).unwrap();
        assert_eq!(streamed.leaves.len(), buffered.leaves.len());
        // (The leaves, 2 KB of values each, are what is not read first: in a 256-voxel fire 19 of its 19.5 MB.)
        assert!(head + buffered.leaves.len() * LEAF_BYTES <= g.grid_size as usize);
        assert_eq!(starts.len(), buffered.leaves.len());
        let mut from_file = FileLeaves {
            c: Cursor::over(path, src.clone()),
            starts,
            next: 0,
            scratch: Vec::new(),
        };
        for (a, b) in streamed.leaves.iter().zip(&buffered.leaves) {
            assert!(a.values.is_empty() && a.origin == b.origin && a.mask == b.mask);
            assert_eq!(from_file.values(a).unwrap(), &b.values[..]);
        }
        // One leaf too many is an error naming the file, not a read past the list.
        let e = from_file
            .values(&streamed.leaves[0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("plume48.nvdb"), "{e}");
        // Lower nodes after the leaves: read whole.
        let mut moved = bytes.clone();
        let lower = g.offset + GRID_BYTES + 8;
        let past = (u64_at(&bytes, g.offset + GRID_BYTES) + 64).to_le_bytes();
        moved[lower..lower + 8].copy_from_slice(&past);
        assert_eq!(leaves_start(path, &Bytes::Slice(&moved), g).unwrap(), None);
    }

    #[test]
    fn a_node_referenced_twice_is_refused_before_anything_is_expanded() {
        // The repository's plume (NanoVDB's own tools wrote it) with one lower node's second child entry made a
        // copy of its first: two leaves of the tree become one leaf referenced twice — the shape of an 817-byte
        // file whose shared nodes claimed 134 M leaves and aborted its host through the C ABI.
        let (path, bytes) = plume();
        let grids = table(path, Bytes::Slice(&bytes)).unwrap();
        let g = grids.iter().find(|g| g.name == "density").unwrap();
        assert_eq!(g.codec, 0, "the plume is uncompressed");
        let mut buf = bytes[g.offset..g.offset + g.grid_size as usize].to_vec();
        assert!(tree(path, "density", &buf, buf.len(), LeafBytes::Buffer).is_ok());
        let lower = GRID_BYTES + u64_at(&buf, GRID_BYTES + 8) as usize;
        let words = LOWER.1 / 64;
        let child_mask = lower + 32 + 8 * words;
        let children: Vec<usize> = (0..LOWER.1)
            .filter(|&i| u64_at(&buf, child_mask + 8 * (i / 64)) >> (i % 64) & 1 == 1)
            .take(2)
            .collect();
        assert_eq!(children.len(), 2, "a lower node with two leaves");
        let entry = |i: usize| lower + LOWER.0 + 8 * i;
        let first = buf[entry(children[0])..entry(children[0]) + 8].to_vec();
        buf[entry(children[1])..entry(children[1]) + 8].copy_from_slice(&first);
        let Err(e) = tree(path, "density", &buf, buf.len(), LeafBytes::Buffer) else {
            panic!("a leaf referenced twice was read");
        };
        let e = e.to_string();
        assert!(
            e.contains("referenced a second time") && e.contains("a tree"),
            "{e}"
        );
    }
}
