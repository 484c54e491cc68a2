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
//! - Batch queries take `n` rays and write `n × channels` floats (radiance, transmittance, weights), channel
//!   fastest; `channels` comes from [`FmVolumeInfo`]. Optional outputs may be null.
//! - Rays are in the medium's space (the host applies its transforms); distances are |direction| · Δt, in
//!   metres when the medium's space is in metres.

#![forbid(unsafe_code)]
#![no_std]

use core::ffi::{c_char, c_void};

/// Major version of the C ABI. Changes on any incompatible change of the table or its types.
pub const ABI_MAJOR: u32 = 0;
/// Minor version of the C ABI. Grows when entries are appended to the table.
pub const ABI_MINOR: u32 = 13;
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
/// A host that passes no exits to `volume_integrate` gets the straight-line integration even when the volume
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
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FmVolumeInfo {
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
}

/// A row of a component's parameter table (strings live as long as the library).
#[repr(C)]
#[derive(Debug, Clone, Copy)]
pub struct FmParamInfo {
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
/// `FmLightInfo::weighting`: voxels weighted by the power that leaves the fire (ABI 0.8).
pub const FM_WEIGHTING_ESCAPING: u32 = 2;

/// What a fire light is.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FmLightInfo {
    /// Emitted power over the whole spectrum, W (pbrt mode: over the bins, relative units).
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
    /// ABI 0.9: voxels per side of the blocks the light's line estimate marches through (1: the fire's own
    /// voxels; the `lineblock` parameter); 0 from an older plugin (the field was reserved).
    pub line_block: u32,
}

/// ABI 0.11, [`FmApi::volume_features`]: the volume emits.
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

/// ABI 0.11: a volume's majorant grid ([`FmApi::volume_majorant_grid`]), for a host's own free-path sampling:
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

/// ABI 0.11: a point query ([`FmApi::volume_point`]): at `n` points, each at its time and at `k` wavelengths of
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

/// ABI 0.12: the last error's structure ([`FmApi::last_error_detail`]), beside its message: what a host needs to
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
    /// Where the host said that parameter was given (`volume_create_located`'s location: `file:line:col`).
    pub location: *const c_char,
    /// The file whose reading or content failed.
    pub file: *const c_char,
    /// Where in that file: `byte 1234`, `line 3, column 5`, `grid 'density'`.
    pub position: *const c_char,
}

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
        }
    }
}

/// [`FmCreateInfo::flags`]: `frame` is set.
pub const FM_CREATE_FRAME: u32 = 1 << 0;
/// [`FmCreateInfo::flags`]: `shutter` is set.
pub const FM_CREATE_SHUTTER: u32 = 1 << 1;

/// ABI 0.13: a volume's creation ([`FmApi::volume_create_with`]): the scene's parameters with their locations, and
/// the host's context beside them — threads, memory budget, frame, shutter — instead of as parameters the host must
/// make up. A parameter the scene gives itself (`threads`, `maxbytes`, `frame`, `shutteropen`, `shutterclose`)
/// wins over the context.
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
}

