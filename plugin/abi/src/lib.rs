//! # firemedium-abi: the contract between the fire plugin and its hosts
//!
//! No dependencies, `no_std`: only what both sides must agree on. The plugin exports one symbol,
//! [`ENTRY_SYMBOL`] (`firemedium_plugin_entry`), of type [`FmEntry`]; it returns a pointer to a static
//! [`FmApi`] table that lives as long as the library is loaded. The C header `include/firemedium.h` declares the
//! same types for hosts in other languages (a test compiles a C program against it and loads the plugin).
//!
//! ## Rules
//! - Versioning: a host refuses a plugin whose [`FmApi::abi_major`] differs from its own, or whose
//!   [`FmApi::abi_minor`] is older than the minor it needs, with a message naming both versions; it also
//!   checks [`FmApi::struct_size`] covers the table it uses. Minor versions only append entries.
//! - Every function returns an [`FmStatus`]; on failure [`FmApi::last_error`] gives the message for the calling
//!   thread. No panic crosses the boundary ([`FM_PANIC`] is returned instead).
//! - Handles are opaque; a volume is immutable after creation and may be queried from many threads at once.
//!   Destroy it exactly once; never unload the library while handles live.
//! - Every struct that crosses the boundary begins with `struct_size`, set by the host to the size it was built
//!   with: the plugin reads and writes no more than that, and refuses a struct smaller than its own. Array
//!   elements ([`FmParam`], [`FmRay`], [`FmExit`], [`FmScatter`]) have the layout of the major version.
//! - Batch queries take `n` rays and write `n × channels` floats (radiance, transmittance, weights), channel
//!   fastest; `channels` comes from [`FmVolumeInfo`]. Optional outputs may be null.
//! - A host asks a medium two things, as pbrt-v4 and Mitsuba 3 do: the coefficients at a point, at its own
//!   wavelengths and time ([`FmApi::volume_point`]), and a bound on σ_t ([`FmApi::volume_majorant_grid`]);
//!   or it hands the plugin whole rays ([`FmApi::volume_query`]), the fast path.
//! - Rays are in the medium's space (the host applies its transforms); distances are |direction| · Δt, in
//!   metres when the medium's space is in metres.

#![forbid(unsafe_code)]
#![no_std]

use core::ffi::{c_char, c_void};

/// Major version of the C ABI. Changes on any incompatible change of the table or its types.
pub const ABI_MAJOR: u32 = 1;
/// Minor version of the C ABI. Grows when entries are appended to the table or fields to the end of a struct.
pub const ABI_MINOR: u32 = 4;
/// Name of the exported entry symbol, NUL-terminated for `dlsym`/`GetProcAddress`.
pub const ENTRY_SYMBOL: &[u8] = b"firemedium_plugin_entry\0";

/// Whether a plugin of version (`major`, `minor`) satisfies a host that needs (`need_major`, `need_minor`).
pub const fn compatible(major: u32, minor: u32, need_major: u32, need_minor: u32) -> bool {
    major == need_major && minor >= need_minor
}

/// Status of every call.
pub type FmStatus = i32;
/// Success.
pub const FM_OK: FmStatus = 0;
/// A null pointer, a bad count or an invalid handle was passed.
pub const FM_INVALID_ARGUMENT: FmStatus = 1;
/// A parameter is unknown, of the wrong type, or out of range.
pub const FM_INVALID_PARAMETER: FmStatus = 2;
/// A dataset file could not be read or is malformed (or too large for the memory cap).
pub const FM_DATASET: FmStatus = 3;
/// Something valid that this build does not support.
pub const FM_UNSUPPORTED: FmStatus = 4;
/// The plugin panicked; the call did nothing further and the host may continue.
pub const FM_PANIC: FmStatus = 5;

/// Parameter value types (pbrt-v4's).
pub const FM_TYPE_FLOAT: u32 = 0;
/// `integer` (values are `i64`).
pub const FM_TYPE_INTEGER: u32 = 1;
/// `bool` (values are `u8`, 0 or 1).
pub const FM_TYPE_BOOL: u32 = 2;
/// `string` (values are `const char*`, UTF-8, NUL-terminated).
pub const FM_TYPE_STRING: u32 = 3;
/// `point3` (values are `f64`, three per point).
pub const FM_TYPE_POINT3: u32 = 4;
/// `vector3` (`f64`).
pub const FM_TYPE_VECTOR3: u32 = 5;
/// `rgb` (`f64`).
pub const FM_TYPE_RGB: u32 = 6;
/// `spectrum` (`f64`: one constant or (λ nm, value) pairs).
pub const FM_TYPE_SPECTRUM: u32 = 7;

/// One parameter: `count` values of type `ty` at `values` (`f64`, `i64`, `u8` or `const char*` elements).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmParam {
    /// NUL-terminated name.
    pub name: *const c_char,
    /// One of the `FM_TYPE_*` constants.
    pub ty: u32,
    /// Number of values.
    pub count: u32,
    /// The values.
    pub values: *const c_void,
}

/// A ray segment in medium space: origin + t · direction for t in [tmin, tmax]; `seed` drives its random
/// numbers, so results do not depend on threads or batching.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FmRay {
    /// Origin.
    pub origin: [f64; 3],
    /// Direction (any length).
    pub direction: [f64; 3],
    /// Start parameter.
    pub tmin: f64,
    /// End parameter.
    pub tmax: f64,
    /// Random seed of this ray.
    pub seed: u64,
}

