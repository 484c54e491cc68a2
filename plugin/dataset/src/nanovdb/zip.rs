//! A NanoVDB ZIP grid read as it is inflated, twice: once for its nodes and its leaves' masks (the tree), once for
//! its leaves' values, which go from the stream to the grid's bricks as the grid is filled — the grid is never
//! held whole, as pbrt-v4 holds it (the 256-voxel campfire's ZIP file, decompressed whole, peaked at 83 MB in a
//! render where its uncompressed file takes 49).

use super::{leaves_start_in, tree, GridEntry, LeafBytes, GRID_BYTES, HEAD, LEAF_BYTES};
use crate::compress::Inflater;
use crate::cursor::{Bytes, Cursor};
use crate::sparse::{Leaf, LeafValues, Tree};
use crate::Error;

/// Where ZIP grid `g`'s zlib stream lies in the file: after its u64 size, within the grid's bytes.
fn stream_range(file: &str, src: &Bytes, g: &GridEntry) -> Result<(u64, u64), Error> {
    let at = format!("byte {} (grid '{}')", g.offset, g.name);
    let within = g.file_size.saturating_sub(8);
    if g.file_size < 8 {
        return Err(Error::format(
            file,
            at,
            "a grid of at least its 8-byte compressed size",
            format!("{} bytes", g.file_size),
        ));
    }
    let head = src.read(file, g.offset as u64, 8)?;
    let size = u64::from_le_bytes(head[..8].try_into().unwrap_or([0; 8]));
    if size > within {
        return Err(Error::format(
            file,
            at,
            format!("a zlib stream within the grid's {} bytes", g.file_size),
            format!("{size} bytes"),
        ));
    }
    Ok((g.offset as u64 + 8, size))
}

/// The tree of ZIP grid `g` (named `name`) and its leaves' values to come, read as the stream is inflated; `None`
/// where the grid's layout does not allow it (its leaves not last, or their values out of the stream's order:
/// the grid is then inflated whole).
pub(super) fn tree_and_leaves<'a>(
    file: &'a str,
    src: &Bytes<'a>,
    g: &GridEntry,
    name: &str,
    max_bytes: u64,
) -> Result<Option<(Tree, ZipLeaves<'a>)>, Error> {
    if (g.grid_size as usize) < HEAD {
        return Ok(None);
    }
    let range = stream_range(file, src, g)?;
    let what = format!("grid '{}'", g.name);
    let mut z = Inflater::new(file, what.clone(), src.clone(), range, g.grid_size);
    let mut head = vec![0u8; HEAD];
    z.read(&mut head)?;
    let Some(start) = leaves_start_in(file, &head, g.grid_size)? else {
        return Ok(None);
    };
    // The nodes before the leaves, in memory (a few hundred KB for a 256³ grid).
    let too_large = |bytes: u64| Error::TooLarge {
        file: file.to_string(),
        what: format!("grid '{}' nodes", g.name),
        bytes,
        cap: max_bytes,
    };
    if start as u64 > max_bytes {
        return Err(too_large(start as u64));
    }
    // (Grown as the stream delivers it: a header claiming more nodes than the stream holds allocates no more
    // than the stream gives.)
    while head.len() < start {
        let (from, n) = (head.len(), (start - head.len()).min(1 << 20));
        head.try_reserve_exact(n)
            .map_err(|_| too_large(start as u64))?;
        head.resize(from + n, 0);
        z.read(&mut head[from..])?;
    }
    // The leaves' masks, by index, as the stream passes them (64 bytes a leaf).
    let mut c = Cursor::new(file, &head);
    c.pos = GRID_BYTES + 32;
    let count = c.u32("the leaf count")? as u64;
    if count.saturating_mul(LEAF_BYTES as u64) > g.grid_size - start as u64 {
        return Ok(None);
    }
    // (Grown as the stream proves each leaf: a few bytes claiming millions of leaves allocate nothing for them.)
    if count.saturating_mul(64) > max_bytes {
        return Err(too_large(count.saturating_mul(64)));
    }
    let mut masks: Vec<[u64; 8]> = Vec::new();
    let mut leaf = vec![0u8; LEAF_BYTES];
    for _ in 0..count {
        z.read(&mut leaf)?;
        masks.try_reserve(1).map_err(|_| too_large(count * 64))?;
        let word = |w: usize| {
            let at = 16 + 8 * w;
            u64::from_le_bytes(leaf[at..at + 8].try_into().unwrap_or([0; 8]))
        };
        masks.push(std::array::from_fn(word));
    }
    // (The stream's end and checksum now: the second pass reads the same bytes.)
    z.finish()?;
    let (t, starts) = tree(
        file,
        name,
        &head,
        g.grid_size as usize,
        LeafBytes::Masks(&masks),
    )?;
    if !starts.windows(2).all(|w| w[0] < w[1]) {
        return Ok(None);
    }
    let leaves = ZipLeaves {
        z: Inflater::new(file, what, src.clone(), range, g.grid_size),
        starts,
        next: 0,
        raw: vec![0; 512 * 4],
        values: Vec::with_capacity(512),
    };
    Ok(Some((t, leaves)))
}

