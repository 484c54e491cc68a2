//! The thesis's binary sparse format ("raw"), little-endian.
//!
//! Layout: in the `raw2` variant three `i32` dims w h d; without them (`raw`) the grid is 256³ (or the given
//! dims). Then an `i32` voxel count, then per voxel three `i32` coordinates and four `f64` (r, g, b, a):
//! 44 bytes each. The count must match the file length exactly.
//!
//! Files written for the thesis's shader store coordinates **1-based in the order x, z, y**
//! ([`RawCoords::Thesis`], the default) and encode the value as a colour: [`RawValue::Red`] takes r/256,
//! [`RawValue::MaxRgb`] max(r, g, b)/256 (the thesis's `BIN_ONLY_RED` and `BIN_MAX`). [`RawCoords::Xyz`] reads
//! 0-based x, y, z. Every coordinate is checked against the dims.

use super::cursor::Cursor;
use super::Loaded;
use crate::Error;

/// Coordinate convention of a raw file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RawCoords {
    /// 1-based, stored x, z, y (the thesis's shader files).
    #[default]
    Thesis,
    /// 0-based, stored x, y, z.
    Xyz,
}

/// Which colour channel carries the value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RawValue {
    /// r / 256.
    #[default]
    Red,
    /// max(r, g, b) / 256.
    MaxRgb,
}

const RECORD: u64 = 3 * 4 + 4 * 8;

pub fn read(
    file: &str,
    bytes: &[u8],
    with_header: bool,
    default_dims: [usize; 3],
    coords: RawCoords,
    value: RawValue,
    max_bytes: u64,
) -> Result<Loaded, Error> {
    let mut c = Cursor::new(file, bytes);
    let dims = if with_header {
        let mut d = [0usize; 3];
        for (a, name) in ["width", "height", "depth"].iter().enumerate() {
            let v = c.i32(name)?;
            if v < 1 {
                c.pos -= 4;
                return Err(c.err(format!("a positive {name}"), v));
            }
            d[a] = v as usize;
        }
        d
    } else {
        default_dims
    };
    let count = c.i32("the voxel count")?;
    if count < 0 {
        c.pos -= 4;
        return Err(c.err("a voxel count >= 0", count));
    }
    let need = c.pos as u64 + count as u64 * RECORD;
    if need != bytes.len() as u64 {
        return Err(Error::format(
            file,
            format!("byte {}", c.pos - 4),
            format!("a file of {need} bytes for {count} voxels of {RECORD} bytes"),
            format!("{} bytes", bytes.len()),
        ));
    }
    let base = if coords == RawCoords::Thesis { 1 } else { 0 };
    let start = c.pos;
    // The records, replayed for each of the bricking's two passes (the grid is never dense).
    let records = |put: &mut dyn FnMut([usize; 3], f32)| -> Result<(), Error> {
        let mut c = Cursor::new(file, bytes);
        c.pos = start;
        for n in 0..count {
            let at = c.pos;
            let (p, q, r) = (c.i32("x")?, c.i32("coordinate")?, c.i32("coordinate")?);
            let (x, y, z) = match coords {
                RawCoords::Thesis => (p, r, q),
                RawCoords::Xyz => (p, q, r),
            };
            let ijk = [x - base, y - base, z - base];
            if (0..3).any(|a| ijk[a] < 0 || ijk[a] as usize >= dims[a]) {
                let conv = if base == 1 {
                    "1-based x z y"
                } else {
                    "0-based x y z"
                };
                return Err(Error::format(
                    file,
                    format!("byte {at} (voxel {} of {count})", n + 1),
                    format!(
                        "{conv} coordinates within {}×{}×{}",
                        dims[0], dims[1], dims[2]
                    ),
                    format!("({p}, {q}, {r})"),
                ));
            }
            let rgba = [c.f64("r")?, c.f64("g")?, c.f64("b")?, c.f64("a")?];
            let v = match value {
                RawValue::Red => rgba[0] / 256.0,
                RawValue::MaxRgb => rgba[0].max(rgba[1]).max(rgba[2]) / 256.0,
            };
            put(ijk.map(|v| v as usize), v as f32);
        }
        Ok(())
    };
    super::sparse::brick_as_read(file, dims, 0.0, max_bytes, &records)
}

