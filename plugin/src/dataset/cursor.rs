//! Bounds-checked little-endian reading of a byte buffer, with errors that name the file and byte offset.

use crate::Error;

/// A read position in a file's bytes.
#[derive(Debug, Clone)]
pub(crate) struct Cursor<'a> {
    pub file: &'a str,
    pub data: &'a [u8],
    pub pos: usize,
}

impl<'a> Cursor<'a> {
    pub fn new(file: &'a str, data: &'a [u8]) -> Self {
        Cursor { file, data, pos: 0 }
    }

    /// Error at the current offset.
    pub fn err(&self, expected: impl Into<String>, found: impl std::fmt::Display) -> Error {
        Error::format(self.file, format!("byte {}", self.pos), expected, found)
    }

    pub fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }

    pub fn bytes(&mut self, n: usize, what: &str) -> Result<&'a [u8], Error> {
        // `pos` may have been set past the end by a caller skipping a record: refuse even empty reads then.
        if self.pos > self.data.len() || n > self.remaining() {
            return Err(self.err(
                format!("{n} bytes of {what}"),
                format!(
                    "the end of the file after {} bytes (truncated)",
                    self.remaining()
                ),
            ));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    pub fn skip(&mut self, n: usize, what: &str) -> Result<(), Error> {
        self.bytes(n, what).map(|_| ())
    }

    pub fn seek(&mut self, pos: u64, what: &str) -> Result<(), Error> {
        if pos > self.data.len() as u64 {
            return Err(self.err(
                format!("an offset within the file for {what}"),
                format!("offset {pos} past its end ({} bytes)", self.data.len()),
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
