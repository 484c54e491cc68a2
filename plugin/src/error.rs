//! The plugin's one error type. Every message names the component, the parameter, the value seen and what
//! was expected. Per-sample physics never fails: values are validated when a component is constructed.

use std::fmt;

/// What went wrong while building a component of the fire.
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
