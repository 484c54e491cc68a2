//! The parameter list a host passes to `volume_create(_located)`, read into the plugin's own `Param`s: every
//! pointer checked, every string UTF-8, each value array read with the type its tag names.

use super::bad;
use crate::light::params::LIGHT;
use crate::params::{Component, Param, ParamType, Range, Values};
use crate::volume::params::{DATASET, VOLUME};
use firemedium_abi::*;
use std::ffi::{c_char, CStr};

/// Copies C parameters into Rust ones.
///
/// # Safety
/// `params` points to `count` valid `FmParam`s whose `values` hold `count` elements of their type.
pub(super) unsafe fn read_params(
    params: *const FmParam,
    locations: *const *const c_char,
    count: usize,
) -> Result<Vec<Param>, (FmStatus, String)> {
    if count == 0 {
        return Ok(Vec::new());
    }
    if params.is_null() || count > 1 << 20 {
        return Err(bad(format!(
            "volume_create: {count} parameters at a null or absurd list"
        )));
    }
    // SAFETY: non-null, `count` entries (caller contract).
    let list = unsafe { std::slice::from_raw_parts(params, count) };
    let locations = if locations.is_null() {
        None
    } else {
        // SAFETY: non-null, `count` entries (caller contract of volume_create's FmCreateInfo).
        Some(unsafe { std::slice::from_raw_parts(locations, count) })
    };
    let mut out = Vec::with_capacity(count);
    for (i, p) in list.iter().enumerate() {
        if p.name.is_null() {
            return Err(bad(format!("volume_create: parameter {i} has a null name")));
        }
        // SAFETY: non-null, NUL-terminated (caller contract).
        let name = unsafe { CStr::from_ptr(p.name) }
            .to_str()
            .map_err(|_| bad(format!("volume_create: parameter {i}'s name is not UTF-8")))?
            .to_string();
        let n = p.count as usize;
        if n > 0 && p.values.is_null() {
            return Err(bad(format!(
                "volume_create: parameter '{name}' has {n} values at a null pointer"
            )));
        }
        let ty = match p.ty {
            FM_TYPE_FLOAT => ParamType::Float,
            FM_TYPE_INTEGER => ParamType::Integer,
            FM_TYPE_BOOL => ParamType::Bool,
            FM_TYPE_STRING => ParamType::String,
            FM_TYPE_POINT3 => ParamType::Point3,
            FM_TYPE_VECTOR3 => ParamType::Vector3,
            FM_TYPE_RGB => ParamType::Rgb,
            FM_TYPE_SPECTRUM => ParamType::Spectrum,
            t => {
                return Err(bad(format!(
                    "volume_create: parameter '{name}' has unknown type code {t}"
                )))
            }
        };
        // (Each arm reads `n` values only when n > 0; n == 0 reads nothing.)
        let values = match ty {
            ParamType::Integer => Values::Integers(if n == 0 {
                vec![]
            } else {
                // SAFETY: `values` holds `n` elements of the type `ty` names (caller contract); n > 0, so non-null (checked).
                unsafe { std::slice::from_raw_parts(p.values as *const i64, n) }.to_vec()
            }),
            ParamType::Bool => Values::Bools(if n == 0 {
                vec![]
            } else {
                // SAFETY: `values` holds `n` elements of the type `ty` names (caller contract); n > 0, so non-null (checked).
                unsafe { std::slice::from_raw_parts(p.values as *const u8, n) }
                    .iter()
                    .map(|&b| b != 0)
                    .collect()
            }),
            ParamType::String => {
                let ptrs = if n == 0 {
                    &[][..]
                } else {
                    // SAFETY: `values` holds `n` elements of the type `ty` names (caller contract); n > 0, so non-null (checked).
                    unsafe { std::slice::from_raw_parts(p.values as *const *const c_char, n) }
                };
                let mut v = Vec::with_capacity(n);
                for &s in ptrs {
                    if s.is_null() {
                        return Err(bad(format!(
                            "volume_create: parameter '{name}' has a null string"
                        )));
                    }
                    v.push(
                        // SAFETY: non-null (checked) and NUL-terminated (caller contract).
                        unsafe { CStr::from_ptr(s) }
                            .to_str()
                            .map_err(|_| {
                                bad(format!("volume_create: parameter '{name}' is not UTF-8"))
                            })?
                            .to_string(),
                    );
                }
                Values::Strings(v)
            }
            _ => Values::Numbers(if n == 0 {
                vec![]
            } else {
                // SAFETY: `values` holds `n` elements of the type `ty` names (caller contract); n > 0, so non-null (checked).
                unsafe { std::slice::from_raw_parts(p.values as *const f64, n) }.to_vec()
            }),
        };
        let at = match locations.map(|l| l[i]) {
            Some(s) if !s.is_null() => Some(
                // SAFETY: non-null (checked) and NUL-terminated (caller contract).
                unsafe { CStr::from_ptr(s) }
                    .to_str()
                    .map_err(|_| {
                        bad(format!(
                            "volume_create: parameter '{name}''s location is not UTF-8"
                        ))
                    })?
                    .to_string(),
            ),
            _ => None,
        };
        out.push(Param {
            name,
            ty,
            values,
            at,
            index: Some(i as u32),
        });
    }
    Ok(out)
}

