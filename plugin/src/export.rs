//! The C ABI export: the one `unsafe` module of the plugin. Every exported function checks its pointers, runs
//! under `catch_unwind`, and returns a status; messages go to a per-thread last-error slot. No Rust type
//! crosses the boundary: the table and its types are `firemedium-abi`'s `#[repr(C)]` ones.

use crate::light::{FireLight, Weighting};
use crate::params::{Param, ParamType, Values};
use crate::volume::{ColorMode, Event, FireVolume, Integrator, Ray};
use crate::Error;
use firemedium_abi::*;
use glam::DVec3;
use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::OnceLock;

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

fn set_error(msg: String) {
    LAST_ERROR.with(|e| *e.borrow_mut() = msg);
}

/// Runs `f`, mapping its error and any panic to a status and the last-error message.
fn guard(f: impl FnOnce() -> Result<(), (FmStatus, String)>) -> FmStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => FM_OK,
        Ok(Err((status, msg))) => {
            set_error(msg);
            status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            set_error(format!("firemedium: internal error (panic: {what}); the call did nothing, the host may continue"));
            FM_PANIC
        }
    }
}

fn status_of(e: &Error) -> FmStatus {
    match e {
        Error::InvalidParameter { .. } => FM_INVALID_PARAMETER,
        Error::Format { .. } | Error::Io { .. } | Error::TooLarge { .. } => FM_DATASET,
        Error::Unsupported { .. } => FM_UNSUPPORTED,
    }
}

fn fail(e: Error) -> (FmStatus, String) {
    (status_of(&e), e.to_string())
}

fn bad(msg: impl Into<String>) -> (FmStatus, String) {
    (FM_INVALID_ARGUMENT, msg.into())
}

unsafe extern "C" fn last_error(buf: *mut c_char, cap: usize) -> usize {
    LAST_ERROR.with(|e| {
        let e = e.borrow();
        let bytes = e.as_bytes();
        if !buf.is_null() && cap > 0 {
            let n = bytes.len().min(cap - 1);
            // SAFETY: the caller passes a writable buffer of `cap` bytes (ABI contract); we write n + 1 ≤ cap.
            unsafe {
                std::ptr::copy_nonoverlapping(bytes.as_ptr(), buf as *mut u8, n);
                *buf.add(n) = 0;
            }
        }
        bytes.len()
    })
}

/// Every row of the public parameter tables, as C strings that live as long as the library.
fn param_rows() -> &'static [[CString; 7]] {
    static ROWS: OnceLock<Vec<[CString; 7]>> = OnceLock::new();
    ROWS.get_or_init(|| {
        let c = |s: &str| CString::new(s.replace('\0', " ")).unwrap_or_default();
        crate::volume::params::components()
            .iter()
            .flat_map(|comp| {
                comp.params.iter().map(move |p| {
                    [
                        c(comp.name),
                        c(p.name),
                        c(p.ty.name()),
                        c(p.default),
                        c(p.unit),
                        c(&p.range.describe().replace("\\|", "|")),
                        c(p.doc),
                    ]
                })
            })
            .collect()
    })
}

unsafe extern "C" fn param_count() -> usize {
    catch_unwind(|| param_rows().len()).unwrap_or(0)
}

unsafe extern "C" fn param_info(index: usize, out: *mut FmParamInfo) -> FmStatus {
    guard(|| {
        if out.is_null() {
            return Err(bad("param_info: out is null"));
        }
        let rows = param_rows();
        let r = rows.get(index).ok_or_else(|| {
            bad(format!(
                "param_info: index {index} is not below the {} rows",
                rows.len()
            ))
        })?;
        // SAFETY: out is non-null and points to an FmParamInfo the caller owns (ABI contract).
        unsafe {
            *out = FmParamInfo {
                component: r[0].as_ptr(),
                name: r[1].as_ptr(),
                ty: r[2].as_ptr(),
                default_value: r[3].as_ptr(),
                unit: r[4].as_ptr(),
                range: r[5].as_ptr(),
                doc: r[6].as_ptr(),
            };
        }
        Ok(())
    })
}