/// A ZIP grid's leaf values, inflated from its stream a second time as the grid is filled, in the tree's leaf
/// order (the stream's).
pub(super) struct ZipLeaves<'a> {
    z: Inflater<'a>,
    /// Each leaf's values' place in the inflated grid, increasing.
    starts: Vec<usize>,
    next: usize,
    raw: Vec<u8>,
    values: Vec<f32>,
}

impl LeafValues for ZipLeaves<'_> {
    fn values<'s>(&'s mut self, _leaf: &'s Leaf) -> Result<&'s [f32], Error> {
        let Some(&start) = self.starts.get(self.next) else {
            return Err(Error::Io {
                file: self.z.file().to_string(),
                message: format!("more leaves asked of a grid of {}", self.starts.len()),
            });
        };
        self.next += 1;
        self.z
            .skip((start as u64).saturating_sub(self.z.position()))?;
        self.z.read(&mut self.raw)?;
        self.values.clear();
        self.values.extend(
            self.raw
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        );
        Ok(&self.values)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{read, table};
    use super::*;

    fn data(name: &str) -> (String, Vec<u8>) {
        let path = format!(
            "{}/../../tests/data/valid/nvdb/{name}",
            env!("CARGO_MANIFEST_DIR")
        );
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        (path, bytes)
    }

    #[test]
    fn a_zip_grid_streams_to_the_uncompressed_files_values() {
        // The plume ZIP-compressed by NanoVDB's own tools: each grid's tree comes from a first pass of its stream
        // and its values from a second as the grid is filled — the same dataset as the uncompressed file's, value
        // for value, from memory or from the open file.
        let (zpath, zbytes) = data("plume48_zip.nvdb");
        let (path, bytes) = data("plume48.nvdb");
        let names = ["density", "temperature"];
        let plain = read(&path, Bytes::Slice(&bytes), &names, u64::MAX).unwrap();
        let f = std::fs::File::open(&zpath).unwrap();
        let from_file = Bytes::File {
            file: &f,
            len: zbytes.len() as u64,
        };
        for src in [Bytes::Slice(&zbytes), from_file] {
            for g in table(&zpath, src.clone()).unwrap() {
                assert!(
                    tree_and_leaves(&zpath, &src, &g, &g.name, u64::MAX)
                        .unwrap()
                        .is_some(),
                    "{}: streamed",
                    g.name
                );
            }
            let zip = read(&zpath, src, &names, u64::MAX).unwrap();
            for (a, b) in zip.iter().zip(&plain) {
                // (OpenVDB's round trip moved the map by its rounding.)
                let (ab, bb) = (a.bounds.unwrap(), b.bounds.unwrap());
                assert_eq!(a.dims, b.dims);
                assert!((0..2).all(|k| (ab[k] - bb[k]).abs().max_element() < 1e-12));
                let (a, b) = (a.bricks.as_ref().unwrap(), b.bricks.as_ref().unwrap());
                assert_eq!(a.to_dense(), b.to_dense());
                assert!(a.to_dense().iter().filter(|&&v| v != 0.0).count() > 20_000);
            }
        }
    }

    #[test]
    fn a_zip_stream_cut_short_or_corrupt_is_refused_by_name_and_byte() {
        // The plume's ZIP file cut a quarter before its end (its temperature's stream short), with 64 bytes in the
        // middle of its density's stream overwritten, and with one value's byte changed in its last leaf (inflating
        // as well as before: its checksum is wrong): an error naming the file and where, never a panic or values
        // made up.
        let (path, bytes) = data("plume48_zip.nvdb");
        let cut = &bytes[..bytes.len() * 3 / 4];
        let mut flipped = bytes.clone();
        let mid = bytes.len() / 4;
        flipped[mid..mid + 64].iter_mut().for_each(|b| *b ^= 0x5a);
        let mut summed = bytes.clone();
        let grids = table(&path, Bytes::Slice(&bytes)).unwrap();
        let g = &grids[0];
        let size = u64::from_le_bytes(bytes[g.offset..g.offset + 8].try_into().unwrap()) as usize;
        summed[g.offset + 8 + size - 1] ^= 1;
        for (what, b) in [
            ("cut", cut),
            ("flipped", &flipped[..]),
            ("checksum", &summed[..]),
        ] {
            let Err(e) = read(
                &path,
                Bytes::Slice(b),
                &["density", "temperature"],
                u64::MAX,
            ) else {
                panic!("{what}: read");
            };
            let msg = e.to_string();
            assert!(msg.contains("plume48_zip.nvdb"), "{what}: {msg}");
            if what == "checksum" {
                assert!(
                    msg.contains("checksum") && msg.contains("grid 'density'"),
                    "{msg}"
                );
            }
        }
    }
}
