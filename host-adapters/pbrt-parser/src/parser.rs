//! Tokens → directives. See the crate docs.

use crate::tokenizer::{Token, TokenKind, Tokenizer};
use crate::{Loc, ParseError};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Values of a parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// Numeric types (integer values are integral).
    Numbers(Vec<f64>),
    /// `string`, `texture`, or a named `spectrum`.
    Strings(Vec<String>),
    /// `bool`.
    Bools(Vec<bool>),
}

/// One `"type name" values` parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Type as written (`float`, `rgb`, …; pbrt-v3 spellings normalised: `point` → `point3`, `vector` →
    /// `vector3`, `normal3` → `normal`, `color` → `rgb`).
    pub ty: String,
    /// Name.
    pub name: String,
    /// Values.
    pub values: Values,
    /// Where the declaration is.
    pub loc: Loc,
}

impl Param {
    /// The numbers, if numeric.
    pub fn numbers(&self) -> Option<&[f64]> {
        match &self.values {
            Values::Numbers(v) => Some(v),
            _ => None,
        }
    }
    /// The strings, if textual.
    pub fn strings(&self) -> Option<&[String]> {
        match &self.values {
            Values::Strings(v) => Some(v),
            _ => None,
        }
    }
    /// The bools, if boolean.
    pub fn bools(&self) -> Option<&[bool]> {
        match &self.values {
            Values::Bools(v) => Some(v),
            _ => None,
        }
    }
}

/// `ActiveTransform` targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ActiveTransform {
    /// `StartTime`
    StartTime,
    /// `EndTime`
    EndTime,
    /// `All`
    All,
}

/// A scene directive with its arguments. `Include`/`Import` are followed by the parser and never delivered.
#[derive(Debug, Clone, PartialEq)]
pub enum Directive {
    Identity,
    Translate([f64; 3]),
    Scale([f64; 3]),
    /// Angle in degrees, axis.
    Rotate(f64, [f64; 3]),
    /// Eye, look-at point, up.
    LookAt([f64; 9]),
    /// A 4×4 matrix, column-major as pbrt writes it.
    Transform([f64; 16]),
    ConcatTransform([f64; 16]),
    CoordinateSystem(String),
    CoordSysTransform(String),
    TransformTimes(f64, f64),
    ActiveTransform(ActiveTransform),
    ReverseOrientation,
    AttributeBegin,
    AttributeEnd,
    /// `Attribute "shape|light|material|medium|texture" params`
    Attribute(String, Vec<Param>),
    /// Deprecated in pbrt-v4 (kept working, as pbrt does).
    TransformBegin,
    TransformEnd,
    ObjectBegin(String),
    ObjectEnd,
    ObjectInstance(String),
    Option(Param),
    ColorSpace(String),
    Camera(String, Vec<Param>),
    Film(String, Vec<Param>),
    Sampler(String, Vec<Param>),
    Integrator(String, Vec<Param>),
    PixelFilter(String, Vec<Param>),
    Accelerator(String, Vec<Param>),
    WorldBegin,
    LightSource(String, Vec<Param>),
    AreaLightSource(String, Vec<Param>),
    Material(String, Vec<Param>),
    MakeNamedMaterial(String, Vec<Param>),
    NamedMaterial(String),
    /// Name, value type (`spectrum`/`float`), class, params.
    Texture(String, String, String, Vec<Param>),
    Shape(String, Vec<Param>),
    MakeNamedMedium(String, Vec<Param>),
    /// Inside, outside.
    MediumInterface(String, String),
}

/// Receives directives in file order.
pub trait Target {
    /// One directive at `loc`; an error stops parsing.
    fn directive(&mut self, d: Directive, loc: &Loc) -> Result<(), ParseError>;
}

/// A target that records every directive.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Collect(pub Vec<(Directive, Loc)>);

impl Target for Collect {
    fn directive(&mut self, d: Directive, loc: &Loc) -> Result<(), ParseError> {
        self.0.push((d, loc.clone()));
        Ok(())
    }
}

