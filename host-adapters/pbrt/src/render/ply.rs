//! PLY meshes for `plymesh`: ascii, binary_little_endian and binary_big_endian; vertex `x y z` with optional
//! `nx ny nz` and `u v` (or `s t`, `texture_u texture_v`); faces as index lists (triangles and quads, quads split).
//! Errors name the file and what was expected.

use std::path::Path;

/// (positions xyz…, triangle indices, normals, uvs).
pub type Mesh = (Vec<f64>, Vec<usize>, Option<Vec<f64>>, Option<Vec<f64>>);

#[derive(Debug, Clone, Copy, PartialEq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

fn ty(s: &str) -> Option<Ty> {
    Some(match s {
        "char" | "int8" => Ty::I8,
        "uchar" | "uint8" => Ty::U8,
        "short" | "int16" => Ty::I16,
        "ushort" | "uint16" => Ty::U16,
        "int" | "int32" => Ty::I32,
        "uint" | "uint32" => Ty::U32,
        "float" | "float32" => Ty::F32,
        "double" | "float64" => Ty::F64,
        _ => return None,
    })
}

fn size(t: Ty) -> usize {
    match t {
        Ty::I8 | Ty::U8 => 1,
        Ty::I16 | Ty::U16 => 2,
        Ty::I32 | Ty::U32 | Ty::F32 => 4,
        Ty::F64 => 8,
    }
}

enum Prop {
    Scalar(String, Ty),
    List(String, Ty, Ty),
}

struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

struct Reader<'a> {
    data: &'a [u8],
    pos: usize,
    ascii: bool,
    big: bool,
    file: String,
}

impl Reader<'_> {
    fn read(&mut self, t: Ty) -> Result<f64, crate::Error> {
        if self.ascii {
            while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            let start = self.pos;
            while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
                self.pos += 1;
            }
            let s = std::str::from_utf8(&self.data[start..self.pos]).unwrap_or("");
            return s.parse::<f64>().map_err(|_| {
                crate::Error::file(
                    &self.file,
                    format!("byte {start}: expected a number, found '{s}'"),
                )
            });
        }
        let n = size(t);
        let b = self.data.get(self.pos..self.pos + n).ok_or_else(|| {
            crate::Error::file(
                &self.file,
                format!(
                    "byte {}: expected {n} more bytes, found the end of the file",
                    self.pos
                ),
            )
        })?;
        self.pos += n;
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(b);
        if self.big {
            a[..n].reverse();
        }
        Ok(match t {
            Ty::I8 => a[0] as i8 as f64,
            Ty::U8 => a[0] as f64,
            Ty::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Ty::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Ty::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Ty::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Ty::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Ty::F64 => f64::from_le_bytes(a),
        })
    }
}

/// Reads a PLY mesh, gzip-compressed or not (pbrt-v4-scenes ship `.ply.gz`); a compressed file may inflate to
/// at most `budget` bytes.
pub fn read(path: &Path, budget: u64) -> Result<Mesh, crate::Error> {
    let file = path.display().to_string();
    let data = firemedium_pbrt_parser::read_regular_file(path)
        .map_err(|e| crate::Error::file(&file, format!("cannot read: {e}")))?;
    if data.starts_with(&[0x1f, 0x8b]) {
        let plain = gunzip(&file, &data, budget)?;
        return parse(&file, &plain);
    }
    parse(&file, &data)
}

/// The payload of a gzip member (RFC 1952): its header, its raw deflate stream inflated to at most `budget`
/// bytes (a few bytes can claim gigabytes), and the length its trailer states checked.
pub fn gunzip(file: &str, data: &[u8], budget: u64) -> Result<Vec<u8>, crate::Error> {
    let bad = |what: &str| crate::Error::file(file, format!("not a valid gzip file: {what}"));
    if data.len() < 18 || data[2] != 8 {
        return Err(bad("expected a deflate member of at least 18 bytes"));
    }
    let flags = data[3];
    let mut pos = 10usize;
    if flags & 4 != 0 {
        // FEXTRA: a little-endian length, then that many bytes.
        let n = data
            .get(pos..pos + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]) as usize)
            .ok_or_else(|| bad("the extra field ends early"))?;
        pos += 2 + n;
    }
    for flag in [8u8, 16] {
        // FNAME, FCOMMENT: zero-terminated.
        if flags & flag != 0 {
            let end = data
                .get(pos..)
                .and_then(|rest| rest.iter().position(|&b| b == 0))
                .ok_or_else(|| bad("a header string does not end"))?;
            pos += end + 1;
        }
    }
    if flags & 2 != 0 {
        pos += 2; // FHCRC
    }
    let body = data
        .get(pos..data.len().saturating_sub(8))
        .ok_or_else(|| bad("the header runs past the data"))?;
    let limit = usize::try_from(budget).unwrap_or(usize::MAX);
    let out = miniz_oxide::inflate::decompress_to_vec_with_limit(body, limit).map_err(|e| {
        if e.status == miniz_oxide::inflate::TINFLStatus::HasMoreOutput {
            crate::Error::file(
                file,
                format!("inflates to more than the memory budget of {budget} bytes"),
            )
        } else {
            bad(&format!("{e}"))
        }
    })?;
    let t = &data[data.len() - 4..];
    let isize = u32::from_le_bytes([t[0], t[1], t[2], t[3]]);
    if out.len() as u32 != isize {
        return Err(bad(&format!(
            "it inflates to {} bytes, its trailer says {isize}",
            out.len()
        )));
    }
    Ok(out)
}

