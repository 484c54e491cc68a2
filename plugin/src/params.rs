//! Parameter lists and parameter tables.
//!
//! A [`ParamList`] has the shape of a pbrt-v4 parameter list — name, type, values — so an adapter passes a
//! scene's parameters through unchanged. Each component declares its parameters once, in a table of
//! [`ParamSpec`] (name, type, default, unit, range, doc). That table parses and validates the list
//! ([`ParamReader`]), renders `docs/reference/params.md` ([`markdown`]) and answers the ABI's self-description. A
//! parameter nobody read is an error naming the closest valid name.

use crate::Error;
use std::cell::RefCell;

/// The value type of a parameter, as pbrt-v4 spells it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamType {
    /// `float`
    Float,
    /// `integer`
    Integer,
    /// `bool`
    Bool,
    /// `string`
    String,
    /// `point3` (also `point`)
    Point3,
    /// `vector3` (also `vector`)
    Vector3,
    /// `rgb`
    Rgb,
    /// `spectrum`: (λ nm, value) pairs, or one constant value
    Spectrum,
}

impl ParamType {
    /// The pbrt-v4 spelling.
    pub fn name(self) -> &'static str {
        match self {
            ParamType::Float => "float",
            ParamType::Integer => "integer",
            ParamType::Bool => "bool",
            ParamType::String => "string",
            ParamType::Point3 => "point3",
            ParamType::Vector3 => "vector3",
            ParamType::Rgb => "rgb",
            ParamType::Spectrum => "spectrum",
        }
    }
    /// Parses a pbrt-v4 type name.
    pub fn from_name(s: &str) -> Option<ParamType> {
        Some(match s {
            "float" => ParamType::Float,
            "integer" => ParamType::Integer,
            "bool" => ParamType::Bool,
            "string" => ParamType::String,
            "point3" | "point" => ParamType::Point3,
            "vector3" | "vector" => ParamType::Vector3,
            "rgb" => ParamType::Rgb,
            "spectrum" => ParamType::Spectrum,
            _ => return None,
        })
    }
}

/// The values of a parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// float, point3, vector3, rgb, numeric spectrum
    Numbers(Vec<f64>),
    /// integer
    Integers(Vec<i64>),
    /// bool
    Bools(Vec<bool>),
    /// string (or a named spectrum)
    Strings(Vec<String>),
}

impl Values {
    fn len(&self) -> usize {
        match self {
            Values::Numbers(v) => v.len(),
            Values::Integers(v) => v.len(),
            Values::Bools(v) => v.len(),
            Values::Strings(v) => v.len(),
        }
    }
}

/// One parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Its name.
    pub name: String,
    /// Its declared type.
    pub ty: ParamType,
    /// Its values.
    pub values: Values,
    /// Where it came from (`file:line:col` of a scene), if the host said; errors about it begin with it.
    pub at: Option<String>,
    /// Its place in the host's list (`FmCreateInfo::params`), when a host passed it: errors about it carry it,
    /// so a host finds the parameter without reading the message.
    pub index: Option<u32>,
}

