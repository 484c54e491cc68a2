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
    /// coefficient per channel into `emission` (`u.len() × channels`), if given. At time 0.
    pub fn sample(
        &self,
        u: &[[f64; 6]],
        points: &mut [[f64; 3]],
        pdf: &mut [f64],
        emission: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        self.sample_at(u, None, points, pdf, emission)
    }

    /// As [`sample`](Self::sample) with a time per sample (frames from the grids' time; `None`: time 0): a
    /// volume's embers are sampled where they are then.
    pub fn sample_at(
        &self,
        u: &[[f64; 6]],
        times: Option<&[f64]>,
        points: &mut [[f64; 3]],
        pdf: &mut [f64],
        emission: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        let n = u.len();
        let t_ptr = times_ptr(times, n, "light sample")?;
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
                t_ptr,
                n,
                points.as_mut_ptr() as *mut f64,
                pdf.as_mut_ptr(),
                e_ptr,
            )
        };
        self.inner.check(s)
    }

    /// Density per unit volume of medium-space points (at time 0).
    pub fn pdf(&self, points: &[[f64; 3]], pdf: &mut [f64]) -> Result<(), Error> {
        self.pdf_at(points, None, pdf)
    }

    /// As [`pdf`](Self::pdf) with a time per point.
    pub fn pdf_at(
        &self,
        points: &[[f64; 3]],
        times: Option<&[f64]>,
        pdf: &mut [f64],
    ) -> Result<(), Error> {
        let t_ptr = times_ptr(times, points.len(), "light pdf")?;
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
                t_ptr,
                points.len(),
                pdf.as_mut_ptr(),
            )
        };
        self.inner.check(s)
    }

    /// Solid-angle density of directions seen from origins (medium space), at time 0.
    pub fn pdf_direction(
        &self,
        origins: &[[f64; 3]],
        directions: &[[f64; 3]],
        pdf: &mut [f64],
    ) -> Result<(), Error> {
        self.pdf_direction_at(origins, directions, None, pdf)
    }

    /// As [`pdf_direction`](Self::pdf_direction) with a time per direction.
    pub fn pdf_direction_at(
        &self,
        origins: &[[f64; 3]],
        directions: &[[f64; 3]],
        times: Option<&[f64]>,
        pdf: &mut [f64],
    ) -> Result<(), Error> {
        let t_ptr = times_ptr(times, origins.len(), "light pdf_direction")?;
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
                t_ptr,
                origins.len(),
                pdf.as_mut_ptr(),
            )
        };
        self.inner.check(s)
    }

    /// The fire's emitted radiance (`rays.len() × channels` floats) and, if asked, transmittance along straight
    /// `rays` (medium space), each at its time, as the light estimates them for next-event estimation along a
    /// sampled direction: the volume's march at the light's `linestep`, corrected toward the volume's
    /// own with probability `linecorrection`.
    pub fn integrate_at(
        &self,
        rays: &[crate::Ray],
        times: Option<&[f64]>,
        radiance: &mut [f32],
        transmittance: Option<&mut [f32]>,
    ) -> Result<(), Error> {
        let t_ptr = times_ptr(times, rays.len(), "light integrate")?;
        let need = rays.len().saturating_mul(self.channels);
        if radiance.len() < need || transmittance.as_ref().is_some_and(|t| t.len() < need) {
            return Err(Error::Buffer(format!(
                "light integrate: buffers shorter than {} rays × {} channels",
                rays.len(),
                self.channels
            )));
        }
        let tr = transmittance.map_or(std::ptr::null_mut(), |t| t.as_mut_ptr());
        // SAFETY: sized above; rays.len() rays.
        let s = unsafe {
            (self.inner.api().light_integrate)(
                self.handle,
                rays.as_ptr(),
                t_ptr,
                rays.len(),
                radiance.as_mut_ptr(),
                tr,
            )
        };
        self.inner.check(s)
    }
}

impl Light {
    /// How many of the volume's channels the light's line estimate marches: its channel count, or
    /// fewer (`linechannels`).
    pub fn line_channels(&self) -> Result<u32, Error> {
        let mut out = 0u32;
        // SAFETY: a live handle; `out` is one writable u32.
        let s = unsafe { (self.inner.api().light_line_channels)(self.handle, &mut out) };
        self.inner.check(s)?;
        Ok(out)
    }
}

/// The times' pointer for `n` entries (null for none), checked long enough.
fn times_ptr(times: Option<&[f64]>, n: usize, what: &str) -> Result<*const f64, Error> {
    match times {
        None => Ok(std::ptr::null()),
        Some(t) if t.len() >= n => Ok(t.as_ptr()),
        Some(t) => Err(Error::Buffer(format!(
            "{what}: {} times for {n} entries",
            t.len()
        ))),
    }
}
