//! # firemedium-loader: the fire, for any Rust renderer
//!
//! Loads the firemedium plugin (a `cdylib`) at run time through its C ABI, checks the ABI version, keeps the
//! library alive for as long as any handle lives, and turns status codes into a typed [`Error`].
//!
//! ```no_run
//! use firemedium_loader::{Plugin, Param, Ray};
//! // SAFETY: loading a library runs its initialisers: load only a firemedium plugin you trust (see
//! // `Plugin::load`). This one is the file FIREMEDIUM_PLUGIN names, or found on FIREMEDIUM_PLUGIN_PATH.
//! let plugin = unsafe { Plugin::from_env() }?;
//! let fire = plugin.create_volume(&[Param::string("filename", "fire.vdb"), Param::float("temperaturescale", 1000.0)])?;
//! let c = fire.info().channels as usize;
//! let rays = [Ray { origin: [0.0, -2.0, 1.0], direction: [0.0, 1.0, 0.0], tmin: 0.0, tmax: 10.0, seed: 1 }];
//! let (mut radiance, mut transmittance) = (vec![0.0f32; c], vec![0.0f32; c]);
//! fire.integrate(&rays, &mut radiance, Some(&mut transmittance), None)?;
//! # Ok::<(), firemedium_loader::Error>(())
//! ```
//!
//! Volumes are `Send + Sync`: query one from many threads at once.

use firemedium_abi as abi;
pub use firemedium_abi::{
    FmExit as Exit, FmLightInfo as LightInfo, FmRay as Ray, FmScatter as Scatter,
    FmVolumeInfo as VolumeInfo, FM_FEATURE_DIFFUSION, FM_FEATURE_EMBERS, FM_FEATURE_EMITS,
    FM_FEATURE_EMITS_WITHOUT_ABSORPTION, FM_FEATURE_MOTION, FM_FEATURE_REFRACTION,
    FM_FEATURE_SCATTERS, FM_FEATURE_THICK_LINES,
};
use std::ffi::{c_char, c_void, CStr, CString};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

mod light;
mod volume;
pub use light::Light;
pub use volume::{MajorantGrid, Medium, Point, Sampling, Tables, Volume};

