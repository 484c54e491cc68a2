//! OpenVDB (`.vdb`) writer: float and vector grids as the reader ([`super::read`]) and OpenVDB read them — dense
//! arrays, sparse leaves or tiles, with each grid's name, class and bounding-box metadata.

use super::*;

/// Encodes float grids as an OpenVDB file (format 224, library 12.0, standard 5-4-3 trees, full floats, no
/// compression, no metadata), the layout [`read`] and OpenVDB read: per grid, the root with one child per 4096³
/// block, internal nodes (tile values all background, inactive), and a leaf for every 8³ block holding a non-zero
/// value; a leaf's non-zero voxels are active. Voxel (i, j, k) of a grid is centred at `p0 + (i + ½) · voxel`
/// (the grids share the lattice, dims and `p0`), so reading it back gives the active box of the grids.
/// Grids are `(name, dims, values x fastest)`; the background is 0.
pub fn write(grids: &[(&str, [usize; 3], &[f32])], p0: DVec3, voxel: DVec3) -> Vec<u8> {
    write_with_vectors(grids, &[], p0, voxel)
}

/// A vector grid to write: its name, dims and its x, y and z components (dense, x fastest).
pub type VdbVector<'a> = (&'a str, [usize; 3], [&'a [f32]; 3]);

/// As [`write`], with vector grids (`Tree_vec3s_5_4_3`, as Houdini's `vel`) after the float grids: each given
/// as its three components' dense arrays; a voxel is active where any component is non-zero.
pub fn write_with_vectors(
    grids: &[(&str, [usize; 3], &[f32])],
    vectors: &[VdbVector],
    p0: DVec3,
    voxel: DVec3,
) -> Vec<u8> {
    let mut all: Vec<WriteGrid> = grids
        .iter()
        .map(|&(name, dims, values)| (name, 1, dense_leaves(dims, values), Vec::new()))
        .collect();
    for &(name, dims, [x, y, z]) in vectors {
        // The leaves of the component-wise largest magnitude, their values then interleaved x, y, z.
        let mag: Vec<f32> = (0..x.len())
            .map(|i| x[i].abs().max(y[i].abs()).max(z[i].abs()))
            .collect();
        let leaves = dense_leaves(dims, &mag)
            .into_iter()
            .map(|(o, mask, _)| {
                let mut vals = Vec::with_capacity(3 * 512);
                for i in 0..512 {
                    let (a, b, c) = (
                        o[0] as usize + (i >> 6),
                        o[1] as usize + ((i >> 3) & 7),
                        o[2] as usize + (i & 7),
                    );
                    let inside = a < dims[0] && b < dims[1] && c < dims[2];
                    let k = a + dims[0] * (b + dims[1] * c);
                    for comp in [x, y, z] {
                        vals.push(if inside { comp[k] } else { 0.0 });
                    }
                }
                (o, mask, vals)
            })
            .collect();
        all.push((name, 3, leaves, Vec::new()));
    }
    write_grids(&all, p0, voxel)
}

/// A leaf to write: its origin (index space, multiples of 8), active mask (words are x slabs, bits y·8 + z) and
/// 512 values (z fastest).
pub type VdbLeaf = ([i32; 3], [u64; 8], Vec<f32>);

/// The leaves of a dense grid: one for every 8³ block holding a non-zero value, its non-zero voxels active.
fn dense_leaves(dims: [usize; 3], values: &[f32]) -> Vec<VdbLeaf> {
    let leaf_dims = dims.map(|d| d.div_ceil(8));
    let at = |x: usize, y: usize, z: usize| values[x + dims[0] * (y + dims[1] * z)];
    let mut leaves: Vec<VdbLeaf> = Vec::new();
    for lz in 0..leaf_dims[2] {
        for ly in 0..leaf_dims[1] {
            for lx in 0..leaf_dims[0] {
                let mut mask = [0u64; 8];
                let mut vals = vec![0f32; 512];
                for (i, v) in vals.iter_mut().enumerate() {
                    let (x, y, z) = (8 * lx + (i >> 6), 8 * ly + ((i >> 3) & 7), 8 * lz + (i & 7));
                    if x < dims[0] && y < dims[1] && z < dims[2] {
                        *v = at(x, y, z);
                        if *v != 0.0 {
                            mask[i / 64] |= 1 << (i % 64);
                        }
                    }
                }
                if mask.iter().any(|&w| w != 0) {
                    leaves.push(([8 * lx as i32, 8 * ly as i32, 8 * lz as i32], mask, vals));
                }
            }
        }
    }
    leaves
}

/// As [`write`], for grids given as leaves anywhere in index space (a sparse fire: leaves far apart cost
/// their own bytes, not the box between them). Voxel (i, j, k) is centred at `p0 + (i + ½) · voxel`.
pub fn write_sparse(grids: &[(&str, Vec<VdbLeaf>)], p0: DVec3, voxel: DVec3) -> Vec<u8> {
    let all: Vec<WriteGrid> = grids
        .iter()
        .map(|(name, leaves)| (*name, 1, leaves.clone(), Vec::new()))
        .collect();
    write_grids(&all, p0, voxel)
}

/// As [`write_sparse`], for vector grids (`Tree_vec3s_5_4_3`): each leaf's values are 3 × 512, a voxel's x, y
/// and z together (z fastest over the voxels, as [`VdbLeaf`]'s).
pub fn write_sparse_vectors(grids: &[(&str, Vec<VdbLeaf>)], p0: DVec3, voxel: DVec3) -> Vec<u8> {
    write_sparse_vectors_by(None, grids, p0, voxel)
}

/// [`write_sparse_vectors`], the file's metadata naming its `creator`.
pub fn write_sparse_vectors_by(
    creator: Option<&str>,
    grids: &[(&str, Vec<VdbLeaf>)],
    p0: DVec3,
    voxel: DVec3,
) -> Vec<u8> {
    let all: Vec<WriteGrid> = grids
        .iter()
        .map(|(name, leaves)| (*name, 3, leaves.clone(), Vec::new()))
        .collect();
    write_grids_by(creator, &all, p0, voxel)
}

/// An active constant tile: origin (a multiple of its size), size (8: a tile of a 4-level node, 128: of a
/// 5-level node), value.
pub type VdbTile = ([i32; 3], i32, f32);

/// As [`write_sparse`], with active constant tiles beside the leaves (a tile must not overlap a leaf, as in
/// OpenVDB's trees): a fog volume's interior, as OpenVDB's `prune` leaves it.
pub fn write_tiled(
    grids: &[(&str, Vec<VdbLeaf>, Vec<VdbTile>)],
    p0: DVec3,
    voxel: DVec3,
) -> Vec<u8> {
    let all: Vec<WriteGrid> = grids
        .iter()
        .map(|(name, leaves, tiles)| (*name, 1, leaves.clone(), tiles.clone()))
        .collect();
    write_grids(&all, p0, voxel)
}

/// The grid's metadata as OpenVDB writes it and readers that read metadata alone rely on (Blender, Houdini list
/// grids by their `name` and place them by `file_bbox_min`/`file_bbox_max` before loading any voxel): its name,
/// class, the active voxels' index-space bounds and count.
fn write_grid_metadata(out: &mut Vec<u8>, name: &str, leaves: &[VdbLeaf], tiles: &[VdbTile]) {
    let (mut lo, mut hi, mut count) = ([i32::MAX; 3], [i32::MIN; 3], 0i64);
    let mut grow = |a: [i32; 3], b: [i32; 3], n: i64| {
        for k in 0..3 {
            lo[k] = lo[k].min(a[k]);
            hi[k] = hi[k].max(b[k]);
        }
        count += n;
    };
    for (origin, mask, _) in leaves {
        for (w, word) in mask.iter().enumerate() {
            let mut bits = *word;
            while bits != 0 {
                let n = (w * 64 + bits.trailing_zeros() as usize) as i32;
                bits &= bits - 1;
                // A leaf's voxel n is (x, y, z) = (n >> 6, (n >> 3) & 7, n & 7) from its origin.
                let v = [
                    origin[0] + (n >> 6),
                    origin[1] + ((n >> 3) & 7),
                    origin[2] + (n & 7),
                ];
                grow(v, v, 1);
            }
        }
    }
    for (origin, size, _) in tiles {
        grow(
            *origin,
            origin.map(|o| o + size - 1),
            i64::from(*size).pow(3),
        );
    }
    if count == 0 {
        (lo, hi) = ([0; 3], [0; 3]);
    }
    let entry = |out: &mut Vec<u8>, key: &str, ty: &str, value: &[u8]| {
        for s in [key, ty] {
            out.extend_from_slice(&(s.len() as u32).to_le_bytes());
            out.extend_from_slice(s.as_bytes());
        }
        out.extend_from_slice(&(value.len() as u32).to_le_bytes());
        out.extend_from_slice(value);
    };
    let vec3i = |v: [i32; 3]| v.iter().flat_map(|c| c.to_le_bytes()).collect::<Vec<u8>>();
    out.extend_from_slice(&5u32.to_le_bytes());
    entry(out, "class", "string", b"unknown");
    entry(out, "file_bbox_max", "vec3i", &vec3i(hi));
    entry(out, "file_bbox_min", "vec3i", &vec3i(lo));
    entry(out, "file_voxel_count", "int64", &count.to_le_bytes());
    entry(out, "name", "string", name.as_bytes());
}

/// A grid to write: name, floats per voxel, leaves, tiles.
type WriteGrid<'a> = (&'a str, usize, Vec<VdbLeaf>, Vec<VdbTile>);

