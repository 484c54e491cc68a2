//! The C ABI export: the one `unsafe` module of the plugin. Every exported function checks its pointers, runs
//! under `catch_unwind`, and returns a status; messages go to a per-thread last-error slot. No Rust type
//! crosses the boundary: the table and its types are `firemedium-abi`'s `#[repr(C)]` ones.

mod buffers;
mod light;
mod params;
mod volume;

use crate::Error;
use firemedium_abi::*;
use light::*;
use std::cell::{Cell, RefCell};
use std::ffi::{c_char, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Once, OnceLock};
use volume::*;

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
    /// The last error's status and parts (parameter, location, file, position) and its parameter's index, for
    /// `last_error_detail`.
    static LAST_DETAIL: RefCell<(FmStatus, [Option<CString>; 4], Option<u32>)> = const { RefCell::new((FM_OK, [None, None, None, None], None)) };
    /// The parts of an error [`fail`] converted, until [`guard`] reports it (or the call succeeds after all).
    static PENDING_PARTS: RefCell<Option<Parts>> = const { RefCell::new(None) };
    /// Set while an entry runs under [`guard`]: a panic there is caught and reported, so the hook stays quiet.
    static IN_GUARD: Cell<bool> = const { Cell::new(false) };
    /// Where the last caught panic happened (`file:line`), for its message.
    static PANIC_AT: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Makes panics inside an entry quiet: the default hook would print a message (and a backtrace) on the host's
/// stderr for a panic that the entry catches and returns as `FM_PANIC` — output the host did not ask for. The
/// hook records where the panic happened instead; a panic anywhere else goes to the previous hook. (In the
/// cdylib this is the plugin's own copy of std's hook: the host's panics are untouched.)
fn quiet_panics() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if IN_GUARD.with(Cell::get) {
                let at = info
                    .location()
                    .map(|l| format!("{}:{}", l.file(), l.line()))
                    .unwrap_or_default();
                PANIC_AT.with(|p| *p.borrow_mut() = at);
            } else {
                previous(info)
            }
        }));
    });
}

fn set_error(msg: String) {
    LAST_ERROR.with(|e| *e.borrow_mut() = msg);
}

/// An error's parts for `last_error_detail`: (parameter, location, file, position), and the parameter's index in
/// the host's list.
#[derive(Default)]
struct Parts {
    text: [Option<String>; 4],
    index: Option<u32>,
}

/// Records the last error's status and parts for `last_error_detail`.
fn set_detail(status: FmStatus, parts: Parts) {
    let c = |s: Option<String>| s.map(|s| CString::new(s.replace('\0', "?")).unwrap_or_default());
    let [a, b, f, p] = parts.text;
    LAST_DETAIL.with(|d| *d.borrow_mut() = (status, [c(a), c(b), c(f), c(p)], parts.index));
}

