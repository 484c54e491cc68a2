//! Bounds-checked little-endian reading of a file's bytes, with errors that name the file and byte offset: from
//! bytes in memory, or streamed from an open file through a window (so a loader holds what it decodes, not the
//! file — a grid the scene does not name is never read).

use crate::Error;

/// Bytes of a window read at a time from a file (more when one read asks for more).
const WINDOW: usize = 1 << 20;

/// Where a cursor's bytes come from.
#[derive(Debug, Clone)]
pub enum Bytes<'a> {
    /// The whole file in memory.
    Slice(&'a [u8]),
    /// An open regular file of `len` bytes, read by offset.
    File { file: &'a std::fs::File, len: u64 },
}

impl Bytes<'_> {
    /// The file's length.
    pub fn len(&self) -> u64 {
        match self {
            Bytes::Slice(s) => s.len() as u64,
            Bytes::File { len, .. } => *len,
        }
    }

    /// The whole file (the single-grid formats are decoded from memory).
    pub fn all(&self, name: &str) -> Result<std::borrow::Cow<'_, [u8]>, Error> {
        self.read(name, 0, usize::try_from(self.len()).unwrap_or(usize::MAX))
    }

    /// Bytes [pos, pos + n) (the caller has checked them against [`len`](Self::len)): borrowed from memory,
    /// or read from the file into a buffer whose allocation may fail (an error naming `file`, not an abort).
    pub fn read(
        &self,
        name: &str,
        pos: u64,
        n: usize,
    ) -> Result<std::borrow::Cow<'_, [u8]>, Error> {
        match self {
            Bytes::Slice(s) => Ok(std::borrow::Cow::Borrowed(
                &s[pos as usize..pos as usize + n],
            )),
            Bytes::File { file, .. } => {
                let mut buf = Vec::new();
                read_at(name, file, pos, n, &mut buf)?;
                Ok(std::borrow::Cow::Owned(buf))
            }
        }
    }
}

/// Reads `n` bytes at `pos` of `file` into `buf` (replacing its contents).
fn read_at(
    name: &str,
    file: &std::fs::File,
    pos: u64,
    n: usize,
    buf: &mut Vec<u8>,
) -> Result<(), Error> {
    buf.clear();
    buf.try_reserve_exact(n).map_err(|_| Error::Io {
        file: name.to_string(),
        message: format!("{n} bytes at byte {pos}: more than this machine can hold"),
    })?;
    buf.resize(n, 0);
    let io = |e: std::io::Error| Error::Io {
        file: name.to_string(),
        message: format!("reading {n} bytes at byte {pos}: {e}"),
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileExt;
        file.read_exact_at(buf, pos).map_err(io)
    }
    #[cfg(not(unix))]
    {
        use std::io::{Read, Seek, SeekFrom};
        let mut f = file;
        f.seek(SeekFrom::Start(pos)).map_err(io)?;
        f.read_exact(buf).map_err(io)
    }
}

/// A read position in a file's bytes.
#[derive(Debug, Clone)]
pub struct Cursor<'a> {
    pub file: &'a str,
    src: Bytes<'a>,
    pub pos: usize,
    /// A file's bytes [base, base + window.len()) (unused for bytes in memory).
    window: Vec<u8>,
    base: usize,
}

impl<'a> Cursor<'a> {
    pub fn new(file: &'a str, data: &'a [u8]) -> Self {
        Cursor::over(file, Bytes::Slice(data))
    }

    /// A cursor over `src` at byte 0.
    pub fn over(file: &'a str, src: Bytes<'a>) -> Self {
        Cursor {
            file,
            src,
            pos: 0,
            window: Vec::new(),
            base: 0,
        }
    }

    /// The file's length.
    pub fn len(&self) -> usize {
        usize::try_from(self.src.len()).unwrap_or(usize::MAX)
    }

    /// Error at the current offset.
    pub fn err(&self, expected: impl Into<String>, found: impl std::fmt::Display) -> Error {
        Error::format(self.file, format!("byte {}", self.pos), expected, found)
    }

    pub fn remaining(&self) -> usize {
        self.len().saturating_sub(self.pos)
    }

    pub fn bytes(&mut self, n: usize, what: &str) -> Result<&[u8], Error> {
        // `pos` may have been set past the end by a caller skipping a record: refuse even empty reads then.
        if self.pos > self.len() || n > self.remaining() {
            return Err(self.err(
                format!("{n} bytes of {what}"),
                format!(
                    "the end of the file after {} bytes (truncated)",
                    self.remaining()
                ),
            ));
        }
        let at = self.pos;
        self.pos += n;
        match &self.src {
            Bytes::Slice(s) => Ok(&s[at..at + n]),
            Bytes::File { file, len } => {
                if at < self.base || at + n > self.base + self.window.len() {
                    // (The window reads ahead, up to the end of the file.)
                    let want = n.max(WINDOW).min((*len as usize).saturating_sub(at));
                    read_at(self.file, file, at as u64, want, &mut self.window)?;
                    self.base = at;
                }
                Ok(&self.window[at - self.base..at - self.base + n])
            }
        }
    }

    pub fn skip(&mut self, n: usize, what: &str) -> Result<(), Error> {
        if self.pos > self.len() || n > self.remaining() {
            return self.bytes(n, what).map(|_| ());
        }
        // (Skipped bytes are not read.)
        self.pos += n;
        Ok(())
    }

    pub fn seek(&mut self, pos: u64, what: &str) -> Result<(), Error> {
        if pos > self.len() as u64 {
            return Err(self.err(
                format!("an offset within the file for {what}"),
                format!("offset {pos} past its end ({} bytes)", self.len()),
            ));
        }
        self.pos = pos as usize;
        Ok(())
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], Error> {
        let b = self.bytes(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(b);
        Ok(a)
    }

    pub fn u8(&mut self, what: &str) -> Result<u8, Error> {
        Ok(self.array::<1>(what)?[0])
    }
    pub fn u16(&mut self, what: &str) -> Result<u16, Error> {
        Ok(u16::from_le_bytes(self.array(what)?))
    }
    pub fn i32(&mut self, what: &str) -> Result<i32, Error> {
        Ok(i32::from_le_bytes(self.array(what)?))
    }
    pub fn u32(&mut self, what: &str) -> Result<u32, Error> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }
    pub fn i64(&mut self, what: &str) -> Result<i64, Error> {
        Ok(i64::from_le_bytes(self.array(what)?))
    }
    pub fn u64(&mut self, what: &str) -> Result<u64, Error> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }
    pub fn f32(&mut self, what: &str) -> Result<f32, Error> {
        Ok(f32::from_le_bytes(self.array(what)?))
    }
    pub fn f64(&mut self, what: &str) -> Result<f64, Error> {
        Ok(f64::from_le_bytes(self.array(what)?))
    }
}
