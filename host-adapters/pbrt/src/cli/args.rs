//! Argument parsers shared by the commands (values clap cannot check by itself).

/// `WxH`, both from 1 to 65536.
pub fn parse_resolution(s: &str) -> Result<(usize, usize), String> {
    let bad =
        || format!("'{s}' is not a resolution WxH with W and H from 1 to 65536 (say, 320x240)");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (usize, usize) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

/// A memory size in GB: a finite number above 0.
pub fn parse_gb(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v < 1e9 => Ok(v),
        _ => Err(format!(
            "'{s}' is not a memory size in GB (a number above 0, say 4 or 0.5)"
        )),
    }
}
