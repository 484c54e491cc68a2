//! Buffers whose size comes from input, allocated fallibly: when the allocator refuses, the caller returns an
//! error naming what did not fit — never `memory allocation of N bytes failed` and an abort, which would kill the
//! host that loaded the plugin. Sizes are checked against the budget (`maxbytes`) before this is called.

/// `n` copies of `value`, or `None` when the allocator cannot hold them.
pub fn filled<T: Clone>(n: usize, value: T) -> Option<Vec<T>> {
    let mut v = with_capacity(n)?;
    v.resize(n, value);
    Some(v)
}

/// An empty vector with room for `n` items, or `None` when the allocator cannot hold them.
pub fn with_capacity<T>(n: usize) -> Option<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).ok()?;
    Some(v)
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_refusal_is_none_not_an_abort() {
        assert!(super::filled::<u64>(usize::MAX / 4, 0).is_none());
        assert_eq!(super::filled(3, 7u8), Some(vec![7, 7, 7]));
    }
}
