//! The thesis's ASCII formats (Dorta-Perez 2015, section 4.1).
//!
//! **Dense**: the first line holds `w h d`, then w·h·d values separated by white space. The thesis's text shows
//! x varying fastest; its shader code loops with z fastest. [`AxisOrder`] picks one; the default is x fastest.
//!
//! **Sparse** (Uintah export): `w h d`, a voxel count, a background value, then `count` lines `x y z value`
//! with 0-based coordinates; voxels not listed hold the background. A coordinate listed twice keeps its last
//! value.

use super::text::Tokens;
use super::{AxisOrder, Loaded};
use crate::Error;

const MAX_DIM: i64 = 1 << 20;

fn dims(t: &mut Tokens) -> Result<[usize; 3], Error> {
    let w = t.integer("the width w", 1, MAX_DIM)?;
    let h = t.integer("the height h", 1, MAX_DIM)?;
    let d = t.integer("the depth d", 1, MAX_DIM)?;
    Ok([w as usize, h as usize, d as usize])
}

/// Reads a dense ASCII grid.
pub fn read_dense(
    file: &str,
    text: &str,
    order: AxisOrder,
    max_bytes: u64,
) -> Result<Loaded, Error> {
    let mut t = Tokens::new(file, text);
    let dims = dims(&mut t)?;
    let [w, h, d] = dims;
    // Each value takes at least two bytes (a digit and a separator): a header claiming far more values than the
    // text can hold is refused before the grid is allocated (15 bytes claiming 1000³ allocated 4 GB). A small
    // claim is left to the reader, whose error names the first missing value.
    let claimed = (w as u64).saturating_mul(h as u64).saturating_mul(d as u64);
    let room = (text.len() as u64).div_ceil(2);
    let within_cap = claimed.saturating_mul(4) <= max_bytes;
    if within_cap && claimed > room && claimed > 1 << 20 {
        return Err(Error::format(
            file,
            format!("the header `{w} {h} {d}`"),
            format!("at most {room} values in its {} bytes", text.len()),
            format!("a claim of {claimed} values"),
        ));
    }
    let n = w * h * d;
    let body = t.clone();
    // The values, parsed again for each of the bricking's two passes (the grid is never dense).
    let values = |put: &mut dyn FnMut([usize; 3], f32)| -> Result<(), Error> {
        let mut t = body.clone();
        for idx in 0..n {
            let v = t.number_of(|| format!("value {} of {n} (w·h·d = {w}·{h}·{d})", idx + 1))?;
            let ijk = match order {
                AxisOrder::XFastest => [idx % w, (idx / w) % h, idx / (w * h)],
                AxisOrder::ZFastest => {
                    let (z, rest) = (idx % d, idx / d);
                    [rest / h, rest % h, z]
                }
            };
            put(ijk, v as f32);
        }
        t.expect_end(&format!("the {n} values of a {w}×{h}×{d} grid"))
    };
    super::sparse::brick_as_read(file, dims, 0.0, max_bytes, &values)
}