/// What went wrong.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// The library could not be opened.
    Open {
        /// Path tried.
        path: PathBuf,
        /// The loader's message.
        message: String,
    },
    /// The library has no `firemedium_plugin_entry` symbol (not a firemedium plugin).
    NoEntry {
        /// Path.
        path: PathBuf,
    },
    /// The plugin's ABI version is not one this host can use.
    Abi {
        /// Path.
        path: PathBuf,
        /// The plugin's (major, minor).
        plugin: (u32, u32),
        /// This host's (major, minor).
        host: (u32, u32),
    },
    /// The library exports the entry symbol but its table cannot be used: the entry returned null, the table is
    /// smaller than its version promises, or an entry this host calls is null.
    Broken {
        /// Path.
        path: PathBuf,
        /// What is wrong with it.
        what: String,
    },
    /// No plugin file was found.
    NotFound {
        /// Where we looked.
        searched: Vec<PathBuf>,
    },
    /// A call returned a failure status.
    Status {
        /// The `FM_*` status.
        code: i32,
        /// The plugin's message.
        message: String,
        /// Its parts, for pointing a user at the cause without parsing the message .
        detail: Box<ErrorDetail>,
    },
    /// A buffer passed to a batch call is too small.
    Buffer(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Open { path, message } => write!(f, "cannot load the firemedium plugin {}: {message}", path.display()),
            Error::NoEntry { path } => write!(f, "{} is not a firemedium plugin (no firemedium_plugin_entry symbol)", path.display()),
            Error::Abi { path, plugin, host } => write!(
                f,
                "{} speaks firemedium ABI {}.{}, this host needs {}.{} (same major, minor at least {})",
                path.display(),
                plugin.0,
                plugin.1,
                host.0,
                host.1,
                host.1
            ),
            Error::Broken { path, what } => write!(f, "{} is a broken firemedium plugin: {what}", path.display()),
            Error::NotFound { searched } => {
                let s: Vec<String> = searched.iter().map(|p| p.display().to_string()).collect();
                write!(f, "no firemedium plugin found (set FIREMEDIUM_PLUGIN to its file; in a source tree, `cargo build --release` builds it); looked in: {}", s.join(", "))
            }
            // (The code is for programs, in the variant; people read the plugin's message.)
            Error::Status { message, .. } => write!(f, "{message}"),
            Error::Buffer(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for Error {}

/// The plugin's file name on this platform (`libfiremedium_plugin.so`, `.dylib`, `firemedium_plugin.dll`).
pub fn library_file_name() -> String {
    format!(
        "{}firemedium_plugin{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    )
}

struct Inner {
    api: *const abi::FmApi,
    path: PathBuf,
    // Dropped last: every handle holds an Arc<Inner>, so the library outlives them all.
    _lib: libloading::Library,
}

// SAFETY: `api` points to the plugin's immutable static table; the ABI guarantees every function is safe to call
// from any thread, and the library stays loaded while `Inner` lives.
unsafe impl Send for Inner {}
// SAFETY: as above.
unsafe impl Sync for Inner {}

impl Inner {
    fn api(&self) -> &abi::FmApi {
        // SAFETY: checked non-null at load; static in the loaded library, which `self` keeps alive.
        unsafe { &*self.api }
    }
    fn last_error(&self) -> String {
        let api = self.api();
        // SAFETY: a null buffer asks for the length only (ABI contract).
        let n = unsafe { (api.last_error)(std::ptr::null_mut(), 0) };
        let mut buf = vec![0u8; n + 1];
        // SAFETY: buf has n + 1 writable bytes.
        unsafe { (api.last_error)(buf.as_mut_ptr() as *mut c_char, buf.len()) };
        buf.truncate(n);
        String::from_utf8_lossy(&buf).into_owned()
    }
    /// The last error's parts on this thread .
    fn last_error_detail(&self) -> ErrorDetail {
        let mut d = abi::FmErrorDetail::default();
        // SAFETY: a struct of the size it says.
        if unsafe { (self.api().last_error_detail)(&mut d) } != abi::FM_OK {
            return ErrorDetail::default();
        }
        let owned = |p: *const c_char| {
            (!p.is_null()).then(|| {
                // SAFETY: a NUL-terminated string the plugin keeps until the next call on this thread (non-null,
                // checked), copied now.
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            })
        };
        ErrorDetail {
            parameter: owned(d.parameter),
            location: owned(d.location),
            file: owned(d.file),
            position: owned(d.position),
            index: usize::try_from(d.index).ok(),
        }
    }
    fn check(&self, status: i32) -> Result<(), Error> {
        if status == abi::FM_OK {
            Ok(())
        } else {
            Err(Error::Status {
                code: status,
                message: self.last_error(),
                detail: Box::new(self.last_error_detail()),
            })
        }
    }
}

/// A host's thread pool for the plugin's builds: `pool(n, task)` runs `task(i)` for every i in 0..n, on its
/// threads as it likes, and returns when every one has returned.
pub type ThreadPool = Arc<dyn Fn(usize, &(dyn Fn(usize) + Sync)) + Send + Sync>;

/// The host's context for a volume ([`Plugin::create_volume_with`]): what the renderer knows and the
/// scene does not say.
#[derive(Clone, Default)]
pub struct Context {
    /// Threads the build may use (`None`: the plugin's default, the machine's).
    pub threads: Option<u32>,
    /// The volume's memory budget, bytes (`None`: the plugin's default).
    pub max_bytes: Option<u64>,
    /// The frame a `####` in a file name takes.
    pub frame: Option<i64>,
    /// The camera's shutter, frames from the grids' time (for motion blur).
    pub shutter: Option<[f64; 2]>,
    /// The host's thread pool (`None`: the plugin starts threads of its own for its builds): the volume's and its
    /// lights' parallel parts run as its tasks. The volume keeps it.
    pub pool: Option<ThreadPool>,
    /// The folder the scene's relative file names are in (`None`: the working directory): the plugin resolves
    /// its own file parameters against it.
    pub directory: Option<PathBuf>,
    /// What the medium type the scene named means (`None`: the scene's `mode`, else the paper's fire).
    pub kind: Option<Kind>,
    /// The render's spectral bins (`None`: the scene's `bins`, `lambdamin`, `lambdamax`, else the plugin's).
    pub bins: Option<Bins>,
}

/// What a medium type a host's scene names means ([`Context::kind`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// The paper's fire (`mode` `physical`).
    Fire,
    /// pbrt-v4's grid media, `uniformgrid` and `nanovdb` (`mode` `pbrt`).
    Pbrt,
}

/// A render's spectral bins ([`Context::bins`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bins {
    /// How many (1 to 4096).
    pub count: u32,
    /// Their span, nm: shortest, longest (200 to 2000).
    pub nm: [f64; 2],
}

impl std::fmt::Debug for Context {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("threads", &self.threads)
            .field("max_bytes", &self.max_bytes)
            .field("frame", &self.frame)
            .field("shutter", &self.shutter)
            .field("pool", &self.pool.as_ref().map(|_| "the host's"))
            .field("directory", &self.directory)
            .field("kind", &self.kind)
            .field("bins", &self.bins)
            .finish()
    }
}