/// Runs `f`, mapping its error and any panic to a status and the last-error message (and its detail).
fn guard(f: impl FnOnce() -> Result<(), (FmStatus, String)>) -> FmStatus {
    let outer = IN_GUARD.with(|g| g.replace(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    IN_GUARD.with(|g| g.set(outer));
    let parts = PENDING_PARTS.with(|p| p.borrow_mut().take());
    match result {
        Ok(Ok(())) => FM_OK,
        Ok(Err((status, msg))) => {
            set_error(msg);
            set_detail(status, parts.unwrap_or_default());
            status
        }
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            let at = PANIC_AT.with(|p| std::mem::take(&mut *p.borrow_mut()));
            set_error(format!("firemedium: internal error (panic at {at}: {what}); the call did nothing, the host may continue"));
            set_detail(FM_PANIC, Default::default());
            FM_PANIC
        }
    }
}

fn status_of(e: &Error) -> FmStatus {
    match e {
        Error::InvalidParameter { .. } => FM_INVALID_PARAMETER,
        Error::Format { .. } | Error::Io { .. } | Error::TooLarge { .. } => FM_DATASET,
        Error::Unsupported { .. } => FM_UNSUPPORTED,
    }
}

fn fail(e: Error) -> (FmStatus, String) {
    // The error's parts, for `last_error_detail`: (parameter, location, file, position), and the index.
    let parts = match &e {
        Error::InvalidParameter {
            at, name, index, ..
        } => Parts {
            text: [Some(name.clone()), at.clone(), None, None],
            index: *index,
        },
        Error::Format { file, at, .. } => Parts {
            text: [None, None, Some(file.clone()), Some(at.clone())],
            index: None,
        },
        Error::Io { file, .. } | Error::Unsupported { file, .. } | Error::TooLarge { file, .. } => {
            Parts {
                text: [None, None, Some(file.clone()), None],
                index: None,
            }
        }
    };
    PENDING_PARTS.with(|p| *p.borrow_mut() = Some(parts));
    (status_of(&e), e.to_string())
}

/// Checks a struct the host passed whose first field is its `struct_size` (every ABI struct but array elements): refused
/// when null or smaller than this plugin's `T` — `what` names the argument, `c_type` its C type.
///
/// # Safety
/// `p` is null or points at a struct whose first field is a `size_t` (the caller's contract).
unsafe fn sized<T>(p: *const T, what: &str, c_type: &str) -> Result<(), (FmStatus, String)> {
    if p.is_null() {
        return Err(bad(format!("{what} is null")));
    }
    // SAFETY: non-null (checked); the host's struct starts with its size (contract).
    let size = unsafe { p.cast::<usize>().read_unaligned() };
    let want = std::mem::size_of::<T>();
    if size < want {
        return Err(bad(format!(
            "{what}->struct_size {size}, expected at least {want} (set it to sizeof({c_type}))"
        )));
    }
    Ok(())
}

/// Reads a struct the host passed whose first field is its `struct_size`, as far as that size covers it: a struct
/// grows only at its end between minor versions, so an older host's smaller struct is read as this plugin's with
/// the newer fields zero — their defaults — and a newer host's larger one as far as this plugin knows it.
/// Refused when null or smaller than `min` (the size the struct had in ABI 1.0).
///
/// # Safety
/// `p` is null or points at `struct_size` readable bytes that begin with that `size_t` (the caller's contract);
/// `T` is a `repr(C)` struct every field of which is valid as zero bytes (integers, floats, raw pointers, `Option`s
/// of function pointers).
unsafe fn read_sized<T>(
    p: *const T,
    min: usize,
    what: &str,
    c_type: &str,
) -> Result<T, (FmStatus, String)> {
    if p.is_null() {
        return Err(bad(format!("{what} is null")));
    }
    // SAFETY: non-null (checked); the host's struct starts with its size (contract).
    let size = unsafe { p.cast::<usize>().read_unaligned() };
    if size < min {
        return Err(bad(format!(
            "{what}->struct_size {size}, expected at least {min} (set it to sizeof({c_type}))"
        )));
    }
    let mut v = std::mem::MaybeUninit::<T>::zeroed();
    let n = size.min(std::mem::size_of::<T>());
    // SAFETY: the host's `size` ≥ n bytes are readable (contract), `v` has size_of::<T>() ≥ n writable bytes; the
    // rest stay zero, which every field of T holds validly (this function's contract on T).
    unsafe {
        std::ptr::copy_nonoverlapping(p.cast::<u8>(), v.as_mut_ptr().cast::<u8>(), n);
        Ok(v.assume_init())
    }
}

/// Writes `value` into the host's struct at `out`, as far as its `struct_size` covers it (an older minor
/// version's host gets the fields it knows). Refused when null or smaller than `min` (the struct's ABI 1.0 size).
///
/// # Safety
/// `out` is null or points at `struct_size` writable bytes that begin with that `size_t` (the caller's contract).
unsafe fn write_sized<T>(
    out: *mut T,
    value: T,
    min: usize,
    what: &str,
    c_type: &str,
) -> Result<(), (FmStatus, String)> {
    if out.is_null() {
        return Err(bad(format!("{what} is null")));
    }
    // SAFETY: non-null (checked); the host's struct starts with its size (contract).
    let size = unsafe { out.cast::<usize>().read_unaligned() };
    if size < min {
        return Err(bad(format!(
            "{what}->struct_size {size}, expected at least {min} (set it to sizeof({c_type}))"
        )));
    }
    let n = size.min(std::mem::size_of::<T>());
    // SAFETY: the host's `size` ≥ n bytes are writable (contract); `value` is n ≥ bytes long, copied as bytes
    // (its struct_size field included: the plugin's own size, which a host reads as what was written).
    unsafe {
        std::ptr::copy_nonoverlapping((&value as *const T).cast::<u8>(), out.cast::<u8>(), n);
    }
    Ok(())
}

unsafe extern "C" fn last_error_detail(out: *mut FmErrorDetail) -> FmStatus {
    // (A misuse is itself the last error then: its message, and a detail of its status alone.)
    let detail = LAST_DETAIL.with(|d| {
        let d = d.borrow();
        let ptr = |s: &Option<CString>| s.as_ref().map_or(std::ptr::null(), |s| s.as_ptr());
        // (The strings live in this thread's slot until the next failing call on it.)
        FmErrorDetail {
            struct_size: std::mem::size_of::<FmErrorDetail>(),
            status: d.0,
            reserved: 0,
            parameter: ptr(&d.1[0]),
            location: ptr(&d.1[1]),
            file: ptr(&d.1[2]),
            position: ptr(&d.1[3]),
            index: d.2.map_or(-1, |i| i as i64),
        }
    });
    // SAFETY: null or the host's FmErrorDetail of its struct_size (contract); a 1.0–1.3 host's ends before `index`.
    match unsafe {
        write_sized(
            out,
            detail,
            FM_ERROR_DETAIL_SIZE_1_0,
            "last_error_detail: out",
            "FmErrorDetail",
        )
    } {
        Ok(()) => FM_OK,
        Err(e) => guard(|| Err(e)),
    }
}

fn bad(msg: impl Into<String>) -> (FmStatus, String) {
    (FM_INVALID_ARGUMENT, msg.into())
}

/// Calls `f` with two per-ray buffers of `c` channels: on the stack up to 64 channels (hosts call with one ray
/// at a time: no allocation per call), else on the heap.
fn with_channels<R>(c: usize, f: impl FnOnce(&mut [f64], &mut [f64]) -> R) -> R {
    const STACK: usize = 64;
    if c <= STACK {
        let mut a = [0f64; 2 * STACK];
        let (l, t) = a.split_at_mut(STACK);
        f(&mut l[..c], &mut t[..c])
    } else {
        let mut v = vec![0f64; 2 * c];
        let (l, t) = v.split_at_mut(c);
        f(l, t)
    }
}

/// Whether `n` elements of `T` fit what one allocation may span (isize::MAX bytes): a larger count is a host's
/// bug, refused before a slice is made of it.
fn span<T>(n: usize, what: &str) -> Result<(), (FmStatus, String)> {
    if n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return Err(bad(format!(
            "{what}: {n} elements: more than memory can hold"
        )));
    }
    Ok(())
}

