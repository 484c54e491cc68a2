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
//! Every offset is checked to land on a node of the right level inside the buffer before it is followed.

use super::compress::zlib;
use super::cursor::{Bytes, Cursor};
use super::sparse::{bit, densify, missing_grid, InLeaves, Leaf, Tile, Transform, Tree};
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

/// Parses one float grid's buffer into a tree.
fn tree(file: &str, name: &str, buf: &[u8]) -> Result<Tree, Error> {
    let mut c = Cursor::new(file, buf);
    let at_grid = |what: &str| format!("grid '{name}' {what}");
    let transform = map(&mut c, file, name)?;
    let tree = GRID_BYTES;
    c.seek(tree as u64, &at_grid("tree"))?;
    let mut off = [0u64; 4];
    for o in off.iter_mut() {
        *o = c.u64("a node offset")?;
    }
    let counts = [
        c.u32("the leaf count")? as usize,
        c.u32("the lower-node count")? as usize,
        c.u32("the upper-node count")? as usize,
    ];
    let base = |level: usize| (tree as u64).saturating_add(off[level]);
    let strides = [LEAF_BYTES, LOWER.0 + 8 * LOWER.1, UPPER.0 + 8 * UPPER.1];
    for level in 0..3 {
        let end = base(level)
            .saturating_add((counts[level] as u64).saturating_mul(strides[level] as u64));
        if end > buf.len() as u64 {
            return Err(Error::format(
                file,
                at_grid("tree"),
                format!(
                    "{} level-{level} nodes within the {}-byte grid",
                    counts[level],
                    buf.len()
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
    for (origin, idx) in leaves {
        let start = base(0) as usize + idx * LEAF_BYTES;
        c.pos = start + 16;
        let mut mask = [0u64; 8];
        for w in mask.iter_mut() {
            *w = c.u64("a leaf mask")?;
        }
        c.pos = start + 96;
        let values = (0..512)
            .map(|_| c.f32("a leaf value"))
            .collect::<Result<Vec<_>, _>>()?;
        t.leaves.push(Leaf {
            origin,
            values,
            mask,
        });
    }
    Ok(t)
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
        let buf = buffer(file, &src, g, max_bytes)?;
        trees.push((name, tree(file, name, &buf)?, InLeaves));
    }
    densify(file, trees, max_bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u64_at(b: &[u8], at: usize) -> u64 {
        u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
    }

    #[test]
    fn a_node_referenced_twice_is_refused_before_anything_is_expanded() {
        // The repository's plume (NanoVDB's own tools wrote it) with one lower node's second child entry made a
        // copy of its first: two leaves of the tree become one leaf referenced twice — the shape of an 817-byte
        // file whose shared nodes claimed 134 M leaves and aborted its host through the C ABI.
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tests/data/valid/nvdb/plume48.nvdb"
        );
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let grids = table(path, Bytes::Slice(&bytes)).unwrap();
        let g = grids.iter().find(|g| g.name == "density").unwrap();
        assert_eq!(g.codec, 0, "the plume is uncompressed");
        let mut buf = bytes[g.offset..g.offset + g.grid_size as usize].to_vec();
        assert!(tree(path, "density", &buf).is_ok());
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
        let Err(e) = tree(path, "density", &buf) else {
            panic!("a leaf referenced twice was read");
        };
        let e = e.to_string();
        assert!(
            e.contains("referenced a second time") && e.contains("a tree"),
            "{e}"
        );
    }
}