/// Where the plugin stopped following a ray: the host continues from here (rays may bend inside the medium).
/// A host that passes no exits to `volume_query` gets the straight-line integration even when the volume
/// refracts (what NEE and light paths, whose pdfs assume straight lines, want).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FmExit {
    /// Point (medium space).
    pub point: [f64; 3],
    /// Unit direction there (bent when the volume's `refraction` is on).
    pub direction: [f64; 3],
    /// Parameter along the input ray (with refraction: entry parameter + arc length / |direction|).
    pub t: f64,
}

/// The ray left the medium (weights are its transmittance).
pub const FM_EVENT_ESCAPED: u32 = 0;
/// A real scattering event (weights multiply the in-scattered radiance).
pub const FM_EVENT_SCATTERED: u32 = 1;
/// Absorbed.
pub const FM_EVENT_ABSORBED: u32 = 2;

/// A sampled scattering event.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FmScatter {
    /// One of the `FM_EVENT_*` constants.
    pub event: u32,
    /// Padding (zero).
    pub reserved: u32,
    /// Parameter of the event (tmax when escaped).
    pub t: f64,
    /// Point of the event.
    pub point: [f64; 3],
}

/// Channels are spectral bins (radiance in W·m⁻²·sr⁻¹·nm⁻¹).
pub const FM_SPACE_SPECTRAL: u32 = 0;
/// Channels are CIE XYZ (Y in cd/m²).
pub const FM_SPACE_XYZ: u32 = 1;

/// Integrators.
pub const FM_INTEGRATOR_MARCH: u32 = 0;
/// Ratio tracking.
pub const FM_INTEGRATOR_RATIO: u32 = 1;
/// Delta tracking.
pub const FM_INTEGRATOR_DELTA: u32 = 2;

/// What a volume is.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FmVolumeInfo {
    /// Set by the host to `size_of::<FmVolumeInfo>()`.
    pub struct_size: usize,
    /// Lower corner of the medium-space bounds.
    pub bounds_min: [f64; 3],
    /// Upper corner.
    pub bounds_max: [f64; 3],
    /// Channels per radiance/transmittance value.
    pub channels: u32,
    /// `FM_SPACE_*`.
    pub channel_space: u32,
    /// Spectral range of the bins, nm (spectral space).
    pub lambda_min: f64,
    /// Upper end, nm.
    pub lambda_max: f64,
    /// Henyey–Greenstein g of the scattering.
    pub g: f64,
    /// 1 when σ_s > 0 anywhere.
    pub scatters: u32,
    /// `FM_INTEGRATOR_*`.
    pub integrator: u32,
    /// March step, medium units.
    pub step: f64,
    /// Bytes held (dataset and tables).
    pub bytes: u64,
    /// Seconds spent creating the volume.
    pub build_seconds: f64,
    /// (1.2) The dataset's lattice: samples per axis, cell-centred over `lattice_min`..`lattice_max` (medium
    /// space) — where a host that bakes or samples the fire's grids asks for them (`volume_coefficients`).
    pub dims: [u32; 3],
    /// Reserved (0).
    pub reserved: u32,
    /// (1.2) The lattice's lower corner, medium space.
    pub lattice_min: [f64; 3],
    /// (1.2) Its upper corner.
    pub lattice_max: [f64; 3],
}

/// The size [`FmVolumeInfo`] had in ABI 1.0 and 1.1, before the lattice was appended (1.2): the least a host may
/// pass; the plugin writes no more than the host's `struct_size`.
pub const FM_VOLUME_INFO_SIZE_1_0: usize = core::mem::offset_of!(FmVolumeInfo, dims);

/// A row of a component's parameter table (strings live as long as the library).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmParamInfo {
    /// Set by the host to `size_of::<FmParamInfo>()`.
    pub struct_size: usize,
    /// Component (`dataset`, `volume`).
    pub component: *const c_char,
    /// Parameter name.
    pub name: *const c_char,
    /// Type name (`float`, `string`, …).
    pub ty: *const c_char,
    /// Default, as text (empty when none).
    pub default_value: *const c_char,
    /// Unit (may be empty).
    pub unit: *const c_char,
    /// Accepted values, as text.
    pub range: *const c_char,
    /// One-line description.
    pub doc: *const c_char,
}

/// An opaque volume handle.
pub type FmVolume = c_void;
/// An opaque fire-light handle.
pub type FmLight = c_void;

/// Voxel weights by the luminance of their emission.
pub const FM_WEIGHTING_LUMINANCE: u32 = 0;
/// Voxel weights by their emitted power over the bins.
pub const FM_WEIGHTING_POWER: u32 = 1;
/// `FmLightInfo::weighting`: voxels weighted by the power that leaves the fire.
pub const FM_WEIGHTING_ESCAPING: u32 = 2;