/// Copies C parameters into Rust ones.
///
/// # Safety
/// `params` points to `count` valid `FmParam`s whose `values` hold `count` elements of their type.
unsafe fn read_params(
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
        // SAFETY: non-null, `count` entries (caller contract of volume_create_located).
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

unsafe extern "C" fn volume_create(
    params: *const FmParam,
    count: usize,
    out: *mut *mut FmVolume,
) -> FmStatus {
    // SAFETY: the caller's contract, as volume_create_located's without locations.
    unsafe { volume_create_located(params, std::ptr::null(), count, out) }
}

unsafe extern "C" fn volume_create_located(
    params: *const FmParam,
    locations: *const *const c_char,
    count: usize,
    out: *mut *mut FmVolume,
) -> FmStatus {
    guard(|| {
        if out.is_null() {
            return Err(bad("volume_create: out is null"));
        }
        // SAFETY: the caller's contract for `params`/`locations`/`count` (documented in FmApi).
        let list = unsafe { read_params(params, locations, count) }?;
        let v = FireVolume::new(&list).map_err(fail)?;
        // SAFETY: out is non-null and writable (checked, contract).
        unsafe { *out = std::sync::Arc::into_raw(std::sync::Arc::new(v)) as *mut FmVolume };
        Ok(())
    })
}

unsafe extern "C" fn volume_destroy(volume: *mut FmVolume) {
    if !volume.is_null() {
        let _ = catch_unwind(|| {
            // SAFETY: a handle from volume_create (Arc::into_raw), destroyed once (contract); lights hold their
            // own references.
            drop(unsafe { std::sync::Arc::from_raw(volume as *const FireVolume) });
        });
    }
}

/// The volume behind a handle.
///
/// # Safety
/// `v` is null or a live handle from `volume_create`.
unsafe fn vol<'a>(v: *const FmVolume, what: &str) -> Result<&'a FireVolume, (FmStatus, String)> {
    if v.is_null() {
        return Err(bad(format!("{what}: volume is null")));
    }
    // SAFETY: live handle (contract); volumes are immutable and Sync.
    Ok(unsafe { &*(v as *const FireVolume) })
}

/// `n × c` mutable f32 outputs at `p` (null → None).
///
/// # Safety
/// `p` is null or points to `n × c` writable f32.
unsafe fn out_f32<'a>(
    p: *mut f32,
    n: usize,
    c: usize,
) -> Result<Option<&'a mut [f32]>, (FmStatus, String)> {
    if p.is_null() {
        return Ok(None);
    }
    let len = n
        .checked_mul(c)
        .ok_or_else(|| bad(format!("{n} rays × {c} channels overflow")))?;
    // SAFETY: caller provides n × c floats (contract).
    Ok(Some(unsafe { std::slice::from_raw_parts_mut(p, len) }))
}

/// # Safety
/// `rays` points to `n` rays.
unsafe fn rays<'a>(rays: *const FmRay, n: usize) -> Result<&'a [FmRay], (FmStatus, String)> {
    if n == 0 {
        return Ok(&[]);
    }
    if rays.is_null() {
        return Err(bad(format!("{n} rays at a null pointer")));
    }
    // SAFETY: n rays (contract).
    Ok(unsafe { std::slice::from_raw_parts(rays, n) })
}

fn ray_of(r: &FmRay) -> Ray {
    Ray {
        o: DVec3::from(r.origin),
        d: DVec3::from(r.direction),
        t0: r.tmin,
        t1: r.tmax,
        seed: r.seed,
    }
}

