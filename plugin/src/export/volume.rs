//! The fire volume's entries: create (from the host's creation info), destroy, describe, the fast whole-ray query
//! (integrate, transmittance, scattering events), point coefficients in the channels, temperature range.

use super::buffers::{in_f64, out_f32, out_values, ray_of, rays, store, times};
use super::params::read_params;
use super::{bad, fail, guard};
use crate::par::Pool;

use crate::volume::{ColorMode, Event, FireVolume, HostContext, Integrator, Mode, Ray, Want};
use firemedium_abi::*;
use glam::DVec3;
use std::ffi::c_void;
use std::panic::catch_unwind;
use std::sync::Arc;

pub(super) unsafe extern "C" fn volume_create(
    info: *const FmCreateInfo,
    out: *mut *mut FmVolume,
) -> FmStatus {
    guard(|| {
        if out.is_null() {
            return Err(bad("volume_create: out is null"));
        }
        // SAFETY: null or the host's FmCreateInfo of its struct_size (contract); its fields are integers, pointers
        // and an Option of a function pointer, each valid as zero (a 1.0 host's struct lacks `directory`: null).
        let ci = unsafe {
            super::read_sized(
                info,
                firemedium_abi::FM_CREATE_INFO_SIZE_1_0,
                "volume_create: info",
                "FmCreateInfo",
            )
        }?;
        // SAFETY: the caller's contract for the parameter arrays (documented in FmCreateInfo).
        let mut list = unsafe { read_params(ci.params, ci.locations, ci.count) }?;
        if !ci.directory.is_null() {
            // SAFETY: non-null, a NUL-terminated string (the caller's contract).
            let dir = unsafe { std::ffi::CStr::from_ptr(ci.directory) };
            let dir = dir.to_str().map_err(|_| {
                bad(format!(
                    "volume_create: directory {:?}: expected UTF-8",
                    dir.to_string_lossy()
                ))
            })?;
            super::params::resolve_paths(&mut list, std::path::Path::new(dir));
        }
        // The host's context, typed: it stands where the scene does not set the same itself.
        if ci.threads > 4096 {
            return Err(bad(format!(
                "volume_create: threads {}: expected 0 (every core) to 4096",
                ci.threads
            )));
        }
        let frame = (ci.flags & FM_CREATE_FRAME != 0).then_some(ci.frame);
        if frame.is_some_and(|f| f.unsigned_abs() > 1_000_000_000) {
            return Err(bad(format!(
                "volume_create: frame {}: expected −10⁹ to 10⁹",
                ci.frame
            )));
        }
        let shutter = (ci.flags & FM_CREATE_SHUTTER != 0).then_some(ci.shutter);
        if let Some(s) = shutter {
            if !s.iter().all(|t| t.is_finite() && t.abs() <= 1e6) || s[0] > s[1] {
                return Err(bad(format!(
                    "volume_create: shutter {s:?}: expected finite open ≤ close, within ±10⁶ frames"
                )));
            }
        }
        let mode = match ci.kind {
            FM_KIND_SCENE => None,
            FM_KIND_FIRE => Some(Mode::Physical),
            FM_KIND_PBRT => Some(Mode::Pbrt),
            k => {
                return Err(bad(format!(
                    "volume_create: kind {k}: expected FM_KIND_SCENE (0), FM_KIND_FIRE (1) or FM_KIND_PBRT (2)"
                )))
            }
        };
        if ci.bins > 4096 {
            return Err(bad(format!(
                "volume_create: bins {}: expected 0 (the scene's) to 4096",
                ci.bins
            )));
        }
        let w = ci.wavelengths;
        let wavelengths = (w != [0.0; 2]).then_some(w);
        if wavelengths.is_some() && !(200.0 <= w[0] && w[0] < w[1] && w[1] <= 2000.0) {
            return Err(bad(format!(
                "volume_create: wavelengths {w:?} nm: expected shortest < longest, within 200 to 2000 nm (or both 0: the scene's)"
            )));
        }
        let ctx = HostContext {
            threads: (ci.threads > 0).then_some(ci.threads as usize),
            max_bytes: (ci.max_bytes > 0).then_some(ci.max_bytes),
            frame,
            shutter,
            mode,
            bins: (ci.bins > 0).then_some(ci.bins as usize),
            wavelengths,
        };
        let pool = ci.parallel_for.map(|f| host_pool(f, ci.pool));
        let v = crate::par::with_pool(pool.clone(), || FireVolume::new_in(&list, &ctx))
            .map_err(fail)?;
        let handle = VolumeHandle {
            volume: Arc::new(v),
            pool,
        };
        // SAFETY: out is non-null and writable (checked, contract).
        unsafe { *out = Box::into_raw(Box::new(handle)) as *mut FmVolume };
        Ok(())
    })
}