/// The plugin's view of a [`ThreadPool`]: `pool` is the `ThreadPool` a volume keeps.
unsafe extern "C" fn parallel_for(
    pool: *mut c_void,
    count: usize,
    task: abi::FmTask,
    data: *mut c_void,
) {
    struct Data(*mut c_void);
    // SAFETY: the plugin's contract: its task may run on any thread, several at once.
    unsafe impl Sync for Data {}
    let data = Data(data);
    // SAFETY: `pool` points at the ThreadPool the volume keeps (create_volume_with), alive across the call.
    let pool = unsafe { &*(pool as *const ThreadPool) };
    let run = |i: usize| {
        let data = &data;
        // SAFETY: the plugin's task for index i < count with its data (its contract); it never unwinds.
        unsafe { task(data.0, i) }
    };
    // (A panicking pool must not unwind into the plugin: the parts it did not run, the plugin runs itself.)
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| pool(count, &run)));
}

/// The parts of a plugin error : what a host needs to point its user at the cause.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ErrorDetail {
    /// The parameter at fault, as the host named it.
    pub parameter: Option<String>,
    /// Where the host said that parameter was given (`Param::at`: `file:line:col`).
    pub location: Option<String>,
    /// The file whose reading or content failed.
    pub file: Option<String>,
    /// Where in that file: `byte 1234`, `line 3, column 5`, `grid 'density'`.
    pub position: Option<String>,
    /// The parameter at fault as its index in the list the failing call was given (a look's parameter: the
    /// look's): where a host that keeps its parameters' places finds it.
    pub index: Option<usize>,
}

/// A loaded plugin.
#[derive(Clone)]
pub struct Plugin {
    inner: Arc<Inner>,
}

impl fmt::Debug for Plugin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Plugin({}, ABI {}.{})",
            self.inner.path.display(),
            self.version().0,
            self.version().1
        )
    }
}

/// A row of the plugin's parameter tables.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamInfo {
    /// Component.
    pub component: String,
    /// Name.
    pub name: String,
    /// Type name.
    pub ty: String,
    /// Default.
    pub default: String,
    /// Unit.
    pub unit: String,
    /// Accepted values.
    pub range: String,
    /// Description.
    pub doc: String,
}

/// A parameter value (pbrt-v4's types).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// `float`
    Float(Vec<f64>),
    /// `integer`
    Integer(Vec<i64>),
    /// `bool`
    Bool(Vec<bool>),
    /// `string`
    String(Vec<String>),
    /// `point3`
    Point3(Vec<f64>),
    /// `vector3`
    Vector3(Vec<f64>),
    /// `rgb`
    Rgb(Vec<f64>),
    /// `spectrum` (constant or (λ, value) pairs)
    Spectrum(Vec<f64>),
}

