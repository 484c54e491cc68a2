//! The buffers a host hands the plugin, read once at the boundary: each pointer checked against null, each
//! length against overflow and the address space, each number the plugin will compute with checked finite —
//! so that no entry computes with what it has not checked.

use super::bad;
use crate::volume::Ray;
use firemedium_abi::*;
use glam::DVec3;

/// `n × k` doubles at `p`, required.
///
/// # Safety
/// `p` is null or points to `n × k` doubles.
pub(super) unsafe fn in_f64<'a>(
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
    super::span::<f64>(len, what)?;
    // SAFETY: caller provides n × k doubles (contract).
    let v = unsafe { std::slice::from_raw_parts(p, len) };
    // Every number is checked: a NaN would propagate into a sample or a pdf the host then trusts.
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(bad(format!(
            "{what}[{i}] = {}: expected finite numbers ({n} rows of {k})",
            v[i]
        )));
    }
    Ok(v)
}

/// `n × k` writable values at `p` (null refused unless `n` is 0).
///
/// # Safety
/// `p` is null or points to `n × k` writable values.
pub(super) unsafe fn out_values<'a, T>(
    p: *mut T,
    n: usize,
    k: usize,
    what: &str,
) -> Result<&'a mut [T], (FmStatus, String)> {
    if n == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(bad(format!("{what} is null")));
    }
    let len = n
        .checked_mul(k)
        .ok_or_else(|| bad(format!("{what}: {n} × {k} overflows")))?;
    super::span::<T>(len, what)?;
    // SAFETY: caller provides n × k writable values (contract).
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// `n × c` mutable f32 outputs at `p` (null → None).
///
/// # Safety
/// `p` is null or points to `n × c` writable f32.
pub(super) unsafe fn out_f32<'a>(
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
    super::span::<f32>(len, "outputs")?;
    // SAFETY: caller provides n × c floats (contract).
    Ok(Some(unsafe { std::slice::from_raw_parts_mut(p, len) }))
}

/// # Safety
/// `rays` points to `n` rays.
pub(super) unsafe fn rays<'a>(
    rays: *const FmRay,
    n: usize,
) -> Result<&'a [FmRay], (FmStatus, String)> {
    if n == 0 {
        return Ok(&[]);
    }
    if rays.is_null() {
        return Err(bad(format!("{n} rays at a null pointer")));
    }
    super::span::<FmRay>(n, "rays")?;
    // SAFETY: n rays (contract).
    let rs = unsafe { std::slice::from_raw_parts(rays, n) };
    // Origins and directions finite, tmin and tmax not NaN (tmax may be +∞; tmin ≥ tmax is an empty segment):
    // a NaN would reach a sample's arithmetic; this checks it once per call instead of once per step.
    for (i, r) in rs.iter().enumerate() {
        let finite = r.origin.iter().chain(&r.direction).all(|x| x.is_finite());
        if !finite || r.tmin.is_nan() || r.tmax.is_nan() {
            return Err(bad(format!(
                "ray {i}: origin {:?}, direction {:?}, t in [{}, {}]: expected a finite origin and direction and t not NaN",
                r.origin, r.direction, r.tmin, r.tmax
            )));
        }
        direction(r.direction).map_err(|e| bad(format!("ray {i}: {e}")))?;
    }
    Ok(rs)
}

/// Refuses a finite direction whose length lies outside [`firemedium_abi::FM_DIRECTION_LENGTH_RANGE`] (zero
/// included): its length computed without under- or overflow, scaled by its largest component.
pub(super) fn direction(d: [f64; 3]) -> Result<(), String> {
    let (short, long) = firemedium_abi::FM_DIRECTION_LENGTH_RANGE;
    let m = d.iter().fold(0f64, |a, x| a.max(x.abs()));
    let len = if m > 0.0 {
        m * d.iter().map(|x| (x / m) * (x / m)).sum::<f64>().sqrt()
    } else {
        0.0
    };
    if (short..=long).contains(&len) {
        Ok(())
    } else {
        Err(format!(
            "direction {d:?} of length {len:e}: expected a length from {short:e} to {long:e}"
        ))
    }
}

/// The plugin's ray from the host's (checked by [`rays`]).
pub(super) fn ray_of(r: &FmRay) -> Ray {
    Ray {
        o: DVec3::from(r.origin),
        d: DVec3::from(r.direction),
        t0: r.tmin,
        t1: r.tmax,
        seed: r.seed,
        first: None,
    }
}

/// Ray `i`'s channels `v` into its row of `out` (rows of `v.len()` floats).
pub(super) fn store(out: &mut [f32], i: usize, v: &[f64]) {
    let c = v.len();
    for (o, x) in out[i * c..(i + 1) * c].iter_mut().zip(v) {
        *o = *x as f32;
    }
}

/// A call's ray times: the caller's (checked finite), or every ray at time 0 (the grids' own). Indexed per ray,
/// without a copy (hosts call with one ray at a time).
pub(super) struct Times<'a>(Option<&'a [f64]>);

impl std::ops::Index<usize> for Times<'_> {
    type Output = f64;
    fn index(&self, i: usize) -> &f64 {
        match self.0 {
            Some(t) => &t[i],
            None => &0.0,
        }
    }
}

/// `n` ray times at `p` (null: every ray at time 0).
///
/// # Safety
/// `p` is null or points to `n` doubles.
pub(super) unsafe fn times<'a>(
    p: *const f64,
    n: usize,
    what: &str,
) -> Result<Times<'a>, (FmStatus, String)> {
    if p.is_null() || n == 0 {
        return Ok(Times(None));
    }
    super::span::<f64>(n, what)?;
    // SAFETY: `p` is non-null and holds `n` doubles (caller contract).
    let t = unsafe { std::slice::from_raw_parts(p, n) };
    // Every time is checked (the message is made only for a bad one).
    if let Some(i) = t.iter().position(|x| !x.is_finite()) {
        return Err(bad(format!(
            "{what}: times[{i}] = {}: expected finite numbers ({n} rows of 1)",
            t[i]
        )));
    }
    Ok(Times(Some(t)))
}

/// `bytes` into the host's `buf` of `cap` bytes (null or 0: nothing written), truncated to `cap − 1` and
/// NUL-terminated; returns the full length.
///
/// # Safety
/// `buf` is null or points to `cap` writable bytes.
pub(super) unsafe fn copy_c_string(bytes: &[u8], buf: *mut std::ffi::c_char, cap: usize) -> usize {
    if !buf.is_null() && cap > 0 {
        let n = bytes.len().min(cap - 1);
        // SAFETY: `buf` holds `cap` writable bytes (caller contract); n + 1 ≤ cap are written.
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), buf as *mut u8, n);
            *buf.add(n) = 0;
        }
    }
    bytes.len()
}
