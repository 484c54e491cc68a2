//! The parameter list a host passes to `volume_create(_located)`, read into the plugin's own `Param`s: every
//! pointer checked, every string UTF-8, each value array read with the type its tag names.

use super::bad;
use crate::params::{Param, ParamType, Values};
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
        });
    }
    Ok(out)
}
