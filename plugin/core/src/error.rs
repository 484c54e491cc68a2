//! The physics core's one error: a construction-time value outside its domain. Per-sample physics never fails.

use std::fmt;

/// A value given to a physics constructor (a fuel's optical table, a spectral range, a species) is outside its
/// documented domain.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// A parameter has a value outside its documented domain.
    InvalidParameter {
        /// Component that owns the parameter (`soot`, `species`, `spectrum`, …).
        component: &'static str,
        /// Parameter name as the user wrote it.
        name: String,
        /// The value seen, formatted.
        value: String,
        /// What was expected instead.
        expected: String,
    },
}

impl Error {
    pub(crate) fn invalid(
        component: &'static str,
        name: impl Into<String>,
        value: impl fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Error::InvalidParameter {
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
                component,
                name,
                value,
                expected,
            } => write!(
                f,
                "{component}: parameter '{name}' = {value}: expected {expected}"
            ),
        }
    }
}

impl std::error::Error for Error {}