/// What a fire light is.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FmLightInfo {
    /// Set by the host to `size_of::<FmLightInfo>()`.
    pub struct_size: usize,
    /// Emitted power over the whole spectrum, W: the soot's and the atoms' over all wavelengths, the blue core's
    /// bands whole (over the bins — relative units in pbrt mode — only where the emission does not follow the
    /// physics: an emission grid, a tint or a colour ramp).
    pub power_w: f64,
    /// Luminous power over the bins, lm.
    pub power_lm: f64,
    /// Emitting voxels (the only ones stored).
    pub voxels: u64,
    /// Bytes of the distribution.
    pub bytes: u64,
    /// Seconds to build.
    pub build_seconds: f64,
    /// `FM_WEIGHTING_*`.
    pub weighting: u32,
    /// Voxels per side of the blocks the light's line estimate marches through (1: the fire's own voxels; the
    /// `lineblock` parameter).
    pub line_block: u32,
}

impl Default for FmVolumeInfo {
    fn default() -> Self {
        FmVolumeInfo {
            struct_size: core::mem::size_of::<FmVolumeInfo>(),
            bounds_min: [0.0; 3],
            bounds_max: [0.0; 3],
            channels: 0,
            channel_space: 0,
            lambda_min: 0.0,
            lambda_max: 0.0,
            g: 0.0,
            scatters: 0,
            integrator: 0,
            step: 0.0,
            bytes: 0,
            build_seconds: 0.0,
            dims: [0; 3],
            reserved: 0,
            lattice_min: [0.0; 3],
            lattice_max: [0.0; 3],
        }
    }
}

impl Default for FmLightInfo {
    fn default() -> Self {
        FmLightInfo {
            struct_size: core::mem::size_of::<FmLightInfo>(),
            power_w: 0.0,
            power_lm: 0.0,
            voxels: 0,
            bytes: 0,
            build_seconds: 0.0,
            weighting: 0,
            line_block: 0,
        }
    }
}

/// [`FmApi::volume_features`]: the volume emits.
pub const FM_FEATURE_EMITS: u64 = 1 << 0;
/// It scatters (σ_s > 0).
pub const FM_FEATURE_SCATTERS: u64 = 1 << 1;
/// Its lookups move over the shutter (velocity motion blur): point coefficients depend on time.
pub const FM_FEATURE_MOTION: u64 = 1 << 2;
/// Rays bend in it (refraction): a host tracking straight rays loses the bending.
pub const FM_FEATURE_REFRACTION: u64 = 1 << 3;
/// It carries embers (opaque moving spheres, not a medium): only the whole-ray queries see them.
pub const FM_FEATURE_EMBERS: u64 = 1 << 4;
/// Atomic lines integrated across their profiles (optically thick lines): only the whole-ray queries.
pub const FM_FEATURE_THICK_LINES: u64 = 1 << 5;
/// Its smoke's multiple scattering is read as emission (diffusion): only the whole-ray queries.
pub const FM_FEATURE_DIFFUSION: u64 = 1 << 6;
/// It emits where it may not absorb (an emission grid): Le = j/σ_a is undefined there, j is not.
pub const FM_FEATURE_EMITS_WITHOUT_ABSORPTION: u64 = 1 << 7;

/// The volume's coefficients in closed form ([`FmApi::volume_tables`], 1.2), for a host that textures the fire
/// rather than asking for points: with d, T and les the fields ([`FmApi::volume_fields`]) interpolated trilinearly
/// from the lattice's voxel values (a zero layer around the lattice; nothing outside the volume's bounds), d and
/// les clamped at 0, r = clamp(T / dt, 0, rows − 1) and A, J linear between rows,
/// σ_a = d · A(r), σ_s = d · S, j = e · J(r) where T > t_emit (else 0), e = les with
/// [`FM_TABLES_EMISSION_GRID`], d · les without — in the volume's channels, per medium unit, as
/// [`FmApi::volume_coefficients`] gives them at every point. The host sets `struct_size` and the three table
/// pointers (each may be null: a first call learns `channels` and `rows`); the plugin writes the rest.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmTables {
    /// Set by the host to `size_of::<FmTables>()` before the call.
    pub struct_size: usize,
    /// The volume's channels.
    pub channels: u32,
    /// Rows of the temperature tables.
    pub rows: u32,
    /// `FM_TABLES_*` bits.
    pub flags: u32,
    /// Reserved (0).
    pub reserved: u32,
    /// Kelvin between rows: row r holds T = r · dt.
    pub dt: f64,
    /// The fire emits where T > t_emit (pbrt mode's 100 K; 0 in physical mode; −∞ without a temperature grid).
    pub t_emit: f64,
    /// Host's buffer of `rows × channels` floats (row-major), or null: σ_a per unit density over T.
    pub absorption: *mut f32,
    /// Host's buffer of `channels` floats, or null: σ_s per unit density.
    pub scattering: *mut f32,
    /// Host's buffer of `rows × channels` floats, or null: j per unit of e over T.
    pub emission: *mut f32,
}

impl Default for FmTables {
    fn default() -> Self {
        FmTables {
            struct_size: core::mem::size_of::<FmTables>(),
            channels: 0,
            rows: 0,
            flags: 0,
            reserved: 0,
            dt: 0.0,
            t_emit: 0.0,
            absorption: core::ptr::null_mut(),
            scattering: core::ptr::null_mut(),
            emission: core::ptr::null_mut(),
        }
    }
}

/// [`FmTables::flags`]: the emission follows an emission grid (e = les), not the density (e = d · les).
pub const FM_TABLES_EMISSION_GRID: u32 = 1;

