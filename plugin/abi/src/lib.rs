//! # firemedium-abi: the contract between the fire plugin and its hosts
//!
//! This crate has no dependencies and holds only what both sides must agree on. Today that is the version of
//! the contract and the name of the one exported entry symbol; the function table, the `#[repr(C)]` ray and
//! parameter types and the status codes join it with the ABI itself (DESIGN.md, "The ABI").
//!
//! Versioning: a host refuses a plugin whose [`ABI_MAJOR`] differs from its own, or whose [`ABI_MINOR`] is
//! older than the minor the host needs, with a message naming both versions. Minor versions only add.

#![no_std]

/// Major version of the C ABI. Changes on any incompatible change of the table or its types.
pub const ABI_MAJOR: u32 = 0;
/// Minor version of the C ABI. Grows when entries are appended to the table.
pub const ABI_MINOR: u32 = 1;
/// Name of the exported entry symbol, NUL-terminated for `dlsym`/`GetProcAddress`.
pub const ENTRY_SYMBOL: &[u8] = b"firemedium_plugin_entry\0";

/// Whether a plugin of version (`major`, `minor`) satisfies a host that needs (`need_major`, `need_minor`).
pub const fn compatible(major: u32, minor: u32, need_major: u32, need_minor: u32) -> bool {
    major == need_major && minor >= need_minor
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_symbol_is_a_c_string() {
        assert_eq!(ENTRY_SYMBOL.last(), Some(&0));
        assert!(!ENTRY_SYMBOL[..ENTRY_SYMBOL.len() - 1].contains(&0));
    }

    #[test]
    fn version_rules() {
        assert!(compatible(ABI_MAJOR, ABI_MINOR, ABI_MAJOR, ABI_MINOR));
        assert!(compatible(0, 3, 0, 1));
        assert!(!compatible(0, 1, 0, 2));
        assert!(!compatible(1, 1, 0, 1));
    }
}
