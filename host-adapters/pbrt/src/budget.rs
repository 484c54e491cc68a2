//! One memory budget for what a render builds in the host — the film, images read as textures, light maps or
//! references — checked before each allocation, so that a few bytes of input claiming a huge size are an error
//! naming what would not fit, never an allocation failure that aborts the process. The same number is passed to
//! the plugin as its `maxbytes` (each grid's cap) unless a scene sets that itself.

/// Half the machine's physical memory (`/proc/meminfo`), or 8 GiB where that cannot be read.
pub fn default_bytes() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("MemTotal:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map_or(8 << 30, |kb| kb.saturating_mul(1024) / 2)
}

/// An error unless `count` items of `size` bytes (`what`, named in the message) fit in `budget` bytes.
pub fn check(what: &str, count: u64, size: u64, budget: u64) -> Result<(), crate::Error> {
    match count.checked_mul(size) {
        Some(bytes) if bytes <= budget => Ok(()),
        bytes => Err(crate::Error::Budget {
            what: what.to_string(),
            bytes,
            budget,
        }),
    }
}

/// Peak resident memory of this process (VmHWM), bytes, where /proc tells.
pub fn peak_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_checked_before_anything_is_allocated() {
        assert!(check("a film", 1920 * 1080, 36, 1 << 30).is_ok());
        let e = check("a film of 1e5 × 1e5 pixels", 100_000 * 100_000, 36, 1 << 30)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("needs 360000000000 bytes") && e.contains("budget of 1073741824"),
            "{e}"
        );
        let e = check("x", u64::MAX, 2, u64::MAX).unwrap_err().to_string();
        assert!(e.contains("more than 2^64"), "{e}");
        assert!(default_bytes() >= 1 << 20);
    }
}
