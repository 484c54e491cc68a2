//! # firemedium-pbrt-parser: pbrt-v4 scene files
//!
//! Shaped like pbrt-v4's own parser (`src/pbrt/parser.cpp`): a [`Tokenizer`] that knows every token's file,
//! line and column, and a [`parse_file`]/[`parse_str`] that turns tokens into [`Directive`]s delivered, one by
//! one, to a [`Target`]. `Include` and `Import` are followed relative to the including file. Every error names
//! `file:line:col`. No input panics (the tests mutate real scene files thousands of times).
//!
//! Parameters are pbrt-v4's `"type name" value` or `"type name" [ values ]`, with types `integer`, `float`,
//! `point2`, `vector2`, `point3`, `vector3`, `normal`, `rgb`, `spectrum` (numbers or a named spectrum/file),
//! `blackbody`, `bool`, `string`, `texture` (plus pbrt-v3's `point`, `vector`, `normal3`, `color` spellings).
//! `Rotate` angles are degrees, as in pbrt.

#![forbid(unsafe_code)]
mod dict;
mod parser;
mod tokenizer;
pub mod v3;

pub use dict::{closest, ParamDict};

pub use parser::{
    parse_file, parse_str, ActiveTransform, Collect, Directive, Param, Target, Values,
};
pub use tokenizer::{Token, TokenKind, Tokenizer};

use std::fmt;
use std::sync::Arc;

/// A position in a scene file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Loc {
    /// The file (as given, or resolved for includes).
    pub file: Arc<str>,
    /// 1-based line.
    pub line: u32,
    /// 1-based column, in characters.
    pub col: u32,
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

/// A parse error at a position.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// Where.
    pub loc: Loc,
    /// What is wrong.
    pub message: String,
}

impl ParseError {
    pub(crate) fn new(loc: &Loc, message: impl Into<String>) -> Self {
        ParseError {
            loc: loc.clone(),
            message: message.into(),
        }
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Line 0: the error is about the file itself (it cannot be read), whose message names it.
        if self.loc.line == 0 {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.loc, self.message)
        }
    }
}

impl std::error::Error for ParseError {}

/// Reads a regular file to the length it had when opened. A device (`/dev/zero`) never ends and a FIFO blocks
/// its reader forever (checked before opening: opening one blocks too); a scene, an `Include` and the files a
/// scene names (meshes, images) are read with this.
pub fn read_regular_file(path: &std::path::Path) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::other(
            "not a regular file (a directory, device or FIFO): scene files are read from files of a known size",
        ));
    }
    let f = std::fs::File::open(path)?;
    let len = f.metadata()?.len();
    let mut buf = Vec::new();
    usize::try_from(len)
        .ok()
        .and_then(|n| buf.try_reserve_exact(n).ok())
        .ok_or_else(|| {
            std::io::Error::other(format!("{len} bytes: more than this machine can hold"))
        })?;
    f.take(len).read_to_end(&mut buf)?;
    Ok(buf)
}
