//! Decoders for the compressed blocks of OpenVDB and NanoVDB files: blosc1 frames (LZ4, byte shuffle),
//! zlib streams, and IEEE binary16 half floats. Every size is checked against the caller's expectation before
//! anything is allocated; malformed input is an error, never a panic.

use crate::Error;

/// A decoder's complaint: what it expected and what it found, or a feature this build lacks.
#[derive(Debug, Clone, PartialEq)]
pub enum DecodeError {
    /// Malformed data.
    Bad { expected: String, found: String },
    /// Valid data this build cannot decode: the name of the cargo feature it lacks (`blosc`, `zip`).
    #[cfg_attr(all(feature = "blosc", feature = "zip"), allow(dead_code))]
    Feature(&'static str),
}

impl DecodeError {
    fn bad(expected: impl Into<String>, found: impl std::fmt::Display) -> Self {
        DecodeError::Bad {
            expected: expected.into(),
            found: found.to_string(),
        }
    }
    /// The crate error at position `at` of `file`.
    pub fn at(self, file: &str, at: String) -> Error {
        match self {
            DecodeError::Bad { expected, found } => Error::format(file, at, expected, found),
            DecodeError::Feature(feature) => Error::Unsupported {
                file: file.to_string(),
                what: format!("{at}: {feature}-compressed data in a build without it"),
                hint: format!("rebuild the plugin with cargo feature '{feature}'"),
            },
        }
    }
}

/// Decodes one blosc1 frame expected to hold `expected` bytes (OpenVDB pads buffers under 48 bytes to 128
/// before compressing, so a frame may hold up to 128 bytes for a smaller expectation; the prefix is returned).
pub fn blosc(src: &[u8], expected: usize) -> Result<Vec<u8>, DecodeError> {
    if src.len() < 16 {
        return Err(DecodeError::bad(
            "a 16-byte blosc header",
            format!("{} bytes", src.len()),
        ));
    }
    let (flags, typesize) = (src[2], src[3].max(1) as usize);
    let rd = |o: usize| u32::from_le_bytes([src[o], src[o + 1], src[o + 2], src[o + 3]]) as usize;
    let (nbytes, blocksize, cbytes) = (rd(4), rd(8), rd(12));
    if nbytes < expected || nbytes > expected.max(128) {
        return Err(DecodeError::bad(
            format!("a blosc frame of {expected} bytes"),
            format!("one of {nbytes}"),
        ));
    }
    if cbytes > src.len() {
        return Err(DecodeError::bad(
            format!("a blosc frame of {cbytes} bytes"),
            format!("only {} (truncated)", src.len()),
        ));
    }
    let mut out = vec![0u8; nbytes];
    if flags & 0x2 != 0 {
        // MEMCPYED: stored as is, no shuffle.
        let body = src
            .get(16..16 + nbytes)
            .ok_or_else(|| DecodeError::bad("a stored blosc frame", "a truncated one"))?;
        out.copy_from_slice(body);
        out.truncate(expected);
        return Ok(out);
    }
    if flags & 0x4 != 0 {
        return Err(DecodeError::bad(
            "byte-shuffled blosc data",
            "bit-shuffle (unsupported)",
        ));
    }
    let codec = flags >> 5;
    if codec != 1 {
        let name = ["blosclz", "lz4", "snappy", "zlib", "zstd"]
            .get(codec as usize)
            .copied()
            .unwrap_or("unknown");
        return Err(DecodeError::bad(
            "blosc with LZ4 (OpenVDB's choice)",
            format!("compressor '{name}' (unsupported)"),
        ));
    }
    if nbytes == 0 {
        return Ok(out);
    }
    if blocksize == 0 || blocksize > nbytes.max(1) {
        return Err(DecodeError::bad(
            format!("a blosc block size within 1..{nbytes}"),
            blocksize,
        ));
    }
    let dont_split = flags & 0x10 != 0;
    let shuffle = flags & 0x1 != 0 && typesize > 1;
    let nblocks = nbytes.div_ceil(blocksize);
    let starts = src
        .get(16..16 + 4 * nblocks)
        .ok_or_else(|| DecodeError::bad("blosc block offsets", "a truncated frame"))?;
    let mut tmp = vec![0u8; blocksize];
    for j in 0..nblocks {
        let leftover = j == nblocks - 1 && nbytes % blocksize != 0;
        let bsize = if leftover {
            nbytes % blocksize
        } else {
            blocksize
        };
        let mut pos = u32::from_le_bytes([
            starts[4 * j],
            starts[4 * j + 1],
            starts[4 * j + 2],
            starts[4 * j + 3],
        ]) as usize;
        let nsplits = if !dont_split && typesize <= 16 && bsize / typesize >= 128 && !leftover {
            typesize
        } else {
            1
        };
        let neblock = bsize / nsplits;
        let dest = if shuffle {
            &mut tmp[..bsize]
        } else {
            &mut out[j * blocksize..j * blocksize + bsize]
        };
        for s in 0..nsplits {
            let size_bytes = src
                .get(pos..pos + 4)
                .ok_or_else(|| DecodeError::bad("a blosc split size", "the end of the frame"))?;
            let csize =
                i32::from_le_bytes([size_bytes[0], size_bytes[1], size_bytes[2], size_bytes[3]]);
            pos += 4;
            if csize < 0 {
                return Err(DecodeError::bad("a blosc split size >= 0", csize));
            }
            let data = src
                .get(pos..pos + csize as usize)
                .ok_or_else(|| DecodeError::bad("blosc split data", "the end of the frame"))?;
            pos += csize as usize;
            let target = &mut dest[s * neblock..(s + 1) * neblock];
            if csize as usize == neblock {
                target.copy_from_slice(data);
            } else {
                lz4(data, target)?;
            }
        }
        if shuffle {
            unshuffle(
                typesize,
                &tmp[..bsize],
                &mut out[j * blocksize..j * blocksize + bsize],
            );
        }
    }
    out.truncate(expected);
    Ok(out)
}

#[cfg(feature = "blosc")]
fn lz4(src: &[u8], dest: &mut [u8]) -> Result<(), DecodeError> {
    match lz4_flex::block::decompress_into(src, dest) {
        Ok(n) if n == dest.len() => Ok(()),
        Ok(n) => Err(DecodeError::bad(
            format!("an LZ4 block of {} bytes", dest.len()),
            n,
        )),
        Err(e) => Err(DecodeError::bad(
            "a valid LZ4 block",
            format!("corrupt data ({e})"),
        )),
    }
}

#[cfg(not(feature = "blosc"))]
fn lz4(_src: &[u8], _dest: &mut [u8]) -> Result<(), DecodeError> {
    Err(DecodeError::Feature("blosc"))
}

/// Blosc's byte unshuffle: byte b of element i comes from src[b·n + i]; trailing bytes are copied.
fn unshuffle(typesize: usize, src: &[u8], dest: &mut [u8]) {
    let n = src.len() / typesize;
    for i in 0..n {
        for b in 0..typesize {
            dest[i * typesize + b] = src[b * n + i];
        }
    }
    let tail = n * typesize;
    dest[tail..].copy_from_slice(&src[tail..]);
}

/// Inflates a zlib stream expected to hold exactly `expected` bytes.
#[cfg(feature = "zip")]
pub fn zlib(src: &[u8], expected: usize) -> Result<Vec<u8>, DecodeError> {
    match miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(src, expected) {
        Ok(v) if v.len() == expected => Ok(v),
        Ok(v) => Err(DecodeError::bad(
            format!("a zlib stream of {expected} bytes"),
            v.len(),
        )),
        Err(e) => Err(DecodeError::bad(
            format!("a zlib stream of {expected} bytes"),
            format!("corrupt or longer data ({:?})", e.status),
        )),
    }
}

/// A zlib stream inflated as it is read: `len` compressed bytes at byte `pos` of `src`, read a window at a time,
/// holding `expected` bytes — neither the stream nor what it holds is ever in memory whole (a NanoVDB ZIP
/// grid's leaves go from it to the grid's bricks).
#[cfg(feature = "zip")]
pub struct Inflater<'a> {
    file: &'a str,
    /// What the stream holds, for errors ("grid 'density'").
    what: String,
    src: crate::cursor::Bytes<'a>,
    /// Where the stream starts in `src`, the next compressed byte to read, and the stream's end.
    start: u64,
    next: u64,
    end: u64,
    /// Compressed bytes read and not yet inflated: `input[at..]`.
    input: Vec<u8>,
    at: usize,
    state: Box<miniz_oxide::inflate::stream::InflateState>,
    /// Bytes inflated so far, and the most the stream may hold.
    out: u64,
    expected: u64,
    scratch: Vec<u8>,
    /// Compressed bytes read at a time ([`INFLATE_WINDOW`]).
    window: usize,
}