/// A named parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Name.
    pub name: String,
    /// Value.
    pub value: Value,
    /// Where it came from (`file:line:col` of a scene), if anywhere: the plugin's errors about it begin there.
    pub at: Option<String>,
}

impl Param {
    /// A float.
    pub fn float(name: &str, v: f64) -> Param {
        Param {
            name: name.into(),
            value: Value::Float(vec![v]),
            at: None,
        }
    }
    /// An integer.
    pub fn int(name: &str, v: i64) -> Param {
        Param {
            name: name.into(),
            value: Value::Integer(vec![v]),
            at: None,
        }
    }
    /// A bool.
    pub fn bool(name: &str, v: bool) -> Param {
        Param {
            name: name.into(),
            value: Value::Bool(vec![v]),
            at: None,
        }
    }
    /// A string.
    pub fn string(name: &str, v: &str) -> Param {
        Param {
            name: name.into(),
            value: Value::String(vec![v.into()]),
            at: None,
        }
    }
}

/// The names of `FmApi`'s function pointers, in order (for messages; a test checks the count).
const ENTRIES: [&str; 29] = [
    "last_error",
    "last_error_detail",
    "param_count",
    "param_info",
    "volume_create",
    "volume_destroy",
    "volume_info",
    "volume_channel_xyz",
    "volume_temperature_range",
    "volume_white_temperature",
    "volume_capped_rays",
    "volume_query",
    "volume_features",
    "volume_majorant_grid",
    "volume_point",
    "volume_coefficients",
    "light_create",
    "light_destroy",
    "light_info",
    "light_sample",
    "light_pdf",
    "light_pdf_direction",
    "light_integrate",
    "light_line_channels",
    "volume_note_count",
    "volume_note",
    "volume_tables",
    "volume_fields",
    "volume_bricks",
];

/// `FmApi` as raw words: its four u32 fields, then the function pointers, which may be read as null.
#[repr(C)]
struct RawApi {
    _header: [u32; 4],
    entries: [*const c_void; ENTRIES.len()],
}

impl Plugin {
    /// Loads the plugin at `path` and checks its ABI.
    ///
    /// # Safety
    ///
    /// Loading a dynamic library runs its initialisers, and the checks here can prove only that the file
    /// exports a table of the right version and size with no null entry: that the functions behind it keep the
    /// ABI's contract is the caller's trust in the file. Load only a firemedium plugin (whose initialisers are
    /// Rust's runtime alone) from a path you trust.
    pub unsafe fn load(path: impl AsRef<Path>) -> Result<Plugin, Error> {
        let path = path.as_ref().to_path_buf();
        // SAFETY: the caller vouches for the file (this function's contract).
        let lib = unsafe { libloading::Library::new(&path) }.map_err(|e| Error::Open {
            path: path.clone(),
            message: e.to_string(),
        })?;
        // SAFETY: the symbol has type FmEntry per the ABI; checked by name.
        let entry: libloading::Symbol<abi::FmEntry> = unsafe { lib.get(abi::ENTRY_SYMBOL) }
            .map_err(|_| Error::NoEntry { path: path.clone() })?;
        // SAFETY: calling the entry point, which returns a pointer to a static table.
        let api = unsafe { entry() };
        if api.is_null() {
            return Err(Error::Broken {
                path,
                what: "its firemedium_plugin_entry returned no table (null)".into(),
            });
        }
        // SAFETY: non-null; the version fields come first in every ABI version.
        let (major, minor, size) =
            unsafe { ((*api).abi_major, (*api).abi_minor, (*api).struct_size) };
        if !abi::compatible(major, minor, abi::ABI_MAJOR, abi::ABI_MINOR) {
            return Err(Error::Abi {
                path,
                plugin: (major, minor),
                host: (abi::ABI_MAJOR, abi::ABI_MINOR),
            });
        }
        let need = std::mem::size_of::<abi::FmApi>();
        if (size as usize) < need {
            return Err(Error::Broken {
                path,
                what: format!("its ABI {major}.{minor} table declares {size} bytes, ABI {major}.{minor} has at least {need}"),
            });
        }
        // Every function pointer this host may call, read as a raw word before it is trusted as a Rust fn
        // pointer (which may not be null).
        // SAFETY: the table holds at least `need` bytes (checked): the header, then ENTRIES.len() pointers.
        let raw = unsafe { std::ptr::read(api as *const RawApi) };
        if let Some(k) = raw.entries.iter().position(|p| p.is_null()) {
            return Err(Error::Broken {
                path,
                what: format!("its entry '{}' is null", ENTRIES[k]),
            });
        }
        Ok(Plugin {
            inner: Arc::new(Inner {
                api,
                path,
                _lib: lib,
            }),
        })
    }

