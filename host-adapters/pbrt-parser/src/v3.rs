//! pbrt-v3 → pbrt-v4: what a pbrt-v3 scene says, and what pbrt-v4 says instead (pbrt-v4's `docs/` "Converting
//! from pbrt-v3" and its `--upgrade` rules), for the messages that refuse a v3 name.

/// Directive types pbrt-v3 had and pbrt-v4 renamed or dropped: (kind, v3 name, what pbrt-v4 has).
const TYPES: [(&str, &str, &str); 16] = [
    ("film", "image", "\"rgb\""),
    (
        "material",
        "matte",
        "\"diffuse\" (its \"Kd\" is \"reflectance\")",
    ),
    (
        "material",
        "plastic",
        "\"coateddiffuse\" (a rough dielectric coat over a diffuse base)",
    ),
    ("material", "substrate", "\"coateddiffuse\""),
    ("material", "metal", "\"conductor\""),
    (
        "material",
        "mirror",
        "\"conductor\" with \"float roughness\" 0",
    ),
    ("material", "glass", "\"dielectric\""),
    ("material", "translucent", "\"diffusetransmission\""),
    (
        "material",
        "uber",
        "no single material: \"coateddiffuse\" or \"dielectric\", by what it should look like",
    ),
    (
        "material",
        "fourier",
        "no measured BSDF files (\"measured\" takes pbrt-v4's .bsdf format)",
    ),
    (
        "medium",
        "heterogeneous",
        "\"uniformgrid\" (\"density\" the same; \"p0\", \"p1\" the same)",
    ),
    (
        "integrator",
        "directlighting",
        "\"volpath\" with \"integer maxdepth\" 1",
    ),
    ("integrator", "whitted", "\"path\" or \"volpath\""),
    (
        "integrator",
        "bdpt",
        "\"bdpt\" (rendered here with volpath)",
    ),
    ("sampler", "lowdiscrepancy", "\"zsobol\" or \"sobol\""),
    ("sampler", "02sequence", "\"zsobol\" or \"sobol\""),
];

/// Parameters pbrt-v3 named differently: (v3 name, pbrt-v4's).
const PARAMETERS: [(&str, &str); 5] = [
    ("Kd", "\"reflectance\""),
    ("Kr", "\"reflectance\""),
    ("Kt", "\"transmittance\""),
    ("Ks", "a coat's \"roughness\" and \"eta\" (coateddiffuse)"),
    ("index", "\"eta\""),
];

/// " (pbrt-v3's `kind` \"name\" is pbrt-v4's …)" when `name` is a pbrt-v3 type of that kind, else "".
pub fn type_hint(kind: &str, name: &str) -> String {
    TYPES
        .iter()
        .find(|(k, v3, _)| *k == kind && *v3 == name)
        .map_or(String::new(), |(_, _, v4)| {
            format!(" (pbrt-v3's {kind} \"{name}\" is pbrt-v4's {v4})")
        })
}

/// " (pbrt-v3's \"name\" is pbrt-v4's \"…\")" when pbrt-v3 named a parameter `name` that pbrt-v4 renamed.
pub fn parameter_hint(name: &str) -> Option<String> {
    PARAMETERS
        .iter()
        .find(|(v3, v4)| *v3 == name && v3 != v4)
        .map(|(_, v4)| format!(" (pbrt-v3's \"{name}\" is pbrt-v4's {v4})"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn v3_names_get_their_v4_names() {
        assert_eq!(
            type_hint("film", "image"),
            " (pbrt-v3's film \"image\" is pbrt-v4's \"rgb\")"
        );
        assert!(type_hint("material", "matte").contains("\"diffuse\""));
        assert!(type_hint("medium", "heterogeneous").contains("\"uniformgrid\""));
        assert_eq!(type_hint("material", "bogus"), "");
        assert_eq!(
            parameter_hint("Kd").as_deref(),
            Some(" (pbrt-v3's \"Kd\" is pbrt-v4's \"reflectance\")")
        );
        assert_eq!(parameter_hint("reflectance"), None);
    }
}
