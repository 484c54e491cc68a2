//! Particle files: PLY (ascii, binary little- or big-endian; the `vertex` element) and CSV (a header row of
//! names, then one particle per row), as simulators and Houdini write them.
//!
//! Each particle has a position, a radius and a temperature, and may have a velocity and an age. Names are
//! matched after lowercasing and dropping everything but letters and digits (`P[x]`, `P.x` and `px` are one
//! name): position `x`/`px`/`posx`/`positionx` (…y, …z); radius `radius`/`pscale`/`r` (or `width`/`diameter`,
//! halved); temperature `temperature`/`temp`/`kelvin`; velocity `vx`/`velx`/`velocityx`/`vvx` (…); age `age`.
//! Other columns are ignored. Sizes are checked against the file before anything is allocated, and every value
//! against its domain, so a malformed file is an error naming the file, the place and the value.

use crate::Error;
use glam::DVec3;

/// One particle as its file gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// Position (medium units).
    pub p: DVec3,
    /// Velocity (medium units per second).
    pub v: DVec3,
    /// Radius (medium units; metres for the cooling).
    pub r: f64,
    /// Temperature (K) at age 0.
    pub t: f64,
    /// Seconds since the particle was born (at the grids' time).
    pub age: f64,
}

/// The most particles a file may hold (the acceleration grid indexes them with u32).
pub const MAX_PARTICLES: usize = 1 << 28;

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Field {
    X,
    Y,
    Z,
    Radius,
    Diameter,
    Temperature,
    Vx,
    Vy,
    Vz,
    Age,
}

fn field(name: &str) -> Option<Field> {
    let n: String = name
        .chars()
        .filter(|c| c.is_ascii_alphanumeric())
        .map(|c| c.to_ascii_lowercase())
        .collect();
    Some(match n.as_str() {
        "x" | "px" | "posx" | "positionx" => Field::X,
        "y" | "py" | "posy" | "positiony" => Field::Y,
        "z" | "pz" | "posz" | "positionz" => Field::Z,
        "radius" | "pscale" | "r" => Field::Radius,
        "width" | "diameter" => Field::Diameter,
        "temperature" | "temp" | "kelvin" => Field::Temperature,
        "vx" | "velx" | "velocityx" | "vvx" => Field::Vx,
        "vy" | "vely" | "velocityy" | "vvy" => Field::Vy,
        "vz" | "velz" | "velocityz" | "vvz" => Field::Vz,
        "age" => Field::Age,
        _ => return None,
    })
}

/// Which column holds each field, checked for the required ones.
struct Columns {
    of: Vec<Option<Field>>,
}

impl Columns {
    fn new(file: &str, names: &[String], at: &str) -> Result<Columns, Error> {
        let of: Vec<Option<Field>> = names.iter().map(|n| field(n)).collect();
        for (need, what) in [
            (&[Field::X][..], "x"),
            (&[Field::Y], "y"),
            (&[Field::Z], "z"),
            (
                &[Field::Radius, Field::Diameter],
                "radius (or pscale, width)",
            ),
            (&[Field::Temperature], "temperature"),
        ] {
            if !of.iter().flatten().any(|f| need.contains(f)) {
                return Err(Error::format(
                    file,
                    at,
                    format!("a particle property named {what}"),
                    format!("properties {}", names.join(", ")),
                ));
            }
        }
        for (i, f) in of.iter().enumerate() {
            if let Some(f) = f {
                if of[..i].contains(&Some(*f)) {
                    return Err(Error::format(
                        file,
                        at,
                        "each particle property once",
                        format!("'{}' a second time", names[i]),
                    ));
                }
            }
        }
        Ok(Columns { of })
    }