const MAX_INCLUDE_DEPTH: usize = 64;

/// The most `Include`s one scene may follow, counting each time a file is included (a file included twice by
/// each of 40 files in a chain — a diamond, neither a cycle nor deep — is 2⁴⁰ parses; a production scene's
/// geometry includes number in the thousands).
const MAX_INCLUDES: u64 = 1 << 16;

/// The most bytes of scene text one scene may parse, its includes' repeats counted.
const MAX_SCENE_BYTES: u64 = 1 << 36;

/// The files being included (the chain from the scene file) and what the whole parse has read so far.
#[derive(Debug, Default)]
struct Includes {
    stack: Vec<PathBuf>,
    count: u64,
    bytes: u64,
}

/// Parses the scene file at `path` (and everything it includes) into `target`.
pub fn parse_file(path: &Path, target: &mut dyn Target) -> Result<(), ParseError> {
    let loc = Loc {
        file: Arc::from(path.display().to_string()),
        line: 0,
        col: 0,
    };
    parse_path(path, target, &mut Includes::default(), &loc)
}

/// Parses scene text; `name` labels positions and `dir` resolves relative `Include`s.
pub fn parse_str(
    name: &str,
    text: &str,
    dir: &Path,
    target: &mut dyn Target,
) -> Result<(), ParseError> {
    let mut p = Parser {
        tok: Tokenizer::new(Arc::from(name), text),
        peeked: None,
        dir: dir.to_path_buf(),
        stack: Includes::default(),
    };
    p.run(target)
}

fn parse_path(
    path: &Path,
    target: &mut dyn Target,
    inc: &mut Includes,
    from: &Loc,
) -> Result<(), ParseError> {
    let canon = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    if inc.stack.contains(&canon) {
        return Err(ParseError::new(
            from,
            format!("{} includes itself (an Include cycle)", path.display()),
        ));
    }
    if inc.stack.len() >= MAX_INCLUDE_DEPTH {
        return Err(ParseError::new(
            from,
            format!("Includes nested deeper than {MAX_INCLUDE_DEPTH}"),
        ));
    }
    inc.count += 1;
    if inc.count > MAX_INCLUDES {
        return Err(ParseError::new(
            from,
            format!(
                "{}: the scene's Include number {}: expected at most {MAX_INCLUDES} (files that include another more than once in a chain multiply: is a file included twice at each level?)",
                path.display(),
                inc.count
            ),
        ));
    }
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    inc.bytes = inc.bytes.saturating_add(len);
    if inc.bytes > MAX_SCENE_BYTES {
        return Err(ParseError::new(
            from,
            format!(
                "{} ({len} bytes): the scene's text, its includes counted each time, reaches {} bytes: expected at most {MAX_SCENE_BYTES}",
                path.display(),
                inc.bytes
            ),
        ));
    }
    let bytes = crate::read_regular_file(path)
        .map_err(|e| ParseError::new(from, format!("cannot read {}: {e}", path.display())))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        // Position of the bad byte: lines and characters of the valid prefix.
        let prefix = std::str::from_utf8(&e.as_bytes()[..at]).unwrap_or("");
        let line = prefix.matches('\n').count() as u32 + 1;
        let col = prefix.rsplit('\n').next().map_or(0, |l| l.chars().count()) as u32 + 1;
        ParseError::new(
            &Loc {
                file: Arc::from(path.display().to_string()),
                line,
                col,
            },
            format!("byte {at}: not UTF-8 text"),
        )
    })?;
    inc.stack.push(canon);
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut p = Parser {
        tok: Tokenizer::new(Arc::from(path.display().to_string()), &text),
        peeked: None,
        dir,
        stack: std::mem::take(inc),
    };
    let r = p.run(target);
    *inc = std::mem::take(&mut p.stack);
    inc.stack.pop();
    r
}

struct Parser<'a> {
    tok: Tokenizer<'a>,
    peeked: Option<Token>,
    dir: PathBuf,
    stack: Includes,
}