/// A volume's majorant grid ([`FmApi::volume_majorant_grid`]), for a host's own free-path sampling:
/// cells of `cell` medium units tiling `bounds` (the last per axis may be cut by the box), `counts` of them,
/// and per cell (x fastest) a bound on σ_t over every channel and every point of the cell — over the shutter
/// with motion blur. A point of the volume's bounds outside the cells' box (pbrt mode's half-voxel margin)
/// takes the nearest cell's bound.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmMajorantGrid {
    /// Set by the host to `size_of::<FmMajorantGrid>()` before the call (the plugin writes no more).
    pub struct_size: usize,
    /// Lower and upper corner of the cells' box, medium space.
    pub bounds: [f64; 6],
    /// A cell's edge per axis, medium units.
    pub cell: [f64; 3],
    /// Cells per axis.
    pub counts: [u32; 3],
    /// Reserved (0).
    pub reserved: u32,
    /// `counts[0] · counts[1] · counts[2]` bounds on σ_t (medium units⁻¹), x fastest; owned by the volume and
    /// valid while it lives.
    pub sigma_t: *const f64,
}

impl Default for FmMajorantGrid {
    fn default() -> Self {
        FmMajorantGrid {
            struct_size: core::mem::size_of::<FmMajorantGrid>(),
            bounds: [0.0; 6],
            cell: [0.0; 3],
            counts: [0; 3],
            reserved: 0,
            sigma_t: core::ptr::null(),
        }
    }
}

/// A point query ([`FmApi::volume_point`]): at `n` points, each at its time and at `k` wavelengths of
/// its own, σ_a, σ_s, the emitted radiance Le and the emission coefficient j = σ_a·Le — the closed forms at each
/// wavelength (soot's κ(λ) and Planck's B(λ, T); pbrt-v4's spectra and peak-normalised blackbody), not the bins.
/// Outputs are `n · k` doubles each, point-major (may be null); a volume whose layers the closed forms cannot
/// express (atomic lines, art direction, a scatter colour grid, diffusion, refraction, embers) is refused with
/// `FM_UNSUPPORTED` naming the layer.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmPointQuery {
    /// Set by the host to `size_of::<FmPointQuery>()`.
    pub struct_size: usize,
    /// Points.
    pub n: usize,
    /// `3n` doubles, medium space (required).
    pub points: *const f64,
    /// `n` times (frames from the grids' time), or null: time 0.
    pub times: *const f64,
    /// Wavelengths per point.
    pub k: u32,
    /// Reserved (0).
    pub reserved: u32,
    /// `n · k` wavelengths, nm (required).
    pub lambdas: *const f64,
    /// σ_a, medium units⁻¹.
    pub sigma_a: *mut f64,
    /// σ_s, medium units⁻¹.
    pub sigma_s: *mut f64,
    /// Le, radiance (0 where σ_a = 0: an emission grid's j still emits there).
    pub le: *mut f64,
    /// j = σ_a·Le, radiance per medium unit.
    pub j: *mut f64,
}

/// The last error's structure ([`FmApi::last_error_detail`]), beside its message: what a host needs to
/// point its user at the cause without parsing text. Strings are NUL-terminated UTF-8 owned by the plugin, valid
/// until the next call on the same thread; null when the error has no such part.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmErrorDetail {
    /// Set by the host to `size_of::<FmErrorDetail>()`.
    pub struct_size: usize,
    /// The status the failing call returned (`FM_OK` when no call has failed on this thread).
    pub status: FmStatus,
    /// Reserved (0).
    pub reserved: i32,
    /// The parameter at fault, as the host named it.
    pub parameter: *const c_char,
    /// Where the host said that parameter was given ([`FmCreateInfo::locations`]: `file:line:col`).
    pub location: *const c_char,
    /// The file whose reading or content failed.
    pub file: *const c_char,
    /// Where in that file: `byte 1234`, `line 3, column 5`, `grid 'density'`.
    pub position: *const c_char,
    /// The parameter at fault as its index in the failing call's list ([`FmCreateInfo::params`], or
    /// `light_create`'s `params`), or −1 when the error names none the host passed (1.4). A parameter a `look`
    /// supplied is the look's index. A host that keeps its own places for its parameters finds the place here,
    /// and may pass no `locations`: the message then begins with no place of the plugin's making.
    pub index: i64,
}

/// The size [`FmErrorDetail`] had in ABI 1.0 to 1.3, before `index` was appended: the least a host may pass. The
/// plugin writes as much as a host's `struct_size` covers.
pub const FM_ERROR_DETAIL_SIZE_1_0: usize = core::mem::offset_of!(FmErrorDetail, index);

impl Default for FmErrorDetail {
    fn default() -> Self {
        FmErrorDetail {
            struct_size: core::mem::size_of::<FmErrorDetail>(),
            status: FM_OK,
            reserved: 0,
            parameter: core::ptr::null(),
            location: core::ptr::null(),
            file: core::ptr::null(),
            position: core::ptr::null(),
            index: -1,
        }
    }
}

/// [`FmCreateInfo::flags`]: `frame` is set.
pub const FM_CREATE_FRAME: u32 = 1 << 0;
/// [`FmCreateInfo::flags`]: `shutter` is set.
pub const FM_CREATE_SHUTTER: u32 = 1 << 1;