/// Compressed bytes an [`Inflater`] reads from its source at a time.
#[cfg(feature = "zip")]
const INFLATE_WINDOW: usize = 1 << 18;

#[cfg(feature = "zip")]
impl<'a> Inflater<'a> {
    pub fn new(
        file: &'a str,
        what: String,
        src: crate::cursor::Bytes<'a>,
        (pos, len): (u64, u64),
        expected: u64,
    ) -> Inflater<'a> {
        use miniz_oxide::DataFormat;
        Inflater {
            file,
            what,
            src,
            start: pos,
            next: pos,
            end: pos.saturating_add(len),
            input: Vec::new(),
            at: 0,
            state: miniz_oxide::inflate::stream::InflateState::new_boxed(DataFormat::Zlib),
            out: 0,
            expected,
            scratch: Vec::new(),
            window: INFLATE_WINDOW,
        }
    }

    /// Bytes inflated so far.
    pub fn position(&self) -> u64 {
        self.out
    }

    /// The file the stream is read from.
    pub fn file(&self) -> &'a str {
        self.file
    }

    /// Fills `buf` with the stream's next bytes: an error naming the stream's byte where it is corrupt, ends
    /// short, or would hold more than expected.
    pub fn read(&mut self, buf: &mut [u8]) -> Result<(), Error> {
        use miniz_oxide::MZStatus;
        let expected = format!("a zlib stream of {} bytes", self.expected);
        if self.out.saturating_add(buf.len() as u64) > self.expected {
            let asked = self.out + buf.len() as u64;
            return Err(self.fail(expected, format!("{asked} bytes asked of it")));
        }
        let (mut filled, mut stalled) = (0, false);
        while filled < buf.len() {
            let (written, status, more);
            (written, stalled, status, more) = self.step(&mut buf[filled..], stalled)?;
            filled += written;
            let found = match status {
                Ok(MZStatus::StreamEnd) if filled < buf.len() => {
                    format!("one of {} (it ends)", self.out)
                }
                // (No progress for want of room or input: room is checked by the loop, input below.)
                Ok(_) | Err(miniz_oxide::MZError::Buf)
                    if stalled && !more && filled < buf.len() =>
                {
                    format!("one of {} (truncated)", self.out)
                }
                Ok(_) | Err(miniz_oxide::MZError::Buf) => continue,
                Err(e) => format!("corrupt data or a wrong checksum ({e:?})"),
            };
            return Err(self.fail(expected, found));
        }
        Ok(())
    }

    /// Inflates the rest of the stream (all `expected` bytes) and its end: an error unless it ends there with
    /// its checksum (Adler-32) right — what proves values already read from it were the stream's.
    pub fn finish(&mut self) -> Result<(), Error> {
        use miniz_oxide::MZStatus;
        self.skip(self.expected - self.out)?;
        let (mut spare, mut stalled) = ([0u8; 1], false);
        loop {
            let (written, status, more);
            (written, stalled, status, more) = self.step(&mut spare, stalled)?;
            let found = match status {
                _ if written > 0 => "more data than that",
                Ok(MZStatus::StreamEnd) => return Ok(()),
                Err(miniz_oxide::MZError::Data) => "a wrong checksum or corrupt data",
                _ if stalled && !more => "no end (truncated)",
                _ => continue,
            };
            let expected = format!("a zlib stream of {} bytes and its end", self.expected);
            return Err(self.fail(expected, found));
        }
    }

    /// One call of the inflater into `out`, after a refill where the input is spent or the last call `stalled`:
    /// the bytes it wrote, whether it stalled (nothing read or written), its status, and whether compressed
    /// bytes remain unread.
    fn step(
        &mut self,
        out: &mut [u8],
        stalled: bool,
    ) -> Result<(usize, bool, miniz_oxide::MZResult, bool), Error> {
        use miniz_oxide::inflate::stream::inflate;
        if self.at == self.input.len() || stalled {
            self.refill()?;
        }
        let more = self.next < self.end;
        let r = inflate(
            &mut self.state,
            &self.input[self.at..],
            out,
            miniz_oxide::MZFlush::None,
        );
        self.at += r.bytes_consumed;
        self.out += r.bytes_written as u64;
        let stalled = r.bytes_consumed == 0 && r.bytes_written == 0;
        Ok((r.bytes_written, stalled, r.status, more))
    }

    /// The error of a stream that is not `expected`, at the byte inflated so far.
    fn fail(&self, expected: String, found: impl std::fmt::Display) -> Error {
        DecodeError::bad(expected, found).at(
            self.file,
            format!(
                "{}: byte {} of its zlib stream at byte {}",
                self.what, self.out, self.start
            ),
        )
    }

    /// More compressed bytes, after those not yet inflated (a window's end may cut a code: it is kept in
    /// front); none once the stream's bytes are all read.
    fn refill(&mut self) -> Result<(), Error> {
        if self.next < self.end {
            let n = (self.end - self.next).min(self.window as u64) as usize;
            let fresh = self.src.read(self.file, self.next, n)?;
            self.input.drain(..self.at);
            self.input.extend_from_slice(&fresh);
            (self.at, self.next) = (0, self.next + n as u64);
        }
        Ok(())
    }

    /// Inflates and drops the stream's next `n` bytes.
    pub fn skip(&mut self, mut n: u64) -> Result<(), Error> {
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.resize(INFLATE_WINDOW, 0);
        while n > 0 {
            let k = n.min(scratch.len() as u64) as usize;
            self.read(&mut scratch[..k])?;
            n -= k as u64;
        }
        self.scratch = scratch;
        Ok(())
    }
}

