//! `firemedium bench components`: what the plugin builds for the same fire with and without species, refraction
//! and the fire light — bytes and set-up time per component (unused parts cost nothing).

use crate::{repository_file, ComponentsArgs};

/// Per configuration: (name, [(component, bytes, set-up seconds)], total bytes).
type Components = Vec<(&'static str, Vec<(String, usize, f64)>, usize)>;

pub fn components(file: &str) -> Result<Components, String> {
    use firemedium_plugin::light::{FireLight, Weighting};
    use firemedium_plugin::params::Param;
    use firemedium_plugin::volume::FireVolume;
    let mut out = Vec::new();
    for (name, extra, light) in [
        ("soot + blackbody", vec![], false),
        (
            "+ sodium lines",
            vec![Param::string("species", "Na")],
            false,
        ),
        (
            "+ sodium, refraction",
            vec![
                Param::string("species", "Na"),
                Param::bool("refraction", true),
            ],
            false,
        ),
        (
            "+ sodium, refraction, fire light",
            vec![
                Param::string("species", "Na"),
                Param::bool("refraction", true),
            ],
            true,
        ),
    ] {
        let mut list = vec![Param::string("filename", file)];
        list.extend(extra);
        let v = FireVolume::new(&list).map_err(|e| e.to_string())?;
        let tables: usize = v.tables().iter().map(|t| t.bytes).sum();
        let mut rows = vec![(
            "dataset grids (density, temperature, species)".to_string(),
            v.bytes() - tables,
            f64::NAN,
        )];
        rows.extend(
            v.tables()
                .iter()
                .map(|t| (t.name.clone(), t.bytes, t.seconds)),
        );
        let mut total = v.bytes();
        if light {
            let l = FireLight::new(std::sync::Arc::new(v), Weighting::Power)
                .map_err(|e| e.to_string())?;
            rows.push((
                "fire light (CDFs over emitting voxels)".into(),
                l.bytes(),
                l.build_seconds(),
            ));
            total += l.bytes();
        }
        out.push((name, rows, total));
    }
    Ok(out)
}

pub fn report(a: &ComponentsArgs) -> Result<String, String> {
    let file = a
        .dataset
        .clone()
        .unwrap_or_else(|| repository_file("scenes/spectroscopy/torch.vdb"))
        .to_string_lossy()
        .into_owned();
    let mut out = format!(
        "dataset {file}\n\n| configuration | component | bytes | set-up s |\n|---|---|---|---|\n"
    );
    for (name, rows, total) in components(&file)? {
        let seconds: f64 = rows.iter().map(|r| r.2).filter(|s| s.is_finite()).sum();
        for (k, (c, bytes, s)) in rows.iter().enumerate() {
            let s = if s.is_finite() {
                format!("{s:.4}")
            } else {
                "—".into()
            };
            out += &format!(
                "| {} | {c} | {bytes} | {s} |\n",
                if k == 0 { name } else { "" }
            );
        }
        out += &format!("| | **total** | **{total}** | **{seconds:.4}** |\n");
    }
    Ok(out)
}
