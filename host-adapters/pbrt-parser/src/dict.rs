//! A directive's parameters with a used flag each, shaped like pbrt-v4's `ParameterDictionary`: getters mark
//! what they read, and [`ParamDict::report_unused`] names every parameter nothing read, at its own
//! `file:line:col` — an error with the closest valid name when pbrt-v4 does not know it either (a typo), a
//! warning when pbrt-v4 reads it and this renderer does not (yet) — so no parameter is dropped silently
//! (pbrt-v4's `ReportUnused`).

use crate::{Loc, Param, ParseError};
use std::cell::Cell;

/// A directive's parameters and which of them were read.
#[derive(Debug)]
pub struct ParamDict<'a> {
    params: &'a [Param],
    used: Vec<Cell<bool>>,
}

impl<'a> ParamDict<'a> {
    /// The parameters of one directive, none read yet.
    pub fn new(params: &'a [Param]) -> ParamDict<'a> {
        ParamDict {
            params,
            used: params.iter().map(|_| Cell::new(false)).collect(),
        }
    }

    /// The parameter `name`, marked read.
    pub fn get(&self, name: &str) -> Option<&'a Param> {
        let i = self.params.iter().position(|p| p.name == name)?;
        self.used[i].set(true);
        Some(&self.params[i])
    }

    /// Whether `name` is given (does not mark it read).
    pub fn has(&self, name: &str) -> bool {
        self.params.iter().any(|p| p.name == name)
    }

    /// The numbers of `name`, if given and numeric.
    pub fn numbers(&self, name: &str) -> Option<&'a [f64]> {
        self.get(name).and_then(Param::numbers)
    }

    /// The first number of `name`, or `default`.
    pub fn float(&self, name: &str, default: f64) -> f64 {
        self.numbers(name)
            .and_then(|v| v.first().copied())
            .unwrap_or(default)
    }

    /// The first string of `name`.
    pub fn string(&self, name: &str) -> Option<&'a str> {
        self.get(name)
            .and_then(Param::strings)
            .and_then(|v| v.first())
            .map(String::as_str)
    }

    /// The first bool of `name`, or `default`.
    pub fn bool(&self, name: &str, default: bool) -> bool {
        self.get(name)
            .and_then(Param::bools)
            .and_then(|v| v.first().copied())
            .unwrap_or(default)
    }

    /// Every parameter, without marking any read.
    pub fn params(&self) -> &'a [Param] {
        self.params
    }

    /// Marks every parameter read (they were handed on whole, to a component that checks them itself).
    pub fn mark_all_used(&self) {
        self.used.iter().for_each(|u| u.set(true));
    }

    /// The parameters nothing read, in order.
    pub fn unused(&self) -> impl Iterator<Item = &'a Param> + '_ {
        self.params
            .iter()
            .zip(&self.used)
            .filter(|(_, u)| !u.get())
            .map(|(p, _)| p)
    }

    /// Names every parameter nothing read. `what` names the directive (`sphere`, `diffuse material`); `pbrt`
    /// lists the parameters pbrt-v4 reads for it. Unknown to pbrt-v4 too: an error at the parameter, with the
    /// closest name of `pbrt`. Known to pbrt-v4: a warning at the parameter (returned, in order).
    pub fn report_unused(
        &self,
        what: &str,
        pbrt: &[&str],
    ) -> Result<Vec<(Loc, String)>, ParseError> {
        let mut warnings = Vec::new();
        for p in self.unused() {
            if pbrt.contains(&p.name.as_str()) {
                warnings.push((
                    p.loc.clone(),
                    format!(
                        "{what}: \"{} {}\" is read by pbrt-v4 but not supported by this renderer; it is ignored",
                        p.ty, p.name
                    ),
                ));
            } else {
                let hint = match closest(&p.name, pbrt) {
                    _ if crate::v3::parameter_hint(&p.name).is_some() => {
                        crate::v3::parameter_hint(&p.name).unwrap_or_default()
                    }
                    Some(n) => format!(" (did you mean \"{n}\"?)"),
                    None if pbrt.is_empty() => " (it takes none)".to_string(),
                    None => format!(" (pbrt-v4 reads: {})", pbrt.join(", ")),
                };
                return Err(ParseError {
                    loc: p.loc.clone(),
                    message: format!("{what}: unknown parameter \"{} {}\"{hint}", p.ty, p.name),
                });
            }
        }
        Ok(warnings)
    }
}

/// The name of `names` closest to `name` by edit distance (case-insensitive), if it is close enough to be a
/// plausible typo.
pub fn closest<'n>(name: &str, names: &[&'n str]) -> Option<&'n str> {
    let lower = name.to_ascii_lowercase();
    names
        .iter()
        .map(|n| (levenshtein(&lower, &n.to_ascii_lowercase()), *n))
        .min()
        .filter(|(d, _)| *d <= 3.max(name.len() / 3))
        .map(|(_, n)| n)
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{parse_str, Collect, Directive};

    fn shape_params(text: &str) -> Vec<Param> {
        let mut c = Collect::default();
        parse_str("t.pbrt", text, std::path::Path::new("."), &mut c).unwrap();
        match c.0.into_iter().next() {
            Some((Directive::Shape(_, p), _)) => p,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn unread_parameters_are_named_at_their_own_position() {
        let p = shape_params(
            "Shape \"sphere\" \"float radius\" 2\n  \"float zmin\" -1 \"float radus\" 3\n",
        );
        let d = ParamDict::new(&p);
        assert_eq!(d.float("radius", 1.0), 2.0);
        // zmin: pbrt-v4 reads it, we did not → a warning where it stands.
        // radus: nobody knows it → an error, with the closest name.
        let pbrt = ["radius", "zmin", "zmax", "phimax", "alpha"];
        let e = d.report_unused("sphere", &pbrt).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.pbrt:2:19: sphere: unknown parameter \"float radus\" (did you mean \"radius\"?)"
        );
        let _ = d.get("radus");
        let w = d.report_unused("sphere", &pbrt).unwrap();
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].0.to_string(), "t.pbrt:2:3");
        assert!(
            w[0].1
                .contains("\"float zmin\" is read by pbrt-v4 but not supported"),
            "{}",
            w[0].1
        );
        d.mark_all_used();
        assert!(d.report_unused("sphere", &pbrt).unwrap().is_empty());
    }

    #[test]
    fn closest_names_only_plausible_typos() {
        assert_eq!(closest("Lescal", &["Lescale", "scale"]), Some("Lescale"));
        assert_eq!(closest("zzzzzzzzzz", &["radius"]), None);
        assert_eq!(levenshtein("kitten", "sitting"), 3);
    }
}