/// [`FmCreateInfo::kind`]: the scene's `mode` parameter says, else the paper's fire.
pub const FM_KIND_SCENE: u32 = 0;
/// [`FmCreateInfo::kind`]: the paper's fire (`mode` `physical`).
pub const FM_KIND_FIRE: u32 = 1;
/// [`FmCreateInfo::kind`]: pbrt-v4's grid media, `uniformgrid` and `nanovdb` (`mode` `pbrt`: σ spectra × density,
/// a peak-normalised blackbody × `Lescale`).
pub const FM_KIND_PBRT: u32 = 2;

/// A volume's creation ([`FmApi::volume_create`]): the scene's parameters with their locations, and
/// the host's context beside them — threads, memory budget, frame, shutter, the kind of medium the scene named,
/// the render's spectral bins — instead of as parameters the host must make up. A parameter the scene gives
/// itself (`threads`, `maxbytes`, `frame`, `shutteropen`, `shutterclose`, `mode`, `bins`, `lambdamin`,
/// `lambdamax`) wins over the context.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmCreateInfo {
    /// Set by the host to `size_of::<FmCreateInfo>()`.
    pub struct_size: usize,
    /// The scene's parameters (may be null when `count` is 0).
    pub params: *const FmParam,
    /// Per parameter its `file:line:col`, or null (the whole array may be null).
    pub locations: *const *const c_char,
    /// Parameters.
    pub count: usize,
    /// Threads the build may use (0: the plugin's default, the machine's).
    pub threads: u32,
    /// `FM_CREATE_*` bits: which of `frame` and `shutter` are set.
    pub flags: u32,
    /// The memory budget of the volume, bytes (0: the plugin's default).
    pub max_bytes: u64,
    /// The frame a `####` in a file name takes.
    pub frame: i64,
    /// The camera's shutter, frames from the grids' time (motion blur).
    pub shutter: [f64; 2],
    /// The host's thread pool, or null: the plugin's builds (this volume's and its lights') run their parallel
    /// parts as its tasks instead of starting threads of their own (`threads` still bounds how many parts a
    /// fan-out cuts). Must stay callable while the volume and its lights live.
    pub parallel_for: Option<FmParallelFor>,
    /// The pool's own pointer, handed back to `parallel_for` (may be null).
    pub pool: *mut c_void,
    /// The folder relative file names are in (a scene's: NUL-terminated UTF-8), or null: the process's working
    /// directory. The plugin resolves its own file parameters (the `Range::Path` rows of its tables, docs/reference/params.md)
    /// against it, so a host need not know which of the fire's parameters name files.
    pub directory: *const c_char,
    /// What the scene's medium type means, `FM_KIND_*` (1.4; 0: the scene's `mode`, else the paper's fire).
    pub kind: u32,
    /// The render's spectral bins (1.4; 0: the scene's `bins`, else the plugin's default).
    pub bins: u32,
    /// The bins' span, nm, shortest and longest (1.4; both 0: the scene's `lambdamin` and `lambdamax`, else the
    /// plugin's defaults).
    pub wavelengths: [f64; 2],
}

/// The wavelengths a host may ask the medium level about, nm: from the far ultraviolet to the far infrared (a
/// wavelength outside is refused, naming it: the soot's κ ∝ λ^−α and Planck's λ^−5 have no meaning there).
pub const FM_WAVELENGTH_RANGE_NM: (f64, f64) = (1.0, 1.0e6);
/// A ray direction's length the plugin takes, from the smallest to the largest: outside, |d|² under- or
/// overflows and the ray would silently miss; refused, naming it.
pub const FM_DIRECTION_LENGTH_RANGE: (f64, f64) = (1.0e-150, 1.0e150);

/// The size [`FmCreateInfo`] had in ABI 1.0, before `directory` was appended (1.1): the least a host may pass. A
/// 1.0 host's struct is read as far as its `struct_size` covers it, the newer fields taking their defaults.
pub const FM_CREATE_INFO_SIZE_1_0: usize = core::mem::offset_of!(FmCreateInfo, directory);

/// A part of the plugin's build work ([`FmParallelFor`]): `task(data, index)`; it never unwinds into the host.
pub type FmTask = unsafe extern "C" fn(data: *mut c_void, index: usize);
/// A host's thread pool ([`FmCreateInfo::parallel_for`]): runs `task(data, i)` for every i in 0..count — on its
/// threads as it likes, in any order, the calling thread included — and returns when every one has returned.
pub type FmParallelFor =
    unsafe extern "C" fn(pool: *mut c_void, count: usize, task: FmTask, data: *mut c_void);

/// [`FmRayQuery::what`]: emitted radiance (required) and transmittance (may be null) along each ray, and where
/// it leaves (`exits`, may be null).
pub const FM_QUERY_INTEGRATE: u32 = 0;
/// [`FmRayQuery::what`]: transmittance only (shadow rays), required.
pub const FM_QUERY_TRANSMITTANCE: u32 = 1;
/// [`FmRayQuery::what`]: the first real scattering event per ray (`events`, `weights`, required) and the
/// emitted radiance before it (`radiance`, may be null).
pub const FM_QUERY_SCATTER: u32 = 2;

