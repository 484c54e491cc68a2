//! The plugin's one error type. Every message names the component, the parameter, the value seen and what
//! was expected. Per-sample physics never fails: values are validated when a component is constructed.

use std::fmt;

/// What went wrong while building a component of the fire.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A parameter has a value outside its documented domain.
    InvalidParameter {
        /// Where the parameter was given (`file:line:col` of a scene), when the host said.
        at: Option<String>,
        /// The parameter's index in the host's list, when the host passed it (a look's: the look's).
        index: Option<u32>,
        /// Component that owns the parameter (`soot`, `species`, `spectrum`, …).
        component: &'static str,
        /// Parameter name as the user wrote it.
        name: String,
        /// The value seen, formatted.
        value: String,
        /// What was expected instead.
        expected: String,
    },
    /// A file's content is not what its format says: names the file, the position (byte offset, line and
    /// column, or grid), what was expected and what was found.
    Format {
        /// The file.
        file: String,
        /// Where in the file: `byte 1234`, `line 3, column 5`, `grid 'density'`.
        at: String,
        /// What the format requires there.
        expected: String,
        /// What the file holds.
        found: String,
    },
    /// The file could not be read at all (missing, permissions, …).
    Io {
        /// The file.
        file: String,
        /// The operating system's message.
        message: String,
    },
    /// A valid file uses something this build does not read (a compression whose feature is off, a map type).
    Unsupported {
        /// The file.
        file: String,
        /// What is unsupported.
        what: String,
        /// How to get it (the cargo feature, an alternative).
        hint: String,
    },
    /// Loading would allocate more than the configured memory cap (checked before allocating).
    TooLarge {
        /// The file.
        file: String,
        /// What would be allocated.
        what: String,
        /// Bytes requested (saturating).
        bytes: u64,
        /// The cap, bytes.
        cap: u64,
    },
}

impl Error {
    pub fn invalid(
        component: &'static str,
        name: impl Into<String>,
        value: impl fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
            at: None,
            index: None,
            component,
            name: name.into(),
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidParameter {
                at,
                component,
                index: _,
                name,
                value,
                expected,
            } => {
                if let Some(at) = at {
                    write!(f, "{at}: ")?;
                }
                if value.is_empty() {
                    return write!(f, "{component}: unknown parameter '{name}' ({expected})");
                }
                write!(
                    f,
                    "{component}: parameter '{name}' = {value}: expected {expected}"
                )
            }
            Error::Format {
                file,
                at,
                expected,
                found,
            } => {
                write!(f, "{file}: {at}: expected {expected}, found {found}")
            }
            Error::Io { file, message } => write!(f, "{file}: cannot read: {message}"),
            Error::Unsupported { file, what, hint } => {
                write!(f, "{file}: unsupported: {what} ({hint})")
            }
            Error::TooLarge {
                file,
                what,
                bytes,
                cap,
            } => {
                // (Sizes are saturating products: u64::MAX stands for one past what u64 counts.)
                let needs = if *bytes == u64::MAX {
                    "more than 2^64".to_string()
                } else {
                    bytes.to_string()
                };
                write!(
                    f,
                    "{file}: {what} needs {needs} bytes, above the memory cap of {cap} bytes (raise 'maxbytes' if intended)"
                )
            }
        }
    }
}

impl std::error::Error for Error {}

/// A number as a person reads it: plain, or in exponent form when plain would take more than a dozen digits
/// (`1e-320`, not 320 zeros).
pub fn short(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e15).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

impl From<firemedium_core::Error> for Error {
    fn from(e: firemedium_core::Error) -> Self {
        match e {
            firemedium_core::Error::InvalidParameter {
                component,
                name,
                value,
                expected,
            } => Error::InvalidParameter {
                at: None,
                index: None,
                component,
                name,
                value,
                expected,
            },
        }
    }
}

impl Error {
    /// The error with the origin of the parameter it names — where it was given and its index in the host's list
    /// — when `origin(name)` gives one (hosts pass their parameters in a list, with where each came from; see
    /// `FmCreateInfo::locations` and `params::location_in`).
    pub fn located<'a>(
        self,
        origin: impl Fn(&str) -> Option<(Option<&'a str>, Option<u32>)>,
    ) -> Error {
        match self {
            Error::InvalidParameter {
                at: None,
                index: None,
                component,
                name,
                value,
                expected,
            } => {
                let (at, index) = origin(&name).unwrap_or_default();
                Error::InvalidParameter {
                    at: at.map(str::to_string),
                    index,
                    component,
                    name,
                    value,
                    expected,
                }
            }
            e => e,
        }
    }

    /// A format error at `at` in `file`.
    pub fn format(
        file: &str,
        at: impl Into<String>,
        expected: impl Into<String>,
        found: impl fmt::Display,
    ) -> Self {
        Error::Format {
            file: file.to_string(),
            at: at.into(),
            expected: expected.into(),
            found: found.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_size_past_u64_says_so_not_u64_max() {
        // A brick table of a 2³¹-voxel box overflows u64: the saturated count is not a number of bytes.
        let e = |bytes| {
            Error::TooLarge {
                file: "far.vdb".into(),
                what: "the brick table".into(),
                bytes,
                cap: 1_000_000_000,
            }
            .to_string()
        };
        assert_eq!(
            e(u64::MAX),
            "far.vdb: the brick table needs more than 2^64 bytes, above the memory cap of 1000000000 bytes (raise 'maxbytes' if intended)"
        );
        assert!(e(5_000_000_000).contains("needs 5000000000 bytes"));
    }
}
