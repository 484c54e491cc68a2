//! Whitespace-separated tokens with line and column, for the ASCII formats.

use crate::Error;

/// A place in the text: byte offset, line, the byte its line starts at.
type Place = (usize, usize, usize);

#[derive(Clone)]
pub struct Tokens<'a> {
    file: &'a str,
    text: &'a str,
    pos: usize,
    line: usize,
    line_start: usize,
}

impl<'a> Tokens<'a> {
    pub fn new(file: &'a str, text: &'a str) -> Self {
        Tokens {
            file,
            text,
            pos: 0,
            line: 1,
            line_start: 0,
        }
    }

    /// "line L, column C" of a place, counted only when an error names it (counting the column for every token
    /// made a file of one long line quadratic: an 8 MB line of values never finished loading).
    fn at(&self, (pos, line, line_start): Place) -> String {
        format!(
            "line {line}, column {}",
            self.text[line_start..pos].chars().count() + 1
        )
    }

    /// The next token and where it starts, or `None` at the end.
    fn next_token(&mut self) -> Option<(&'a str, Place)> {
        let bytes = self.text.as_bytes();
        while self.pos < bytes.len() && bytes[self.pos].is_ascii_whitespace() {
            if bytes[self.pos] == b'\n' {
                self.line += 1;
                self.line_start = self.pos + 1;
            }
            self.pos += 1;
        }
        if self.pos >= bytes.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < bytes.len() && !bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        // Token boundaries are ASCII whitespace, so slicing stays on char boundaries.
        Some((
            &self.text[start..self.pos],
            (start, self.line, self.line_start),
        ))
    }

    fn end_error(&self, what: &str) -> Error {
        Error::format(
            self.file,
            self.at((self.pos, self.line, self.line_start)),
            what.to_string(),
            "the end of the file",
        )
    }

    /// The next token as an f64 (finite or not: policies judge values later).
    pub fn number(&mut self, what: &str) -> Result<f64, Error> {
        self.number_of(|| what.to_string())
    }

    /// [`number`](Self::number), the expectation's text made only for an error (a grid's values are millions).
    pub fn number_of(&mut self, what: impl FnOnce() -> String) -> Result<f64, Error> {
        let Some((tok, at)) = self.next_token() else {
            return Err(self.end_error(&what()));
        };
        match tok.parse::<f64>() {
            // Grid values are stored as f32: 1e39 would become inf and be reported as "found inf".
            Ok(v) if v.is_finite() && v.abs() > f32::MAX as f64 => Err(Error::format(
                self.file,
                self.at(at),
                format!("{} within f32's range (±3.4e38)", what()),
                format!("'{}'", shorten(tok)),
            )),
            Ok(v) => Ok(v),
            Err(_) => Err(Error::format(
                self.file,
                self.at(at),
                what(),
                format!("'{}'", shorten(tok)),
            )),
        }
    }

    /// The next token as an integer in [lo, hi].
    pub fn integer(&mut self, what: &str, lo: i64, hi: i64) -> Result<i64, Error> {
        self.integer_of(|| what.to_string(), lo, hi)
    }

    /// [`integer`](Self::integer), the expectation's text made only for an error.
    pub fn integer_of(
        &mut self,
        what: impl FnOnce() -> String,
        lo: i64,
        hi: i64,
    ) -> Result<i64, Error> {
        let Some((tok, at)) = self.next_token() else {
            return Err(self.end_error(&what()));
        };
        match tok.parse::<i64>() {
            Ok(v) if (lo..=hi).contains(&v) => Ok(v),
            _ => Err(Error::format(
                self.file,
                self.at(at),
                format!("{} (an integer from {lo} to {hi})", what()),
                format!("'{}'", shorten(tok)),
            )),
        }
    }

    /// Error unless only whitespace remains.
    pub fn expect_end(&mut self, after: &str) -> Result<(), Error> {
        match self.next_token() {
            None => Ok(()),
            Some((tok, at)) => Err(Error::format(
                self.file,
                self.at(at),
                format!("the end of the file after {after}"),
                format!("'{}'", shorten(tok)),
            )),
        }
    }
}

fn shorten(s: &str) -> String {
    if s.chars().count() > 32 {
        s.chars().take(32).collect::<String>() + "…"
    } else {
        s.to_string()
    }
}
