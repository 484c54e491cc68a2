//! Files before decoding: frame numbers in names, reading (in parallel parts when large), text, the format a
//! file is in and the grids it holds.

use super::*;

/// Replaces the first run of `#` (`fire_####.vdb`) or a `%0Nd` with the zero-padded frame number.
pub fn frame_path(path: &Path, frame: Option<i64>) -> Result<PathBuf, Error> {
    let s = path.to_string_lossy();
    let (start, len, width) = if let Some(start) = s.find('#') {
        let len = s[start..].chars().take_while(|&c| c == '#').count();
        (start, len, len)
    } else if let Some(start) = s.find('%') {
        let rest = &s[start + 1..];
        let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        if rest[digits.len()..].starts_with('d') {
            (
                start,
                digits.len() + 2,
                digits.trim_start_matches('0').parse().unwrap_or(0),
            )
        } else {
            return Ok(path.to_path_buf());
        }
    } else {
        return Ok(path.to_path_buf());
    };
    let Some(frame) = frame else {
        return Err(Error::invalid(
            "dataset",
            "frame",
            "unset",
            format!("a frame number for the pattern in '{s}'"),
        ));
    };
    let num = if frame < 0 {
        format!("-{:0width$}", -frame, width = width)
    } else {
        format!("{frame:0width$}")
    };
    Ok(PathBuf::from(format!(
        "{}{}{}",
        &s[..start],
        num,
        &s[start + len..]
    )))
}

/// The bytes of `path`. A large file is read in parallel, one part per thread at its offset (the copy out of
/// the page cache is bound by one core's memory copy: 27.6 → 20.1 ms, medians of 10, for the 42.5 MB of the 256³
/// campfire on 2 cores).
pub fn read_file(path: &Path) -> Result<Vec<u8>, Error> {
    let io = |e: std::io::Error| Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    };
    open_regular(path)?;
    let alloc = |len: u64| -> Result<Vec<u8>, Error> {
        usize::try_from(len)
            .ok()
            .and_then(crate::alloc::with_capacity)
            .ok_or_else(|| Error::Io {
                file: path.display().to_string(),
                message: format!("{len} bytes: more than this machine can hold"),
            })
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileExt;
        /// Below this a single read is as fast.
        const PARALLEL_BYTES: u64 = 8 << 20;
        let f = std::fs::File::open(path).map_err(io)?;
        let len = f.metadata().map_err(io)?.len();
        let threads = crate::par::threads(4);
        if len >= PARALLEL_BYTES && threads > 1 {
            let mut buf = alloc(len)?;
            let len = len as usize;
            buf.resize(len, 0);
            let part = len.div_ceil(threads);
            let f = &f;
            let done: Vec<std::io::Result<()>> = crate::par::scope(|s| {
                let jobs: Vec<_> = buf
                    .chunks_mut(part)
                    .enumerate()
                    .map(|(k, chunk)| s.spawn(move || f.read_exact_at(chunk, (k * part) as u64)))
                    .collect();
                jobs.into_iter()
                    .map(|j| {
                        j.join().unwrap_or_else(|_| {
                            Err(std::io::Error::other("a reading thread stopped"))
                        })
                    })
                    .collect()
            });
            for r in done {
                r.map_err(io)?;
            }
            return Ok(buf);
        }
    }
    use std::io::Read;
    let f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let mut buf = alloc(len)?;
    f.take(len).read_to_end(&mut buf).map_err(io)?;
    Ok(buf)
}

/// `path` opened for reading, with its length: only regular files, read to the length they had when opened —
/// a device (/dev/zero) never ends and a FIFO blocks its reader forever (it is checked before it is opened:
/// opening one blocks too).
pub fn open_regular(path: &Path) -> Result<(std::fs::File, u64), Error> {
    let io = |e: std::io::Error| Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(Error::Io {
            file: path.display().to_string(),
            message: "not a regular file (a directory, device or FIFO): datasets are read from files of a known size".into(),
        });
    }
    let f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    Ok((f, len))
}

pub fn as_text<'a>(file: &str, bytes: &'a [u8]) -> Result<&'a str, Error> {
    std::str::from_utf8(bytes).map_err(|e| {
        Error::format(
            file,
            format!("byte {}", e.valid_up_to()),
            "ASCII text",
            "a byte that is not text (a binary file?)",
        )
    })
}

/// A grid inside a file, as listed by [`list_grids`].
#[derive(Debug, Clone, PartialEq)]
pub struct GridEntry {
    /// Its name (single-grid formats: `density`).
    pub name: String,
    /// Its value type as the file names it.
    pub kind: String,
    /// Whether this component can load it (float grids).
    pub loadable: bool,
}

/// The format `opts` or the extension gives `path`.
pub fn format_of(path: &Path, opts: &LoadOptions) -> Result<Format, Error> {
    opts.format
        .or_else(|| Format::from_extension(path))
        .ok_or_else(|| {
            Error::invalid(
                "dataset",
                "format",
                format!("unset for '{}'", path.display()),
                format!(
                    "a known extension (.vdb .nvdb .raw .raw2 .txt) or 'format' one of {}",
                    Format::NAMES.join(", ")
                ),
            )
        })
}

/// What wrote the OpenVDB file at `path`: its file metadata's `creator` string (`None`: it names none). An error
/// when the file is not an OpenVDB file.
pub fn creator_of(path: &Path) -> Result<Option<String>, Error> {
    let file = path.display().to_string();
    let (f, len) = open_regular(path)?;
    Ok(vdb::read_header_from(&file, Bytes::File { file: &f, len })?.creator)
}

/// The grids a file holds (after frame substitution). Single-grid formats hold one grid, `density`.
pub fn list_grids(path: &Path, opts: &LoadOptions) -> Result<Vec<GridEntry>, Error> {
    let path = frame_path(path, opts.frame)?;
    let file = path.display().to_string();
    Ok(match format_of(&path, opts)? {
        Format::Vdb => {
            let (f, len) = open_regular(&path)?;
            vdb::read_header_from(&file, Bytes::File { file: &f, len })?
                .grids
                .into_iter()
                .map(|g| GridEntry {
                    loadable: g.tree_type == "Tree_float_5_4_3" && g.instance_parent_is_empty(),
                    kind: g.tree_type.clone() + if g.half { " (half)" } else { "" },
                    name: g.name,
                })
                .collect()
        }
        Format::NanoVdb => {
            let (f, len) = open_regular(&path)?;
            nanovdb::grid_names(&file, Bytes::File { file: &f, len })?
                .into_iter()
                .map(|(name, float)| GridEntry {
                    name,
                    kind: if float {
                        "float".into()
                    } else {
                        "other".into()
                    },
                    loadable: float,
                })
                .collect()
        }
        _ => {
            read_file(&path)?;
            vec![GridEntry {
                name: "density".into(),
                kind: "float".into(),
                loadable: true,
            }]
        }
    })
}
