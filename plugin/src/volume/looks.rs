//! Looks: named parameter sets for the fires artists ask for (`"string look"`), each a set of defaults the
//! scene's own parameters override. Every value is an ordinary parameter of docs/reference/params.md, so a look says
//! exactly what it changes:
//!
//! - `candle`: propane-like soot (paraffin's optical constants are close to propane's; Dalzell & Sarofim
//!   give both as hydrocarbon soot) and a thin plume: `smokescale` 0.3 — a steady candle releases little
//!   visible smoke.
//! - `campfire`: propane-like soot whose aggregates scatter: `sootscatter` 2e6 m⁻¹ per unit volume fraction (an
//!   albedo of about 0.2 at 550 nm against the soot's ≈ 9e6 m⁻¹ absorption per unit volume fraction — soot
//!   aggregates' single-scattering albedo is 0.1–0.3, Sorensen 2001), forward-peaked, `g` 0.6. Per unit of
//!   soot, not of density: on a simulator's density (Houdini's, EmberGen's) it keeps that albedo.
//! - `gasburner`: a premixed, nearly soot-free flame: `sootscale` 0.02 and `smokescale` 0, its colour the
//!   reaction zone's blue (CH* at 431 nm, C₂* Swan bands at 473–563 nm) as a colour ramp of the blackbody's
//!   luminance — art direction (`physical` 0) standing in for the chemiluminescence the physics does not
//!   model yet.
//! - `explosion`: acetylene's sootier, redder soot, thick smoke (`smokescale` 3) that scatters like the
//!   campfire's.

use crate::params::Param;
use std::borrow::Cow;

/// The looks, by name ("": none).
pub(crate) const CHOICES: [&str; 5] = ["", "candle", "campfire", "gasburner", "explosion"];

/// The parameters of look `name`.
fn params(name: &str) -> Vec<Param> {
    match name {
        "candle" => vec![
            Param::string("fuel", "propane"),
            Param::float("smokescale", 0.3),
        ],
        "campfire" => vec![
            Param::string("fuel", "propane"),
            Param::float("sootscatter", 2e6),
            Param::float("g", 0.6),
        ],
        "gasburner" => vec![
            Param::string("fuel", "propane"),
            Param::float("sootscale", 0.02),
            Param::float("smokescale", 0.0),
            // (Keys T r g b: the blue of the reaction zone over the flame's temperatures.)
            Param::floats(
                "colorramp",
                &[
                    800.0, 0.02, 0.25, 1.00, 1500.0, 0.03, 0.40, 1.00, 2200.0, 0.10, 0.60, 1.00,
                ],
            ),
            Param::float("physical", 0.0),
        ],
        "explosion" => vec![
            Param::string("fuel", "acetylene"),
            Param::float("smokescale", 3.0),
            Param::float("sootscatter", 2e6),
            Param::float("g", 0.6),
        ],
        _ => Vec::new(),
    }
}

/// `list` with its look's parameters added where the list does not give them (each located where the look
/// was given); the list itself without a look. An unknown look is left for the parameter check to refuse.
pub(crate) fn expand(list: &[Param]) -> Cow<'_, [Param]> {
    let Some(look) = list.iter().find(|p| p.name == "look") else {
        return Cow::Borrowed(list);
    };
    let name = match &look.values {
        crate::params::Values::Strings(v) if v.len() == 1 => v[0].clone(),
        _ => return Cow::Borrowed(list),
    };
    // (A look's `sootscatter` gives way to the scene's `sigma_s`: one of the two says how the smoke scatters.)
    let given = |name: &str| {
        list.iter()
            .any(|q| q.name == name || (name == "sootscatter" && q.name == "sigma_s"))
    };
    let mut out = list.to_vec();
    for mut p in params(&name) {
        if !given(&p.name) {
            p.at = look.at.clone();
            p.index = look.index;
            out.push(p);
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_look_fills_in_what_the_scene_leaves_and_nothing_else() {
        let list = vec![
            Param::string("look", "explosion"),
            Param::float("smokescale", 1.5),
        ];
        let out = expand(&list);
        let get = |n: &str| out.iter().filter(|p| p.name == n).count();
        assert_eq!(get("smokescale"), 1, "the scene's own value stays");
        assert_eq!(get("fuel"), 1);
        assert_eq!(get("sootscatter"), 1);
        // The scene's own scattering, per unit density, replaces the look's per unit soot.
        let own = [
            Param::string("look", "campfire"),
            Param::floats("sigma_s", &[3.0]),
        ];
        let out = expand(&own);
        assert!(out.iter().all(|p| p.name != "sootscatter"));
        assert!(matches!(expand(&list[1..]), Cow::Borrowed(_)));
        for n in &CHOICES[1..] {
            assert!(!params(n).is_empty(), "{n}");
        }
    }
}
