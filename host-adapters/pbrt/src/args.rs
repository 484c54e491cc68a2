//! Argument values the commands share (what clap cannot check by itself): resolutions, frame lists, memory sizes.

/// `WxH`, both from 1 to 65536.
pub fn parse_resolution(s: &str) -> Result<(usize, usize), crate::Error> {
    let bad = || {
        crate::Error::value(format!(
            "'{s}' is not a resolution WxH with W and H from 1 to 65536 (say, 320x240)"
        ))
    };
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (usize, usize) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

/// A memory size in GB: a finite number above 0.
pub fn parse_gb(s: &str) -> Result<f64, crate::Error> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v < 1e9 => Ok(v),
        _ => Err(crate::Error::value(format!(
            "'{s}' is not a memory size in GB (a number above 0, say 4 or 0.5)"
        ))),
    }
}

/// `--max-memory` in bytes: the budget every size read from input is checked against (default: half the
/// machine's memory).
pub fn budget(gb: Option<f64>) -> u64 {
    gb.map_or_else(crate::budget::default_bytes, |gb| (gb * 1e9) as u64)
}

/// The frames of `--frames`.
#[derive(Debug, Clone)]
pub struct Frames(pub Vec<i64>);

/// `A-B` or `A-B:STEP` (A ≤ B, STEP ≥ 1, at most a million frames; negative numbers allowed: `-5--1`).
pub fn parse_frames(s: &str) -> Result<Frames, crate::Error> {
    let bad = || {
        crate::Error::value(format!(
            "'{s}': expected A-B or A-B:STEP (inclusive, A ≤ B, STEP ≥ 1), e.g. 1-240 or 1-240:2"
        ))
    };
    let (range, step) = match s.split_once(':') {
        Some((r, st)) => (r, st.trim().parse::<i64>().map_err(|_| bad())?),
        None => (s, 1),
    };
    // The dash between A and B: the first '-' after a digit (A may be negative).
    let at = range
        .char_indices()
        .skip(1)
        .find(|&(i, c)| c == '-' && range[..i].ends_with(|p: char| p.is_ascii_digit()))
        .map(|(i, _)| i)
        .ok_or_else(bad)?;
    let a: i64 = range[..at].trim().parse().map_err(|_| bad())?;
    let b: i64 = range[at + 1..].trim().parse().map_err(|_| bad())?;
    if !(a <= b && step >= 1 && a.abs() <= 1_000_000_000 && b.abs() <= 1_000_000_000) {
        return Err(bad());
    }
    let n = (b - a) / step + 1;
    if n > 1_000_000 {
        return Err(crate::Error::value(format!(
            "'{s}': {n} frames; at most 1 000 000"
        )));
    }
    Ok(Frames((0..n).map(|k| a + k * step).collect()))
}