/// What an `FmVolume` points at: the volume, shared with its lights, and the host's pool for their builds.
pub(super) struct VolumeHandle {
    pub(super) volume: Arc<FireVolume>,
    pub(super) pool: Option<Pool>,
}

/// The host's thread pool (`FmCreateInfo::parallel_for` and its pointer) as the plugin's [`Pool`]: each fan-out
/// hands it one task per part, through a trampoline that never unwinds.
fn host_pool(parallel_for: FmParallelFor, pool: *mut c_void) -> Pool {
    struct Host(FmParallelFor, *mut c_void);
    // SAFETY: the host's contract: its pool may be called from any thread while the volume lives.
    unsafe impl Send for Host {}
    // SAFETY: as above.
    unsafe impl Sync for Host {}
    unsafe extern "C" fn run(data: *mut c_void, index: usize) {
        // SAFETY: `data` is the task reference below, alive until the host's call returns (its contract).
        let task = unsafe { &*(data as *const &(dyn Fn(usize) + Sync)) };
        // (A part catches its own panic; nothing may unwind into the host's frames.)
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| task(index)));
    }
    let host = Host(parallel_for, pool);
    Arc::new(move |n, task: &(dyn Fn(usize) + Sync)| {
        let host = &host;
        let task: &(dyn Fn(usize) + Sync) = task;
        // SAFETY: the host runs `run(data, i)` for every i < n and returns when all have (its contract); `task`
        // outlives the call.
        unsafe { (host.0)(host.1, n, run, &task as *const _ as *mut c_void) }
    })
}

pub(super) unsafe extern "C" fn volume_destroy(volume: *mut FmVolume) {
    if !volume.is_null() {
        let _ = catch_unwind(|| {
            // SAFETY: a handle from volume_create (Box::into_raw), destroyed once (contract); lights hold their
            // own references to the volume.
            drop(unsafe { Box::from_raw(volume as *mut VolumeHandle) });
        });
    }
}

/// The volume behind a handle.
///
/// # Safety
/// `v` is null or a live handle from `volume_create`.
pub(super) unsafe fn vol<'a>(
    v: *const FmVolume,
    what: &str,
) -> Result<&'a FireVolume, (FmStatus, String)> {
    if v.is_null() {
        return Err(bad(format!("{what}: volume is null")));
    }
    // SAFETY: live handle (contract); volumes are immutable and Sync.
    Ok(unsafe { &(*(v as *const VolumeHandle)).volume })
}

/// `n` first uniform numbers at `p` (null: none given), each checked to lie in [0, 1).
///
/// # Safety
/// `p` is null or points to `n` doubles.
unsafe fn firsts<'a>(
    p: *const f64,
    n: usize,
    what: &str,
) -> Result<Option<&'a [f64]>, (FmStatus, String)> {
    if p.is_null() || n == 0 {
        return Ok(None);
    }
    super::span::<f64>(n, what)?;
    // SAFETY: `p` is non-null and holds `n` doubles (caller contract).
    let u = unsafe { std::slice::from_raw_parts(p, n) };
    if let Some(i) = u.iter().position(|x| !(0.0..1.0).contains(x)) {
        return Err(bad(format!(
            "{what}: u[{i}] = {}: expected a number in [0, 1)",
            u[i]
        )));
    }
    Ok(Some(u))
}