/// Parses a PLY mesh held in memory (`file` names it in errors).
pub fn parse(file: &str, data: &[u8]) -> Result<Mesh, crate::Error> {
    let end = data
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| crate::Error::file(file, "expected a PLY header ending in end_header"))?;
    let header = std::str::from_utf8(&data[..end])
        .map_err(|_| crate::Error::file(file, "the PLY header is not text"))?;
    let mut lines = header.lines();
    if lines.next().map(str::trim) != Some("ply") {
        return Err(crate::Error::file(
            file,
            "expected the magic 'ply' on the first line",
        ));
    }
    let (mut ascii, mut big) = (false, false);
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in lines.enumerate() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["format", f, _] => match *f {
                "ascii" => ascii = true,
                "binary_little_endian" => {}
                "binary_big_endian" => big = true,
                other => {
                    return Err(crate::Error::file(
                        file,
                        format!("line {}: unknown PLY format '{other}'", i + 2),
                    ))
                }
            },
            ["element", name, count] => elements.push(Element {
                name: name.to_string(),
                count: count.parse().map_err(|_| {
                    crate::Error::file(file, format!("line {}: bad element count '{count}'", i + 2))
                })?,
                props: Vec::new(),
            }),
            ["property", "list", ct, it, name] => {
                let (c, t) = (
                    ty(ct).ok_or_else(|| {
                        crate::Error::file(file, format!("line {}: unknown type '{ct}'", i + 2))
                    })?,
                    ty(it).ok_or_else(|| {
                        crate::Error::file(file, format!("line {}: unknown type '{it}'", i + 2))
                    })?,
                );
                elements
                    .last_mut()
                    .ok_or_else(|| {
                        crate::Error::file(
                            file,
                            format!("line {}: property before any element", i + 2),
                        )
                    })?
                    .props
                    .push(Prop::List(name.to_string(), c, t));
            }
            ["property", t, name] => {
                let t = ty(t).ok_or_else(|| {
                    crate::Error::file(file, format!("line {}: unknown type '{t}'", i + 2))
                })?;
                elements
                    .last_mut()
                    .ok_or_else(|| {
                        crate::Error::file(
                            file,
                            format!("line {}: property before any element", i + 2),
                        )
                    })?
                    .props
                    .push(Prop::Scalar(name.to_string(), t));
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            _ => {
                return Err(crate::Error::file(
                    file,
                    format!("line {}: unexpected header line '{line}'", i + 2),
                ))
            }
        }
    }
    let mut body_start = end + "end_header".len();
    while body_start < data.len() && (data[body_start] == b'\r' || data[body_start] == b'\n') {
        body_start += 1;
        if !ascii && data[body_start - 1] == b'\n' {
            break;
        }
    }
    let mut r = Reader {
        data,
        pos: body_start,
        ascii,
        big,
        file: file.to_string(),
    };
    let (mut pos, mut normals, mut uvs, mut idx) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for el in &elements {
        if el.count > data.len() {
            return Err(crate::Error::file(
                file,
                format!(
                    "element '{}' claims {} entries in a {}-byte file",
                    el.name,
                    el.count,
                    data.len()
                ),
            ));
        }
        for _ in 0..el.count {
            let mut v = [f64::NAN; 8]; // x y z nx ny nz u v
            for p in &el.props {
                match p {
                    Prop::Scalar(name, t) => {
                        let x = r.read(*t)?;
                        let slot = match name.as_str() {
                            "x" => 0,
                            "y" => 1,
                            "z" => 2,
                            "nx" => 3,
                            "ny" => 4,
                            "nz" => 5,
                            "u" | "s" | "texture_u" | "texture_s" => 6,
                            "v" | "t" | "texture_v" | "texture_t" => 7,
                            _ => continue,
                        };
                        v[slot] = x;
                    }
                    Prop::List(name, ct, it) => {
                        let n = r.read(*ct)? as usize;
                        if n > 64 {
                            return Err(crate::Error::file(
                                file,
                                format!("a face of {n} vertices (expected 3 or 4)"),
                            ));
                        }
                        let ids: Vec<usize> = (0..n)
                            .map(|_| r.read(*it).map(|x| x as usize))
                            .collect::<Result<_, _>>()?;
                        if el.name == "face" && (name == "vertex_indices" || name == "vertex_index")
                        {
                            match ids.len() {
                                3 => idx.extend_from_slice(&ids),
                                4 => idx.extend_from_slice(&[
                                    ids[0], ids[1], ids[2], ids[0], ids[2], ids[3],
                                ]),
                                k => {
                                    return Err(crate::Error::file(
                                        file,
                                        format!("a face of {k} vertices (expected 3 or 4)"),
                                    ))
                                }
                            }
                        }
                    }
                }
            }
            if el.name == "vertex" {
                pos.extend_from_slice(&v[..3]);
                normals.extend_from_slice(&v[3..6]);
                uvs.extend_from_slice(&v[6..8]);
            }
        }
    }
    if pos.iter().any(|x| x.is_nan()) {
        return Err(crate::Error::file(file, "vertices need x, y and z"));
    }
    let nv = pos.len() / 3;
    if let Some(&bad) = idx.iter().find(|&&i| i >= nv) {
        return Err(crate::Error::file(
            file,
            format!("face index {bad} is not below the {nv} vertices"),
        ));
    }
    let normals = (!normals.iter().any(|x| x.is_nan())).then_some(normals);
    let uvs = (!uvs.iter().any(|x| x.is_nan())).then_some(uvs);
    Ok((pos, idx, normals, uvs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_and_binary_quads() {
        let dir = std::env::temp_dir().join(format!("firemedium-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = dir.join("a.ply");
        std::fs::write(&a, "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n").unwrap();
        let (p, i, n, uv) = read(&a, u64::MAX).unwrap();
        assert_eq!(
            (p.len(), i, n.is_none(), uv.is_none()),
            (12, vec![0, 1, 2, 0, 2, 3], true, true)
        );
        let b = dir.join("b.ply");
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
        for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes.push(3);
        for k in [0i32, 1, 2] {
            bytes.extend_from_slice(&k.to_le_bytes());
        }
        std::fs::write(&b, &bytes).unwrap();
        assert_eq!(read(&b, u64::MAX).unwrap().1, vec![0, 1, 2]);
        bytes.truncate(bytes.len() - 2);
        std::fs::write(&b, &bytes).unwrap();
        assert!(read(&b, u64::MAX)
            .unwrap_err()
            .to_string()
            .contains("end of the file"));
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A gzip member of `data` (header without options, deflate, CRC left zero, the length).
    pub(crate) fn gzip(data: &[u8]) -> Vec<u8> {
        let mut gz = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 0xff];
        gz.extend(miniz_oxide::deflate::compress_to_vec(data, 6));
        gz.extend([0u8; 4]);
        gz.extend((data.len() as u32).to_le_bytes());
        gz
    }

    #[test]
    fn gzipped_meshes_read_and_bombs_are_refused() {
        let dir = std::env::temp_dir().join(format!("firemedium-plygz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let f = dir.join("m.ply.gz");
        std::fs::write(&f, gzip(text.as_bytes())).unwrap();
        assert_eq!(read(&f, 1 << 20).unwrap().1, vec![0, 1, 2]);
        // 16 MB of zeros in 16 KB: refused at a 1 MB budget before it is inflated past it.
        let bomb = gzip(&vec![0u8; 16 << 20]);
        assert!(bomb.len() < 64 << 10);
        std::fs::write(&f, &bomb).unwrap();
        let e = read(&f, 1 << 20).unwrap_err().to_string();
        assert!(e.contains("m.ply.gz") && e.contains("memory budget"), "{e}");
        // A truncated member names what is wrong.
        std::fs::write(&f, &bomb[..12]).unwrap();
        assert!(read(&f, 1 << 20)
            .unwrap_err()
            .to_string()
            .contains("not a valid gzip file"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