/// Where `list` says the parameter `name` came from — its location and its index in the host's list — for
/// [`crate::Error::located`].
pub fn location_in<'a>(
    list: &'a [Param],
) -> impl Fn(&str) -> Option<(Option<&'a str>, Option<u32>)> + 'a {
    move |name| {
        list.iter()
            .find(|p| p.name == name)
            .map(|p| (p.at.as_deref(), p.index))
    }
}

impl Param {
    /// A `float` parameter.
    pub fn float(name: &str, v: f64) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Float,
            values: Values::Numbers(vec![v]),
            at: None,
            index: None,
        }
    }
    /// A `float` array parameter.
    pub fn floats(name: &str, v: &[f64]) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Float,
            values: Values::Numbers(v.to_vec()),
            at: None,
            index: None,
        }
    }
    /// An `rgb` parameter.
    pub fn rgb(name: &str, v: [f64; 3]) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Rgb,
            values: Values::Numbers(v.to_vec()),
            at: None,
            index: None,
        }
    }
    /// An `integer` parameter.
    pub fn int(name: &str, v: i64) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Integer,
            values: Values::Integers(vec![v]),
            at: None,
            index: None,
        }
    }
    /// An `integer` array parameter.
    pub fn ints(name: &str, v: &[i64]) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Integer,
            values: Values::Integers(v.to_vec()),
            at: None,
            index: None,
        }
    }
    /// A `string` parameter.
    pub fn string(name: &str, v: &str) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::String,
            values: Values::Strings(vec![v.into()]),
            at: None,
            index: None,
        }
    }
    /// A `string` array parameter.
    pub fn strings(name: &str, v: &[&str]) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::String,
            values: Values::Strings(v.iter().map(|s| s.to_string()).collect()),
            at: None,
            index: None,
        }
    }
    /// A `bool` parameter.
    pub fn bool(name: &str, v: bool) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Bool,
            values: Values::Bools(vec![v]),
            at: None,
            index: None,
        }
    }
    /// A `point3` parameter.
    pub fn point3(name: &str, v: [f64; 3]) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Point3,
            values: Values::Numbers(v.to_vec()),
            at: None,
            index: None,
        }
    }
    /// A `spectrum` parameter: (λ nm, value) pairs flattened, or one constant.
    pub fn spectrum(name: &str, v: &[f64]) -> Param {
        Param {
            name: name.into(),
            ty: ParamType::Spectrum,
            values: Values::Numbers(v.to_vec()),
            at: None,
            index: None,
        }
    }
}

/// A parameter list.
pub type ParamList = Vec<Param>;

/// A parameter whose value names one of a type's values: the names in the table's order, and the values in the
/// same order. A table row's range is `Range::Choices(T::NAMES)` and the reader's [`ParamReader::choice`] gives
/// the value, so docs/reference/params.md, the ABI's self-description, the check and the parse read one list.
pub trait Choice: Sized + Copy + 'static {
    /// The names, in the table's order.
    const NAMES: &'static [&'static str];
    /// The values, in the same order.
    const VALUES: &'static [Self];
}

/// Implements [`Choice`] for a type from `value => "name"` pairs.
macro_rules! choice {
    ($t:ty { $($v:expr => $n:literal),+ $(,)? }) => {
        impl $crate::params::Choice for $t {
            const NAMES: &'static [&'static str] = &[$($n),+];
            const VALUES: &'static [Self] = &[$($v),+];
        }
    };
}
pub(crate) use choice;

/// The table's name of a choice's value.
pub fn name_of<T: Choice + PartialEq>(v: T) -> &'static str {
    T::VALUES
        .iter()
        .position(|x| *x == v)
        .map_or("", |i| T::NAMES[i])
}

/// The accepted values of a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Range {
    /// Anything of the type.
    Any,
    /// Numbers in [lo, hi].
    Between(f64, f64),
    /// Numbers > lo.
    Above(f64),
    /// One of these strings.
    Choices(&'static [&'static str]),
    /// File names: a relative one is the host's folder's (`FmCreateInfo::directory`: a scene's).
    Path,
}

impl Range {
    /// Human-readable form, for errors and docs.
    pub fn describe(&self) -> String {
        let num = |v: f64| {
            if v != 0.0 && (v.abs() >= 1e6 || v.abs() < 1e-3) {
                format!("{v:e}")
            } else {
                format!("{v}")
            }
        };
        match self {
            Range::Any => String::new(),
            Range::Path => "a file (relative: to the scene's folder)".to_string(),
            Range::Between(a, b) => format!("{} to {}", num(*a), num(*b)),
            Range::Above(a) => format!("> {}", num(*a)),
            Range::Choices(c) => c
                .iter()
                .map(|x| if x.is_empty() { "\"\"" } else { x })
                .collect::<Vec<_>>()
                .join(" \\| "),
        }
    }
}

/// One row of a component's parameter table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Name, matched exactly.
    pub name: &'static str,
    /// Type.
    pub ty: ParamType,
    /// Default as text (parsed for scalars; empty = unset).
    pub default: &'static str,
    /// Unit (empty for none).
    pub unit: &'static str,
    /// Accepted values.
    pub range: Range,
    /// One-line doc.
    pub doc: &'static str,
}

