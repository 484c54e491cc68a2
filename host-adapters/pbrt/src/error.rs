//! The renderer library's one error type: what went wrong and where, kept as data until a command prints it.
//!
//! A variant says what kind of thing failed — a scene statement (with its `file:line:col`), a file, the memory
//! budget, the plugin, a value given on the command line, an interrupt — so that a caller can act on it (the
//! command line maps it to an exit status in [`Error::exit_status`], the only place that mapping lives) and a
//! message never has to be re-parsed for its location. `Display` gives the one line a user reads.

use firemedium_pbrt_parser::{Loc, ParseError};
use std::fmt;

/// An error of the renderer library.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// A statement of a scene refused: where it is, and why.
    Scene { loc: Loc, message: String },
    /// A scene file that cannot be read or does not parse.
    Parse(ParseError),
    /// A file (image, mesh, scene as a whole, output) that cannot be read, written or understood: its name as
    /// the user gave it, and what is wrong.
    File { file: String, message: String },
    /// A size above the memory budget, found before anything was allocated: what, its bytes (`None` above
    /// 2^64), the budget.
    Budget {
        what: String,
        bytes: Option<u64>,
        budget: u64,
    },
    /// The plugin refused a call or failed in one.
    Plugin(firemedium_loader::Error),
    /// A value given to a command (an argument, an option) refused: the message names it and what was expected.
    Value(String),
    /// Input refused that is neither one statement nor one file (files that disagree, a job's state): the
    /// message names what and why.
    Input(String),
    /// Work stopped by a signal (2 SIGINT, 15 SIGTERM, 1 SIGHUP) after what was done was kept.
    Interrupted { signal: i32, message: String },
}

/// The renderer library's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// A statement at `loc` refused.
    pub fn at(loc: &Loc, message: impl fmt::Display) -> Error {
        Error::Scene {
            loc: loc.clone(),
            message: message.to_string(),
        }
    }

    /// `file` refused.
    pub fn file(file: impl fmt::Display, message: impl fmt::Display) -> Error {
        Error::File {
            file: file.to_string(),
            message: message.to_string(),
        }
    }

    /// A value refused.
    pub fn value(message: impl fmt::Display) -> Error {
        Error::Value(message.to_string())
    }

    /// Input refused, as the message says.
    pub fn input(message: impl fmt::Display) -> Error {
        Error::Input(message.to_string())
    }

    /// The process's exit status for this error: 2 for a value given on the command line, 128 + the signal when
    /// interrupted, 1 for everything the input refused (a file, a scene, the budget, the plugin).
    pub fn exit_status(&self) -> u8 {
        match self {
            Error::Value(_) => 2,
            Error::Interrupted { signal, .. } => {
                128u8.saturating_add(u8::try_from(*signal).unwrap_or(0))
            }
            _ => 1,
        }
    }

    /// Where in a scene file the error is, when it is about one.
    pub fn loc(&self) -> Option<&Loc> {
        match self {
            Error::Scene { loc, .. } => Some(loc),
            Error::Parse(e) if e.loc.line > 0 => Some(&e.loc),
            _ => None,
        }
    }

    /// The same error seen from a statement at `loc` (a file read for a scene's texture): the statement's
    /// location first, then what `self` says, prefixed with `what`.
    pub fn within(self, loc: &Loc, what: &str) -> Error {
        match self {
            e @ (Error::Scene { .. } | Error::Parse(_)) => e,
            e if what.is_empty() => Error::at(loc, e),
            e => Error::at(loc, format!("{what}: {e}")),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Scene { loc, message } => write!(f, "{loc}: {message}"),
            Error::Parse(e) => write!(f, "{e}"),
            Error::File { file, message } => write!(f, "{file}: {message}"),
            Error::Budget { what, bytes, budget } => write!(
                f,
                "{what} needs {} bytes, above the memory budget of {budget} bytes (--max-memory raises it)",
                bytes.map_or_else(|| "more than 2^64".to_string(), |b| b.to_string())
            ),
            Error::Plugin(e) => write!(f, "{e}"),
            Error::Value(m) | Error::Input(m) | Error::Interrupted { message: m, .. } => f.write_str(m),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Parse(e) => Some(e),
            Error::Plugin(e) => Some(e),
            _ => None,
        }
    }
}

impl From<ParseError> for Error {
    fn from(e: ParseError) -> Error {
        Error::Parse(e)
    }
}

impl From<firemedium_loader::Error> for Error {
    fn from(e: firemedium_loader::Error) -> Error {
        Error::Plugin(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loc() -> Loc {
        Loc {
            file: "scene.pbrt".into(),
            line: 12,
            col: 3,
        }
    }

    #[test]
    fn each_kind_reads_as_one_line_and_maps_to_its_exit_status() {
        let e = Error::at(&loc(), "bogus");
        assert_eq!(
            (e.to_string().as_str(), e.exit_status()),
            ("scene.pbrt:12:3: bogus", 1)
        );
        assert_eq!(e.loc().map(|l| l.line), Some(12));
        let e = Error::file("a.exr", "cannot read: gone");
        assert_eq!(
            (e.to_string().as_str(), e.exit_status()),
            ("a.exr: cannot read: gone", 1)
        );
        assert!(e.loc().is_none());
        let e = Error::value("--spp 0: expected at least 1");
        assert_eq!(e.exit_status(), 2);
        let e = Error::Interrupted {
            signal: 2,
            message: "interrupted".into(),
        };
        assert_eq!(e.exit_status(), 130);
        let e = Error::Budget {
            what: "a film".into(),
            bytes: None,
            budget: 1024,
        };
        assert_eq!(
            e.to_string(),
            "a film needs more than 2^64 bytes, above the memory budget of 1024 bytes (--max-memory raises it)"
        );
    }

    #[test]
    fn a_file_error_inside_a_statement_keeps_the_statement_s_location() {
        let e = Error::file("wood.png", "not a PNG").within(&loc(), "imagemap");
        assert_eq!(
            e.to_string(),
            "scene.pbrt:12:3: imagemap: wood.png: not a PNG"
        );
        assert_eq!(e.loc().map(|l| l.col), Some(3));
        // An error that already has a location keeps its own.
        let inner = Loc { line: 40, ..loc() };
        let e = Error::at(&inner, "x").within(&loc(), "Include");
        assert_eq!(e.loc().map(|l| l.line), Some(40));
    }
}