unsafe extern "C" fn last_error(buf: *mut c_char, cap: usize) -> usize {
    LAST_ERROR.with(|e| {
        // SAFETY: `buf` is null or holds `cap` writable bytes (ABI contract).
        unsafe { buffers::copy_c_string(e.borrow().as_bytes(), buf, cap) }
    })
}

/// Every row of the public parameter tables, as C strings that live as long as the library.
fn param_rows() -> &'static [[CString; 7]] {
    static ROWS: OnceLock<Vec<[CString; 7]>> = OnceLock::new();
    ROWS.get_or_init(|| {
        let c = |s: &str| CString::new(s.replace('\0', " ")).unwrap_or_default();
        params::components()
            .iter()
            .flat_map(|comp| {
                comp.params.iter().map(move |p| {
                    [
                        c(comp.name),
                        c(p.name),
                        c(p.ty.name()),
                        c(p.default),
                        c(p.unit),
                        c(&p.range.describe().replace("\\|", "|")),
                        c(p.doc),
                    ]
                })
            })
            .collect()
    })
}

unsafe extern "C" fn param_count() -> usize {
    catch_unwind(|| param_rows().len()).unwrap_or(0)
}

unsafe extern "C" fn param_info(index: usize, out: *mut FmParamInfo) -> FmStatus {
    guard(|| {
        // SAFETY: null or the host's FmParamInfo (contract).
        unsafe { sized(out, "param_info: out", "FmParamInfo") }?;
        let rows = param_rows();
        let r = rows.get(index).ok_or_else(|| {
            bad(format!(
                "param_info: index {index} is not below the {} rows",
                rows.len()
            ))
        })?;
        // SAFETY: out is non-null with at least our struct's size writable (checked, ABI contract).
        unsafe {
            out.write_unaligned(FmParamInfo {
                struct_size: std::mem::size_of::<FmParamInfo>(),
                component: r[0].as_ptr(),
                name: r[1].as_ptr(),
                ty: r[2].as_ptr(),
                default_value: r[3].as_ptr(),
                unit: r[4].as_ptr(),
                range: r[5].as_ptr(),
                doc: r[6].as_ptr(),
            });
        }
        Ok(())
    })
}