/// One row of a component's table.
pub(crate) const fn row(
    name: &'static str,
    ty: ParamType,
    default: &'static str,
    unit: &'static str,
    range: Range,
    doc: &'static str,
) -> ParamSpec {
    ParamSpec {
        name,
        ty,
        default,
        unit,
        range,
        doc,
    }
}

/// A component's table.
#[derive(Debug, Clone, Copy)]
pub struct Component {
    /// Component name (`dataset`, `volume`, …).
    pub name: &'static str,
    /// One-line description.
    pub doc: &'static str,
    /// Its parameters.
    pub params: &'static [ParamSpec],
}

/// Reads typed, validated values from a list against component tables, and reports unused parameters.
#[derive(Debug)]
pub struct ParamReader<'a> {
    component: &'static str,
    list: &'a [Param],
    specs: Vec<&'static ParamSpec>,
    used: RefCell<Vec<bool>>,
}

pub(crate) use firemedium_dataset::short;

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, &cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + (ca != cb) as usize)
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

impl<'a> ParamReader<'a> {
    /// A reader over `list` for the parameters of `components` (errors name `component`).
    pub fn new(
        component: &'static str,
        list: &'a [Param],
        components: &[&'static Component],
    ) -> Self {
        let specs = components.iter().flat_map(|c| c.params.iter()).collect();
        ParamReader {
            component,
            list,
            specs,
            used: RefCell::new(vec![false; list.len()]),
        }
    }

    fn spec(&self, name: &str) -> &'static ParamSpec {
        // Every getter names a parameter of the tables; a missing row is a bug caught by the tests.
        self.specs
            .iter()
            .find(|s| s.name == name)
            .copied()
            .unwrap_or_else(|| panic!("parameter '{name}' is not in the tables"))
    }

    fn err(&self, name: &str, value: impl std::fmt::Display, expected: impl Into<String>) -> Error {
        Error::invalid(self.component, name, value, expected)
    }

