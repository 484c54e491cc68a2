//! A fire light handle: sampling, pdfs per volume and per solid angle, its power.

use crate::{abi, Error, Inner, LightInfo};
use std::fmt;
use std::sync::Arc;

/// The fire light of a volume (it keeps its volume alive inside the plugin). Immutable; `Send + Sync`.
pub struct Light {
    pub(crate) inner: Arc<Inner>,
    pub(crate) handle: *mut abi::FmLight,
    pub(crate) info: abi::FmLightInfo,
    pub(crate) channels: usize,
}

// SAFETY: lights are immutable and safe to query from many threads (ABI contract); `inner` keeps the library.
unsafe impl Send for Light {}
// SAFETY: as above.
unsafe impl Sync for Light {}

impl fmt::Debug for Light {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Light({:?})", self.info)
    }
}

impl Drop for Light {
    fn drop(&mut self) {
        // SAFETY: the handle came from light_create and is destroyed exactly once, here.
        unsafe { (self.inner.api().light_destroy)(self.handle) }
    }
}

impl Light {
    /// Power, voxels, bytes, build time.
    pub fn info(&self) -> LightInfo {
        self.info
    }

    /// Samples one point per 6 uniform numbers: (medium-space point, pdf per unit volume), and the emission
    /// coefficient per channel into `emission` (`u.len() × channels`), if given.
    pub fn sample(
        &self,
        u: &[[f64; 6]],
        points: &mut [[f64; 3]],
        pdf: &mut [f64],
        emission: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        let n = u.len();
        if points.len() < n || pdf.len() < n {
            return Err(Error::Buffer(format!(
                "light sample: {} points and {} pdfs for {n} samples",
                points.len(),
                pdf.len()
            )));
        }
        let e_ptr = match emission {
            Some(e) if e.len() >= n * self.channels => e.as_mut_ptr(),
            Some(e) => {
                return Err(Error::Buffer(format!(
                    "light sample: {} floats for {n} × {} channels",
                    e.len(),
                    self.channels
                )))
            }
            None => std::ptr::null_mut(),
        };
        // SAFETY: buffers sized above; [f64; 3] and [f64; 6] are contiguous doubles.
        let s = unsafe {
            (self.inner.api().light_sample)(
                self.handle,
                u.as_ptr() as *const f64,
                n,
                points.as_mut_ptr() as *mut f64,
                pdf.as_mut_ptr(),
                e_ptr,
            )
        };
        self.inner.check(s)
    }

    /// Density per unit volume of medium-space points.
    pub fn pdf(&self, points: &[[f64; 3]], pdf: &mut [f64]) -> Result<(), Error> {
        if pdf.len() < points.len() {
            return Err(Error::Buffer(
                "light pdf: output shorter than the points".into(),
            ));
        }
        // SAFETY: sized above.
        let s = unsafe {
            (self.inner.api().light_pdf)(
                self.handle,
                points.as_ptr() as *const f64,
                points.len(),
                pdf.as_mut_ptr(),
            )
        };
        self.inner.check(s)
    }

    /// Solid-angle density of directions seen from origins (medium space).
    pub fn pdf_direction(
        &self,
        origins: &[[f64; 3]],
        directions: &[[f64; 3]],
        pdf: &mut [f64],
    ) -> Result<(), Error> {
        if directions.len() < origins.len() || pdf.len() < origins.len() {
            return Err(Error::Buffer(
                "light pdf_direction: buffers shorter than the origins".into(),
            ));
        }
        // SAFETY: sized above.
        let s = unsafe {
            (self.inner.api().light_pdf_direction)(
                self.handle,
                origins.as_ptr() as *const f64,
                directions.as_ptr() as *const f64,
                origins.len(),
                pdf.as_mut_ptr(),
            )
        };
        self.inner.check(s)
    }
}