unsafe extern "C" fn volume_info(volume: *const FmVolume, out: *mut FmVolumeInfo) -> FmStatus {
    guard(|| {
        // SAFETY: contract of the handle.
        let v = unsafe { vol(volume, "volume_info") }?;
        if out.is_null() {
            return Err(bad("volume_info: out is null"));
        }
        let [p0, p1] = v.bounds();
        let (space, lo, hi) = match v.color_mode() {
            ColorMode::Spectral(g) => (FM_SPACE_SPECTRAL, g.min_nm(), g.max_nm()),
            ColorMode::Rgb => (FM_SPACE_XYZ, 380.0, 780.0),
        };
        let info = FmVolumeInfo {
            bounds_min: p0.to_array(),
            bounds_max: p1.to_array(),
            channels: v.channels() as u32,
            channel_space: space,
            lambda_min: lo,
            lambda_max: hi,
            g: v.g(),
            scatters: v.scatters() as u32,
            integrator: match v.integrator() {
                Integrator::March => FM_INTEGRATOR_MARCH,
                Integrator::Ratio => FM_INTEGRATOR_RATIO,
                Integrator::Delta => FM_INTEGRATOR_DELTA,
            },
            step: v.step_length(),
            bytes: v.bytes() as u64,
            build_seconds: v.build_seconds(),
        };
        // SAFETY: non-null, writable (contract).
        unsafe { *out = info };
        Ok(())
    })
}

unsafe extern "C" fn volume_channel_xyz(
    volume: *const FmVolume,
    out: *mut f64,
    cap: usize,
) -> FmStatus {
    guard(|| {
        // SAFETY: contract of the handle.
        let v = unsafe { vol(volume, "volume_channel_xyz") }?;
        let w = v.channel_xyz();
        if out.is_null() || cap < 3 * w.len() {
            return Err(bad(format!(
                "volume_channel_xyz: need room for {} doubles, have {cap}",
                3 * w.len()
            )));
        }
        // SAFETY: non-null with cap ≥ 3·channels doubles (checked, contract).
        let o = unsafe { std::slice::from_raw_parts_mut(out, 3 * w.len()) };
        for (i, x) in w.iter().enumerate() {
            o[3 * i..3 * i + 3].copy_from_slice(&x.to_array());
        }
        Ok(())
    })
}

unsafe extern "C" fn volume_integrate(
    volume: *const FmVolume,
    rays_ptr: *const FmRay,
    n: usize,
    radiance: *mut f32,
    transmittance: *mut f32,
    exits: *mut FmExit,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_integrate") }?;
        // SAFETY: `rays` holds `n` rays (caller contract); null or absurd counts are refused.
        let rs = unsafe { rays(rays_ptr, n) }?;
        let c = v.channels();
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let l_out = unsafe { out_f32(radiance, n, c) }?
            .ok_or_else(|| bad("volume_integrate: radiance is null"))?;
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let mut t_out = unsafe { out_f32(transmittance, n, c) }?;
        let mut e_out = if exits.is_null() {
            None
        } else {
            // SAFETY: `exits` is non-null here and holds `n` entries (caller contract).
            Some(unsafe { std::slice::from_raw_parts_mut(exits, n) })
        };
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        for (i, r) in rs.iter().enumerate() {
            let ray = ray_of(r);
            // A host that does not ask where the ray leaves gets the straight ray (light paths, NEE).
            let (p_exit, d_exit, t_exit) = if e_out.is_some() {
                v.integrate_exit(&ray, &mut l, &mut t)
            } else {
                let te = v.integrate(&ray, &mut l, &mut t);
                (ray.o + ray.d * te, ray.d, te)
            };
            for k in 0..c {
                l_out[i * c + k] = l[k] as f32;
            }
            if let Some(to) = t_out.as_deref_mut() {
                for k in 0..c {
                    to[i * c + k] = t[k] as f32;
                }
            }
            if let Some(eo) = e_out.as_deref_mut() {
                eo[i] = FmExit {
                    point: p_exit.to_array(),
                    direction: d_exit.to_array(),
                    t: t_exit,
                };
            }
        }
        Ok(())
    })
}

unsafe extern "C" fn volume_transmittance(
    volume: *const FmVolume,
    rays_ptr: *const FmRay,
    n: usize,
    transmittance: *mut f32,
) -> FmStatus {
    guard(|| {
        // SAFETY: the caller's buffers are as the ABI documents.
        let v = unsafe { vol(volume, "volume_transmittance") }?;
        // SAFETY: `rays` holds `n` rays (caller contract); null or absurd counts are refused.
        let rs = unsafe { rays(rays_ptr, n) }?;
        let c = v.channels();
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let out = unsafe { out_f32(transmittance, n, c) }?
            .ok_or_else(|| bad("volume_transmittance: transmittance is null"))?;
        let mut t = vec![0.0; c];
        for (i, r) in rs.iter().enumerate() {
            v.transmittance(&ray_of(r), &mut t);
            for k in 0..c {
                out[i * c + k] = t[k] as f32;
            }
        }
        Ok(())
    })
}

