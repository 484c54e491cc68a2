//! Which tool wrote a dataset, from its grids' names and values: the `source` convention the plugin reads it with.

use crate::{Dataset, GridEntry, HOUDINI_KELVIN};

/// The `source` a file's grids look like (its name, and why, as `firemedium info` and `firemedium scene` say it): Blender's Mantaflow cache (a `flame` grid beside `density`, with its
/// `shadow` or vector `velocity`), or density and temperature in kelvin (a temperature grid reaching 500 K).
pub fn looks_like(entries: &[GridEntry], ds: &Dataset) -> Option<(String, String)> {
    let has = |n: &str| entries.iter().any(|g| g.name == n);
    if has("smoke") && has("temperature") && (has("flames") || has("fuel")) {
        return Some((
            "embergen".into(),
            "EmberGen's grids (smoke, temperature, flames/fuel): \"string source\" \"embergen\" reads its smoke as the density".into(),
        ));
    }
    if has("density") && has("flame") && !has("temperature") {
        return Some((
            "blender".into(),
            "a Mantaflow domain cache (density, flame, no temperature): \"string source\" \"blender\" reads its flame as Cycles does".into(),
        ));
    }
    if has("density") && has("flame") && (has("shadow") || has("velocity")) {
        return Some((
            "blender".into(),
            "a Mantaflow domain cache (density, flame, shadow/velocity): \"string source\" \"blender\" reads its flame as Cycles does".into(),
        ));
    }
    let t = ds.channels().iter().find(|c| c.name == "temperature")?;
    if has("density")
        && t.stats.max > 0.0
        && t.stats.max < 50.0
        && (has("flame") || has("vel") || has("heat"))
    {
        return Some((
            "houdini".into(),
            format!(
                "Houdini Pyro's grids, the temperature relative (up to {:.2}): \"string source\" \"houdini\" reads it as {} K per unit",
                t.stats.max,
                HOUDINI_KELVIN
            ),
        ));
    }
    (has("density") && t.stats.max >= 500.0).then(|| {
        (
            "kelvin".into(),
            format!(
                "density and temperature in kelvin (up to {:.0} K): the default",
                t.stats.max
            ),
        )
    })
}
