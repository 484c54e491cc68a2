//! pbrt-v4 tokens: quoted strings (with `\n \t \\ \"` escapes), `[` and `]`, `#` comments to the end of the line,
//! and words (directive names, numbers, `true`/`false`) separated by white space.

use crate::{Loc, ParseError};
use std::sync::Arc;

/// The kind of a token.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TokenKind {
    /// A bare word: a directive, a number, `true`/`false`.
    Word,
    /// A quoted string (text is unescaped).
    Str,
    /// `[`
    Open,
    /// `]`
    Close,
}

/// One token with its position.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    /// Kind.
    pub kind: TokenKind,
    /// Text (strings without quotes, unescaped).
    pub text: String,
    /// Position of its first character.
    pub loc: Loc,
}

/// Splits a scene file's text into tokens.
#[derive(Debug)]
pub struct Tokenizer<'a> {
    file: Arc<str>,
    src: &'a str,
    pos: usize,
    line: u32,
    col: u32,
}

impl<'a> Tokenizer<'a> {
    /// Tokens of `src`, positions reported in `file`.
    pub fn new(file: Arc<str>, src: &'a str) -> Self {
        Tokenizer {
            file,
            src,
            pos: 0,
            line: 1,
            col: 1,
        }
    }

    fn loc(&self) -> Loc {
        Loc {
            file: self.file.clone(),
            line: self.line,
            col: self.col,
        }
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.src[self.pos..].chars().next()?;
        self.pos += c.len_utf8();
        if c == '\n' {
            self.line = self.line.saturating_add(1);
            self.col = 1;
        } else {
            self.col = self.col.saturating_add(1);
        }
        Some(c)
    }

    fn peek(&self) -> Option<char> {
        self.src[self.pos..].chars().next()
    }

    /// The next token, `None` at the end.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Result<Option<Token>, ParseError> {
        loop {
            match self.peek() {
                None => return Ok(None),
                Some(c) if c.is_whitespace() => {
                    self.bump();
                }
                Some('#') => {
                    while let Some(c) = self.bump() {
                        if c == '\n' {
                            break;
                        }
                    }
                }
                Some(_) => break,
            }
        }
        let loc = self.loc();
        let c = self.bump().unwrap_or(' ');
        let tok = |kind, text: String| {
            Ok(Some(Token {
                kind,
                text,
                loc: loc.clone(),
            }))
        };
        match c {
            '[' => tok(TokenKind::Open, "[".into()),
            ']' => tok(TokenKind::Close, "]".into()),
            '"' => {
                let mut s = String::new();
                loop {
                    match self.bump() {
                        None => return Err(ParseError::new(&loc, "unterminated string: expected a closing '\"' before the end of the file")),
                        Some('\n') => return Err(ParseError::new(&loc, "unterminated string: expected a closing '\"' before the end of the line")),
                        Some('"') => break,
                        Some('\\') => match self.bump() {
                            Some('n') => s.push('\n'),
                            Some('t') => s.push('\t'),
                            Some('b') => s.push('\u{8}'),
                            Some('f') => s.push('\u{c}'),
                            Some('r') => s.push('\r'),
                            Some(e @ ('\\' | '"' | '\'')) => s.push(e),
                            Some(e) => return Err(ParseError::new(&self.loc(), format!("unknown escape '\\{e}' in a string"))),
                            None => return Err(ParseError::new(&loc, "unterminated string at the end of the file")),
                        },
                        Some(ch) => s.push(ch),
                    }
                }
                tok(TokenKind::Str, s)
            }
            _ => {
                let mut s = String::from(c);
                while let Some(n) = self.peek() {
                    if n.is_whitespace() || n == '"' || n == '[' || n == ']' || n == '#' {
                        break;
                    }
                    s.push(n);
                    self.bump();
                }
                tok(TokenKind::Word, s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(src: &str) -> Result<Vec<(TokenKind, String, u32, u32)>, ParseError> {
        let mut t = Tokenizer::new("t.pbrt".into(), src);
        let mut v = Vec::new();
        while let Some(k) = t.next()? {
            v.push((k.kind, k.text, k.loc.line, k.loc.col));
        }
        Ok(v)
    }

    #[test]
    fn tokens_and_positions() {
        let v = all("Shape \"sphere\" # a comment\n  \"float radius\" [ 2.5 ]\n").unwrap();
        assert_eq!(v[0], (TokenKind::Word, "Shape".into(), 1, 1));
        assert_eq!(v[1], (TokenKind::Str, "sphere".into(), 1, 7));
        assert_eq!(v[2], (TokenKind::Str, "float radius".into(), 2, 3));
        assert_eq!(v[3], (TokenKind::Open, "[".into(), 2, 18));
        assert_eq!(v[4], (TokenKind::Word, "2.5".into(), 2, 20));
        assert_eq!(v[5], (TokenKind::Close, "]".into(), 2, 24));
        assert_eq!(v.len(), 6);
        // Brackets and strings need no spaces; non-ASCII counts as one column.
        let v = all("[1 2]\"é\"x").unwrap();
        assert_eq!(
            v.iter().map(|t| t.1.as_str()).collect::<Vec<_>>(),
            ["[", "1", "2", "]", "é", "x"]
        );
        assert_eq!(v[5].3, 9);
        assert_eq!(all("\"a\\\"b\\n\"").unwrap()[0].1, "a\"b\n");
    }

    #[test]
    fn bad_strings() {
        assert_eq!(
            all("Shape \"sph").unwrap_err().to_string(),
            "t.pbrt:1:7: unterminated string: expected a closing '\"' before the end of the file"
        );
        assert!(all("\"a\nb\"")
            .unwrap_err()
            .to_string()
            .contains("end of the line"));
        assert!(all("\"\\q\"")
            .unwrap_err()
            .to_string()
            .contains("unknown escape '\\q'"));
    }
}