    /// The parameter named `name`, checked against its declared type; marks it used.
    fn find(&self, name: &str) -> Result<Option<&'a Param>, Error> {
        let spec = self.spec(name);
        let Some(i) = self.list.iter().position(|p| p.name == name) else {
            return Ok(None);
        };
        if self.list[i + 1..].iter().any(|p| p.name == name) {
            return Err(self.err(name, "given twice", "one value"));
        }
        self.used.borrow_mut()[i] = true;
        let p = &self.list[i];
        let compatible = p.ty == spec.ty
            || (spec.ty == ParamType::Spectrum
                && matches!(p.ty, ParamType::Float | ParamType::Rgb))
            || (spec.ty == ParamType::Point3 && p.ty == ParamType::Vector3);
        if !compatible {
            return Err(self.err(
                name,
                format!("{} {} value", article(p.ty.name()), p.ty.name()),
                format!(
                    "{} {} (e.g. \"{} {name}\")",
                    article(spec.ty.name()),
                    spec.ty.name(),
                    spec.ty.name()
                ),
            ));
        }
        Ok(Some(p))
    }

    fn check_number(&self, spec: &ParamSpec, v: f64) -> Result<f64, Error> {
        let ok = v.is_finite()
            && match spec.range {
                Range::Between(a, b) => (a..=b).contains(&v),
                Range::Above(a) => v > a,
                _ => true,
            };
        if ok {
            Ok(v)
        } else {
            let r = spec.range.describe();
            Err(self.err(
                spec.name,
                short(v),
                if r.is_empty() {
                    "a finite number".to_string()
                } else {
                    format!("a finite number {r}")
                },
            ))
        }
    }

    /// All numbers of a numeric parameter (float, point3, rgb, spectrum), or `None` when absent.
    pub fn numbers(&self, name: &str) -> Result<Option<Vec<f64>>, Error> {
        let spec = self.spec(name);
        match self.find(name)? {
            None => Ok(None),
            Some(p) => match &p.values {
                Values::Numbers(v) => {
                    if v.is_empty() {
                        return Err(self.err(name, "no values", "at least one value"));
                    }
                    v.iter()
                        .map(|&x| {
                            if spec.ty == ParamType::Spectrum {
                                Ok(x)
                            } else {
                                self.check_number(spec, x)
                            }
                        })
                        .collect::<Result<Vec<_>, _>>()
                        .map(Some)
                }
                Values::Integers(v) => v
                    .iter()
                    .map(|&x| self.check_number(spec, x as f64))
                    .collect::<Result<Vec<_>, _>>()
                    .map(Some),
                _ => Err(self.err(
                    name,
                    "non-numeric values",
                    format!("{} numbers", spec.ty.name()),
                )),
            },
        }
    }

    /// A single float (or the table default).
    pub fn float(&self, name: &str) -> Result<f64, Error> {
        let spec = self.spec(name);
        match self.numbers(name)? {
            Some(v) if v.len() == 1 => Ok(v[0]),
            Some(v) => Err(self.err(name, format!("{} values", v.len()), "one value")),
            None => self.check_number(spec, spec.default.parse().unwrap_or(0.0)),
        }
    }

    /// Whether the list gives `name` (without reading it: it is not marked used).
    pub fn list_has(&self, name: &str) -> bool {
        self.list.iter().any(|p| p.name == name)
    }

    /// A single float if given (no default).
    pub fn opt_float(&self, name: &str) -> Result<Option<f64>, Error> {
        match self.numbers(name)? {
            Some(v) if v.len() == 1 => Ok(Some(v[0])),
            Some(v) => Err(self.err(name, format!("{} values", v.len()), "one value")),
            None => Ok(None),
        }
    }

    /// A single integer (or the table default).
    pub fn int(&self, name: &str) -> Result<i64, Error> {
        let spec = self.spec(name);
        match self.ints(name)? {
            Some(v) if v.len() == 1 => Ok(v[0]),
            Some(v) => Err(self.err(name, format!("{} values", v.len()), "one value")),
            None => Ok(spec.default.parse().unwrap_or(0)),
        }
    }

    /// All integers of an integer parameter, or `None` when absent.
    pub fn ints(&self, name: &str) -> Result<Option<Vec<i64>>, Error> {
        let spec = self.spec(name);
        match self.find(name)? {
            None => Ok(None),
            Some(p) => match &p.values {
                Values::Integers(v) => {
                    for &x in v {
                        self.check_number(spec, x as f64)?;
                    }
                    Ok(Some(v.clone()))
                }
                _ => Err(self.err(name, "non-integer values", "integers")),
            },
        }
    }

    /// A single string (or the table default), checked against its choices.
    pub fn string(&self, name: &str) -> Result<String, Error> {
        let spec = self.spec(name);
        let v = match self.strings(name)? {
            Some(v) if v.len() == 1 => v[0].clone(),
            Some(v) => return Err(self.err(name, format!("{} values", v.len()), "one value")),
            None => spec.default.to_string(),
        };
        if let Range::Choices(c) = spec.range {
            if !c.contains(&v.as_str()) {
                return Err(self.err(name, format!("\"{v}\""), format!("one of {}", c.join(", "))));
            }
        }
        Ok(v)
    }

    /// A choice (or the table default) as its typed value.
    pub fn choice<T: Choice>(&self, name: &str) -> Result<T, Error> {
        let s = self.string(name)?;
        T::NAMES
            .iter()
            .position(|n| *n == s)
            .map(|i| T::VALUES[i])
            .ok_or_else(|| {
                self.err(
                    name,
                    format!("\"{s}\""),
                    format!("one of {}", T::NAMES.join(", ")),
                )
            })
    }

    /// All strings of a string parameter, or `None` when absent.
    pub fn strings(&self, name: &str) -> Result<Option<Vec<String>>, Error> {
        match self.find(name)? {
            None => Ok(None),
            Some(p) => match &p.values {
                Values::Strings(v) => Ok(Some(v.clone())),
                _ => Err(self.err(name, "non-string values", "strings")),
            },
        }
    }

    /// A single bool (or the table default).
    pub fn bool(&self, name: &str) -> Result<bool, Error> {
        let spec = self.spec(name);
        match self.find(name)? {
            None => Ok(spec.default == "true"),
            Some(p) => match &p.values {
                Values::Bools(v) if v.len() == 1 => Ok(v[0]),
                _ => Err(self.err(name, format!("{} values", p.values.len()), "one bool")),
            },
        }
    }

    /// A point3 if given.
    pub fn point3(&self, name: &str) -> Result<Option<[f64; 3]>, Error> {
        match self.numbers(name)? {
            Some(v) if v.len() == 3 => Ok(Some([v[0], v[1], v[2]])),
            Some(v) => Err(self.err(name, format!("{} values", v.len()), "three coordinates")),
            None => Ok(None),
        }
    }

    /// Errors on the first parameter that no table knows, naming the closest valid name. Call it first, so a
    /// typo is reported before the missing value it causes.
    pub fn check_names(&self) -> Result<(), Error> {
        for p in self.list {
            if !self.specs.iter().any(|s| s.name == p.name) {
                let best = self
                    .specs
                    .iter()
                    .map(|s| {
                        (
                            levenshtein(&p.name.to_ascii_lowercase(), &s.name.to_ascii_lowercase()),
                            s.name,
                        )
                    })
                    .min();
                let hint = match best {
                    Some((d, n)) if d <= 3.max(p.name.len() / 3) => format!("did you mean '{n}'?"),
                    _ => "docs/reference/params.md lists the known ones".to_string(),
                };
                // (An empty value: the parameter's name is the problem — "unknown parameter".)
                return Err(Error::invalid(self.component, &p.name, "", hint));
            }
        }
        Ok(())
    }

    /// After reading: errors on any parameter no table knows ([`ParamReader::check_names`]) and on any known
    /// parameter that nothing read (it does nothing in this configuration: `fuelnk` without fuel "custom", a
    /// file option for an inline grid…), as pbrt-v4's `ReportUnused` does, so a parameter is never silently
    /// dropped.
    pub fn finish(&self) -> Result<(), Error> {
        self.check_names()?;
        let used = self.used.borrow();
        match self.list.iter().zip(used.iter()).find(|(_, &u)| !u) {
            None => Ok(()),
            Some((p, _)) => Err(Error::invalid(
                self.component,
                &p.name,
                "given, but nothing in this configuration reads it",
                "only the parameters that apply (docs/reference/params.md says when each does)",
            )),
        }
    }
}