    /// Finds the plugin: the file `FIREMEDIUM_PLUGIN` names, else the library file in each directory of
    /// `FIREMEDIUM_PLUGIN_PATH` (`:`-separated; `;` on Windows), then relative to the running executable:
    /// beside it, in `../lib/firemedium` (an installed layout: `tools/install.sh`), in its `deps` (Cargo's tests)
    /// and one folder up and its `deps` (Cargo's examples, in `target/release/examples`).
    ///
    /// # Safety
    ///
    /// As [`Plugin::load`], for whatever file the environment or the executable's directory provides.
    pub unsafe fn from_env() -> Result<Plugin, Error> {
        if let Some(f) = std::env::var_os("FIREMEDIUM_PLUGIN") {
            // SAFETY: the file the environment names (this function's contract).
            return unsafe { Plugin::load(PathBuf::from(f)) };
        }
        let mut dirs: Vec<PathBuf> = std::env::var_os("FIREMEDIUM_PLUGIN_PATH")
            .map(|p| std::env::split_paths(&p).collect())
            .unwrap_or_default();
        if let Some(d) = std::env::current_exe()
            .ok()
            .and_then(|e| e.parent().map(Path::to_path_buf))
        {
            dirs.push(d.clone());
            dirs.push(d.join("../lib/firemedium"));
            dirs.push(d.join("deps"));
            if let Some(up) = d.parent() {
                dirs.push(up.to_path_buf());
                dirs.push(up.join("deps"));
            }
        }
        // SAFETY: the caller vouches for the environment's files (this function's contract).
        unsafe { Plugin::find(&dirs) }
    }

    /// Loads the library file from the first of `dirs` that holds one this host can use. A library of an
    /// incompatible ABI (say, a stale build left in an earlier directory) is skipped; if no directory holds a
    /// compatible one, the first incompatible one is the error.
    ///
    /// # Safety
    ///
    /// As [`Plugin::load`], for the library file in each of `dirs`.
    pub unsafe fn find(dirs: &[PathBuf]) -> Result<Plugin, Error> {
        let name = library_file_name();
        let mut searched = Vec::new();
        let mut incompatible = None;
        for d in dirs {
            let p = d.join(&name);
            if p.is_file() {
                // SAFETY: the caller vouches for the files in `dirs` (this function's contract).
                match unsafe { Plugin::load(p.clone()) } {
                    Err(e @ Error::Abi { .. }) => {
                        incompatible.get_or_insert(e);
                    }
                    other => return other,
                }
            }
            searched.push(p);
        }
        Err(incompatible.unwrap_or(Error::NotFound { searched }))
    }

    /// The plugin's ABI version.
    pub fn version(&self) -> (u32, u32) {
        let api = self.inner.api();
        (api.abi_major, api.abi_minor)
    }

    /// The file it was loaded from.
    pub fn path(&self) -> &Path {
        &self.inner.path
    }

