//! The parameters pbrt-v4 reads, per directive and type (from pbrt-v4's `Create` functions: `cameras.cpp`,
//! `film.cpp`, `samplers.cpp`, `filters.cpp`, `integrators.cpp`, `lights.cpp`, `materials.cpp`, `textures.cpp`,
//! `media.cpp`, `shapes.cpp`). The scene builder reads what it supports through a `ParamDict`; whatever is left
//! is a warning when pbrt-v4 reads it (named here) and an error with the closest name when it does not.

/// What a directive is, for its parameter list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Camera,
    Film,
    Sampler,
    PixelFilter,
    Integrator,
    Light,
    AreaLight,
    Material,
    Texture,
    Medium,
    Shape,
}

/// Texture mapping parameters (every texture class takes them).
const MAPPING: &[&str] = &[
    "mapping",
    "uscale",
    "vscale",
    "udelta",
    "vdelta",
    "v1",
    "v2",
    "dimension",
];

/// The parameters pbrt-v4 reads for directive `kind` of type `ty`, or `None` for a type pbrt-v4 does not have.
pub fn parameters(kind: Kind, ty: &str) -> Option<Vec<&'static str>> {
    let own = own_parameters(kind, ty)?;
    Some(common_parameters(kind).iter().chain(own).copied().collect())
}

/// The parameters pbrt-v4 reads for every type of directive `kind`.
fn common_parameters(kind: Kind) -> &'static [&'static str] {
    match kind {
        Kind::Camera => &[
            "shutteropen",
            "shutterclose",
            "screenwindow",
            "frameaspectratio",
        ],
        Kind::Film => &[
            "xresolution",
            "yresolution",
            "cropwindow",
            "pixelbounds",
            "diagonal",
            "filename",
            "sensor",
            "iso",
            "whitebalance",
            "exposuretime",
            "maxcomponentvalue",
            "savefp16",
        ],
        Kind::Sampler => &["pixelsamples", "seed"],
        Kind::PixelFilter => &["xradius", "yradius"],
        Kind::Integrator => &["maxdepth", "regularize", "lightsampler"],
        Kind::Light => &["scale", "power", "illuminance"],
        Kind::AreaLight => &[],
        Kind::Material => &["type", "displacement", "normalmap"],
        Kind::Texture => MAPPING,
        Kind::Medium => &["type"],
        Kind::Shape => &["alpha", "emissionfilename"],
    }
}