static API: FmApi = FmApi {
    abi_major: ABI_MAJOR,
    abi_minor: ABI_MINOR,
    struct_size: std::mem::size_of::<FmApi>() as u32,
    reserved: 0,
    last_error,
    last_error_detail,
    param_count,
    param_info,
    volume_create,
    volume_destroy,
    volume_info,
    volume_channel_xyz,
    volume_temperature_range,
    volume_white_temperature,
    volume_capped_rays,
    volume_query,
    volume_features,
    volume_majorant_grid,
    volume_point,
    volume_coefficients,
    light_create,
    light_destroy,
    light_info,
    light_sample,
    light_pdf,
    light_pdf_direction,
    light_integrate,
    light_line_channels,
    volume_note_count,
    volume_note,
    volume_tables,
    volume_fields,
    volume_bricks,
};

/// The plugin's entry point: the static function table.
#[no_mangle]
pub extern "C" fn firemedium_plugin_entry() -> *const FmApi {
    quiet_panics();
    &API
}

#[cfg(test)]
mod tests {
    //! The panic guard, through the same `extern "C"` table a host gets. The `faultinjection` parameter that
    //! panics exists only in this crate's unit-test build (`cfg(test)`), never in the shipped library.
    use super::*;
    use std::ffi::CStr;

    fn param(name: &CStr, ty: u32, count: u32, values: *const std::ffi::c_void) -> FmParam {
        FmParam {
            name: name.as_ptr(),
            ty,
            count,
            values,
        }
    }

    /// Creates a 2³ soot slab at 1500 K through the table, with `fault` as its fault-injection point.
    fn create(api: &FmApi, fault: &CStr) -> (FmStatus, *mut FmVolume) {
        let d = [1.0f64; 8];
        let t = [1500.0f64; 8];
        let n = [2i64];
        let fault_ptr = [fault.as_ptr()];
        let list = [
            param(c"density", FM_TYPE_FLOAT, 8, d.as_ptr().cast()),
            param(c"temperature", FM_TYPE_FLOAT, 8, t.as_ptr().cast()),
            param(c"nx", FM_TYPE_INTEGER, 1, n.as_ptr().cast()),
            param(c"ny", FM_TYPE_INTEGER, 1, n.as_ptr().cast()),
            param(c"nz", FM_TYPE_INTEGER, 1, n.as_ptr().cast()),
            param(
                c"faultinjection",
                FM_TYPE_STRING,
                1,
                fault_ptr.as_ptr().cast(),
            ),
        ];
        let mut out = std::ptr::null_mut();
        let info = FmCreateInfo {
            params: list.as_ptr(),
            count: list.len(),
            ..FmCreateInfo::default()
        };
        // SAFETY: every parameter points at live values of its type and count; `out` is writable.
        let status = unsafe { (api.volume_create)(&info, &mut out) };
        (status, out)
    }

    fn last(api: &FmApi) -> String {
        let mut buf = vec![0 as c_char; 512];
        // SAFETY: the buffer holds `buf.len()` chars.
        unsafe { (api.last_error)(buf.as_mut_ptr(), buf.len()) };
        // SAFETY: last_error NUL-terminates within the capacity.
        unsafe { CStr::from_ptr(buf.as_ptr()) }
            .to_string_lossy()
            .into_owned()
    }