/// The fast whole-ray query ([`FmApi::volume_query`]): `n` rays, each at its time, integrated, attenuated or
/// tracked to a scattering event by the plugin. Outputs are `n × channels` floats (channel fastest) or `n`
/// entries; the ones `what` does not use must be null.
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmRayQuery {
    /// Set by the host to `size_of::<FmRayQuery>()`.
    pub struct_size: usize,
    /// `FM_QUERY_*`.
    pub what: u32,
    /// Reserved (0).
    pub reserved: u32,
    /// Rays.
    pub n: usize,
    /// `n` rays (required when `n` > 0).
    pub rays: *const FmRay,
    /// `n` times (frames from the grids' time, inside the volume's shutter), or null: time 0. A volume with
    /// motion blur (a `velocitygrid` and an open shutter) is looked up where its velocity carried it from; embers
    /// are where theirs carried them.
    pub times: *const f64,
    /// `n` uniform numbers in [0, 1), or null: the first random number each ray's estimator draws (the march's
    /// offset along the ray, tracking's first free-flight distance) — the host's own sample, stratified as its
    /// sampler stratifies; the rest come from the ray's `seed`.
    pub u: *const f64,
    /// [`FM_QUERY_INTEGRATE`] without exits: the march's step, medium units, when longer than the volume's own
    /// (a coarse estimate, as the fire light's line); 0: the volume's. A tracking volume ignores it.
    pub step: f64,
    /// Emitted radiance (`n × channels`).
    pub radiance: *mut f32,
    /// Transmittance (`n × channels`).
    pub transmittance: *mut f32,
    /// Where each ray leaves (`n`): rays bend in a refracting volume. Without exits the ray stays straight (what
    /// next-event estimation and light paths, whose pdfs assume straight lines, want).
    pub exits: *mut FmExit,
    /// Scattering events (`n`).
    pub events: *mut FmScatter,
    /// The events' weights (`n × channels`): the transmittance when the ray escaped, the factor on the
    /// in-scattered radiance when it scattered.
    pub weights: *mut f32,
}

impl Default for FmRayQuery {
    fn default() -> Self {
        FmRayQuery {
            struct_size: core::mem::size_of::<FmRayQuery>(),
            what: FM_QUERY_INTEGRATE,
            reserved: 0,
            n: 0,
            rays: core::ptr::null(),
            times: core::ptr::null(),
            u: core::ptr::null(),
            step: 0.0,
            radiance: core::ptr::null_mut(),
            transmittance: core::ptr::null_mut(),
            exits: core::ptr::null_mut(),
            events: core::ptr::null_mut(),
            weights: core::ptr::null_mut(),
        }
    }
}

impl Default for FmCreateInfo {
    fn default() -> Self {
        FmCreateInfo {
            struct_size: core::mem::size_of::<FmCreateInfo>(),
            params: core::ptr::null(),
            locations: core::ptr::null(),
            count: 0,
            threads: 0,
            flags: 0,
            max_bytes: 0,
            frame: 0,
            shutter: [0.0; 2],
            parallel_for: None,
            pool: core::ptr::null_mut(),
            directory: core::ptr::null(),
            kind: FM_KIND_SCENE,
            bins: 0,
            wavelengths: [0.0; 2],
        }
    }
}