    /// The particle of one row's values, each checked; `at(i)` names value i's place.
    fn particle(
        &self,
        file: &str,
        values: &[f64],
        at: &dyn Fn(usize) -> String,
    ) -> Result<Particle, Error> {
        let mut p = Particle {
            p: DVec3::ZERO,
            v: DVec3::ZERO,
            r: 0.0,
            t: 0.0,
            age: 0.0,
        };
        for (i, (&x, f)) in values.iter().zip(&self.of).enumerate() {
            let Some(f) = f else { continue };
            let bad = |expected: &str| {
                Err(Error::format(
                    file,
                    at(i),
                    expected.to_string(),
                    format!("{x}"),
                ))
            };
            let finite_within = |lim: f64| x.is_finite() && x.abs() <= lim;
            match f {
                Field::X | Field::Y | Field::Z if !finite_within(1e9) => {
                    return bad("a position within ±1e9")
                }
                Field::Radius | Field::Diameter if !(x > 0.0 && x <= 1e6) => {
                    return bad("a radius (or width) above 0 and at most 1e6")
                }
                Field::Temperature if !(x.is_finite() && (0.0..=1e6).contains(&x)) => {
                    return bad("a temperature in K from 0 to 1e6")
                }
                Field::Vx | Field::Vy | Field::Vz if !finite_within(1e9) => {
                    return bad("a velocity within ±1e9")
                }
                Field::Age if !(x.is_finite() && (0.0..=1e9).contains(&x)) => {
                    return bad("an age in seconds from 0 to 1e9")
                }
                _ => {}
            }
            match f {
                Field::X => p.p.x = x,
                Field::Y => p.p.y = x,
                Field::Z => p.p.z = x,
                Field::Radius => p.r = x,
                Field::Diameter => p.r = 0.5 * x,
                Field::Temperature => p.t = x,
                Field::Vx => p.v.x = x,
                Field::Vy => p.v.y = x,
                Field::Vz => p.v.z = x,
                Field::Age => p.age = x,
            }
        }
        Ok(p)
    }
}

/// A vector of `n` particles, refused (not aborted) beyond `max_bytes` or the allocator.
fn particles(file: &str, n: usize, max_bytes: u64) -> Result<Vec<Particle>, Error> {
    let bytes = (n as u64).saturating_mul(std::mem::size_of::<Particle>() as u64);
    if n > MAX_PARTICLES || bytes > max_bytes {
        return Err(Error::TooLarge {
            file: file.into(),
            what: format!("{n} particles"),
            bytes,
            cap: max_bytes.min((MAX_PARTICLES * std::mem::size_of::<Particle>()) as u64),
        });
    }
    crate::alloc::with_capacity(n).ok_or_else(|| Error::TooLarge {
        file: file.into(),
        what: format!("{n} particles (the allocator refused)"),
        bytes,
        cap: max_bytes,
    })
}

/// The particles of a PLY or CSV file's bytes (PLY when they begin with `ply`).
pub fn parse(file: &str, bytes: &[u8], max_bytes: u64) -> Result<Vec<Particle>, Error> {
    if bytes.starts_with(b"ply") {
        ply(file, bytes, max_bytes)
    } else {
        csv(file, bytes, max_bytes)
    }
}

#[derive(Clone, Copy, Debug)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn read(self, b: &[u8], big: bool) -> f64 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => get!(i16, 2),
            Scalar::U16 => get!(u16, 2),
            Scalar::I32 => get!(i32, 4),
            Scalar::U32 => get!(u32, 4),
            Scalar::F32 => get!(f32, 4),
            Scalar::F64 => get!(f64, 8),
        }
    }
}