    /// Every parameter of every component.
    pub fn parameters(&self) -> Vec<ParamInfo> {
        let api = self.inner.api();
        // SAFETY: plain call.
        let n = unsafe { (api.param_count)() };
        let s = |p: *const c_char| {
            if p.is_null() {
                String::new()
            } else {
                // SAFETY: non-null (checked); the plugin's table strings are NUL-terminated and live as long
                // as the library (ABI contract).
                unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
            }
        };
        (0..n)
            .filter_map(|i| {
                let null = std::ptr::null();
                let mut info = abi::FmParamInfo {
                    struct_size: std::mem::size_of::<abi::FmParamInfo>(),
                    component: null,
                    name: null,
                    ty: null,
                    default_value: null,
                    unit: null,
                    range: null,
                    doc: null,
                };
                // SAFETY: writes one FmParamInfo (its size set) on success.
                (unsafe { (api.param_info)(i, &mut info) } == abi::FM_OK).then(|| ParamInfo {
                    component: s(info.component),
                    name: s(info.name),
                    ty: s(info.ty),
                    default: s(info.default_value),
                    unit: s(info.unit),
                    range: s(info.range),
                    doc: s(info.doc),
                })
            })
            .collect()
    }

    /// Creates a fire volume from dataset and volume parameters.
    pub fn create_volume(&self, params: &[Param]) -> Result<Volume, Error> {
        self.create_volume_with(params, &Context::default())
    }

    /// As [`create_volume`](Self::create_volume), with the host's context beside the scene's parameters:
    /// threads, memory budget, frame, shutter. A parameter the scene sets itself wins over the context.
    pub fn create_volume_with(&self, params: &[Param], context: &Context) -> Result<Volume, Error> {
        let mut handle: *mut abi::FmVolume = std::ptr::null_mut();
        // (Boxed: the plugin keeps its address, and the volume keeps the box.)
        let pool = context.pool.clone().map(Box::new);
        let directory =
            match &context.directory {
                Some(d) => Some(d.to_str().and_then(|s| CString::new(s).ok()).ok_or_else(
                    || {
                        Error::Buffer(format!(
                            "the scene's folder {}: expected UTF-8 without NUL bytes",
                            d.display()
                        ))
                    },
                )?),
                None => None,
            };
        let api = self.inner.api();
        let status = with_c_params(params, |list, at_ptrs| {
            let info = abi::FmCreateInfo {
                struct_size: std::mem::size_of::<abi::FmCreateInfo>(),
                params: list.as_ptr(),
                locations: at_ptrs.as_ptr(),
                count: list.len(),
                threads: context.threads.unwrap_or(0),
                flags: context.frame.map_or(0, |_| abi::FM_CREATE_FRAME)
                    | context.shutter.map_or(0, |_| abi::FM_CREATE_SHUTTER),
                max_bytes: context.max_bytes.unwrap_or(0),
                frame: context.frame.unwrap_or(0),
                shutter: context.shutter.unwrap_or([0.0, 0.0]),
                parallel_for: pool.as_ref().map(|_| parallel_for as abi::FmParallelFor),
                pool: pool.as_deref().map_or(std::ptr::null_mut(), |p| {
                    p as *const ThreadPool as *mut c_void
                }),
                directory: directory.as_ref().map_or(std::ptr::null(), |d| d.as_ptr()),
                kind: match context.kind {
                    None => abi::FM_KIND_SCENE,
                    Some(Kind::Fire) => abi::FM_KIND_FIRE,
                    Some(Kind::Pbrt) => abi::FM_KIND_PBRT,
                },
                bins: context.bins.map_or(0, |b| b.count),
                wavelengths: context.bins.map_or([0.0; 2], |b| b.nm),
            };
            // SAFETY: `info`, `list`, `at_ptrs` (one entry per parameter) and everything they point to live until
            // after the call; `handle` is writable.
            unsafe { (api.volume_create)(&info, &mut handle) }
        })?;
        self.inner.check(status)?;
        let mut info = abi::FmVolumeInfo::default();
        // SAFETY: a live handle and a writable info.
        let s = unsafe { (api.volume_info)(handle, &mut info) };
        let vol = Volume {
            inner: self.inner.clone(),
            handle,
            info,
            _pool: pool,
        };
        self.inner.check(s)?;
        Ok(vol)
    }
}