/// Writes a raw file (tests and tools): `header` dims, then the voxels as given (coordinates verbatim).
pub fn encode(header: Option<[i32; 3]>, voxels: &[([i32; 3], [f64; 4])]) -> Vec<u8> {
    let mut out = Vec::new();
    if let Some(d) = header {
        d.iter()
            .for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
    }
    out.extend_from_slice(&(voxels.len() as i32).to_le_bytes());
    for (c, v) in voxels {
        c.iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        v.iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAP: u64 = 1 << 30;

    #[test]
    fn thesis_convention_red_and_max() {
        // Voxel (x=2, y=0, z=1) 0-based on 3×2×2 is stored 1-based as x, z, y = (3, 2, 1).
        let f = encode(Some([3, 2, 2]), &[([3, 2, 1], [128.0, 200.0, 0.0, 1.0])]);
        let red = read(
            "a.raw2",
            &f,
            true,
            [0; 3],
            RawCoords::Thesis,
            RawValue::Red,
            CAP,
        )
        .unwrap();
        assert_eq!(red.dims, [3, 2, 2]);
        let red = red.bricks.unwrap().to_dense();
        assert_eq!(red[2 + 3 * 2], 0.5); // (2, 0, 1)
        assert_eq!(red.iter().filter(|&&v| v != 0.0).count(), 1);
        let max = read(
            "a.raw2",
            &f,
            true,
            [0; 3],
            RawCoords::Thesis,
            RawValue::MaxRgb,
            CAP,
        )
        .unwrap();
        assert_eq!(max.bricks.unwrap().to_dense()[2 + 3 * 2], 200.0 / 256.0);
        let xyz = read(
            "a.raw2",
            &encode(Some([3, 2, 2]), &[([2, 0, 1], [64.0, 0.0, 0.0, 1.0])]),
            true,
            [0; 3],
            RawCoords::Xyz,
            RawValue::Red,
            CAP,
        )
        .unwrap();
        assert_eq!(xyz.bricks.unwrap().to_dense()[2 + 3 * 2], 0.25);
    }

    #[test]
    fn headerless_is_256_cubed() {
        let f = encode(None, &[([256, 256, 256], [256.0, 0.0, 0.0, 1.0])]);
        let g = read(
            "a.raw",
            &f,
            false,
            [256; 3],
            RawCoords::Thesis,
            RawValue::Red,
            CAP,
        )
        .unwrap();
        assert_eq!(g.dims, [256; 3]);
        // One brick stored (the corner's), not 256³ values.
        let grid = g.bricks.unwrap();
        assert_eq!(grid.topology().active_bricks(), 1);
        assert_eq!(grid.at(255, 255, 255), 1.0);
        assert_eq!(grid.at(0, 0, 0), 0.0);
    }

    #[test]
    fn bad_files() {
        let mut f = encode(Some([3, 2, 2]), &[([1, 1, 1], [1.0, 0.0, 0.0, 1.0])]);
        f.pop();
        let e = read(
            "a.raw2",
            &f,
            true,
            [0; 3],
            RawCoords::Thesis,
            RawValue::Red,
            CAP,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("a.raw2: byte 12")
                && e.contains("60 bytes for 1 voxels")
                && e.contains("59 bytes"),
            "{e}"
        );
        let f = encode(Some([3, 2, 2]), &[([4, 1, 1], [1.0, 0.0, 0.0, 1.0])]);
        let e = read(
            "a.raw2",
            &f,
            true,
            [0; 3],
            RawCoords::Thesis,
            RawValue::Red,
            CAP,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("byte 16 (voxel 1 of 1)")
                && e.contains("1-based x z y")
                && e.contains("(4, 1, 1)"),
            "{e}"
        );
        let e = read(
            "a.raw2",
            &encode(Some([0, 2, 2]), &[]),
            true,
            [0; 3],
            RawCoords::Thesis,
            RawValue::Red,
            CAP,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("byte 0") && e.contains("positive width"), "{e}");
        let e = read(
            "a.raw2",
            &[1, 0],
            true,
            [0; 3],
            RawCoords::Thesis,
            RawValue::Red,
            CAP,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("truncated"), "{e}");
        let e = read(
            "a.raw2",
            &encode(Some([1 << 30, 1 << 30, 4]), &[]),
            true,
            [0; 3],
            RawCoords::Thesis,
            RawValue::Red,
            CAP,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("memory cap"), "{e}");
    }
}