/// The writer: grids of `comps` floats per voxel (1: float, 3: vec3s), their leaves' values `comps` per voxel,
/// and tiles (float grids).
fn write_grids(grids: &[WriteGrid], p0: DVec3, voxel: DVec3) -> Vec<u8> {
    write_grids_by(None, grids, p0, voxel)
}

/// [`write_grids`] with the file metadata's `creator` string (what wrote the file: a command that replaces only
/// the files it wrote reads it back, [`super::Header::creator`]).
fn write_grids_by(creator: Option<&str>, grids: &[WriteGrid], p0: DVec3, voxel: DVec3) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(&MAGIC.to_le_bytes());
    out.extend_from_slice(&224u32.to_le_bytes());
    out.extend_from_slice(&12u32.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.push(1); // grid offsets
    out.extend_from_slice(b"00000000-0000-0000-0000-000000000000");
    let put_str = |out: &mut Vec<u8>, s: &str| {
        out.extend_from_slice(&(s.len() as u32).to_le_bytes());
        out.extend_from_slice(s.as_bytes());
    };
    // File metadata: the creator, or none.
    match creator {
        Some(c) => {
            out.extend_from_slice(&1u32.to_le_bytes());
            put_str(&mut out, "creator");
            put_str(&mut out, "string");
            put_str(&mut out, c);
        }
        None => out.extend_from_slice(&0u32.to_le_bytes()),
    }
    out.extend_from_slice(&(grids.len() as i32).to_le_bytes());
    for (name, comps, leaves, tiles) in grids {
        let comps = *comps;
        put_str(&mut out, name);
        put_str(
            &mut out,
            if comps == 3 {
                "Tree_vec3s_5_4_3"
            } else {
                "Tree_float_5_4_3"
            },
        );
        put_str(&mut out, "");
        let offsets_at = out.len();
        out.extend_from_slice(&[0u8; 24]);
        let grid_pos = out.len();
        out.extend_from_slice(&0u32.to_le_bytes()); // compression: none
        write_grid_metadata(&mut out, name, leaves, tiles);
        put_str(&mut out, "ScaleTranslateMap");
        let translation = p0 + 0.5 * voxel;
        for v in [
            translation,
            voxel,
            voxel,
            DVec3::ONE / voxel,
            DVec3::ONE / (voxel * voxel),
            0.5 / voxel,
        ] {
            for c in v.to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&1i32.to_le_bytes()); // buffer count
        for _ in 0..comps {
            out.extend_from_slice(&0f32.to_le_bytes()); // background
        }
        // The leaves, keyed by origin, grouped into 4- and 5-level nodes.
        let mut leaves: Vec<&VdbLeaf> = leaves.iter().collect();
        // Node order: the root's children by origin, then each node's children by their index (x slowest).
        let key5 = |o: [i32; 3]| o.map(|v| v >> 12);
        let index4 = |o: [i32; 3]| {
            (((o[0] >> 7) & 31) << 10 | ((o[1] >> 7) & 31) << 5 | ((o[2] >> 7) & 31)) as usize
        };
        let index_leaf = |o: [i32; 3]| {
            (((o[0] >> 3) & 15) << 8 | ((o[1] >> 3) & 15) << 4 | ((o[2] >> 3) & 15)) as usize
        };
        leaves.sort_by_key(|(o, _, _)| (key5(*o), index4(*o), index_leaf(*o)));
        let mut roots: Vec<[i32; 3]> = leaves
            .iter()
            .map(|(o, _, _)| key5(*o))
            .chain(tiles.iter().map(|t| key5(t.0)))
            .collect();
        roots.sort();
        roots.dedup();

        out.extend_from_slice(&0u32.to_le_bytes()); // root tiles
        out.extend_from_slice(&(roots.len() as u32).to_le_bytes());
        let put_values = |out: &mut Vec<u8>, vals: &[f32]| {
            out.push(6); // NO_MASK_AND_ALL_VALS
            for v in vals {
                out.extend_from_slice(&v.to_le_bytes());
            }
        };
        let put_mask = |out: &mut Vec<u8>, m: &[u64]| {
            for w in m {
                out.extend_from_slice(&w.to_le_bytes());
            }
        };
        for r in &roots {
            for c in r.map(|v| v << 12) {
                out.extend_from_slice(&c.to_le_bytes());
            }
            let in5: Vec<usize> = (0..leaves.len())
                .filter(|&i| key5(leaves[i].0) == *r)
                .collect();
            let t5: Vec<&VdbTile> = tiles.iter().filter(|t| key5(t.0) == *r).collect();
            let mut child5 = vec![0u64; 512];
            let (mut active5, mut values5) = (vec![0u64; 512], vec![0f32; 32768 * comps]);
            for k in in5
                .iter()
                .map(|&i| index4(leaves[i].0))
                .chain(t5.iter().filter(|t| t.1 == 8).map(|t| index4(t.0)))
            {
                child5[k / 64] |= 1 << (k % 64);
            }
            for t in t5.iter().filter(|t| t.1 == 128) {
                let k = index4(t.0);
                active5[k / 64] |= 1 << (k % 64);
                values5[k] = t.2;
            }
            put_mask(&mut out, &child5);
            put_mask(&mut out, &active5);
            put_values(&mut out, &values5);
            let k4s: Vec<usize> = (0..32768)
                .filter(|&k| child5[k / 64] >> (k % 64) & 1 == 1)
                .collect();
            for k4 in k4s {
                let in4: Vec<usize> = in5
                    .iter()
                    .copied()
                    .filter(|&i| index4(leaves[i].0) == k4)
                    .collect();
                let mut child4 = [0u64; 64];
                for &i in &in4 {
                    let k = index_leaf(leaves[i].0);
                    child4[k / 64] |= 1 << (k % 64);
                }
                let (mut active4, mut values4) = ([0u64; 64], vec![0f32; 4096 * comps]);
                for t in t5.iter().filter(|t| t.1 == 8 && index4(t.0) == k4) {
                    let k = index_leaf(t.0);
                    active4[k / 64] |= 1 << (k % 64);
                    values4[k] = t.2;
                }
                put_mask(&mut out, &child4);
                put_mask(&mut out, &active4);
                put_values(&mut out, &values4);
                for &i in &in4 {
                    put_mask(&mut out, &leaves[i].1);
                }
            }
        }
        let block_pos = out.len();
        for (_, mask, vals) in &leaves {
            put_mask(&mut out, mask);
            put_values(&mut out, vals);
        }
        let end_pos = out.len();
        for (k, v) in [grid_pos, block_pos, end_pos].into_iter().enumerate() {
            out[offsets_at + 8 * k..offsets_at + 8 * k + 8]
                .copy_from_slice(&(v as i64).to_le_bytes());
        }
    }
    out
}