/// The plugin's function table (ABI 1.0).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmApi {
    /// [`ABI_MAJOR`] of the plugin.
    pub abi_major: u32,
    /// [`ABI_MINOR`] of the plugin.
    pub abi_minor: u32,
    /// `sizeof(FmApi)` as the plugin built it.
    pub struct_size: u32,
    /// Zero.
    pub reserved: u32,
    /// Copies the calling thread's last error message (UTF-8, NUL-terminated, truncated to `cap`) into `buf`;
    /// returns its full length in bytes without the NUL. `buf` may be null to ask for the length.
    pub last_error: unsafe extern "C" fn(buf: *mut c_char, cap: usize) -> usize,
    /// The last error on this thread as a structure into `*out` (required, its `struct_size` set by the host);
    /// see [`FmErrorDetail`].
    pub last_error_detail: unsafe extern "C" fn(out: *mut FmErrorDetail) -> FmStatus,
    /// Number of rows in the parameter tables of all components.
    pub param_count: unsafe extern "C" fn() -> usize,
    /// Row `index` of the parameter tables into `*out` (its `struct_size` set by the host).
    pub param_info: unsafe extern "C" fn(index: usize, out: *mut FmParamInfo) -> FmStatus,
    /// Creates a fire volume (dataset + volume parameters, and the host's context: see [`FmCreateInfo`]; `info`
    /// and `out` required); `*out` receives the handle.
    pub volume_create:
        unsafe extern "C" fn(info: *const FmCreateInfo, out: *mut *mut FmVolume) -> FmStatus,
    /// Destroys a volume (null is ignored).
    pub volume_destroy: unsafe extern "C" fn(volume: *mut FmVolume),
    /// Describes a volume into `*out` (its `struct_size` set by the host).
    pub volume_info:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut FmVolumeInfo) -> FmStatus,
    /// Writes 3 × channels f64: the XYZ of unit radiance in each channel (to turn channel radiance into XYZ).
    pub volume_channel_xyz:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut f64, cap: usize) -> FmStatus,
    /// The lowest and highest temperature (K) of the volume's grid after its mapping, into `out[0..2]`; both 0
    /// when the volume has no temperature grid.
    pub volume_temperature_range:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut f64) -> FmStatus,
    /// The temperature (K) whose blackbody a viewer adapts to for this volume, into `*out`: its hottest
    /// temperature when its colour is the physics' (Planck emission), 0 when its colour is art-directed (a
    /// `tint`, or a `colorramp` short of `physical` 1: meant to be seen against a D65 white) or it has no
    /// temperature grid.
    pub volume_white_temperature:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut f64) -> FmStatus,
    /// How many rays' tracking (ratio, delta, scattering events) stopped at the per-ray collision cap so far,
    /// into `*out`: each was cut short as if absorbed, a bias towards dark that a host should report.
    pub volume_capped_rays:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut u64) -> FmStatus,
    /// The fast path: whole rays (see [`FmRayQuery`]; `query` required).
    pub volume_query:
        unsafe extern "C" fn(volume: *const FmVolume, query: *const FmRayQuery) -> FmStatus,
    /// What the volume holds beyond absorption, into `*out` (required): `FM_FEATURE_*` bits. A host that tracks
    /// the medium itself (from [`volume_point`](Self::volume_point) and
    /// [`volume_majorant_grid`](Self::volume_majorant_grid)) refuses, or keeps to the whole-ray query for, what it
    /// cannot handle.
    pub volume_features: unsafe extern "C" fn(volume: *const FmVolume, out: *mut u64) -> FmStatus,
    /// The volume's majorant grid into `*out` (required, its `struct_size` set by the host).
    pub volume_majorant_grid:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut FmMajorantGrid) -> FmStatus,
    /// The point query at the host's wavelengths (see [`FmPointQuery`]; `query` required).
    pub volume_point:
        unsafe extern "C" fn(volume: *const FmVolume, query: *const FmPointQuery) -> FmStatus,
    /// σ_a, σ_s (m⁻¹) and the emission coefficient j = σ_a L_e in the volume's own channels at `n` points (3 f64
    /// each; every layer, lines and art direction included, at time 0); each output `n × channels` f32, any may
    /// be null.
    pub volume_coefficients: unsafe extern "C" fn(
        volume: *const FmVolume,
        points: *const f64,
        n: usize,
        sigma_a: *mut f32,
        sigma_s: *mut f32,
        emission: *mut f32,
    ) -> FmStatus,
    /// Builds the fire light of a volume (parameters: `string weighting` power (default) | luminance | escaping,
    /// and the rest of the `light` table). The light keeps the volume alive; destroy both.
    pub light_create: unsafe extern "C" fn(
        volume: *const FmVolume,
        params: *const FmParam,
        count: usize,
        out: *mut *mut FmLight,
    ) -> FmStatus,
    /// Destroys a light (null is ignored).
    pub light_destroy: unsafe extern "C" fn(light: *mut FmLight),
    /// Describes a light into `*out` (its `struct_size` set by the host).
    pub light_info: unsafe extern "C" fn(light: *const FmLight, out: *mut FmLightInfo) -> FmStatus,
    /// Samples `n` points from 6 uniform numbers each (`u`, 6n doubles), each at its time (`times`: `n` doubles,
    /// frames from the grids' time, or null for time 0: a volume's embers move while the shutter is open, and
    /// the light samples them where they are then): medium-space points (3n), their density per unit volume
    /// (n), and the emission coefficient j = σ_a L_e there (n × channels, may be null; an ember is a surface:
    /// its light reaches a host through `volume_query` along the point's direction).
    pub light_sample: unsafe extern "C" fn(
        light: *const FmLight,
        u: *const f64,
        times: *const f64,
        n: usize,
        points: *mut f64,
        pdf: *mut f64,
        emission: *mut f32,
    ) -> FmStatus,
    /// Density per unit volume of `n` medium-space points (3n doubles), each at its time (as
    /// [`light_sample`](Self::light_sample)).
    pub light_pdf: unsafe extern "C" fn(
        light: *const FmLight,
        points: *const f64,
        times: *const f64,
        n: usize,
        pdf: *mut f64,
    ) -> FmStatus,
    /// Solid-angle density of the sampled point's direction, seen from `origins` along `directions` (3n each,
    /// medium space): ∫ pdf(o + s d̂) s² ds, for a sample drawn at each time (as
    /// [`light_sample`](Self::light_sample)).
    pub light_pdf_direction: unsafe extern "C" fn(
        light: *const FmLight,
        origins: *const f64,
        directions: *const f64,
        times: *const f64,
        n: usize,
        pdf: *mut f64,
    ) -> FmStatus,
    /// The fire's emitted radiance and transmittance along `n` straight rays, as the light estimates them for
    /// next-event estimation along a sampled direction (`radiance`, required, and `transmittance`, may be null:
    /// `n × channels` floats; `times` as [`light_sample`](Self::light_sample)): the volume's march at the
    /// light's `linestep`, corrected toward the volume's own march with probability `linecorrection`. Where its
    /// step is the volume's, the same as `volume_query` without exits.
    pub light_integrate: unsafe extern "C" fn(
        light: *const FmLight,
        rays: *const FmRay,
        times: *const f64,
        n: usize,
        radiance: *mut f32,
        transmittance: *mut f32,
    ) -> FmStatus,
    /// How many of the volume's channels the light's line estimate marches, into `*out` (required): the volume's
    /// channel count, or fewer (`linechannels`: a soot fire's spectral bins, the others following from them).
    pub light_line_channels: unsafe extern "C" fn(light: *const FmLight, out: *mut u32) -> FmStatus,
    /// (1.1) How many notes the volume's build left, into `*out` (required): what a user should hear whatever
    /// host renders it — species whose lines fall outside the channels, flame colours the model cannot give.
    pub volume_note_count:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut usize) -> FmStatus,
    /// (1.1) Note `index` (< the count), UTF-8, NUL-terminated and truncated to `cap` bytes, into `buf` (may be
    /// null to ask for the length); its full length in bytes without the NUL into `*len` (required).
    pub volume_note: unsafe extern "C" fn(
        volume: *const FmVolume,
        index: usize,
        buf: *mut c_char,
        cap: usize,
        len: *mut usize,
    ) -> FmStatus,
    /// (1.2) The volume's coefficients in closed form into `*out` (required, its `struct_size` and table
    /// pointers set by the host; see [`FmTables`]); `FM_UNSUPPORTED` naming what is not of that form (atomic
    /// lines, a scatter colour grid, diffusion, refraction, embers, motion blur, a dataset not interpolated
    /// trilinearly).
    pub volume_tables:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut FmTables) -> FmStatus,
    /// (1.2) The fields of the closed form at `n` medium-space points (3n doubles) into `out` (3n floats, point-major):
    /// soot density d, temperature T (K) and the Lescale or emission grid's value les (1 without one), as the
    /// volume interpolates them; zeros outside. At the lattice's voxel centres, the voxels' own values: what a
    /// host textures.
    pub volume_fields: unsafe extern "C" fn(
        volume: *const FmVolume,
        points: *const f64,
        n: usize,
        out: *mut f32,
    ) -> FmStatus,
    /// (1.3) The bricks of 8³ samples the volume's grids store — what its dataset holds, not its box: two fires
    /// far apart are bricks of their own — in the lattice's sample indices ([`FmVolumeInfo::dims`]): per brick
    /// the index (i, j, k) of its first sample, 3 `int64_t` each, in no set order. An index may be
    /// below 0 (a sparse file's leaves stay whole where the lattice starts inside one); samples outside 0..dims
    /// are not the fire's. Their count into `*count` (required); `out` may be null with `cap` 0 to ask for it
    /// alone; a `cap` below the count is `FM_INVALID_ARGUMENT`, nothing written. What a host that bakes or
    /// textures the fire sparsely asks for, rather than reading the dataset again.
    pub volume_bricks: unsafe extern "C" fn(
        volume: *const FmVolume,
        out: *mut i64,
        cap: usize,
        count: *mut usize,
    ) -> FmStatus,
}