pub(super) unsafe extern "C" fn volume_info(
    volume: *const FmVolume,
    out: *mut FmVolumeInfo,
) -> FmStatus {
    guard(|| {
        // SAFETY: contract of the handle.
        let v = unsafe { vol(volume, "volume_info") }?;
        let [p0, p1] = v.bounds();
        let ds = v.dataset();
        let [l0, l1] = ds.bounds();
        let dims = ds.dims().map(|n| u32::try_from(n).unwrap_or(u32::MAX));
        let (space, lo, hi) = match v.color_mode() {
            ColorMode::Spectral(g) => (FM_SPACE_SPECTRAL, g.min_nm(), g.max_nm()),
            ColorMode::Rgb => (FM_SPACE_XYZ, 380.0, 780.0),
        };
        let info = FmVolumeInfo {
            struct_size: std::mem::size_of::<FmVolumeInfo>(),
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
            dims,
            reserved: 0,
            lattice_min: l0.to_array(),
            lattice_max: l1.to_array(),
        };
        // SAFETY: null or the host's FmVolumeInfo of its struct_size (contract).
        unsafe {
            super::write_sized(
                out,
                info,
                FM_VOLUME_INFO_SIZE_1_0,
                "volume_info: out",
                "FmVolumeInfo",
            )
        }
    })
}