unsafe extern "C" fn volume_sample_scatter(
    volume: *const FmVolume,
    rays_ptr: *const FmRay,
    n: usize,
    events: *mut FmScatter,
    weights: *mut f32,
    emitted: *mut f32,
) -> FmStatus {
    guard(|| {
        // SAFETY: the caller's buffers are as the ABI documents.
        let v = unsafe { vol(volume, "volume_sample_scatter") }?;
        // SAFETY: `rays` holds `n` rays (caller contract); null or absurd counts are refused.
        let rs = unsafe { rays(rays_ptr, n) }?;
        let c = v.channels();
        if events.is_null() && n > 0 {
            return Err(bad("volume_sample_scatter: events is null"));
        }
        let ev = if n == 0 {
            &mut [][..]
        } else {
            // SAFETY: `events` is non-null here and holds `n` entries (caller contract).
            unsafe { std::slice::from_raw_parts_mut(events, n) }
        };
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let w_out = unsafe { out_f32(weights, n, c) }?
            .ok_or_else(|| bad("volume_sample_scatter: weights is null"))?;
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let mut l_out = unsafe { out_f32(emitted, n, c) }?;
        let (mut l, mut w) = (vec![0.0; c], vec![0.0; c]);
        for (i, r) in rs.iter().enumerate() {
            let ray = ray_of(r);
            let e = v.sample_scatter(&ray, &mut l, &mut w);
            let (event, t) = match e {
                Event::Escaped => (FM_EVENT_ESCAPED, ray.t1),
                Event::Scattered(t) => (FM_EVENT_SCATTERED, t),
                Event::Absorbed => (FM_EVENT_ABSORBED, ray.t1),
            };
            ev[i] = FmScatter {
                event,
                reserved: 0,
                t,
                point: (ray.o + ray.d * t).to_array(),
            };
            for k in 0..c {
                w_out[i * c + k] = w[k] as f32;
            }
            if let Some(lo) = l_out.as_deref_mut() {
                for k in 0..c {
                    lo[i * c + k] = l[k] as f32;
                }
            }
        }
        Ok(())
    })
}

unsafe extern "C" fn volume_coefficients(
    volume: *const FmVolume,
    points: *const f64,
    n: usize,
    sigma_a: *mut f32,
    sigma_s: *mut f32,
    emission: *mut f32,
) -> FmStatus {
    guard(|| {
        // SAFETY: the caller's buffers are as the ABI documents.
        let v = unsafe { vol(volume, "volume_coefficients") }?;
        if points.is_null() && n > 0 {
            return Err(bad("volume_coefficients: points is null"));
        }
        let pts = if n == 0 {
            &[][..]
        } else {
            // SAFETY: `points` is non-null here and holds `3 n` doubles (caller contract).
            unsafe { std::slice::from_raw_parts(points, 3 * n) }
        };
        let c = v.channels();
        let mut outs = [
            // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
            unsafe { out_f32(sigma_a, n, c) }?,
            // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
            unsafe { out_f32(sigma_s, n, c) }?,
            // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
            unsafe { out_f32(emission, n, c) }?,
        ];
        let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        for i in 0..n {
            v.coefficients(
                DVec3::new(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]),
                &mut a,
                &mut s,
                &mut j,
            );
            for (o, src) in outs.iter_mut().zip([&a, &s, &j]) {
                if let Some(o) = o.as_deref_mut() {
                    for k in 0..c {
                        o[i * c + k] = src[k] as f32;
                    }
                }
            }
        }
        Ok(())
    })
}