/// The plugin's function table.
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
    /// Number of rows in the parameter tables of all components.
    pub param_count: unsafe extern "C" fn() -> usize,
    /// Row `index` of the parameter tables.
    pub param_info: unsafe extern "C" fn(index: usize, out: *mut FmParamInfo) -> FmStatus,
    /// Creates a fire volume (dataset + volume parameters); `*out` receives the handle.
    pub volume_create: unsafe extern "C" fn(
        params: *const FmParam,
        count: usize,
        out: *mut *mut FmVolume,
    ) -> FmStatus,
    /// Destroys a volume (null is ignored).
    pub volume_destroy: unsafe extern "C" fn(volume: *mut FmVolume),
    /// Describes a volume.
    pub volume_info:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut FmVolumeInfo) -> FmStatus,
    /// Writes 3 × channels f64: the XYZ of unit radiance in each channel (to turn channel radiance into XYZ).
    pub volume_channel_xyz:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut f64, cap: usize) -> FmStatus,
    /// Integrates emission–absorption along `n` rays: radiance (required) and transmittance (optional),
    /// `n × channels` f32 each; exits (optional), `n` entries.
    pub volume_integrate: unsafe extern "C" fn(
        volume: *const FmVolume,
        rays: *const FmRay,
        n: usize,
        radiance: *mut f32,
        transmittance: *mut f32,
        exits: *mut FmExit,
    ) -> FmStatus,
    /// Transmittance only (shadow rays): `n × channels` f32.
    pub volume_transmittance: unsafe extern "C" fn(
        volume: *const FmVolume,
        rays: *const FmRay,
        n: usize,
        transmittance: *mut f32,
    ) -> FmStatus,
    /// Samples the first real scattering event per ray: events (`n`), weights and emitted radiance before the
    /// event (`n × channels` f32 each; emitted may be null).
    pub volume_sample_scatter: unsafe extern "C" fn(
        volume: *const FmVolume,
        rays: *const FmRay,
        n: usize,
        events: *mut FmScatter,
        weights: *mut f32,
        emitted: *mut f32,
    ) -> FmStatus,
    /// σ_a, σ_s (m⁻¹) and the emission coefficient j = σ_a L_e per channel at `n` points (3 f64 each); each
    /// output `n × channels` f32, any may be null.
    pub volume_coefficients: unsafe extern "C" fn(
        volume: *const FmVolume,
        points: *const f64,
        n: usize,
        sigma_a: *mut f32,
        sigma_s: *mut f32,
        emission: *mut f32,
    ) -> FmStatus,
    /// ABI 0.2. Builds the fire light of a volume (parameters: `string weighting` power (default) | luminance). The light
    /// keeps the volume alive; destroy both.
    pub light_create: unsafe extern "C" fn(
        volume: *const FmVolume,
        params: *const FmParam,
        count: usize,
        out: *mut *mut FmLight,
    ) -> FmStatus,
    /// Destroys a light (null is ignored).
    pub light_destroy: unsafe extern "C" fn(light: *mut FmLight),
    /// Describes a light.
    pub light_info: unsafe extern "C" fn(light: *const FmLight, out: *mut FmLightInfo) -> FmStatus,
    /// Samples `n` points from 6 uniform numbers each (`u`, 6n doubles): medium-space points (3n), their
    /// density per unit volume (n), and the emission coefficient j = σ_a L_e there (n × channels, may be null).
    pub light_sample: unsafe extern "C" fn(
        light: *const FmLight,
        u: *const f64,
        n: usize,
        points: *mut f64,
        pdf: *mut f64,
        emission: *mut f32,
    ) -> FmStatus,
    /// Density per unit volume of `n` medium-space points (3n doubles).
    pub light_pdf: unsafe extern "C" fn(
        light: *const FmLight,
        points: *const f64,
        n: usize,
        pdf: *mut f64,
    ) -> FmStatus,
    /// Solid-angle density of the sampled point's direction, seen from `origins` along `directions` (3n each,
    /// medium space): ∫ pdf(o + s d̂) s² ds.
    pub light_pdf_direction: unsafe extern "C" fn(
        light: *const FmLight,
        origins: *const f64,
        directions: *const f64,
        n: usize,
        pdf: *mut f64,
    ) -> FmStatus,
    /// ABI 0.3: the lowest and highest temperature (K) of the volume's grid after its mapping, into `out[0..2]`;
    /// both 0 when the volume has no temperature grid. (A tone mapper's white point: the blackbody at the
    /// fire's hottest temperature.)
    pub volume_temperature_range:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut f64) -> FmStatus,
    /// ABI 0.4: [`volume_create`](Self::volume_create) with where each parameter came from: `locations` holds
    /// `count` NUL-terminated strings (`file:line:col` of the scene that gave the parameter; an entry may be
    /// null, and `locations` itself may be null). An error about a parameter then begins with its location.
    pub volume_create_located: unsafe extern "C" fn(
        params: *const FmParam,
        locations: *const *const c_char,
        count: usize,
        out: *mut *mut FmVolume,
    ) -> FmStatus,
    /// ABI 0.4: how many rays' tracking (ratio, delta, scattering events) stopped at the per-ray collision cap so
    /// far, into `*out`: each was cut short as if absorbed, a bias towards dark that a host should report.
    pub volume_capped_rays:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut u64) -> FmStatus,
    /// ABI 0.5: [`volume_integrate`](Self::volume_integrate) with a time per ray: `times` holds `n` doubles,
    /// frames from the grids' time inside the volume's shutter (`shutteropen`, `shutterclose`), or is null
    /// (every ray at time 0). A volume with motion blur (a `velocitygrid` and an open shutter) is looked up
    /// where its velocity carried it from; any other volume ignores the times.
    pub volume_integrate_at: unsafe extern "C" fn(
        volume: *const FmVolume,
        rays: *const FmRay,
        times: *const f64,
        n: usize,
        radiance: *mut f32,
        transmittance: *mut f32,
        exits: *mut FmExit,
    ) -> FmStatus,
    /// ABI 0.5: [`volume_transmittance`](Self::volume_transmittance) with a time per ray (as
    /// [`volume_integrate_at`](Self::volume_integrate_at)).
    pub volume_transmittance_at: unsafe extern "C" fn(
        volume: *const FmVolume,
        rays: *const FmRay,
        times: *const f64,
        n: usize,
        transmittance: *mut f32,
    ) -> FmStatus,
    /// ABI 0.5: [`volume_sample_scatter`](Self::volume_sample_scatter) with a time per ray (as
    /// [`volume_integrate_at`](Self::volume_integrate_at)).
    pub volume_sample_scatter_at: unsafe extern "C" fn(
        volume: *const FmVolume,
        rays: *const FmRay,
        times: *const f64,
        n: usize,
        events: *mut FmScatter,
        weights: *mut f32,
        emitted: *mut f32,
    ) -> FmStatus,
    /// ABI 0.6: the temperature (K) whose blackbody a viewer adapts to for this volume, into `*out`: its hottest
    /// temperature when its colour is the physics' (Planck emission), 0 when its colour is art-directed (a
    /// `tint`, or a `colorramp` short of `physical` 1: meant to be seen against a D65 white) or it has no
    /// temperature grid.
    pub volume_white_temperature:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut f64) -> FmStatus,
    /// ABI 0.7: [`light_sample`](Self::light_sample) with a time per sample (`times`: `n` doubles, frames from
    /// the grids' time, or null for time 0): a volume's embers move while the shutter is open, and the light
    /// samples them where they are then. The emission output is the volume's j at the point (an ember is a
    /// surface: its light reaches a host through `volume_integrate_at` along the point's direction).
    pub light_sample_at: unsafe extern "C" fn(
        light: *const FmLight,
        u: *const f64,
        times: *const f64,
        n: usize,
        points: *mut f64,
        pdf: *mut f64,
        emission: *mut f32,
    ) -> FmStatus,
    /// ABI 0.7: [`light_pdf`](Self::light_pdf) with a time per point (as [`light_sample_at`](Self::light_sample_at)).
    pub light_pdf_at: unsafe extern "C" fn(
        light: *const FmLight,
        points: *const f64,
        times: *const f64,
        n: usize,
        pdf: *mut f64,
    ) -> FmStatus,
    /// ABI 0.7: [`light_pdf_direction`](Self::light_pdf_direction) with a time per direction (as
    /// [`light_sample_at`](Self::light_sample_at)): the density a sample drawn at that time has.
    pub light_pdf_direction_at: unsafe extern "C" fn(
        light: *const FmLight,
        origins: *const f64,
        directions: *const f64,
        times: *const f64,
        n: usize,
        pdf: *mut f64,
    ) -> FmStatus,
    /// ABI 0.8: the fire's emitted radiance and transmittance along `n` straight rays, as the light estimates
    /// them for next-event estimation along a sampled direction (`radiance`, required, and `transmittance`,
    /// may be null: `n × channels` floats; `times` as [`light_sample_at`](Self::light_sample_at)): the volume's
    /// march at the light's `linestep`, corrected toward the volume's own march with probability
    /// `linecorrection`. Where its step is the volume's, the same as `volume_integrate_at` without exits.
    pub light_integrate_at: unsafe extern "C" fn(
        light: *const FmLight,
        rays: *const FmRay,
        times: *const f64,
        n: usize,
        radiance: *mut f32,
        transmittance: *mut f32,
    ) -> FmStatus,
    /// ABI 0.10: how many of the volume's channels the light's line estimate marches, into `*out` (required):
    /// the volume's channel count, or fewer (`linechannels`: a soot fire's spectral bins, the others following
    /// from them).
    pub light_line_channels: unsafe extern "C" fn(light: *const FmLight, out: *mut u32) -> FmStatus,
    /// ABI 0.11: what the volume holds beyond absorption, into `*out` (required): `FM_FEATURE_*` bits. A host that
    /// tracks the medium itself (from [`volume_coefficients`](Self::volume_coefficients) and
    /// [`volume_majorant_grid`](Self::volume_majorant_grid)) refuses, or keeps to the whole-ray queries for, what
    /// it cannot handle.
    pub volume_features: unsafe extern "C" fn(volume: *const FmVolume, out: *mut u64) -> FmStatus,
    /// ABI 0.11: the volume's majorant grid into `*out` (required, its `struct_size` set by the host).
    pub volume_majorant_grid:
        unsafe extern "C" fn(volume: *const FmVolume, out: *mut FmMajorantGrid) -> FmStatus,
    /// ABI 0.11: the point query (see [`FmPointQuery`]; `query` required).
    pub volume_point:
        unsafe extern "C" fn(volume: *const FmVolume, query: *const FmPointQuery) -> FmStatus,
    /// ABI 0.12: the last error on this thread as a structure into `*out` (required, its `struct_size` set by
    /// the host); see [`FmErrorDetail`].
    pub last_error_detail: unsafe extern "C" fn(out: *mut FmErrorDetail) -> FmStatus,
    /// ABI 0.13: a volume from a creation info (see [`FmCreateInfo`]; `info` and `out` required).
    pub volume_create_with:
        unsafe extern "C" fn(info: *const FmCreateInfo, out: *mut *mut FmVolume) -> FmStatus,
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
        assert!(compatible(0, 3, 0, 1));
        assert!(!compatible(0, 1, 0, 2));
        assert!(!compatible(1, 1, 0, 1));
    }

    #[test]
    fn layouts_are_stable() {
        // The C header declares the same sizes (checked again by the C test against the built plugin).
        assert_eq!(core::mem::size_of::<FmRay>(), 72);
        assert_eq!(core::mem::size_of::<FmExit>(), 56);
        assert_eq!(core::mem::size_of::<FmScatter>(), 40);
        assert_eq!(core::mem::size_of::<FmVolumeInfo>(), 112);
        assert_eq!(core::mem::size_of::<FmParam>(), 24);
        assert_eq!(core::mem::size_of::<FmParamInfo>(), 56);
        assert_eq!(core::mem::size_of::<FmLightInfo>(), 48);
        // Four u32 fields, then one pointer per entry (0.4 appended `volume_create_located` and
        // `volume_capped_rays`, 0.5 the three `_at` entries, 0.6 `volume_white_temperature`, 0.7 the light's
        // three `_at` entries, 0.8 `light_integrate_at`, 0.10 `light_line_channels`, 0.11 `volume_features` and
        // `volume_majorant_grid` and `volume_point`, 0.12 `last_error_detail`, 0.13 `volume_create_with`).
        assert_eq!(core::mem::size_of::<FmApi>(), 16 + 34 * 8);
        assert_eq!(core::mem::size_of::<FmCreateInfo>(), 72);
        assert_eq!(core::mem::size_of::<FmErrorDetail>(), 48);
        assert_eq!(core::mem::size_of::<FmPointQuery>(), 80);
        assert_eq!(core::mem::size_of::<FmMajorantGrid>(), 104);
    }
}