/// Reads a sparse (Uintah) ASCII grid.
pub fn read_sparse(file: &str, text: &str, max_bytes: u64) -> Result<Loaded, Error> {
    let mut t = Tokens::new(file, text);
    let dims = dims(&mut t)?;
    let total = dims.iter().map(|&d| d as i64).product::<i64>();
    let count = t.integer("the voxel count", 0, total)?;
    let background = t.number("the background value")? as f32;
    let body = t.clone();
    // The voxels, parsed again for each of the bricking's two passes (the grid is never dense).
    let voxels = |put: &mut dyn FnMut([usize; 3], f32)| -> Result<(), Error> {
        let mut t = body.clone();
        for n in 0..count {
            let mut ijk = [0usize; 3];
            for (a, axis) in ["x", "y", "z"].iter().enumerate() {
                let what = || {
                    format!(
                        "coordinate {axis} of voxel {} of {count} (0..{})",
                        n + 1,
                        dims[a] - 1
                    )
                };
                ijk[a] = t.integer_of(what, 0, dims[a] as i64 - 1)? as usize;
            }
            let v = t.number_of(|| format!("the value of voxel {} of {count}", n + 1))?;
            put(ijk, v as f32);
        }
        t.expect_end(&format!("{count} voxels"))
    };
    super::sparse::brick_as_read(file, dims, background, max_bytes, &voxels)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAP: u64 = 1 << 30;

    #[test]
    fn dense_x_fastest_and_z_fastest() {
        // 2×2×2 with values 0..8 in file order.
        let text = "2 2 2\n0 1 2 3\n4 5 6 7\n";
        let x = read_dense("f.txt", text, AxisOrder::XFastest, CAP).unwrap();
        assert_eq!(x.dims, [2, 2, 2]);
        assert_eq!(
            x.bricks.unwrap().to_dense(),
            vec![0., 1., 2., 3., 4., 5., 6., 7.]
        );
        let z = read_dense("f.txt", text, AxisOrder::ZFastest, CAP).unwrap();
        let z = z.bricks.unwrap().to_dense();
        // File value n sits at x = n/4, y = (n/2)%2, z = n%2; stored x fastest.
        // (x,y,z)=(1,0,0) is file value 4 → stored index 1.
        assert_eq!(z[1], 4.0);
        assert_eq!(z[2], 2.0); // (0,1,0) ← file 2
        assert_eq!(z[4], 1.0); // (0,0,1) ← file 1
        assert_eq!(z[7], 7.0);
    }

    #[test]
    fn a_header_claiming_more_values_than_the_text_holds_is_refused_before_allocating() {
        // 15 bytes claiming 1000³ values: refused from the file's length, with a cap of 8 GB that would allow it.
        let e = read_dense("bomb.txt", "1000 1000 1000\n", AxisOrder::XFastest, 8 << 30)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("bomb.txt")
                && e.contains("at most 8 values in its 15 bytes")
                && e.contains("1000000000 values"),
            "{e}"
        );
    }

    #[test]
    fn a_value_beyond_f32_is_named_as_written() {
        let e = read_dense("big.txt", "1 1 2\n1 1e39", AxisOrder::XFastest, CAP)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("big.txt: line 2, column 3")
                && e.contains("within f32's range")
                && e.contains("'1e39'"),
            "{e}"
        );
    }

    #[test]
    fn dense_errors_name_line_and_column() {
        let e = read_dense("f.txt", "2 2 2\n0 1 2\n3 x 5 6 7", AxisOrder::XFastest, CAP)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("f.txt: line 3, column 3")
                && e.contains("'x'")
                && e.contains("value 5 of 8"),
            "{e}"
        );
        let e = read_dense("f.txt", "2 2 2\n0 1 2", AxisOrder::XFastest, CAP)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("value 4 of 8") && e.contains("end of the file"),
            "{e}"
        );
        let e = read_dense("f.txt", "1 1 1\n0 1", AxisOrder::XFastest, CAP)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("end of the file after the 1 values") && e.contains("'1'"),
            "{e}"
        );
        let e = read_dense("f.txt", "0 1 1\n", AxisOrder::XFastest, CAP)
            .unwrap_err()
            .to_string();
        assert!(e.contains("width") && e.contains("'0'"), "{e}");
        let e = read_dense(
            "f.txt",
            "1000000 1000000 1000000\n",
            AxisOrder::XFastest,
            CAP,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("memory cap"), "{e}");
    }

    #[test]
    fn sparse_with_background() {
        let text = "3 2 1\n2\n0.5\n0 0 0 7\n2 1 0 9\n";
        let g = read_sparse("s.txt", text, CAP).unwrap();
        assert_eq!(
            g.bricks.unwrap().to_dense(),
            vec![7.0, 0.5, 0.5, 0.5, 0.5, 9.0]
        );
        let e = read_sparse("s.txt", "3 2 1\n1\n0\n3 0 0 1\n", CAP)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("coordinate x of voxel 1 of 1 (0..2)") && e.contains("'3'"),
            "{e}"
        );
        let e = read_sparse("s.txt", "3 2 1\n7\n0\n", CAP)
            .unwrap_err()
            .to_string();
        assert!(e.contains("voxel count") && e.contains("0 to 6"), "{e}");
    }
}