/// The Markdown reference of the given component tables (docs/reference/params.md).
pub fn markdown(components: &[&Component]) -> String {
    let mut s = String::from(
        "# Parameters\n\n<!-- Generated from the parameter tables in plugin/src (params::markdown); a test fails when this file is stale.\n     Regenerate: FIREMEDIUM_BLESS=1 cargo test -p firemedium-plugin params_doc -->\n\n",
    );
    s += "Every component reads a pbrt-v4-style parameter list (`\"type name\" [values]`). Names are matched exactly; a name\nno component reads is an error that suggests the closest valid one.\n";
    for c in components {
        s += &format!("\n## {}\n\n{}\n\n| name | type | default | unit | range | description |\n|---|---|---|---|---|---|\n", c.name, c.doc);
        for p in c.params {
            let d = if p.default.is_empty() {
                "—".to_string()
            } else {
                format!("`{}`", p.default)
            };
            s += &format!(
                "| `{}` | {} | {} | {} | {} | {} |\n",
                p.name,
                p.ty.name(),
                d,
                p.unit,
                p.range.describe(),
                p.doc
            );
        }
    }
    s
}

/// "an" before a vowel, else "a".
fn article(word: &str) -> &'static str {
    if word.starts_with(['a', 'e', 'i', 'o', 'u']) {
        "an"
    } else {
        "a"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    static T: Component = Component {
        name: "test",
        doc: "a test table",
        params: &[
            ParamSpec {
                name: "stepsize",
                ty: ParamType::Float,
                default: "0.5",
                unit: "voxels",
                range: Range::Above(0.0),
                doc: "",
            },
            ParamSpec {
                name: "bins",
                ty: ParamType::Integer,
                default: "30",
                unit: "",
                range: Range::Between(1.0, 4096.0),
                doc: "",
            },
            ParamSpec {
                name: "mode",
                ty: ParamType::String,
                default: "spectral",
                unit: "",
                range: Range::Choices(&["spectral", "rgb"]),
                doc: "",
            },
            ParamSpec {
                name: "p0",
                ty: ParamType::Point3,
                default: "",
                unit: "",
                range: Range::Any,
                doc: "",
            },
            ParamSpec {
                name: "sigma_a",
                ty: ParamType::Spectrum,
                default: "1",
                unit: "",
                range: Range::Any,
                doc: "",
            },
        ],
    };

    #[test]
    fn typed_reads_and_defaults() {
        let list = vec![
            Param::float("stepsize", 0.25),
            Param::string("mode", "rgb"),
            Param::point3("p0", [1.0, 2.0, 3.0]),
            Param::float("sigma_a", 2.0),
        ];
        let r = ParamReader::new("volume", &list, &[&T]);
        assert_eq!(r.float("stepsize").unwrap(), 0.25);
        assert_eq!(r.int("bins").unwrap(), 30);
        assert_eq!(r.string("mode").unwrap(), "rgb");
        assert_eq!(r.point3("p0").unwrap(), Some([1.0, 2.0, 3.0]));
        assert_eq!(r.numbers("sigma_a").unwrap(), Some(vec![2.0]));
        r.finish().unwrap();
    }

    #[test]
    fn errors_name_value_and_expectation() {
        let list = vec![
            Param::float("stepsize", -1.0),
            Param::string("mode", "hsv"),
            Param::string("bins", "30"),
            Param::float("stepsise", 1.0),
        ];
        let r = ParamReader::new("volume", &list, &[&T]);
        let e = r.float("stepsize").unwrap_err().to_string();
        assert_eq!(
            e,
            "volume: parameter 'stepsize' = -1: expected a finite number > 0"
        );
        let e = r.string("mode").unwrap_err().to_string();
        assert!(
            e.contains("\"hsv\"") && e.contains("one of spectral, rgb"),
            "{e}"
        );
        let e = r.int("bins").unwrap_err().to_string();
        assert!(
            e.contains("a string value") && e.contains("an integer") || e.contains("integer"),
            "{e}"
        );
        let e = r.finish().unwrap_err().to_string();
        assert_eq!(
            e,
            "volume: unknown parameter 'stepsise' (did you mean 'stepsize'?)"
        );
        let list = vec![Param::float("stepsize", f64::NAN)];
        assert!(ParamReader::new("volume", &list, &[&T])
            .float("stepsize")
            .is_err());
        let list = vec![Param::float("stepsize", 1.0), Param::float("stepsize", 2.0)];
        assert!(ParamReader::new("volume", &list, &[&T])
            .float("stepsize")
            .unwrap_err()
            .to_string()
            .contains("twice"));
        let list = vec![Param::float("zzzzzzzzzzzz", 1.0)];
        let e = ParamReader::new("volume", &list, &[&T])
            .finish()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("docs/reference/params.md lists the known ones"),
            "{e}"
        );
    }

    #[test]
    fn a_parameter_nothing_reads_is_an_error_naming_where_it_was_given() {
        // pbrt-v4's ReportUnused: a known parameter that the configuration never reads is not dropped silently.
        let mut list = vec![Param::float("stepsize", 0.5), Param::string("mode", "rgb")];
        list[1].at = Some("fire.pbrt:3:7".into());
        let r = ParamReader::new("volume", &list, &[&T]);
        r.float("stepsize").unwrap();
        let e = r
            .finish()
            .unwrap_err()
            .located(location_in(&list))
            .to_string();
        assert_eq!(
            e,
            "fire.pbrt:3:7: volume: parameter 'mode' = given, but nothing in this configuration reads it: expected only the parameters that apply (docs/reference/params.md says when each does)"
        );
        r.string("mode").unwrap();
        r.finish().unwrap();
    }

    #[test]
    fn levenshtein_distances() {
        assert_eq!(levenshtein("kitten", "sitting"), 3);
        assert_eq!(levenshtein("", "abc"), 3);
        assert_eq!(levenshtein("Lescale", "Lescale"), 0);
    }
}
