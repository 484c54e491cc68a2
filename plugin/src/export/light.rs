//! The fire light's entries: create, destroy, describe, sample, and the pdfs per volume and per solid angle.

use super::buffers::{in_f64, out_f32, out_values, ray_of, rays, store, times};
use super::params::read_params;
use super::{bad, fail, guard};
use crate::light::{FireLight, Weighting};
use firemedium_abi::*;
use glam::DVec3;
use std::panic::catch_unwind;

/// The light behind a handle.
///
/// # Safety
/// `l` is null or a live handle from `light_create`.
pub(super) unsafe fn light<'a>(
    l: *const FmLight,
    what: &str,
) -> Result<&'a FireLight, (FmStatus, String)> {
    if l.is_null() {
        return Err(bad(format!("{what}: light is null")));
    }
    // SAFETY: live handle (contract); lights are immutable and Sync.
    Ok(unsafe { &*(l as *const FireLight) })
}

pub(super) unsafe extern "C" fn light_create(
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
        // (Errors about a parameter carry its index in the host's list.)
        let located = |e: crate::Error| fail(e.located(crate::params::location_in(&list)));
        let r = crate::params::ParamReader::new("light", &list, &[&crate::light::params::LIGHT]);
        r.check_names().map_err(located)?;
        let weighting: Weighting = r.choice("weighting").map_err(located)?;
        let cell = r.int("cell").map_err(located)?;
        let line = crate::light::LineEstimate {
            step_voxels: r.float("linestep").map_err(located)?,
            correction: r.float("linecorrection").map_err(located)?,
            block: r.int("lineblock").map_err(located)?.max(0) as usize,
            channels: r.int("linechannels").map_err(located)?.max(0) as usize,
        };
        r.finish().map_err(located)?;
        // SAFETY: a live handle from volume_create (contract).
        let handle = unsafe { &*(volume as *const super::volume::VolumeHandle) };
        let vol = handle.volume.clone();
        let l = crate::par::with_pool(handle.pool.clone(), || {
            FireLight::with(vol, weighting, cell as usize, line)
        })
        .map_err(fail)?;
        // SAFETY: out is non-null and writable.
        unsafe { *out = Box::into_raw(Box::new(l)) as *mut FmLight };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn light_destroy(l: *mut FmLight) {
    if !l.is_null() {
        let _ = catch_unwind(|| {
            // SAFETY: a handle from light_create, destroyed once (contract).
            drop(unsafe { Box::from_raw(l as *mut FireLight) });
        });
    }
}

pub(super) unsafe extern "C" fn light_info(l: *const FmLight, out: *mut FmLightInfo) -> FmStatus {
    guard(|| {
        // SAFETY: the handle's contract.
        let lt = unsafe { light(l, "light_info") }?;
        // SAFETY: null or the host's FmLightInfo (contract).
        unsafe { super::sized(out, "light_info: out", "FmLightInfo") }?;
        let info = FmLightInfo {
            struct_size: std::mem::size_of::<FmLightInfo>(),
            power_w: lt.power_w(),
            power_lm: lt.power_lm(),
            voxels: lt.voxels() as u64,
            bytes: lt.bytes() as u64,
            build_seconds: lt.build_seconds(),
            weighting: match lt.weighting() {
                Weighting::Power => FM_WEIGHTING_POWER,
                Weighting::Luminance => FM_WEIGHTING_LUMINANCE,
                Weighting::Escaping => FM_WEIGHTING_ESCAPING,
            },
            line_block: lt.line_block() as u32,
        };
        // SAFETY: non-null with at least our struct's size writable (checked, contract).
        unsafe { out.write_unaligned(info) };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn light_sample(
    l: *const FmLight,
    u: *const f64,
    times_ptr: *const f64,
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
        // SAFETY: `times` is null or holds `n` doubles (caller contract).
        let ts = unsafe { times(times_ptr, n, "light_sample") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pts = unsafe { out_values(points, n, 3, "light_sample: points") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pd = unsafe { out_values(pdf, n, 1, "light_sample: pdf") }?;
        let c = lt.volume().channels();
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let mut em = unsafe { out_f32(emission, n, c) }?;
        // (The coefficients' scratch only when the host asks for the emission: a light sample per path vertex
        // paid three allocations for it.)
        let scratch = || vec![0.0; c];
        let (mut a, mut s, mut j) = if em.is_some() {
            (scratch(), scratch(), scratch())
        } else {
            (Vec::new(), Vec::new(), Vec::new())
        };
        for i in 0..n {
            let uu: [f64; 6] =
                std::array::from_fn(|k| us[6 * i + k].clamp(0.0, 1.0 - f64::EPSILON));
            let smp = lt.sample_at(uu, ts[i]);
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

pub(super) unsafe extern "C" fn light_pdf(
    l: *const FmLight,
    points: *const f64,
    times_ptr: *const f64,
    n: usize,
    pdf: *mut f64,
) -> FmStatus {
    guard(|| {
        // SAFETY: `l` is null (refused) or a live handle from light_create (caller contract).
        let lt = unsafe { light(l, "light_pdf") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pts = unsafe { in_f64(points, n, 3, "light_pdf: points") }?;
        // SAFETY: `times` is null or holds `n` doubles (caller contract).
        let ts = unsafe { times(times_ptr, n, "light_pdf") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pd = unsafe { out_values(pdf, n, 1, "light_pdf: pdf") }?;
        for i in 0..n {
            let p = DVec3::new(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]);
            pd[i] = lt.pdf_at(p, ts[i]);
        }
        Ok(())
    })
}

pub(super) unsafe extern "C" fn light_pdf_direction(
    l: *const FmLight,
    origins: *const f64,
    directions: *const f64,
    times_ptr: *const f64,
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
        // SAFETY: `times` is null or holds `n` doubles (caller contract).
        let ts = unsafe { times(times_ptr, n, "light_pdf_direction") }?;
        // SAFETY: the buffer holds `n` rows of the documented width or is null (caller contract).
        let pd = unsafe { out_values(pdf, n, 1, "light_pdf_direction: pdf") }?;
        for i in 0..n {
            let di = [d[3 * i], d[3 * i + 1], d[3 * i + 2]];
            super::buffers::direction(di)
                .map_err(|e| bad(format!("light_pdf_direction: directions row {i}: {e}")))?;
            pd[i] = lt.pdf_direction_at(
                DVec3::new(o[3 * i], o[3 * i + 1], o[3 * i + 2]),
                DVec3::from(di),
                ts[i],
            );
        }
        Ok(())
    })
}

pub(super) unsafe extern "C" fn light_integrate(
    l: *const FmLight,
    rays_ptr: *const FmRay,
    times_ptr: *const f64,
    n: usize,
    radiance: *mut f32,
    transmittance: *mut f32,
) -> FmStatus {
    guard(|| {
        // SAFETY: `l` is null (refused) or a live handle from light_create (caller contract).
        let lt = unsafe { light(l, "light_integrate") }?;
        // SAFETY: `rays` holds `n` rays (caller contract); null or absurd counts are refused.
        let rs = unsafe { rays(rays_ptr, n) }?;
        // SAFETY: `times` is null or holds `n` doubles (caller contract).
        let ts = unsafe { times(times_ptr, n, "light_integrate") }?;
        let c = lt.volume().channels();
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let l_out = unsafe { out_f32(radiance, n, c) }?
            .ok_or_else(|| bad("light_integrate: radiance is null"))?;
        // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
        let mut t_out = unsafe { out_f32(transmittance, n, c) }?;
        super::with_channels(c, |lv, tv| {
            for (i, r) in rs.iter().enumerate() {
                lt.integrate_at(&ray_of(r), ts[i], lv, tv);
                store(l_out, i, lv);
                if let Some(to) = t_out.as_deref_mut() {
                    store(to, i, tv);
                }
            }
        });
        Ok(())
    })
}

pub(super) unsafe extern "C" fn light_line_channels(l: *const FmLight, out: *mut u32) -> FmStatus {
    guard(|| {
        // SAFETY: `l` is null (refused) or a live handle from light_create (caller contract).
        let lt = unsafe { light(l, "light_line_channels") }?;
        if out.is_null() {
            return Err(bad("light_line_channels: out is null"));
        }
        // SAFETY: non-null, writable (caller contract).
        unsafe { *out = lt.line_channels() as u32 };
        Ok(())
    })
}