/// The light behind a handle.
///
/// # Safety
/// `l` is null or a live handle from `light_create`.
unsafe fn light<'a>(l: *const FmLight, what: &str) -> Result<&'a FireLight, (FmStatus, String)> {
    if l.is_null() {
        return Err(bad(format!("{what}: light is null")));
    }
    // SAFETY: live handle (contract); lights are immutable and Sync.
    Ok(unsafe { &*(l as *const FireLight) })
}

unsafe extern "C" fn light_create(
    volume: *const FmVolume,
    params: *const FmParam,
    count: usize,
    out: *mut *mut FmLight,
) -> FmStatus {
    guard(|| {
        if out.is_null() || volume.is_null() {
            return Err(bad("light_create: volume or out is null"));
        }
        // SAFETY: the caller's contract for `params`/`count`.
        let list = unsafe { read_params(params, std::ptr::null(), count) }?;
        let r = crate::params::ParamReader::new("light", &list, &[&crate::volume::params::LIGHT]);
        r.check_names().map_err(fail)?;
        let weighting = match r.string("weighting").map_err(fail)?.as_str() {
            "luminance" => Weighting::Luminance,
            _ => Weighting::Power,
        };
        r.finish().map_err(fail)?;
        // SAFETY: a live handle from volume_create is an Arc::into_raw pointer; take one more reference.
        let vol = unsafe {
            std::sync::Arc::increment_strong_count(volume as *const FireVolume);
            std::sync::Arc::from_raw(volume as *const FireVolume)
        };
        let l = FireLight::new(vol, weighting).map_err(fail)?;
        // SAFETY: out is non-null and writable.
        unsafe { *out = Box::into_raw(Box::new(l)) as *mut FmLight };
        Ok(())
    })
}

unsafe extern "C" fn light_destroy(l: *mut FmLight) {
    if !l.is_null() {
        let _ = catch_unwind(|| {
            // SAFETY: a handle from light_create, destroyed once (contract).
            drop(unsafe { Box::from_raw(l as *mut FireLight) });
        });
    }
}

unsafe extern "C" fn light_info(l: *const FmLight, out: *mut FmLightInfo) -> FmStatus {
    guard(|| {
        // SAFETY: the handle's contract.
        let lt = unsafe { light(l, "light_info") }?;
        if out.is_null() {
            return Err(bad("light_info: out is null"));
        }
        let info = FmLightInfo {
            power_w: lt.power_w(),
            power_lm: lt.power_lm(),
            voxels: lt.voxels() as u64,
            bytes: lt.bytes() as u64,
            build_seconds: lt.build_seconds(),
            weighting: if lt.weighting() == Weighting::Power {
                FM_WEIGHTING_POWER
            } else {
                FM_WEIGHTING_LUMINANCE
            },
            reserved: 0,
        };
        // SAFETY: non-null, writable.
        unsafe { *out = info };
        Ok(())
    })
}

/// `n × k` doubles at `p`, required.
///
/// # Safety
/// `p` is null or points to `n × k` doubles.
unsafe fn in_f64<'a>(
    p: *const f64,
    n: usize,
    k: usize,
    what: &str,
) -> Result<&'a [f64], (FmStatus, String)> {
    if n == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(bad(format!("{what} is null")));
    }
    let len = n
        .checked_mul(k)
        .ok_or_else(|| bad(format!("{what}: {n} × {k} overflows")))?;
    // SAFETY: caller provides n × k doubles (contract).
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// # Safety
/// `p` is null or points to `n × k` writable doubles.
unsafe fn out_f64<'a>(
    p: *mut f64,
    n: usize,
    k: usize,
    what: &str,
) -> Result<&'a mut [f64], (FmStatus, String)> {
    if n == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(bad(format!("{what} is null")));
    }
    let len = n
        .checked_mul(k)
        .ok_or_else(|| bad(format!("{what}: {n} × {k} overflows")))?;
    // SAFETY: caller provides n × k writable doubles (contract).
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