/// Calls `f` with `params` as the ABI's parameter array and their `file:line:col` origins (null where none), both
/// alive — with every string and value array they point to — until `f` returns.
pub(crate) fn with_c_params<R>(
    params: &[Param],
    f: impl FnOnce(&[abi::FmParam], &[*const c_char]) -> R,
) -> Result<R, Error> {
    {
        // Keep every C string and value array alive until the call returns.
        let mut names = Vec::new();
        let mut strings: Vec<Vec<CString>> = Vec::new();
        let mut string_ptrs: Vec<Vec<*const c_char>> = Vec::new();
        let mut f64s: Vec<Vec<f64>> = Vec::new();
        let mut i64s: Vec<Vec<i64>> = Vec::new();
        let mut u8s: Vec<Vec<u8>> = Vec::new();
        let to_c = |s: &str| {
            CString::new(s)
                .map_err(|_| Error::Buffer(format!("parameter text {s:?} holds a NUL byte")))
        };
        let mut raw = Vec::new();
        for p in params {
            names.push(to_c(&p.name)?);
            let (ty, count, values): (u32, usize, *const c_void) = match &p.value {
                Value::Integer(v) => {
                    i64s.push(v.clone());
                    (
                        abi::FM_TYPE_INTEGER,
                        v.len(),
                        i64s.last()
                            .map_or(std::ptr::null(), |v| v.as_ptr() as *const c_void),
                    )
                }
                Value::Bool(v) => {
                    u8s.push(v.iter().map(|&b| b as u8).collect());
                    (
                        abi::FM_TYPE_BOOL,
                        v.len(),
                        u8s.last()
                            .map_or(std::ptr::null(), |v| v.as_ptr() as *const c_void),
                    )
                }
                Value::String(v) => {
                    strings.push(v.iter().map(|s| to_c(s)).collect::<Result<_, _>>()?);
                    string_ptrs.push(
                        strings
                            .last()
                            .map(|v| v.iter().map(|c| c.as_ptr()).collect())
                            .unwrap_or_default(),
                    );
                    (
                        abi::FM_TYPE_STRING,
                        v.len(),
                        string_ptrs
                            .last()
                            .map_or(std::ptr::null(), |v| v.as_ptr() as *const c_void),
                    )
                }
                Value::Float(v)
                | Value::Point3(v)
                | Value::Vector3(v)
                | Value::Rgb(v)
                | Value::Spectrum(v) => {
                    let ty = match &p.value {
                        Value::Float(_) => abi::FM_TYPE_FLOAT,
                        Value::Point3(_) => abi::FM_TYPE_POINT3,
                        Value::Vector3(_) => abi::FM_TYPE_VECTOR3,
                        Value::Rgb(_) => abi::FM_TYPE_RGB,
                        _ => abi::FM_TYPE_SPECTRUM,
                    };
                    f64s.push(v.clone());
                    (
                        ty,
                        v.len(),
                        f64s.last()
                            .map_or(std::ptr::null(), |v| v.as_ptr() as *const c_void),
                    )
                }
            };
            raw.push((ty, count, values));
        }
        let ats: Vec<Option<CString>> = params
            .iter()
            .map(|p| p.at.as_deref().map(to_c).transpose())
            .collect::<Result<_, _>>()?;
        let at_ptrs: Vec<*const c_char> = ats
            .iter()
            .map(|a| a.as_ref().map_or(std::ptr::null(), |c| c.as_ptr()))
            .collect();
        let list: Vec<abi::FmParam> = names
            .iter()
            .zip(&raw)
            .map(|(n, &(ty, count, values))| abi::FmParam {
                name: n.as_ptr(),
                ty,
                count: count as u32,
                values,
            })
            .collect();
        Ok(f(&list, &at_ptrs))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_raw_table_is_the_table() {
        // One name per function pointer, so a null entry is named right.
        assert_eq!(
            std::mem::size_of::<RawApi>(),
            std::mem::size_of::<abi::FmApi>()
        );
    }
}
