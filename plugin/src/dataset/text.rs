//! Whitespace-separated tokens with line and column, for the ASCII formats.

use crate::Error;

pub(crate) struct Tokens<'a> {
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

    fn at(&self, pos: usize, line: usize, line_start: usize) -> String {
        format!(
            "line {line}, column {}",
            self.text[line_start..pos].chars().count() + 1
        )
    }

    /// The next token and its position, or `None` at the end.
    pub fn next_token(&mut self) -> Option<(&'a str, String)> {
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
            self.at(start, self.line, self.line_start),
        ))
    }

    fn end_error(&self, what: &str) -> Error {
        Error::format(
            self.file,
            self.at(self.pos, self.line, self.line_start),
            what.to_string(),
            "the end of the file",
        )
    }

    /// The next token as an f64 (finite or not: policies judge values later).
    pub fn number(&mut self, what: &str) -> Result<f64, Error> {
        let (tok, at) = self.next_token().ok_or_else(|| self.end_error(what))?;
        match tok.parse::<f64>() {
            // Grid values are stored as f32: 1e39 would become inf and be reported as "found inf".
            Ok(v) if v.is_finite() && v.abs() > f32::MAX as f64 => Err(Error::format(
                self.file,
                at,
                format!("{what} within f32's range (±3.4e38)"),
                format!("'{}'", shorten(tok)),
            )),
            Ok(v) => Ok(v),
            Err(_) => Err(Error::format(
                self.file,
                at,
                what.to_string(),
                format!("'{}'", shorten(tok)),
            )),
        }
    }

    /// The next token as an integer in [lo, hi].
    pub fn integer(&mut self, what: &str, lo: i64, hi: i64) -> Result<i64, Error> {
        let (tok, at) = self.next_token().ok_or_else(|| self.end_error(what))?;
        match tok.parse::<i64>() {
            Ok(v) if (lo..=hi).contains(&v) => Ok(v),
            _ => Err(Error::format(
                self.file,
                at,
                format!("{what} (an integer from {lo} to {hi})"),
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
                at,
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