/// Every public component, in documentation order.
pub(crate) fn components() -> [&'static Component; 3] {
    [&DATASET, &VOLUME, &LIGHT]
}

/// Relative file names in `list` (the values of the tables' `Range::Path` rows) made `dir`'s.
pub(crate) fn resolve_paths(list: &mut [Param], dir: &std::path::Path) {
    let is_path = |name: &str| {
        components()
            .iter()
            .flat_map(|c| c.params.iter())
            .any(|p| p.name == name && p.range == Range::Path)
    };
    for p in list.iter_mut().filter(|p| is_path(&p.name)) {
        if let Values::Strings(v) = &mut p.values {
            for s in v.iter_mut().filter(|s| !s.is_empty()) {
                if std::path::Path::new(s.as_str()).is_relative() {
                    *s = dir.join(&*s).display().to_string();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamType as T;
    use crate::volume::params::FAULTS;

    #[test]
    fn params_doc_is_current() {
        // docs/reference/params.md is generated from these tables; regenerate with FIREMEDIUM_BLESS=1.
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/reference/params.md");
        let want = crate::params::markdown(&components());
        if std::env::var_os("FIREMEDIUM_BLESS").is_some() {
            std::fs::write(path, &want).unwrap();
        }
        let have = std::fs::read_to_string(path).unwrap_or_default();
        assert!(have == want, "docs/reference/params.md is stale: run FIREMEDIUM_BLESS=1 cargo test -p firemedium-plugin params_doc");
    }

    #[test]
    fn names_are_unique_and_defaults_parse() {
        let mut seen = std::collections::HashSet::new();
        for c in components().iter().chain([&&FAULTS]) {
            for p in c.params {
                assert!(seen.insert(p.name), "parameter '{}' declared twice", p.name);
                if !p.default.is_empty() {
                    match p.ty {
                        T::Float => p
                            .default
                            .parse::<f64>()
                            .map(|_| ())
                            .unwrap_or_else(|_| panic!("{}: default {}", p.name, p.default)),
                        T::Integer => p.default.split_whitespace().for_each(|v| {
                            v.parse::<i64>()
                                .unwrap_or_else(|_| panic!("{}: default {}", p.name, p.default));
                        }),
                        _ => {}
                    }
                }
                if let Range::Choices(c) = p.range {
                    assert!(
                        c.contains(&p.default),
                        "{}: default {:?} not among {c:?}",
                        p.name,
                        p.default
                    );
                }
            }
        }
    }
}