/// The entry point's type.
pub type FmEntry = unsafe extern "C" fn() -> *const FmApi;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_symbol_is_a_c_string() {
        assert_eq!(ENTRY_SYMBOL.last(), Some(&0));
        assert!(!ENTRY_SYMBOL[..ENTRY_SYMBOL.len() - 1].contains(&0));
    }

    #[test]
    fn version_rules() {
        assert!(compatible(ABI_MAJOR, ABI_MINOR, ABI_MAJOR, ABI_MINOR));
        assert!(compatible(1, 3, 1, 0));
        assert!(!compatible(1, 0, 1, 2));
        // A host built for 0.x and a 1.x plugin, both ways.
        assert!(!compatible(1, 0, 0, 13));
        assert!(!compatible(0, 13, 1, 0));
    }

    #[test]
    fn layouts_are_stable() {
        // The C header declares the same sizes (checked again by the C test against the built plugin).
        assert_eq!(core::mem::size_of::<FmRay>(), 72);
        assert_eq!(core::mem::size_of::<FmExit>(), 56);
        assert_eq!(core::mem::size_of::<FmScatter>(), 40);
        // 1.0/1.1 ended at 120 bytes; 1.2 appended the lattice (dims, reserved, two corners).
        assert_eq!(FM_VOLUME_INFO_SIZE_1_0, 120);
        assert_eq!(core::mem::size_of::<FmVolumeInfo>(), 184);
        assert_eq!(core::mem::size_of::<FmParam>(), 24);
        assert_eq!(core::mem::size_of::<FmParamInfo>(), 64);
        assert_eq!(core::mem::size_of::<FmLightInfo>(), 56);
        // Four u32 fields, then one pointer per entry (26 through 1.1; 1.2 appended volume_tables, volume_fields;
        // 1.3 volume_bricks).
        assert_eq!(core::mem::size_of::<FmApi>(), 16 + 29 * 8);
        assert_eq!(core::mem::size_of::<FmRayQuery>(), 96);
        // 1.4 appended the kind and the bins.
        assert_eq!(core::mem::size_of::<FmCreateInfo>(), 120);
        // 1.0 to 1.3 ended at 48 bytes; 1.4 appended the parameter's index.
        assert_eq!(FM_ERROR_DETAIL_SIZE_1_0, 48);
        assert_eq!(core::mem::size_of::<FmErrorDetail>(), 56);
        assert_eq!(core::mem::size_of::<FmPointQuery>(), 80);
        assert_eq!(core::mem::size_of::<FmMajorantGrid>(), 104);
    }
}
