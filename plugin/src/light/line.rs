//! The light's line estimate: the fire's emission along a sampled direction by the volume's march at the light's
//! coarser step, through the fire's copy in blocks and in a subset of its bins, and the checks that chose them.

use super::*;

impl FireLight {
    /// The side of the blocks the line estimate marches through, voxels (1: the fire's own).
    pub fn line_block(&self) -> usize {
        self.mip.as_ref().map_or(1, |m| {
            (m.dataset().voxel_size().x / self.vol.dataset().voxel_size().x).round() as usize
        })
    }
    /// How many of the volume's channels the line marches (all of them, or the few the others follow from).
    pub fn line_channels(&self) -> usize {
        self.channels
            .as_ref()
            .map_or(self.vol.channels(), |c| c.count())
    }
    /// The line estimate's march step, metres.
    pub fn line_step(&self) -> f64 {
        self.line_step
    }

    /// The fire's emitted radiance `l` and transmittance `t` along `ray` at `time`, as next-event estimation
    /// takes them along a sampled direction: the volume's march at the light's coarser step, and with
    /// probability `linecorrection` also at the volume's own step, the difference over that probability added
    /// (the expectation is then the volume's own march: unbiased against what a camera ray sees). A light whose
    /// step is the volume's — or a volume that tracks — integrates as the volume does. Returns the exit
    /// parameter.
    pub fn integrate_at(
        &self,
        ray: &crate::volume::Ray,
        time: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> f64 {
        let v = &*self.vol;
        if !(self.line_step > v.step_length()) {
            return v.integrate_at(ray, time, l, t);
        }
        let target = self.mip.as_deref().unwrap_or(v);
        let few = self
            .channels
            .as_ref()
            .and_then(|lc| target.integrate_channels(lc, ray, self.line_step, l, t));
        let te =
            few.unwrap_or_else(|| target.integrate_stepped_at(ray, time, self.line_step, l, t));
        let q = self.correction;
        if q > 0.0 {
            // (Its own random number: the march's jitter comes from the ray's seed.)
            let u = crate::rng::Rng::new(ray.seed ^ 0x6c62_272e_07bb_0142).next_f64();
            if u < q {
                // (On the stack for up to 64 channels: no allocation per corrected sample.)
                let c = l.len();
                let (mut stack, mut heap) = ([0f64; 128], Vec::new());
                let fine = if 2 * c <= stack.len() {
                    &mut stack[..2 * c]
                } else {
                    heap.resize(2 * c, 0.0);
                    &mut heap[..]
                };
                let (lf, tf) = fine.split_at_mut(c);
                v.integrate_at(ray, time, lf, tf);
                for k in 0..c {
                    l[k] += (lf[k] - l[k]) / q;
                    t[k] += (tf[k] - t[k]) / q;
                }
            }
        }
        te
    }

    /// The relative difference between the line through the copy `m` and the volume's own march on the
    /// [`BLOCK_RAYS`] check rays: the larger of the two sums' (see [`line_sum`](Self::line_sum)).
    /// Signed: the weighted sum's, or the plain sum's over two (a copy's blocks average a smooth fire's curvature
    /// away to about 0.7 % in the plain sum, which weighs its core; twice the tolerance there keeps such copies
    /// and refuses the campfire's, 1–3 % off).
    pub(super) fn block_bias(&self, m: &FireVolume, fine: [f64; 2]) -> f64 {
        let coarse = self.line_sum(m, Some(self.line_step));
        let [a, b] = [0, 1].map(|k| coarse[k] / fine[k] - 1.0);
        if 0.5 * b.abs() > a.abs() {
            0.5 * b
        } else {
            a
        }
    }

    /// [`block_bias`](Self::block_bias) against the volume's own march.
    #[cfg(test)]
    pub(super) fn block_bias_alone(&self, m: &FireVolume) -> f64 {
        self.block_bias(m, self.line_sum(&self.vol, None))
    }

    /// Two sums of the lines' radiance (every bin) on the [`check_rays`](Self::check_rays), through `m` at `step`
    /// or (None) the volume's own march: next-event estimation's, each line over the density of its direction,
    /// and the plain one. The first is what the light adds up, but the rays of the fire's fringe, whose
    /// directions are rare, outweigh its core's there; the second weighs every ray alike — a copy must hold both
    /// (a campfire's 2³-voxel copy held the first to 0.3 % and summed 2.2–2.9 % low from any point beside it).
    /// NaN where nothing is seen (no check passes).
    pub(super) fn line_sum(&self, m: &FireVolume, step: Option<f64>) -> [f64; 2] {
        let c = m.channels();
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        let mut sum = [0.0; 2];
        for (ray, p) in self.check_rays() {
            match step {
                Some(s) => m.integrate_stepped_at(&ray, 0.0, s, &mut l, &mut t),
                None => m.integrate_at(&ray, 0.0, &mut l, &mut t),
            };
            let e = l.iter().sum::<f64>();
            sum[0] += e / p;
            sum[1] += e;
        }
        if step.is_none() && !(sum[0] > 0.0 && sum[1] > 0.0) {
            return [f64::NAN; 2];
        }
        sum
    }

    /// The rays of the line's build-time checks and the density of each one's direction: [`BLOCK_RAYS`] from a
    /// sphere around the fire toward points this light samples (each line over its direction's density is what
    /// next-event estimation adds up, whose mean is the emission over all directions, however the light aims).
    pub(super) fn check_rays(&self) -> impl Iterator<Item = (crate::volume::Ray, f64)> + '_ {
        let [p0, p1] = self.vol.bounds();
        let (centre, radius) = ((p0 + p1) * 0.5, 0.75 * (p1 - p0).length());
        let mut rng = crate::rng::Rng::new(0x5eed_b10c);
        (0..BLOCK_RAYS).filter_map(move |k| {
            let u = [(); 6].map(|_| rng.next_f64());
            let x = self.sample_at(u, 0.0).point;
            // A uniform direction from the centre places the origin on the sphere.
            let (z, phi) = (
                2.0 * rng.next_f64() - 1.0,
                std::f64::consts::TAU * rng.next_f64(),
            );
            let r = (1.0 - z * z).max(0.0).sqrt();
            let o = centre + DVec3::new(r * phi.cos(), r * phi.sin(), z) * radius;
            let ray = crate::volume::Ray {
                o,
                d: x - o,
                t0: 0.0,
                // (The origin is at least a quarter of the box's diagonal from x and at most 1.25 diagonals from
                // the box's far side: past it by t = 5.)
                t1: 8.0,
                seed: k,
                first: None,
            };
            let p = self.pdf_direction_at(o, ray.d, 0.0);
            (p > 0.0).then_some((ray, p))
        })
    }
}