#[cfg(not(feature = "zip"))]
pub fn zlib(_src: &[u8], _expected: usize) -> Result<Vec<u8>, DecodeError> {
    Err(DecodeError::Feature("zip"))
}

/// IEEE 754 binary16 → f32 (exact: every half is an f32).
pub fn half_to_f32(h: u16) -> f32 {
    let sign = ((h & 0x8000) as u32) << 16;
    let exp = ((h >> 10) & 0x1f) as u32;
    let mant = (h & 0x3ff) as u32;
    let bits = match exp {
        0 if mant == 0 => sign,
        0 => {
            // Subnormal: mant · 2⁻²⁴, normalised for f32.
            let shift = mant.leading_zeros() - 21; // bring the top bit to position 10
            let m = (mant << shift) & 0x3ff;
            sign | ((113 - shift) << 23) | (m << 13)
        }
        31 => sign | 0x7f80_0000 | (mant << 13),
        _ => sign | ((exp + 112) << 23) | (mant << 13),
    };
    f32::from_bits(bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[cfg(feature = "zip")]
    #[test]
    fn a_stream_inflated_a_few_bytes_at_a_time_is_the_stream() {
        // 200 000 bytes of a noisy ramp, zlib-compressed, read through windows of 7 compressed bytes (every code
        // cut somewhere) in pieces of 1 to 4 096 bytes, with skips: the same bytes, and its end and checksum
        // accepted; with the checksum's last byte changed, refused by name; asked for more than it holds, refused.
        let data: Vec<u8> = (0..200_000u32)
            .map(|i| ((i / 7) as u8).wrapping_add((i.wrapping_mul(2_654_435_761) >> 29) as u8))
            .collect();
        let packed = miniz_oxide::deflate::compress_to_vec_zlib(&data, 6);
        /// The stream in `bytes`, read 7 compressed bytes at a time.
        fn open(bytes: &[u8], expected: usize) -> Inflater<'_> {
            let mut z = Inflater::new(
                "f.nvdb",
                "grid 'density'".into(),
                crate::cursor::Bytes::Slice(bytes),
                (0, bytes.len() as u64),
                expected as u64,
            );
            z.window = 7;
            z
        }
        let mut z = open(&packed, data.len());
        let (mut at, mut k) = (0usize, 1usize);
        while at < data.len() {
            let n = (k * k % 4096 + 1).min(data.len() - at);
            if k % 5 == 0 {
                z.skip(n as u64).unwrap();
            } else {
                let mut buf = vec![0u8; n];
                z.read(&mut buf).unwrap();
                assert_eq!(buf, data[at..at + n], "at {at}");
            }
            at += n;
            k += 1;
        }
        z.finish().unwrap();
        let mut wrong = packed.to_vec();
        *wrong.last_mut().unwrap() ^= 1;
        let mut z = open(&wrong, data.len());
        let e = z
            .skip(data.len() as u64)
            .and_then(|_| z.finish())
            .unwrap_err();
        assert!(e.to_string().contains("grid 'density'"), "{e}");
        let mut z = open(&packed, data.len());
        assert!(z.read(&mut vec![0u8; data.len() + 1]).is_err());
    }

    #[test]
    fn half_values() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0x6800), 2048.0);
        assert_eq!(half_to_f32(0x7bff), 65504.0);
        assert_eq!(half_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(half_to_f32(0x03ff), 1023.0 * 2f32.powi(-24));
        assert_eq!(half_to_f32(0x0400), 2f32.powi(-14));
        assert_eq!(half_to_f32(0x8000).to_bits(), 0x8000_0000);
        assert!(half_to_f32(0x7c00).is_infinite() && half_to_f32(0x7e00).is_nan());
        // Monotone over all positive finite halves.
        let mut prev = -1.0f32;
        for h in 0u16..0x7c00 {
            let v = half_to_f32(h);
            assert!(v > prev, "{h:#x}");
            prev = v;
        }
    }

    #[test]
    fn unshuffle_inverts_shuffle() {
        let src: Vec<u8> = (0..23u8).collect();
        // Shuffle by hand: 5 elements of 4 bytes + 3 trailing bytes.
        let mut sh = vec![0u8; 23];
        for i in 0..5 {
            for b in 0..4 {
                sh[b * 5 + i] = src[i * 4 + b];
            }
        }
        sh[20..].copy_from_slice(&src[20..]);
        let mut back = vec![0u8; 23];
        unshuffle(4, &sh, &mut back);
        assert_eq!(back, src);
    }

    #[test]
    fn blosc_rejects_garbage_without_panicking() {
        assert!(blosc(&[0u8; 8], 16).is_err());
        let mut h = [0u8; 16];
        h[2] = 0x20; // lz4, no memcpy
        h[3] = 4;
        h[4..8].copy_from_slice(&64u32.to_le_bytes());
        h[8..12].copy_from_slice(&64u32.to_le_bytes());
        h[12..16].copy_from_slice(&16u32.to_le_bytes());
        assert!(
            matches!(blosc(&h, 64).unwrap_err(), DecodeError::Bad { found, .. } if found.contains("truncated"))
        );
        // Memcpyed frame round trip.
        let mut m = h.to_vec();
        m[2] = 0x02;
        m[12..16].copy_from_slice(&80u32.to_le_bytes());
        m.extend((0..64u8).collect::<Vec<_>>());
        assert_eq!(blosc(&m, 64).unwrap(), (0..64u8).collect::<Vec<_>>());
        assert!(
            matches!(blosc(&m, 1000).unwrap_err(), DecodeError::Bad { expected, .. } if expected.contains("1000"))
        );
    }
}