unsafe extern "C" fn light_sample(
    l: *const FmLight,
    u: *const f64,
    n: usize,
    points: *mut f64,
    pdf: *mut f64,
    emission: *mut f32,
) -> FmStatus {
    guard(|| {
        // SAFETY: `l` is null (refused) or a live handle from light_create (caller contract).
        let lt = unsafe { light(l, "light_sample") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let us = unsafe { in_f64(u, n, 6, "light_sample: u") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pts = unsafe { out_f64(points, n, 3, "light_sample: points") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pd = unsafe { out_f64(pdf, n, 1, "light_sample: pdf") }?;
        let c = lt.volume().channels();
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let mut em = unsafe { out_f32(emission, n, c) }?;
        let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        for i in 0..n {
            let uu = [
                us[6 * i],
                us[6 * i + 1],
                us[6 * i + 2],
                us[6 * i + 3],
                us[6 * i + 4],
                us[6 * i + 5],
            ]
            .map(|x| x.clamp(0.0, 1.0 - f64::EPSILON));
            let smp = lt.sample(uu);
            pts[3 * i..3 * i + 3].copy_from_slice(&smp.point.to_array());
            pd[i] = smp.pdf;
            if let Some(e) = em.as_deref_mut() {
                lt.volume().coefficients(smp.point, &mut a, &mut s, &mut j);
                for k in 0..c {
                    e[i * c + k] = j[k] as f32;
                }
            }
        }
        Ok(())
    })
}

unsafe extern "C" fn light_pdf(
    l: *const FmLight,
    points: *const f64,
    n: usize,
    pdf: *mut f64,
) -> FmStatus {
    guard(|| {
        // SAFETY: `l` is null (refused) or a live handle from light_create (caller contract).
        let lt = unsafe { light(l, "light_pdf") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pts = unsafe { in_f64(points, n, 3, "light_pdf: points") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pd = unsafe { out_f64(pdf, n, 1, "light_pdf: pdf") }?;
        for i in 0..n {
            pd[i] = lt.pdf(DVec3::new(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
        }
        Ok(())
    })
}

unsafe extern "C" fn light_pdf_direction(
    l: *const FmLight,
    origins: *const f64,
    directions: *const f64,
    n: usize,
    pdf: *mut f64,
) -> FmStatus {
    guard(|| {
        // SAFETY: `l` is null (refused) or a live handle from light_create (caller contract).
        let lt = unsafe { light(l, "light_pdf_direction") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let o = unsafe { in_f64(origins, n, 3, "light_pdf_direction: origins") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let d = unsafe { in_f64(directions, n, 3, "light_pdf_direction: directions") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pd = unsafe { out_f64(pdf, n, 1, "light_pdf_direction: pdf") }?;
        for i in 0..n {
            pd[i] = lt.pdf_direction(
                DVec3::new(o[3 * i], o[3 * i + 1], o[3 * i + 2]),
                DVec3::new(d[3 * i], d[3 * i + 1], d[3 * i + 2]),
            );
        }
        Ok(())
    })
}

unsafe extern "C" fn volume_temperature_range(volume: *const FmVolume, out: *mut f64) -> FmStatus {
    guard(|| {
        // SAFETY: contract of the handle.
        let v = unsafe { vol(volume, "volume_temperature_range") }?;
        // SAFETY: room for two doubles (contract).
        let o = unsafe { out_f64(out, 2, 1, "volume_temperature_range: out") }?;
        let [lo, hi] = v.temperature_range().unwrap_or([0.0, 0.0]);
        o[0] = lo;
        o[1] = hi;
        Ok(())
    })
}

static API: FmApi = FmApi {
    abi_major: ABI_MAJOR,
    abi_minor: ABI_MINOR,
    struct_size: std::mem::size_of::<FmApi>() as u32,
    reserved: 0,
    last_error,
    param_count,
    param_info,
    volume_create,
    volume_destroy,
    volume_info,
    volume_channel_xyz,
    volume_integrate,
    volume_transmittance,
    volume_sample_scatter,
    volume_coefficients,
    light_create,
    light_destroy,
    light_info,
    light_sample,
    light_pdf,
    light_pdf_direction,
    volume_temperature_range,
    volume_create_located,
};

/// The plugin's entry point: the static function table.
#[no_mangle]
pub extern "C" fn firemedium_plugin_entry() -> *const FmApi {
    &API
}

#[cfg(test)]
mod tests {
    //! The panic guard, through the same `extern "C"` table a host gets. The `faultinjection` parameter that
    //! panics exists only in this crate's unit-test build (`cfg(test)`), never in the shipped library.
    use super::*;

    fn param(name: &CStr, ty: u32, count: u32, values: *const std::ffi::c_void) -> FmParam {
        FmParam {
            name: name.as_ptr(),
            ty,
            count,
            values,
        }
    }

    /// Creates a 2³ soot slab at 1500 K through the table, with `fault` as its fault-injection point.
    fn create(api: &FmApi, fault: &CStr) -> (FmStatus, *mut FmVolume) {
        let d = [1.0f64; 8];
        let t = [1500.0f64; 8];
        let n = [2i64];
        let fault_ptr = [fault.as_ptr()];
        let list = [
            param(c"density", FM_TYPE_FLOAT, 8, d.as_ptr().cast()),
            param(c"temperature", FM_TYPE_FLOAT, 8, t.as_ptr().cast()),
            param(c"nx", FM_TYPE_INTEGER, 1, n.as_ptr().cast()),
            param(c"ny", FM_TYPE_INTEGER, 1, n.as_ptr().cast()),
            param(c"nz", FM_TYPE_INTEGER, 1, n.as_ptr().cast()),
            param(
                c"faultinjection",
                FM_TYPE_STRING,
                1,
                fault_ptr.as_ptr().cast(),
            ),
        ];
        let mut out = std::ptr::null_mut();
        // SAFETY: every parameter points at live values of its type and count; `out` is writable.
        let status = unsafe { (api.volume_create)(list.as_ptr(), list.len(), &mut out) };
        (status, out)
    }

    fn last(api: &FmApi) -> String {
        let mut buf = vec![0 as c_char; 512];
        // SAFETY: the buffer holds `buf.len()` chars.
        unsafe { (api.last_error)(buf.as_mut_ptr(), buf.len()) };
        // SAFETY: last_error NUL-terminates within the capacity.
        unsafe { CStr::from_ptr(buf.as_ptr()) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn a_panic_inside_the_plugin_is_a_status_and_the_host_lives_on() {
        // SAFETY: the entry returns a pointer to the static table.
        let api = unsafe { &*firemedium_plugin_entry() };
        let (status, v) = create(api, c"create");
        assert_eq!(status, FM_PANIC);
        assert!(v.is_null());
        let msg = last(api);
        assert!(
            msg.contains("panic") && msg.contains("fault injection"),
            "{msg}"
        );

        let (status, v) = create(api, c"integrate");
        assert_eq!(status, FM_OK, "{}", last(api));
        let ray = FmRay {
            origin: [-0.5, 0.5, 0.5],
            direction: [1.0, 0.0, 0.0],
            tmin: 0.0,
            tmax: 3.0,
            seed: 1,
        };
        let mut info = FmVolumeInfo::default();
        // SAFETY: `v` is a live volume, `info` writable.
        assert_eq!(unsafe { (api.volume_info)(v, &mut info) }, FM_OK);
        let mut l = vec![0f32; info.channels as usize];
        assert_eq!(integrate_one(api, v, &ray, &mut l), FM_PANIC);
        assert!(last(api).contains("fault injection"));
        // SAFETY: `v` came from volume_create and is destroyed once.
        unsafe { (api.volume_destroy)(v) };

        // The plugin still works afterwards: the same slab without the fault emits.
        let (status, v) = create(api, c"");
        assert_eq!(status, FM_OK, "{}", last(api));
        assert_eq!(integrate_one(api, v, &ray, &mut l), FM_OK);
        assert!(l.iter().any(|&x| x > 0.0), "{l:?}");
        // SAFETY: as above.
        unsafe { (api.volume_destroy)(v) };
    }

    fn integrate_one(api: &FmApi, v: *mut FmVolume, ray: &FmRay, l: &mut [f32]) -> FmStatus {
        // SAFETY: one ray, `l` holds the volume's channels, optional outputs null.
        unsafe {
            (api.volume_integrate)(
                v,
                ray,
                1,
                l.as_mut_ptr(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        }
    }
}