fn ply(file: &str, bytes: &[u8], max_bytes: u64) -> Result<Vec<Particle>, Error> {
    // The header: lines up to `end_header`, within the first 64 kB.
    let head_len = bytes.len().min(65536);
    let end = bytes[..head_len]
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| {
            Error::format(
                file,
                "byte 0",
                "a PLY header ending in end_header within 64 kB",
                "no end_header",
            )
        })?;
    let mut body = end + 10;
    if bytes.get(body) == Some(&b'\r') {
        body += 1;
    }
    if bytes.get(body) == Some(&b'\n') {
        body += 1;
    }
    let header = super::as_text(file, &bytes[..end])?;
    let (mut format, mut count, mut props) = (None, None::<usize>, Vec::<(Scalar, String)>::new());
    let mut in_vertex = false;
    let mut seen_element = false;
    for (ln, line) in header.lines().enumerate() {
        let at = || format!("line {}", ln + 1);
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["ply"] | [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, "1.0"] => {
                format = Some(match *f {
                    "ascii" => 0,
                    "binary_little_endian" => 1,
                    "binary_big_endian" => 2,
                    _ => {
                        return Err(Error::format(
                            file,
                            at(),
                            "format ascii, binary_little_endian or binary_big_endian",
                            line,
                        ))
                    }
                })
            }
            ["element", name, n] => {
                if seen_element {
                    // Elements after the vertices are not read.
                    in_vertex = false;
                    continue;
                }
                if *name != "vertex" {
                    return Err(Error::format(
                        file,
                        at(),
                        "the vertex element first (the particles)",
                        line,
                    ));
                }
                seen_element = true;
                in_vertex = true;
                count = Some(n.parse().map_err(|_| {
                    Error::format(file, at(), "a particle count", format!("'{n}'"))
                })?);
            }
            ["property", "list", ..] if in_vertex => {
                return Err(Error::format(file, at(), "scalar vertex properties", line))
            }
            ["property", ty, name] if in_vertex => {
                let s = Scalar::from_name(ty).ok_or_else(|| {
                    Error::format(
                        file,
                        at(),
                        "a PLY scalar type (char, uchar, short, ushort, int, uint, float, double)",
                        format!("'{ty}'"),
                    )
                })?;
                props.push((s, name.to_string()));
            }
            ["property", ..] => {}
            _ => return Err(Error::format(file, at(), "a PLY header line", line)),
        }
    }
    let format =
        format.ok_or_else(|| Error::format(file, "the header", "a format line", "none"))?;
    let n = count.ok_or_else(|| {
        Error::format(file, "the header", "element vertex N", "no vertex element")
    })?;
    let names: Vec<String> = props.iter().map(|p| p.1.clone()).collect();
    let cols = Columns::new(file, &names, "the header")?;
    let data = &bytes[body..];
    let mut out;
    let mut values = vec![0.0; props.len()];
    if format == 0 {
        // At least two bytes per value ("0 ") must be there before the particles are allocated.
        if (n as u128) * (2 * props.len().max(1)) as u128 > data.len() as u128 {
            return Err(Error::format(
                file,
                format!("byte {body}"),
                format!("{n} particles of {} values", props.len()),
                format!("{} bytes of data", data.len()),
            ));
        }
        let text = super::as_text(file, data)?;
        out = particles(file, n, max_bytes)?;
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let head_lines = header.lines().count() + 1;
        for k in 0..n {
            let Some((ln, line)) = lines.next() else {
                return Err(Error::format(
                    file,
                    "the end",
                    format!("{n} particles"),
                    format!("{k}"),
                ));
            };
            let mut it = line.split_whitespace();
            for (i, v) in values.iter_mut().enumerate() {
                let tok = it.next().unwrap_or("");
                *v = tok.parse().map_err(|_| {
                    Error::format(
                        file,
                        format!("line {}, value {}", head_lines + ln, i + 1),
                        format!("a number ({})", names[i]),
                        format!("'{tok}'"),
                    )
                })?;
            }
            let line_no = head_lines + ln;
            out.push(cols.particle(file, &values, &|i| format!("line {line_no} ({})", names[i]))?);
        }
    } else {
        let big = format == 2;
        let stride: usize = props.iter().map(|p| p.0.size()).sum();
        let need = (n as u128) * stride as u128;
        if need > data.len() as u128 {
            return Err(Error::format(
                file,
                format!("byte {body}"),
                format!("{n} particles of {stride} bytes ({need} bytes)"),
                format!("{} bytes", data.len()),
            ));
        }
        out = particles(file, n, max_bytes)?;
        for k in 0..n {
            let rec = &data[k * stride..(k + 1) * stride];
            let mut off = 0;
            for (v, (s, _)) in values.iter_mut().zip(&props) {
                *v = s.read(&rec[off..], big);
                off += s.size();
            }
            let base = body + k * stride;
            out.push(cols.particle(file, &values, &|i| {
                format!("byte {base} (particle {k}, {})", names[i])
            })?);
        }
    }
    Ok(out)
}

fn csv(file: &str, bytes: &[u8], max_bytes: u64) -> Result<Vec<Particle>, Error> {
    let text = super::as_text(file, bytes)?;
    let mut rows = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((hl, header)) = rows.next() else {
        return Err(Error::format(
            file,
            "line 1",
            "a header row naming the columns (x,y,z,radius,temperature,…)",
            "an empty file",
        ));
    };
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
    let cols = Columns::new(file, &names, &format!("line {}", hl + 1))?;
    // Each row is at least one byte per column: the count bounds the allocation by the file's size.
    let n = text.lines().count().saturating_sub(hl + 1);
    let mut out = particles(file, n.min(MAX_PARTICLES + 1), max_bytes)?;
    let mut values = vec![0.0; names.len()];
    for (ln, row) in rows {
        let cells: Vec<&str> = row.split(',').map(str::trim).collect();
        if cells.len() != names.len() {
            return Err(Error::format(
                file,
                format!("line {}", ln + 1),
                format!("{} columns, as the header", names.len()),
                format!("{}", cells.len()),
            ));
        }
        for (i, (v, c)) in values.iter_mut().zip(&cells).enumerate() {
            if cols.of[i].is_none() {
                continue;
            }
            *v = c.parse().map_err(|_| {
                Error::format(
                    file,
                    format!("line {}, column {}", ln + 1, i + 1),
                    format!("a number ({})", names[i]),
                    format!("'{c}'"),
                )
            })?;
        }
        out.push(cols.particle(file, &values, &|i| {
            format!("line {}, column {} ({})", ln + 1, i + 1, names[i])
        })?);
    }
    Ok(out)
}