const TYPES: [&str; 17] = [
    "integer",
    "float",
    "point2",
    "vector2",
    "point3",
    "vector3",
    "normal",
    "normal3",
    "point",
    "vector",
    "color",
    "rgb",
    "spectrum",
    "blackbody",
    "bool",
    "string",
    "texture",
];

impl Parser<'_> {
    fn next(&mut self) -> Result<Option<Token>, ParseError> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.tok.next(),
        }
    }
    fn peek(&mut self) -> Result<Option<&Token>, ParseError> {
        if self.peeked.is_none() {
            self.peeked = self.tok.next()?;
        }
        Ok(self.peeked.as_ref())
    }
    fn expect(&mut self, what: &str, after: &Loc) -> Result<Token, ParseError> {
        self.next()?.ok_or_else(|| {
            ParseError::new(after, format!("expected {what}, found the end of the file"))
        })
    }

    fn string(&mut self, what: &str, after: &Loc) -> Result<String, ParseError> {
        let t = self.expect(what, after)?;
        if t.kind != TokenKind::Str {
            return Err(ParseError::new(
                &t.loc,
                format!("expected {what} (a quoted string), found '{}'", t.text),
            ));
        }
        Ok(t.text)
    }

    fn number(&mut self, what: &str, after: &Loc) -> Result<f64, ParseError> {
        let t = self.expect(what, after)?;
        match (t.kind, t.text.parse::<f64>()) {
            (TokenKind::Word, Ok(v)) if v.is_finite() => Ok(v),
            _ => Err(ParseError::new(
                &t.loc,
                format!("expected {what} (a number), found '{}'", t.text),
            )),
        }
    }

    fn numbers<const N: usize>(&mut self, what: &str, after: &Loc) -> Result<[f64; N], ParseError> {
        let mut out = [0.0; N];
        for (i, v) in out.iter_mut().enumerate() {
            *v = self.number(&format!("{what} (value {} of {N})", i + 1), after)?;
        }
        Ok(out)
    }

    /// `[ 16 numbers ]` (the brackets are optional, as pbrt-v4 accepts).
    fn matrix(&mut self, what: &str, after: &Loc) -> Result<[f64; 16], ParseError> {
        let bracket = matches!(self.peek()?, Some(t) if t.kind == TokenKind::Open);
        if bracket {
            self.next()?;
        }
        let m = self.numbers::<16>(what, after)?;
        if bracket {
            let t = self.expect("']' after 16 numbers", after)?;
            if t.kind != TokenKind::Close {
                return Err(ParseError::new(
                    &t.loc,
                    format!(
                        "expected ']' after the 16 numbers of {what}, found '{}'",
                        t.text
                    ),
                ));
            }
        }
        Ok(m)
    }

    /// `"type name" value | [values]` pairs until the next directive.
    fn params(&mut self) -> Result<Vec<Param>, ParseError> {
        let mut out: Vec<Param> = Vec::new();
        let mut seen = std::collections::HashSet::new();
        while let Some(t) = self.peek()? {
            if t.kind != TokenKind::Str {
                break;
            }
            let decl = self.next()?.unwrap_or_else(|| unreachable!("peeked"));
            let parts: Vec<&str> = decl.text.split_whitespace().collect();
            if parts.len() != 2 {
                return Err(ParseError::new(
                    &decl.loc,
                    format!(
                        "expected a parameter declaration \"type name\", found \"{}\"",
                        decl.text
                    ),
                ));
            }
            let ty = match parts[0] {
                "point" => "point3",
                "vector" => "vector3",
                "normal3" => "normal",
                "color" => "rgb",
                t if TYPES.contains(&t) => t,
                t => {
                    return Err(ParseError::new(
                        &decl.loc,
                        format!(
                            "unknown parameter type '{t}' (expected one of {})",
                            TYPES.join(", ")
                        ),
                    ))
                }
            };
            let name = parts[1].to_string();
            // (A set, not a scan of `out`: 200 000 parameters took quadratic time.)
            if !seen.insert(name.clone()) {
                return Err(ParseError::new(
                    &decl.loc,
                    format!("parameter '{name}' given twice"),
                ));
            }
            // Values: one token or a bracketed list.
            let mut raw = Vec::new();
            let first = self.expect(&format!("a value for \"{}\"", decl.text), &decl.loc)?;
            match first.kind {
                TokenKind::Open => loop {
                    let t =
                        self.expect(&format!("a value or ']' for \"{}\"", decl.text), &decl.loc)?;
                    match t.kind {
                        TokenKind::Close => break,
                        TokenKind::Open => {
                            return Err(ParseError::new(
                                &t.loc,
                                "expected a value or ']', found a nested '['",
                            ))
                        }
                        _ => raw.push(t),
                    }
                },
                TokenKind::Close => {
                    return Err(ParseError::new(
                        &first.loc,
                        format!("expected a value for \"{}\", found ']'", decl.text),
                    ))
                }
                _ => raw.push(first),
            }
            let values = match ty {
                "bool" => Values::Bools(
                    raw.iter()
                        .map(|t| match t.text.as_str() {
                            "true" => Ok(true),
                            "false" => Ok(false),
                            s => Err(ParseError::new(&t.loc, format!("expected true or false for \"{}\", found '{s}'", decl.text))),
                        })
                        .collect::<Result<_, _>>()?,
                ),
                "string" | "texture" => Values::Strings(
                    raw.iter()
                        .map(|t| if t.kind == TokenKind::Str { Ok(t.text.clone()) } else { Err(ParseError::new(&t.loc, format!("expected a quoted string for \"{}\", found '{}'", decl.text, t.text))) })
                        .collect::<Result<_, _>>()?,
                ),
                "spectrum" if raw.first().is_some_and(|t| t.kind == TokenKind::Str) => Values::Strings(
                    raw.iter()
                        .map(|t| if t.kind == TokenKind::Str { Ok(t.text.clone()) } else { Err(ParseError::new(&t.loc, format!("expected a spectrum name or file for \"{}\", found '{}'", decl.text, t.text))) })
                        .collect::<Result<_, _>>()?,
                ),
                _ => {
                    let mut v = Vec::with_capacity(raw.len());
                    for t in &raw {
                        let x = match (t.kind, t.text.parse::<f64>()) {
                            (TokenKind::Word, Ok(x)) if x.is_finite() => x,
                            _ => return Err(ParseError::new(&t.loc, format!("expected a number for \"{}\", found '{}'", decl.text, t.text))),
                        };
                        if ty == "integer" && x.fract() != 0.0 {
                            return Err(ParseError::new(&t.loc, format!("expected an integer for \"{}\", found '{}'", decl.text, t.text)));
                        }
                        v.push(x);
                    }
                    let per = match ty {
                        "point2" | "vector2" => 2,
                        "point3" | "vector3" | "normal" | "rgb" => 3,
                        _ => 1,
                    };
                    if v.len() % per != 0 || (ty == "spectrum" && v.len() > 1 && v.len() % 2 != 0) || (ty == "blackbody" && v.len() != 1) {
                        let want = match ty {
                            "spectrum" => "one value or (wavelength, value) pairs".to_string(),
                            "blackbody" => "one temperature".to_string(),
                            _ => format!("a multiple of {per} values"),
                        };
                        return Err(ParseError::new(&decl.loc, format!("\"{}\": expected {want}, found {} values", decl.text, v.len())));
                    }
                    Values::Numbers(v)
                }
            };
            out.push(Param {
                ty: ty.to_string(),
                name,
                values,
                loc: decl.loc,
            });
        }
        Ok(out)
    }

    fn run(&mut self, target: &mut dyn Target) -> Result<(), ParseError> {
        while let Some(t) = self.next()? {
            let loc = t.loc.clone();
            if t.kind != TokenKind::Word {
                return Err(ParseError::new(
                    &loc,
                    format!(
                        "expected a directive, found {}",
                        if t.kind == TokenKind::Str {
                            format!("\"{}\" (a parameter without a directive?)", t.text)
                        } else {
                            format!("'{}'", t.text)
                        }
                    ),
                ));
            }
            let d = match t.text.as_str() {
                "Include" | "Import" => {
                    let file = self.string(&format!("the file to {}", t.text), &loc)?;
                    let path = if Path::new(&file).is_absolute() {
                        PathBuf::from(&file)
                    } else {
                        self.dir.join(&file)
                    };
                    let mut stack = std::mem::take(&mut self.stack);
                    let r = parse_path(&path, target, &mut stack, &loc).map_err(|e| {
                        if e.loc == loc {
                            ParseError::new(&loc, format!("{} \"{file}\": {}", t.text, e.message))
                        } else {
                            e
                        }
                    });
                    self.stack = stack;
                    r?;
                    continue;
                }
                "Identity" => Directive::Identity,
                "Translate" => Directive::Translate(self.numbers("Translate", &loc)?),
                "Scale" => Directive::Scale(self.numbers("Scale", &loc)?),
                "Rotate" => {
                    let a = self.numbers::<4>("Rotate", &loc)?;
                    Directive::Rotate(a[0], [a[1], a[2], a[3]])
                }
                "LookAt" => Directive::LookAt(self.numbers("LookAt", &loc)?),
                "Transform" => Directive::Transform(self.matrix("Transform", &loc)?),
                "ConcatTransform" => {
                    Directive::ConcatTransform(self.matrix("ConcatTransform", &loc)?)
                }
                "CoordinateSystem" => {
                    Directive::CoordinateSystem(self.string("a coordinate system name", &loc)?)
                }
                "CoordSysTransform" => {
                    Directive::CoordSysTransform(self.string("a coordinate system name", &loc)?)
                }
                "TransformTimes" => {
                    let a = self.numbers::<2>("TransformTimes", &loc)?;
                    Directive::TransformTimes(a[0], a[1])
                }
                "ActiveTransform" => {
                    let w = self.expect("StartTime, EndTime or All", &loc)?;
                    Directive::ActiveTransform(match w.text.as_str() {
                        "StartTime" => ActiveTransform::StartTime,
                        "EndTime" => ActiveTransform::EndTime,
                        "All" => ActiveTransform::All,
                        s => {
                            return Err(ParseError::new(
                                &w.loc,
                                format!("expected StartTime, EndTime or All, found '{s}'"),
                            ))
                        }
                    })
                }
                "ReverseOrientation" => Directive::ReverseOrientation,
                "AttributeBegin" => Directive::AttributeBegin,
                "AttributeEnd" => Directive::AttributeEnd,
                "Attribute" => {
                    let what = self.string("shape, light, material, medium or texture", &loc)?;
                    if !["shape", "light", "material", "medium", "texture"].contains(&what.as_str())
                    {
                        return Err(ParseError::new(&loc, format!("Attribute \"{what}\": expected shape, light, material, medium or texture")));
                    }
                    Directive::Attribute(what, self.params()?)
                }
                "TransformBegin" => Directive::TransformBegin,
                "TransformEnd" => Directive::TransformEnd,
                "ObjectBegin" => Directive::ObjectBegin(self.string("an object name", &loc)?),
                "ObjectEnd" => Directive::ObjectEnd,
                "ObjectInstance" => Directive::ObjectInstance(self.string("an object name", &loc)?),
                "Option" => {
                    let mut ps = self.params()?;
                    if ps.len() != 1 {
                        return Err(ParseError::new(
                            &loc,
                            format!(
                                "Option: expected one \"type name\" value, found {}",
                                ps.len()
                            ),
                        ));
                    }
                    Directive::Option(ps.remove(0))
                }
                "ColorSpace" => Directive::ColorSpace(self.string("a color space name", &loc)?),
                "Camera" => Directive::Camera(self.string("a camera type", &loc)?, self.params()?),
                "Film" => Directive::Film(self.string("a film type", &loc)?, self.params()?),
                "Sampler" => {
                    Directive::Sampler(self.string("a sampler type", &loc)?, self.params()?)
                }
                "Integrator" => {
                    Directive::Integrator(self.string("an integrator type", &loc)?, self.params()?)
                }
                "PixelFilter" => {
                    Directive::PixelFilter(self.string("a filter type", &loc)?, self.params()?)
                }
                "Accelerator" => Directive::Accelerator(
                    self.string("an accelerator type", &loc)?,
                    self.params()?,
                ),
                "WorldBegin" => Directive::WorldBegin,
                "WorldEnd" => continue, // pbrt-v3; pbrt-v4 ignores it with a warning
                "LightSource" => {
                    Directive::LightSource(self.string("a light type", &loc)?, self.params()?)
                }
                "AreaLightSource" => Directive::AreaLightSource(
                    self.string("an area light type", &loc)?,
                    self.params()?,
                ),
                "Material" => {
                    Directive::Material(self.string("a material type", &loc)?, self.params()?)
                }
                "MakeNamedMaterial" => Directive::MakeNamedMaterial(
                    self.string("a material name", &loc)?,
                    self.params()?,
                ),
                "NamedMaterial" => Directive::NamedMaterial(self.string("a material name", &loc)?),
                "Texture" => {
                    let name = self.string("a texture name", &loc)?;
                    let ty = self.string("a texture type (spectrum or float)", &loc)?;
                    let class = self.string("a texture class", &loc)?;
                    Directive::Texture(name, ty, class, self.params()?)
                }
                "Shape" => Directive::Shape(self.string("a shape type", &loc)?, self.params()?),
                "MakeNamedMedium" => {
                    Directive::MakeNamedMedium(self.string("a medium name", &loc)?, self.params()?)
                }
                "MediumInterface" => {
                    let inside = self.string("the inside medium name", &loc)?;
                    let outside = match self.peek()? {
                        Some(t) if t.kind == TokenKind::Str => {
                            self.next()?.map(|t| t.text).unwrap_or_default()
                        }
                        _ => inside.clone(),
                    };
                    Directive::MediumInterface(inside, outside)
                }
                other => {
                    return Err(ParseError::new(
                        &loc,
                        format!("unknown directive '{other}'"),
                    ))
                }
            };
            target.directive(d, &loc)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(src: &str) -> Result<Vec<Directive>, ParseError> {
        let mut c = Collect::default();
        parse_str("s.pbrt", src, Path::new("."), &mut c)?;
        Ok(c.0.into_iter().map(|d| d.0).collect())
    }

    #[test]
    fn every_directive() {
        let src = r#"
            Option "bool disablepixeljitter" true
            ColorSpace "srgb"
            LookAt 0 1 2  3 4 5  0 0 1
            Camera "perspective" "float fov" 45 "float lensradius" [0.1] "float focaldistance" 3
            Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" 48 "string filename" "o.exr"
            Sampler "halton" "integer pixelsamples" 16
            Integrator "volpath" "integer maxdepth" 5
            PixelFilter "gaussian"
            Accelerator "bvh"
            TransformTimes 0 1
            WorldBegin
            AttributeBegin
              Identity
              Translate 1 2 3
              Scale 2 2 2
              Rotate 90 0 0 1
              Transform [ 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 ]
              ConcatTransform [ 1 0 0 0 0 1 0 0 0 0 1 0 1 2 3 1 ]
              CoordinateSystem "here"
              CoordSysTransform "here"
              ActiveTransform All
              ReverseOrientation
              Attribute "shape" "float radius" 2
              LightSource "point" "rgb I" [1 2 3] "point3 from" [0 0 0]
              LightSource "spot" "blackbody I" 3000
              AreaLightSource "diffuse" "spectrum L" [400 1 700 2]
              Material "coateddiffuse" "spectrum reflectance" "metal-Cu-eta" "texture roughness" "r"
              MakeNamedMaterial "m" "string type" "diffuse" "color reflectance" [.5 .5 .5]
              NamedMaterial "m"
              Texture "r" "float" "checkerboard" "float uscale" 4
              Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2] "point2 uv" [0 0 1 0 0 1] "normal N" [0 0 1 0 0 1 0 0 1]
              MakeNamedMedium "f" "string type" "fire" "string dataset" "flame.vdb"
              MediumInterface "f" ""
              MediumInterface "f"
              ObjectBegin "o"
              Shape "sphere"
              ObjectEnd
              ObjectInstance "o"
              TransformBegin
              TransformEnd
            AttributeEnd
            WorldEnd
        "#;
        let d = parse(src).unwrap();
        assert_eq!(d.len(), 41); // WorldEnd is dropped, as pbrt-v4 does
        assert!(
            matches!(&d[0], Directive::Option(p) if p.name == "disablepixeljitter" && p.bools() == Some(&[true][..]))
        );
        assert_eq!(
            d[2],
            Directive::LookAt([0., 1., 2., 3., 4., 5., 0., 0., 1.])
        );
        let Directive::Camera(t, ps) = &d[3] else {
            panic!()
        };
        assert_eq!(
            (t.as_str(), ps.len(), ps[1].numbers()),
            ("perspective", 3, Some(&[0.1][..]))
        );
        assert_eq!(d[15], Directive::Rotate(90.0, [0.0, 0.0, 1.0]));
        assert!(matches!(&d[17], Directive::ConcatTransform(m) if m[12] == 1.0 && m[14] == 3.0));
        assert!(
            matches!(&d[23], Directive::LightSource(_, ps) if ps[0].ty == "rgb" && ps[1].ty == "point3")
        );
        assert!(matches!(&d[24], Directive::LightSource(_, ps) if ps[0].ty == "blackbody"));
        assert!(
            matches!(&d[26], Directive::Material(_, ps) if ps[0].strings() == Some(&["metal-Cu-eta".to_string()][..]) && ps[1].ty == "texture")
        );
        assert!(
            matches!(&d[27], Directive::MakeNamedMaterial(n, ps) if n == "m" && ps[1].ty == "rgb")
        );
        assert!(
            matches!(&d[29], Directive::Texture(n, ty, c, _) if n == "r" && ty == "float" && c == "checkerboard")
        );
        assert!(
            matches!(&d[30], Directive::Shape(_, ps) if ps[3].ty == "normal" && ps[3].numbers().unwrap().len() == 9)
        );
        assert_eq!(d[32], Directive::MediumInterface("f".into(), "".into()));
        assert_eq!(d[33], Directive::MediumInterface("f".into(), "f".into()));
    }

    #[test]
    fn errors_name_the_position() {
        let e = |s: &str| parse(s).unwrap_err().to_string();
        assert_eq!(
            e("Shape \"sphere\" \"float radius\" [ 1 two ]"),
            "s.pbrt:1:35: expected a number for \"float radius\", found 'two'"
        );
        assert_eq!(
            e("\n  Translate 1 2"),
            "s.pbrt:2:3: expected Translate (value 3 of 3), found the end of the file"
        );
        assert_eq!(e("Shape \"sphere\" \"flot radius\" 1"), "s.pbrt:1:16: unknown parameter type 'flot' (expected one of integer, float, point2, vector2, point3, vector3, normal, normal3, point, vector, color, rgb, spectrum, blackbody, bool, string, texture)");
        assert!(e("Shpe \"sphere\"").starts_with("s.pbrt:1:1: unknown directive 'Shpe'"));
        assert!(e("Film \"rgb\" \"integer xresolution\" 1.5").contains("expected an integer"));
        assert!(
            e("LightSource \"point\" \"rgb I\" [1 2]").contains("a multiple of 3 values, found 2")
        );
        assert!(e("Shape \"sphere\" \"float radius\" 1 \"float radius\" 2").contains("given twice"));
        assert!(e("\"float radius\" 1").contains("a parameter without a directive"));
        assert!(e("Option \"bool a\" maybe").contains("expected true or false"));
        assert!(e("Include \"missing.pbrt\"")
            .starts_with("s.pbrt:1:1: Include \"missing.pbrt\": cannot read"));
        assert!(e("Translate 1 2 nan").contains("a number"));
    }
}