pub(super) unsafe extern "C" fn volume_channel_xyz(
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

pub(super) unsafe extern "C" fn volume_query(
    volume: *const FmVolume,
    query: *const FmRayQuery,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_query") }?;
        // SAFETY: null or the host's FmRayQuery of its struct_size (contract); integers and pointers, valid as zero.
        let q = unsafe {
            super::read_sized(
                query,
                std::mem::size_of::<FmRayQuery>(),
                "volume_query: query",
                "FmRayQuery",
            )
        }?;
        let n = q.n;
        // SAFETY: `rays` holds `n` rays (caller contract); null or absurd counts are refused.
        let rs = unsafe { rays(q.rays, n) }?;
        // SAFETY: `times` is null or holds `n` doubles (caller contract).
        let ts = unsafe { times(q.times, n, "volume_query") }?;
        // SAFETY: `u` is null or holds `n` doubles (caller contract).
        let us = unsafe { firsts(q.u, n, "volume_query") }?;
        let ray = |i: usize| Ray {
            first: us.map(|u| u[i]),
            ..ray_of(&rs[i])
        };
        let c = v.channels();
        let unused = |name: &str, null: bool| {
            if null {
                Ok(())
            } else {
                Err(bad(format!(
                    "volume_query: {name} is set, but query {} does not write it (set it null)",
                    q.what
                )))
            }
        };
        if !(q.step >= 0.0 && q.step.is_finite()) {
            return Err(bad(format!(
                "volume_query: step {}: expected 0 (the volume's) or a finite length > 0",
                q.step
            )));
        }
        match q.what {
            FM_QUERY_INTEGRATE => {
                unused("events", q.events.is_null())?;
                unused("weights", q.weights.is_null())?;
                if q.step > 0.0 && !q.exits.is_null() {
                    return Err(bad(
                        "volume_query: a step of its own is for straight rays: exits must be null with it",
                    ));
                }
                // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
                let l_out = unsafe { out_f32(q.radiance, n, c) }?
                    .ok_or_else(|| bad("volume_query: radiance is null"))?;
                // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
                let mut t_out = unsafe { out_f32(q.transmittance, n, c) }?;
                let mut e_out = if q.exits.is_null() || n == 0 {
                    None
                } else {
                    // SAFETY: `exits` is non-null here and holds `n` entries (caller contract).
                    Some(unsafe { std::slice::from_raw_parts_mut(q.exits, n) })
                };
                super::with_channels(c, |l, t| {
                    for i in 0..n {
                        let r = ray(i);
                        // A host that does not ask where the ray leaves gets the straight ray (light paths, NEE).
                        let (p_exit, d_exit, t_exit) = if e_out.is_some() {
                            v.query(&r, Some(ts[i]), Want::Exit, l, t).exit(&r)
                        } else {
                            let step = (q.step > 0.0).then_some(q.step);
                            let te = v
                                .query(&r, Some(ts[i]), Want::Radiance { step }, l, t)
                                .end(&r);
                            (r.o + r.d * te, r.d, te)
                        };
                        store(l_out, i, l);
                        if let Some(to) = t_out.as_deref_mut() {
                            store(to, i, t);
                        }
                        if let Some(eo) = e_out.as_deref_mut() {
                            eo[i] = FmExit {
                                point: p_exit.to_array(),
                                direction: d_exit.to_array(),
                                t: t_exit,
                            };
                        }
                    }
                });
            }
            FM_QUERY_TRANSMITTANCE => {
                unused("radiance", q.radiance.is_null())?;
                unused("exits", q.exits.is_null())?;
                unused("events", q.events.is_null())?;
                unused("weights", q.weights.is_null())?;
                // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
                let out = unsafe { out_f32(q.transmittance, n, c) }?
                    .ok_or_else(|| bad("volume_query: transmittance is null"))?;
                super::with_channels(c, |_, t| {
                    for i in 0..n {
                        v.query(&ray(i), Some(ts[i]), Want::Transmittance, &mut [], t);
                        store(out, i, t);
                    }
                });
            }
            FM_QUERY_SCATTER => {
                unused("transmittance", q.transmittance.is_null())?;
                unused("exits", q.exits.is_null())?;
                if q.events.is_null() && n > 0 {
                    return Err(bad("volume_query: events is null"));
                }
                let ev = if n == 0 {
                    &mut [][..]
                } else {
                    // SAFETY: `events` is non-null here and holds `n` entries (caller contract).
                    unsafe { std::slice::from_raw_parts_mut(q.events, n) }
                };
                // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
                let w_out = unsafe { out_f32(q.weights, n, c) }?
                    .ok_or_else(|| bad("volume_query: weights is null"))?;
                // SAFETY: the buffer holds `n × channels` floats or is null (caller contract).
                let mut l_out = unsafe { out_f32(q.radiance, n, c) }?;
                super::with_channels(c, |l, w| {
                    for i in 0..n {
                        let r = ray(i);
                        let (event, t) = match v.query(&r, Some(ts[i]), Want::Scatter, l, w).event() {
                            Event::Escaped => (FM_EVENT_ESCAPED, r.t1),
                            Event::Scattered(t) => (FM_EVENT_SCATTERED, t),
                            Event::Absorbed => (FM_EVENT_ABSORBED, r.t1),
                        };
                        ev[i] = FmScatter {
                            event,
                            reserved: 0,
                            t,
                            point: (r.o + r.d * t).to_array(),
                        };
                        store(w_out, i, w);
                        if let Some(lo) = l_out.as_deref_mut() {
                            store(lo, i, l);
                        }
                    }
                });
            }
            w => {
                return Err(bad(format!(
                    "volume_query: what {w}: expected FM_QUERY_INTEGRATE (0), FM_QUERY_TRANSMITTANCE (1) or FM_QUERY_SCATTER (2)"
                )))
            }
        }
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_coefficients(
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
        // SAFETY: `points` holds `3 n` doubles or is null with n = 0 (caller contract); 3 n is checked.
        let pts = unsafe { in_f64(points, n, 3, "volume_coefficients: points") }?;
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

pub(super) unsafe extern "C" fn volume_tables(
    volume: *const FmVolume,
    out: *mut FmTables,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_tables") }?;
        // SAFETY: null or the host's FmTables of its struct_size (contract); integers, floats and pointers, valid
        // as zero.
        let host = unsafe {
            super::read_sized(
                out,
                std::mem::size_of::<FmTables>(),
                "volume_tables: out",
                "FmTables",
            )
        }?;
        let cf = v.closed_form().map_err(super::fail)?;
        let (c, rows) = (cf.channels, cf.rows);
        let to_u32 = |n: usize, what: &str| {
            u32::try_from(n)
                .map_err(|_| bad(format!("volume_tables: {n} {what}, more than a u32 holds")))
        };
        let tables = FmTables {
            struct_size: std::mem::size_of::<FmTables>(),
            channels: to_u32(c, "channels")?,
            rows: to_u32(rows, "rows")?,
            flags: if cf.emission_grid {
                FM_TABLES_EMISSION_GRID
            } else {
                0
            },
            reserved: 0,
            dt: cf.dt,
            t_emit: cf.t_emit,
            ..host
        };
        // SAFETY: each table pointer is null or holds the floats FmTables documents for these rows and channels
        // (the host learnt them from a first call; contract).
        let absorption = unsafe { out_f32(host.absorption, rows, c) }?;
        // SAFETY: as above.
        let scattering = unsafe { out_f32(host.scattering, 1, c) }?;
        // SAFETY: as above.
        let emission = unsafe { out_f32(host.emission, rows, c) }?;
        if let Some(a) = absorption {
            for (i, x) in a.iter_mut().enumerate() {
                *x = cf.absorption(i / c, i % c);
            }
        }
        if let Some(s) = scattering {
            for (k, x) in s.iter_mut().enumerate() {
                *x = cf.scattering(k);
            }
        }
        if let Some(j) = emission {
            for (i, x) in j.iter_mut().enumerate() {
                *x = cf.emission(i / c, i % c);
            }
        }
        // SAFETY: non-null, struct_size ≥ size_of::<FmTables>() writable bytes (read_sized checked both).
        unsafe { out.write_unaligned(tables) };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_fields(
    volume: *const FmVolume,
    points: *const f64,
    n: usize,
    out: *mut f32,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_fields") }?;
        // SAFETY: `points` holds `3 n` doubles or is null with n = 0 (caller contract); 3 n is checked.
        let pts = unsafe { in_f64(points, n, 3, "volume_fields: points") }?;
        // SAFETY: `out` holds `3 n` floats (caller contract).
        let Some(o) = unsafe { out_f32(out, n, 3) }? else {
            return Err(bad("volume_fields: out is null"));
        };
        for (p, o) in pts.chunks_exact(3).zip(o.chunks_exact_mut(3)) {
            let f = v.fields(DVec3::new(p[0], p[1], p[2]));
            for k in 0..3 {
                o[k] = f[k] as f32;
            }
        }
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_bricks(
    volume: *const FmVolume,
    out: *mut i64,
    cap: usize,
    count: *mut usize,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_bricks") }?;
        if count.is_null() {
            return Err(bad("volume_bricks: count is null"));
        }
        let mut n = 0usize;
        v.for_each_stored_brick(|_| n += 1);
        // SAFETY: `count` is non-null (checked) and writable (caller contract).
        unsafe { *count = n };
        if out.is_null() && cap == 0 {
            return Ok(());
        }
        if cap < n {
            return Err(bad(format!(
                "volume_bricks: room for {cap} bricks: expected at least the volume's {n}"
            )));
        }
        // SAFETY: `out` is null (refused) or holds 3 × `cap` writable int64 (caller contract); only the first
        // 3 × n are written.
        let o = unsafe { out_values(out, n, 3, "volume_bricks: out") }?;
        let mut k = 0;
        v.for_each_stored_brick(|first| {
            o[3 * k..3 * k + 3].copy_from_slice(&first);
            k += 1;
        });
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_temperature_range(
    volume: *const FmVolume,
    out: *mut f64,
) -> FmStatus {
    guard(|| {
        // SAFETY: contract of the handle.
        let v = unsafe { vol(volume, "volume_temperature_range") }?;
        // SAFETY: room for two doubles (contract).
        let o = unsafe { out_values(out, 2, 1, "volume_temperature_range: out") }?;
        let [lo, hi] = v.temperature_range().unwrap_or([0.0, 0.0]);
        o[0] = lo;
        o[1] = hi;
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_white_temperature(
    volume: *const FmVolume,
    out: *mut f64,
) -> FmStatus {
    guard(|| {
        // SAFETY: contract of the handle.
        let v = unsafe { vol(volume, "volume_white_temperature") }?;
        // SAFETY: room for one double (contract).
        let o = unsafe { out_values(out, 1, 1, "volume_white_temperature: out") }?;
        o[0] = v.white_temperature().unwrap_or(0.0);
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_capped_rays(
    volume: *const FmVolume,
    out: *mut u64,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_capped_rays") }?;
        if out.is_null() {
            return Err(bad("volume_capped_rays: out is null"));
        }
        // SAFETY: non-null (checked) and writable (caller contract).
        unsafe { *out = v.capped_rays() };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_note_count(
    volume: *const FmVolume,
    out: *mut usize,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_note_count") }?;
        if out.is_null() {
            return Err(bad("volume_note_count: out is null"));
        }
        // SAFETY: non-null (checked) and writable (caller contract).
        unsafe { *out = v.notes().len() };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_note(
    volume: *const FmVolume,
    index: usize,
    buf: *mut std::ffi::c_char,
    cap: usize,
    len: *mut usize,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_note") }?;
        if len.is_null() {
            return Err(bad("volume_note: len is null"));
        }
        let notes = v.notes();
        let Some(note) = notes.get(index) else {
            return Err(bad(format!(
                "volume_note: index {index}: expected one below the volume's {} notes",
                notes.len()
            )));
        };
        // SAFETY: `buf` is null or holds `cap` writable bytes, `len` is non-null (checked) and writable (caller
        // contract).
        unsafe { *len = super::buffers::copy_c_string(note.as_bytes(), buf, cap) };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_features(
    volume: *const FmVolume,
    out: *mut u64,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_features") }?;
        if out.is_null() {
            return Err(bad("volume_features: out is null"));
        }
        let f = v.features();
        let bits = [
            (f.emits, FM_FEATURE_EMITS),
            (f.scatters, FM_FEATURE_SCATTERS),
            (f.motion, FM_FEATURE_MOTION),
            (f.refraction, FM_FEATURE_REFRACTION),
            (f.embers, FM_FEATURE_EMBERS),
            (f.thick_lines, FM_FEATURE_THICK_LINES),
            (f.diffusion, FM_FEATURE_DIFFUSION),
            (
                f.emits_without_absorption,
                FM_FEATURE_EMITS_WITHOUT_ABSORPTION,
            ),
        ]
        .iter()
        .filter(|(on, _)| *on)
        .fold(0u64, |a, (_, bit)| a | bit);
        // SAFETY: non-null (checked) and writable (caller contract).
        unsafe { *out = bits };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_majorant_grid(
    volume: *const FmVolume,
    out: *mut FmMajorantGrid,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_majorant_grid") }?;
        // SAFETY: null or the host's FmMajorantGrid (contract).
        unsafe { super::sized(out, "volume_majorant_grid: out", "FmMajorantGrid") }?;
        let m = v.majorant_cells();
        let mut counts = [0u32; 3];
        for (c, &n) in counts.iter_mut().zip(&m.counts) {
            *c = u32::try_from(n).map_err(|_| {
                bad(format!(
                    "volume_majorant_grid: {n} cells on an axis, more than the struct's u32 holds"
                ))
            })?;
        }
        let [p0, p1] = m.bounds;
        let grid = FmMajorantGrid {
            struct_size: std::mem::size_of::<FmMajorantGrid>(),
            bounds: [p0.x, p0.y, p0.z, p1.x, p1.y, p1.z],
            cell: m.cell.to_array(),
            counts,
            reserved: 0,
            sigma_t: m.sigma_t.as_ptr(),
        };
        // SAFETY: non-null, and at least size_of::<FmMajorantGrid>() writable bytes (checked above).
        unsafe { out.write_unaligned(grid) };
        Ok(())
    })
}

pub(super) unsafe extern "C" fn volume_point(
    volume: *const FmVolume,
    query: *const FmPointQuery,
) -> FmStatus {
    guard(|| {
        // SAFETY: `volume` is null (refused) or a live handle from volume_create (caller contract).
        let v = unsafe { vol(volume, "volume_point") }?;
        // SAFETY: null or the host's FmPointQuery of its struct_size (contract); integers and pointers, valid as
        // zero.
        let q = unsafe {
            super::read_sized(
                query,
                std::mem::size_of::<FmPointQuery>(),
                "volume_point: query",
                "FmPointQuery",
            )
        }?;
        let (n, k) = (q.n, q.k as usize);
        // SAFETY: the query's arrays as its contract sizes them (null refused or, for times, read as 0).
        let points = unsafe { in_f64(q.points, n, 3, "volume_point: points") }?;
        // SAFETY: as above.
        let lambdas = unsafe { in_f64(q.lambdas, n, k, "volume_point: lambdas") }?;
        let times = if q.times.is_null() {
            None
        } else {
            // SAFETY: as above.
            Some(unsafe { in_f64(q.times, n, 1, "volume_point: times") }?)
        };
        // (The soot's κ ∝ λ^−α and Planck's λ^−5 have no meaning, and no finite f64, far outside light.)
        let (lo, hi) = firemedium_abi::FM_WAVELENGTH_RANGE_NM;
        if let Some(i) = lambdas.iter().position(|&l| !(lo..=hi).contains(&l)) {
            return Err(bad(format!(
                "volume_point: lambdas[{i}] = {:e}: expected wavelengths from {lo} nm to {hi:e} nm",
                lambdas[i]
            )));
        }
        // The outputs the host asked for (each may be null).
        let mut outs: Vec<Option<&mut [f64]>> = Vec::with_capacity(4);
        for (p, what) in [
            (q.sigma_a, "volume_point: sigma_a"),
            (q.sigma_s, "volume_point: sigma_s"),
            (q.le, "volume_point: le"),
            (q.j, "volume_point: j"),
        ] {
            outs.push(if p.is_null() {
                None
            } else {
                // SAFETY: n × k writable doubles (contract).
                Some(unsafe { out_values(p, n, k, what) }?)
            });
        }
        if n == 0 || k == 0 {
            return Ok(());
        }
        // (A row of k, sized like the host's own n × k wavelengths, allocated fallibly.)
        let mut row = crate::alloc::filled(k, crate::volume::PointCoefficients::default())
            .ok_or_else(|| {
                bad(format!(
                    "volume_point: {k} wavelengths per point: no memory for a row"
                ))
            })?;
        for i in 0..n {
            let p = DVec3::from_slice(&points[3 * i..3 * i + 3]);
            let time = times.map_or(0.0, |t| t[i]);
            v.point(p, time, &lambdas[k * i..k * (i + 1)], &mut row)
                .map_err(fail)?;
            for (m, c) in row.iter().enumerate() {
                let values = [c.sigma_a, c.sigma_s, c.le, c.j];
                for (o, value) in outs.iter_mut().zip(values) {
                    if let Some(o) = o {
                        o[k * i + m] = value;
                    }
                }
            }
        }
        Ok(())
    })
}