    #[test]
    fn a_panic_inside_the_plugin_is_a_status_and_the_host_lives_on() {
        // SAFETY: the entry returns a pointer to the static table.
        let api = unsafe { &*firemedium_plugin_entry() };
        let (status, v) = create(api, c"create");
        assert_eq!(status, FM_PANIC);
        assert!(v.is_null());
        let msg = last(api);
        assert!(
            msg.contains("panic") && msg.contains("fault injection"),
            "{msg}"
        );

        let (status, v) = create(api, c"integrate");
        assert_eq!(status, FM_OK, "{}", last(api));
        let ray = FmRay {
            origin: [-0.5, 0.5, 0.5],
            direction: [1.0, 0.0, 0.0],
            tmin: 0.0,
            tmax: 3.0,
            seed: 1,
        };
        let mut info = FmVolumeInfo::default();
        // SAFETY: `v` is a live volume, `info` writable.
        assert_eq!(unsafe { (api.volume_info)(v, &mut info) }, FM_OK);
        let mut l = vec![0f32; info.channels as usize];
        assert_eq!(integrate_one(api, v, &ray, &mut l), FM_PANIC);
        let msg = last(api);
        assert!(
            msg.contains("fault injection") && msg.contains("panic at ") && msg.contains(".rs:"),
            "{msg}"
        );
        // SAFETY: `v` came from volume_create and is destroyed once.
        unsafe { (api.volume_destroy)(v) };

        // The plugin still works afterwards: the same slab without the fault emits.
        let (status, v) = create(api, c"");
        assert_eq!(status, FM_OK, "{}", last(api));
        assert_eq!(integrate_one(api, v, &ray, &mut l), FM_OK);
        assert!(l.iter().any(|&x| x > 0.0), "{l:?}");
        // SAFETY: as above.
        unsafe { (api.volume_destroy)(v) };
    }

    fn integrate_one(api: &FmApi, v: *mut FmVolume, ray: &FmRay, l: &mut [f32]) -> FmStatus {
        let q = FmRayQuery {
            n: 1,
            rays: ray,
            radiance: l.as_mut_ptr(),
            ..FmRayQuery::default()
        };
        // SAFETY: one ray, `l` holds the volume's channels, optional outputs null.
        unsafe { (api.volume_query)(v, &q) }
    }

    #[test]
    fn numbers_are_checked_at_every_entry() {
        // NaN where a number is read, and counts whose products overflow, are errors naming them — never a panic
        // (a NaN in light_sample's u used to panic inside the plugin) and never a read past a buffer.
        // SAFETY: the entry returns a pointer to the static table.
        let api = unsafe { &*firemedium_plugin_entry() };
        let (status, v) = create(api, c"");
        assert_eq!(status, FM_OK, "{}", last(api));
        let mut light = std::ptr::null_mut();
        // SAFETY: a live volume, no parameters, a writable out.
        let s = unsafe { (api.light_create)(v, std::ptr::null(), 0, &mut light) };
        assert_eq!(s, FM_OK, "{}", last(api));
        let u = [0.5, f64::NAN, 0.5, 0.5, 0.5, 0.5];
        let (mut pts, mut pdf) = ([0.0; 3], [0.0; 1]);
        // SAFETY: one row of u, points and pdf as documented; emission null.
        let s = unsafe {
            (api.light_sample)(
                light,
                u.as_ptr(),
                std::ptr::null(),
                1,
                pts.as_mut_ptr(),
                pdf.as_mut_ptr(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(s, FM_INVALID_ARGUMENT);
        assert!(
            last(api).contains("light_sample: u[1] = NaN"),
            "{}",
            last(api)
        );
        // A count whose 3 n overflows: refused before any read.
        let p = [0.0f64; 3];
        // SAFETY: the count is refused before `p` is read.
        let s = unsafe {
            (api.volume_coefficients)(
                v,
                p.as_ptr(),
                usize::MAX / 2,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            )
        };
        assert_eq!(s, FM_INVALID_ARGUMENT, "{}", last(api));
        assert!(last(api).contains("overflows"), "{}", last(api));
        // A ray with a NaN origin.
        let ray = FmRay {
            origin: [f64::NAN, 0.5, 0.5],
            direction: [1.0, 0.0, 0.0],
            tmin: 0.0,
            tmax: 3.0,
            seed: 1,
        };
        let mut l = [0f32; 64];
        assert_eq!(integrate_one(api, v, &ray, &mut l), FM_INVALID_ARGUMENT);
        assert!(last(api).contains("ray 0"), "{}", last(api));
        // SAFETY: both came from their create calls and are destroyed once.
        unsafe {
            (api.light_destroy)(light);
            (api.volume_destroy)(v);
        }
    }
}