/// The parameters pbrt-v4 reads for type `ty` of directive `kind` alone (`None`: no such type).
fn own_parameters(kind: Kind, ty: &str) -> Option<&'static [&'static str]> {
    let own: &[&str] = match (kind, ty) {
        (Kind::Camera, "perspective") => &["fov", "lensradius", "focaldistance"],
        (Kind::Camera, "orthographic") => &["lensradius", "focaldistance"],
        (Kind::Camera, "realistic") => {
            &["lensfile", "aperturediameter", "focusdistance", "aperture"]
        }
        (Kind::Camera, "spherical") => &["mapping"],
        (Kind::Film, "rgb") => &[],
        (Kind::Film, "gbuffer") => &["coordinatesystem"],
        (Kind::Film, "spectral") => &["nbuckets", "lambdamin", "lambdamax"],
        (Kind::Sampler, "zsobol" | "sobol" | "paddedsobol" | "halton") => &["randomization"],
        (Kind::Sampler, "stratified") => &["jitter", "xsamples", "ysamples"],
        (Kind::Sampler, "independent" | "pmj02bn") => &[],
        (Kind::PixelFilter, "box" | "triangle") => &[],
        (Kind::PixelFilter, "gaussian") => &["sigma"],
        (Kind::PixelFilter, "mitchell") => &["B", "C"],
        (Kind::PixelFilter, "sinc" | "lanczos") => &["tau"],
        (Kind::Integrator, "volpath" | "path" | "simplevolpath" | "simplepath") => {
            &["samplelights", "samplebsdf"]
        }
        (Kind::Integrator, "bdpt") => &["visualizestrategies", "visualizeweights"],
        (Kind::Integrator, "mlt") => &[
            "bootstrapsamples",
            "chains",
            "mutationsperpixel",
            "largestepprobability",
            "sigma",
        ],
        (Kind::Integrator, "sppm") => &["iterations", "photonsperiteration", "radius", "seed"],
        (Kind::Integrator, "ambientocclusion") => &["cossample", "maxdistance"],
        (Kind::Integrator, "randomwalk" | "lightpath") => &[],
        (Kind::Light, "point") => &["I", "from"],
        (Kind::Light, "spot") => &["I", "from", "to", "coneangle", "conedeltaangle"],
        (Kind::Light, "goniometric") => &["I", "filename"],
        (Kind::Light, "projection") => &["fov", "filename"],
        (Kind::Light, "distant") => &["L", "from", "to"],
        (Kind::Light, "infinite") => &["L", "filename", "portal"],
        (Kind::AreaLight, "diffuse") => &["L", "scale", "twosided", "power", "filename"],
        (Kind::Material, "interface") => &[],
        (Kind::Material, "diffuse") => &["reflectance"],
        (Kind::Material, "coateddiffuse") => &[
            "reflectance",
            "eta",
            "roughness",
            "uroughness",
            "vroughness",
            "thickness",
            "albedo",
            "g",
            "maxdepth",
            "nsamples",
            "remaproughness",
        ],
        (Kind::Material, "coatedconductor") => &[
            "interface.eta",
            "interface.roughness",
            "interface.uroughness",
            "interface.vroughness",
            "thickness",
            "conductor.eta",
            "conductor.k",
            "reflectance",
            "conductor.roughness",
            "conductor.uroughness",
            "conductor.vroughness",
            "albedo",
            "g",
            "maxdepth",
            "nsamples",
            "remaproughness",
        ],
        (Kind::Material, "conductor") => &[
            "reflectance",
            "eta",
            "k",
            "roughness",
            "uroughness",
            "vroughness",
            "remaproughness",
        ],
        (Kind::Material, "dielectric" | "thindielectric") => &[
            "eta",
            "roughness",
            "uroughness",
            "vroughness",
            "remaproughness",
        ],
        (Kind::Material, "diffusetransmission") => &["reflectance", "transmittance", "scale"],
        (Kind::Material, "mix") => &["materials", "amount"],
        (Kind::Material, "measured") => &["filename"],
        (Kind::Material, "subsurface") => &[
            "eta",
            "g",
            "mfp",
            "name",
            "reflectance",
            "scale",
            "sigma_a",
            "sigma_s",
            "roughness",
            "uroughness",
            "vroughness",
            "remaproughness",
        ],
        (Kind::Material, "hair") => &[
            "sigma_a",
            "reflectance",
            "color",
            "eumelanin",
            "pheomelanin",
            "eta",
            "beta_m",
            "beta_n",
            "alpha",
        ],
        (Kind::Texture, "constant") => &["value"],
        (Kind::Texture, "checkerboard") => &["tex1", "tex2"],
        (Kind::Texture, "imagemap") => &[
            "filename",
            "scale",
            "invert",
            "encoding",
            "wrap",
            "filter",
            "maxanisotropy",
        ],
        (Kind::Texture, "scale") => &["tex", "scale"],
        (Kind::Texture, "mix") => &["tex1", "tex2", "amount"],
        (Kind::Texture, "directionmix") => &["tex1", "tex2", "dir"],
        (Kind::Texture, "bilerp") => &["v00", "v01", "v10", "v11"],
        (Kind::Texture, "dots") => &["inside", "outside"],
        (Kind::Texture, "fbm" | "wrinkled") => &["octaves", "roughness"],
        (Kind::Texture, "windy" | "marble" | "ptex") => &[
            "octaves",
            "roughness",
            "scale",
            "variation",
            "filename",
            "encoding",
        ],
        (Kind::Medium, "homogeneous") => &[
            "sigma_a", "sigma_s", "scale", "g", "Le", "Lescale", "preset",
        ],
        (Kind::Medium, "uniformgrid" | "nanovdb" | "cloud") => &[],
        (Kind::Medium, "rgbgrid") => &[
            "sigma_a", "sigma_s", "Le", "Lescale", "scale", "g", "nx", "ny", "nz", "p0", "p1",
        ],
        (Kind::Shape, "sphere") => &["radius", "zmin", "zmax", "phimax"],
        (Kind::Shape, "disk") => &["radius", "innerradius", "height", "phimax"],
        (Kind::Shape, "cylinder") => &["radius", "zmin", "zmax", "phimax"],
        (Kind::Shape, "trianglemesh") => &["P", "indices", "N", "uv", "S", "faceIndices"],
        (Kind::Shape, "bilinearmesh") => &["P", "indices", "N", "uv", "faceIndices"],
        (Kind::Shape, "plymesh") => &["filename", "displacement", "edgelength"],
        (Kind::Shape, "loopsubdiv") => &["levels", "indices", "P"],
        (Kind::Shape, "curve") => &[
            "P",
            "basis",
            "degree",
            "type",
            "N",
            "width",
            "width0",
            "width1",
            "splitdepth",
        ],
        _ => return None,
    };
    Some(own)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_type_has_its_own_and_the_common_names() {
        let sphere = parameters(Kind::Shape, "sphere").unwrap();
        assert!(sphere.contains(&"radius") && sphere.contains(&"alpha"));
        let film = parameters(Kind::Film, "spectral").unwrap();
        assert!(film.contains(&"nbuckets") && film.contains(&"xresolution"));
        assert!(parameters(Kind::Medium, "homogeneous")
            .unwrap()
            .contains(&"preset"));
        assert!(parameters(Kind::Shape, "teapot").is_none());
    }

    #[test]
    fn pbrt_compat_lists_every_parameter() {
        // docs/reference/pbrt-compat.md has a row per pbrt-v4 directive and type, and every parameter pbrt-v4 reads for it
        // appears (`name`) in that row or the directive's "(all)" row.
        let doc = include_str!("../../../../docs/reference/pbrt-compat.md");
        let rows: Vec<Vec<&str>> = doc
            .lines()
            .filter(|l| l.starts_with('|'))
            .map(|l| l.split('|').map(str::trim).collect())
            .filter(|c: &Vec<&str>| c.len() > 4)
            .collect();
        let types: &[(Kind, &str, &[&str])] = &[
            (
                Kind::Camera,
                "Camera",
                &["perspective", "orthographic", "realistic", "spherical"],
            ),
            (Kind::Film, "Film", &["rgb", "gbuffer", "spectral"]),
            (
                Kind::Sampler,
                "Sampler",
                &[
                    "independent",
                    "stratified",
                    "zsobol",
                    "sobol",
                    "paddedsobol",
                    "halton",
                    "pmj02bn",
                ],
            ),
            (
                Kind::PixelFilter,
                "PixelFilter",
                &["box", "triangle", "gaussian", "mitchell", "sinc", "lanczos"],
            ),
            (
                Kind::Integrator,
                "Integrator",
                &[
                    "volpath",
                    "path",
                    "simplevolpath",
                    "simplepath",
                    "bdpt",
                    "mlt",
                    "sppm",
                    "ambientocclusion",
                    "randomwalk",
                    "lightpath",
                ],
            ),
            (
                Kind::Light,
                "LightSource",
                &[
                    "point",
                    "spot",
                    "goniometric",
                    "projection",
                    "distant",
                    "infinite",
                ],
            ),
            (Kind::AreaLight, "AreaLightSource", &["diffuse"]),
            (
                Kind::Material,
                "Material",
                &[
                    "interface",
                    "diffuse",
                    "coateddiffuse",
                    "coatedconductor",
                    "conductor",
                    "dielectric",
                    "thindielectric",
                    "diffusetransmission",
                    "mix",
                    "measured",
                    "subsurface",
                    "hair",
                ],
            ),
            (
                Kind::Texture,
                "Texture",
                &[
                    "constant",
                    "checkerboard",
                    "imagemap",
                    "scale",
                    "mix",
                    "directionmix",
                    "bilerp",
                    "dots",
                    "fbm",
                    "wrinkled",
                    "windy",
                    "marble",
                    "ptex",
                ],
            ),
            (
                Kind::Medium,
                "MakeNamedMedium",
                &["homogeneous", "uniformgrid", "nanovdb", "rgbgrid", "cloud"],
            ),
            (
                Kind::Shape,
                "Shape",
                &[
                    "sphere",
                    "disk",
                    "cylinder",
                    "trianglemesh",
                    "bilinearmesh",
                    "plymesh",
                    "loopsubdiv",
                    "curve",
                ],
            ),
        ];
        for (kind, directive, tys) in types {
            let all = rows
                .iter()
                .find(|r| r[1] == *directive && r[2] == "(all)")
                .map(|r| r.join("|"))
                .unwrap_or_default();
            for ty in *tys {
                let row = rows
                    .iter()
                    .find(|r| r[1] == *directive && r[2].split(", ").any(|t| t == *ty))
                    .map(|r| r.join("|"))
                    .unwrap_or_else(|| {
                        panic!("docs/reference/pbrt-compat.md: no row for {directive} \"{ty}\"")
                    });
                for name in parameters(*kind, ty).unwrap_or_default() {
                    let quoted = format!("`{name}`");
                    assert!(
                        row.contains(&quoted) || all.contains(&quoted),
                        "docs/reference/pbrt-compat.md: {directive} \"{ty}\" does not say what becomes of {quoted}"
                    );
                }
            }
        }
    }
}
