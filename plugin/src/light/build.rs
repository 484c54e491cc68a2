//! The light's build: the weights over the fire's bricks (by power, luminance or escaping power), dilated for
//! trilinear emission, their CDF, the embers' share; the line estimate's copy of the fire and its channels,
//! each checked against the volume's march.

use super::weigh::Weigher;
use super::*;

impl FireLight {
    /// The bins the coarse line marches (`linechannels`; `None`: all of them).
    pub(super) fn choose_channels(
        &self,
        asked: usize,
    ) -> Result<Option<crate::volume::LineChannels>, Error> {
        let c = self.vol.channels();
        if asked == 1 || (asked > 32 && asked < c) {
            return Err(Error::invalid(
                "light",
                "linechannels",
                asked.to_string(),
                "0 (chosen), 2 to 32 bins, or at least the volume's bins (all of them)",
            ));
        }
        // (At the volume's own step the line is the volume's march, every bin.)
        if !(self.line_step > self.vol.step_length()) || asked >= c {
            return Ok(None);
        }
        let target = self.mip.as_deref().unwrap_or(&self.vol);
        let k = if asked == 0 { LINE_CHANNELS } else { asked };
        let Some(lc) = target.line_channels(k) else {
            return Ok(None);
        };
        if asked == 0 && !(self.channel_bias(target, &lc) <= CHANNEL_BIAS) {
            return Ok(None);
        }
        Ok(Some(lc))
    }

    /// The largest relative difference in X, Y or Z between the line of `target` in the bins of `lc` and in all,
    /// in next-event estimation's sum over the light's check rays ([`check_rays`](Self::check_rays)).
    pub(super) fn channel_bias(
        &self,
        target: &FireVolume,
        lc: &crate::volume::LineChannels,
    ) -> f64 {
        let c = target.channels();
        let xyz = target.channel_xyz();
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        let (mut few, mut all) = (DVec3::ZERO, DVec3::ZERO);
        let sum = |l: &[f64], p: f64| (0..c).map(|k| xyz[k] * (l[k] / p)).sum::<DVec3>();
        for (ray, p) in self.check_rays() {
            target.integrate_stepped_at(&ray, 0.0, self.line_step, &mut l, &mut t);
            all += sum(&l, p);
            if target
                .integrate_channels(lc, &ray, self.line_step, &mut l, &mut t)
                .is_none()
            {
                return f64::INFINITY;
            }
            few += sum(&l, p);
        }
        if all.min_element() > 0.0 {
            (few / all - 1.0).abs().max_element()
        } else {
            f64::INFINITY
        }
    }

    pub(super) fn build(
        vol: Arc<FireVolume>,
        weighting: Weighting,
        cell: usize,
    ) -> Result<FireLight, Error> {
        let start = Instant::now();
        // Nothing to sample: refused before a weight per voxel is allocated (a 16-byte raw file claiming 600³
        // voxels and no temperature built a 3.4 GB light).
        if !vol.can_emit() && vol.embers().is_none_or(|e| e.len() == 0) {
            return Err(no_emission());
        }
        let ds = vol.dataset();
        let dims = ds.dims();
        let voxel = ds.voxel_size();
        let c = vol.channels();
        let xyz = vol.channel_xyz();
        let widths: Vec<f64> = match vol.color_mode() {
            crate::volume::ColorMode::Spectral(g) => vec![g.width_nm(); g.count()],
            crate::volume::ColorMode::Rgb => vec![1.0; 3],
        };
        // Full-spectrum power per unit density over T (soot), and per unit N (lines), physical mode only.
        let src = vol.source().cloned();
        // The bricks to weigh: the stored ones and their neighbours; all of them if a background emits (a
        // grid whose empty bricks read a non-zero value).
        let stored = ds.topology();
        let background_emits = ds.channels().iter().any(|ch| ch.grid.background() != 0.0);
        let topo = if background_emits {
            crate::grid::Topology::build_offset(dims, stored.offset(), |_| true)
        } else {
            stored
                .spread([0; 3], -1, 1)
                .and_then(|list| crate::grid::Topology::from_bricks(dims, stored.offset(), list))
        }
        .ok_or_else(no_emission)?;
        let topo = Arc::new(topo);
        // At most two floats per covered voxel while building (the cells' weights, at `cell 1` one a voxel, and
        // the voxels' weights: a few layers of them, all for `escaping`), within what the volume's budget
        // (`maxbytes`) leaves after its grids and tables.
        let n = topo.values_len();
        let need = (n as u64).saturating_mul(8);
        if need > vol.spare_bytes() {
            return Err(Error::TooLarge {
                file: "fire light".into(),
                what: format!(
                    "the weights of {} bricks of 8³ voxels",
                    topo.active_bricks()
                ),
                bytes: need,
                cap: vol.spare_bytes(),
            });
        }
        let too_many = || {
            Error::invalid(
                "light",
                "fire",
                format!("{n} voxels"),
                "a fire whose per-voxel weights (8 bytes each) the allocator can hold",
            )
        };
        // The weights, a block per brick holding any (indexed by the brick's slot), kept only while a
        // neighbouring brick's dilation may read them.
        let mut w: Vec<Option<Box<[f32; 512]>>> = Vec::new();
        w.try_reserve_exact(n / 512).map_err(|_| too_many())?;
        w.resize_with(n / 512, || None);
        let (mut pw, mut plm) = (0.0, 0.0);
        let mut bricks: Vec<[usize; 3]> = Vec::with_capacity(topo.active_bricks());
        let mut slot_bricks = vec![[0u32; 3]; topo.active_bricks() + 1];
        topo.for_each_slot(|b, slot| {
            bricks.push(b);
            slot_bricks[slot] = b.map(|v| v as u32);
        });
        // (Indices into the weights are u32.)
        if n > u32::MAX as usize {
            return Err(too_many());
        }
        // Per brick (independent: each writes its own slot of the weights), in parallel chunks of bricks under the
        // build's thread budget; the power sums are added brick by brick in the bricks' order, so the light is the
        // same on any number of threads.
        let weigher = Weigher::new(&vol, &topo, weighting, (&xyz, &widths), src.as_ref());
        let run = |part: &[usize]| {
            let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
            part.iter()
                .map(|&i| {
                    let mut out = None;
                    let sums = weigher.brick(&bricks[i], &mut sa, &mut ss, &mut j, &mut out);
                    (sums, out)
                })
                .collect::<Vec<_>>()
        };
        let (cw, found, emitting) = cell_weights(
            &vol,
            &topo,
            &bricks,
            w,
            &run,
            (cell, weighting == Weighting::Escaping),
            voxel,
            &too_many,
        )?;
        let slot_of = |b: &[usize; 3]| {
            let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
            topo.index(span[0].0, span[1].0, span[2].0) / 512
        };
        let per = (8 / cell).pow(3);
        // The power sums brick by brick in the bricks' order: the light is the same on any number of threads.
        for &(bpw, bplm, _) in &found {
            pw += bpw;
            plm += bplm;
        }
        let w = cw;
        let vv = voxel.x * voxel.y * voxel.z;
        let power_w = 4.0 * std::f64::consts::PI * vv * pw;
        let power_lm = 4.0 * std::f64::consts::PI * vv * plm;
        // The bricks holding weight and their CDF (a cell's weights lie in its brick's slot, those outside the
        // grid's dims 0).
        let (brick_slots, cdf, mut total) = brick_cdf(bricks.iter().map(slot_of), &w, per);
        // The embers, by the same measure (their share of the pdf after the fire's).
        let fire_total = total;
        let (mut power_w, mut power_lm) = (power_w, power_lm);
        let (mut ember_w, mut ember_cdf) = (Vec::new(), Vec::new());
        if let Some(em) = vol.embers() {
            let intensity = src.as_ref().map_or(1.0, |s| s.intensity());
            (ember_w, ember_cdf) = ember_weights(
                em,
                intensity,
                weighting,
                (&xyz, &widths),
                vv,
                (&mut total, &mut power_w, &mut power_lm),
            )
            .ok_or_else(too_many)?;
        }
        if !(total > 0.0) {
            return Err(no_emission());
        }
        let ember_p = ember_w.iter().map(|w| w / total).collect();
        Ok(FireLight {
            vol,
            weighting,
            dims,
            voxel,
            total,
            topo,
            cell,
            line_step: 0.0,
            correction: 0.0,
            mip: None,
            channels: None,
            brick_density: Vec::new(),
            weights: w,
            emitting,
            cdf,
            slot_bricks,
            brick_slots,
            fire_total,
            ember_p,
            ember_cdf,
            power_w,
            power_lm,
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }
}

/// Per brick of `bricks` (whose mean extinctions, m⁻¹, are `ext`), the mean over the six axis directions of
/// e^{−τ} from its centre to the grid's edge, τ summed over the bricks on the way (half its own); bricks not
/// listed hold nothing. `size`: a brick's extent per axis. `None` when the bricks' box (4 bytes each) is larger
/// than `budget` or the allocator refuses it.
pub(super) fn escape_fractions(
    topo: &crate::grid::Topology,
    bricks: &[[usize; 3]],
    ext: &[f64],
    size: DVec3,
    budget: u64,
) -> Option<Vec<f64>> {
    let nb = topo.bricks();
    let n = nb[0].checked_mul(nb[1])?.checked_mul(nb[2])?;
    if (n as u64).saturating_mul(8) > budget {
        return None;
    }
    let at = |b: [usize; 3]| b[0] + nb[0] * (b[1] + nb[1] * b[2]);
    let mut sigma = crate::alloc::filled(n, 0f32)?;
    for (b, &e) in bricks.iter().zip(ext) {
        sigma[at(*b)] = e as f32;
    }
    // Per axis, the optical depth from each brick's far face to the edge, both ways, by running sums along
    // each line of bricks; e^{−τ} of both directions accumulated per brick.
    let mut sum = crate::alloc::filled(n, 0f32)?;
    for a in 0..3 {
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        for i in 0..nb[u] {
            for j in 0..nb[v] {
                let line = |k: usize| {
                    let mut b = [0; 3];
                    (b[a], b[u], b[v]) = (k, i, j);
                    at(b)
                };
                for forward in [true, false] {
                    let mut beyond = 0.0f64;
                    for step in 0..nb[a] {
                        let k = if forward { nb[a] - 1 - step } else { step };
                        let s = sigma[line(k)] as f64 * size[a];
                        sum[line(k)] += (-(beyond + 0.5 * s)).exp() as f32;
                        beyond += s;
                    }
                }
            }
        }
    }
    Some(bricks.iter().map(|b| sum[at(*b)] as f64 / 6.0).collect())
}

/// `max(w, f · max of the 26 neighbours)` for each voxel of brick `b` of the topology, from the weights `w` of it
/// and its neighbours, into `out` (its 512 samples in the storage's order): a separable 3×3×3 maximum, three
/// passes over a 10³ neighbourhood (the brick and one voxel around it). A voxel outside the lattice is no
/// neighbour; one in a brick the topology does not hold is 0 and never raised (every voxel a stored weight's
/// dilation reaches is held: the light's topology covers the bricks around the data).
fn dilate_brick(
    w: impl Fn(usize) -> f32,
    topo: &crate::grid::Topology,
    b: [usize; 3],
    f: f32,
    out: &mut [f32; 512],
) {
    const S: usize = 10;
    let dims = topo.dims();
    let off = topo.offset();
    // Local coordinate L ∈ [−1, 8] per axis is sample b·8 − off + L; `cell` its place in the lattice, if any.
    let sample = |l: [usize; 3]| -> Option<[usize; 3]> {
        let mut v = [0; 3];
        for a in 0..3 {
            let x = (b[a] * 8 + l[a]).checked_sub(off[a] + 1)?;
            if x >= dims[a] {
                return None;
            }
            v[a] = x;
        }
        Some(v)
    };
    let at = |x: usize, y: usize, z: usize| x + S * (y + S * z);
    let (mut m, mut held, mut inside) = ([0f32; S * S * S], [false; S * S * S], [[false; S]; 3]);
    for (a, row) in inside.iter_mut().enumerate() {
        for (l, cell) in row.iter_mut().enumerate() {
            *cell = (b[a] * 8 + l)
                .checked_sub(off[a] + 1)
                .is_some_and(|x| x < dims[a]);
        }
    }
    for z in 0..S {
        for y in 0..S {
            for x in 0..S {
                if let Some(v) = sample([x, y, z]) {
                    let n = topo.index(v[0], v[1], v[2]);
                    if n >= 512 {
                        m[at(x, y, z)] = w(n);
                        held[at(x, y, z)] = true;
                    }
                }
            }
        }
    }
    let mut src = [0f32; S * S * S];
    for axis in 0..3 {
        src.copy_from_slice(&m);
        for z in 0..S {
            for y in 0..S {
                for x in 0..S {
                    let p = at(x, y, z);
                    if !held[p] {
                        continue;
                    }
                    let l = [x, y, z];
                    let mut o = m[p];
                    // (A neighbour beyond the neighbourhood is read only for values no later pass uses.)
                    if l[axis] > 0 && inside[axis][l[axis] - 1] {
                        let mut q = l;
                        q[axis] -= 1;
                        o = o.max(src[at(q[0], q[1], q[2])]);
                    }
                    if l[axis] + 1 < S && inside[axis][l[axis] + 1] {
                        let mut q = l;
                        q[axis] += 1;
                        o = o.max(src[at(q[0], q[1], q[2])]);
                    }
                    m[p] = o;
                }
            }
        }
    }
    *out = [0f32; 512];
    for z in 1..9 {
        for y in 1..9 {
            for x in 1..9 {
                if let Some(v) = sample([x, y, z]) {
                    let n = topo.index(v[0], v[1], v[2]);
                    out[n % 512] = w(n).max(f * m[at(x, y, z)]);
                }
            }
        }
    }
}

/// `f` over `items` in `workers` contiguous parts at once (on this thread for one), its results in the items'
/// order whatever the threads.
fn in_parts<T: Send>(
    items: &[usize],
    workers: usize,
    f: &(dyn Fn(&[usize]) -> Vec<T> + Sync),
) -> Vec<T> {
    if workers <= 1 {
        return f(items);
    }
    let chunk = items.len().div_ceil(workers).max(1);
    let parts: Vec<Vec<T>> = crate::par::scope(|sc| {
        let handles: Vec<_> = items
            .chunks(chunk)
            .map(|part| sc.spawn(move || f(part)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    });
    parts.into_iter().flatten().collect()
}

/// The bricks (by their slots, in the bricks' order) whose cells (`per` weights each, at the slot's place in `w`)
/// hold weight, and the CDF over them, with its total.
fn brick_cdf(
    slots: impl Iterator<Item = usize>,
    w: &[f32],
    per: usize,
) -> (Vec<u32>, Vec<f64>, f64) {
    let (mut brick_slots, mut cdf) = (Vec::new(), Vec::new());
    let mut total = 0.0;
    for slot in slots {
        let ws = &w[slot * per..(slot + 1) * per];
        let sum: f64 = ws.iter().map(|&v| v as f64).sum();
        if sum > 0.0 {
            total += sum;
            brick_slots.push(slot as u32);
            cdf.push(total);
        }
    }
    (brick_slots, cdf, total)
}

/// The embers' weights, by the same measure as the fire's voxels: an ember is a Lambertian sphere, π r² L per
/// steradian on average, the power j V of a voxel — in the voxels' units, divided by a voxel's volume `vv`. Their
/// CDF continues the fire's from `total`, and their power (W) and luminous flux (lm) add to the fire's, each
/// advanced ember by ember. `None` when the allocator refuses their weights.
fn ember_weights(
    em: &crate::embers::Embers,
    intensity: f64,
    weighting: Weighting,
    (xyz, widths): (&[DVec3], &[f64]),
    vv: f64,
    (total, power_w, power_lm): (&mut f64, &mut f64, &mut f64),
) -> Option<(Vec<f64>, Vec<f64>)> {
    let c = widths.len();
    let n = em.len();
    let mut ember_w = crate::alloc::filled(n, 0.0)?;
    let mut ember_cdf = crate::alloc::filled(n, 0.0)?;
    let eps = em.emissivity();
    let mut l = vec![0.0; c];
    for i in 0..n {
        em.radiance(i, 0.0, &mut l);
        let r = em.radius(i);
        let area = std::f64::consts::PI * r * r;
        let lum: f64 = (0..c).map(|q| l[q] * xyz[q].y).sum();
        let band: f64 = (0..c).map(|q| l[q] * widths[q]).sum();
        ember_w[i] =
            area * match weighting {
                Weighting::Luminance => lum,
                Weighting::Power | Weighting::Escaping => band,
            } / vv;
        *total += ember_w[i];
        ember_cdf[i] = *total;
        *power_lm += 4.0 * std::f64::consts::PI * area * lum;
        *power_w +=
            intensity * firemedium_core::ember::radiated_power(eps, r, em.temperature(i, 0.0));
    }
    Some((ember_w, ember_cdf))
}

/// The cells' weights (`cell`³ voxels each, a brick's in its slot), from the voxels' weights `w` (a block per
/// brick, filled by `run` over parts of the bricks, in parallel under the build's thread budget): each brick's
/// voxels dilated on their own for trilinear emission and, for `escaping`, scaled by their escape fractions.
/// With the bricks' sums (power, luminance, extinction) in their order and the emitting voxels' count.
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn cell_weights(
    vol: &FireVolume,
    topo: &crate::grid::Topology,
    bricks: &[[usize; 3]],
    mut w: Vec<Option<Box<[f32; 512]>>>,
    run: &(dyn Fn(&[usize]) -> Vec<BrickWeights> + Sync),
    (cell, escaping): (usize, bool),
    voxel: DVec3,
    too_many: &dyn Fn() -> Error,
) -> Result<(Vec<f32>, Vec<(f64, f64, f64)>, usize), Error> {
    let workers = crate::par::threads(16).min(bricks.len().max(1));
    let ds = vol.dataset();
    // With trilinear interpolation a voxel whose centre is dark still emits where it borders a bright one
    // (up to half the neighbour's value at the shared face, about 1/8 of it averaged over the voxel): the
    // pdf's support must cover that, or MIS would drop it. Such voxels get 1/8 of their brightest neighbour.
    let trilinear = ds.interpolation() == crate::grid::Interpolation::Trilinear;
    let slot_of = |b: &[usize; 3]| {
        let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
        topo.index(span[0].0, span[1].0, span[2].0) / 512
    };
    let side = 8 / cell;
    let per = side * side * side;
    // The bricks by z layer, each layer in the bricks' order. A layer's weights are found before the layer
    // below it is dilated and dropped once the layer above it has been: three layers of weights held at a
    // time, not the fire's (all of them for `escaping`, whose factors need every brick's extinction first).
    let mut layers = vec![Vec::new(); topo.bricks()[2]];
    for (i, b) in bricks.iter().enumerate() {
        layers[b[2]].push(i);
    }
    let mut found = vec![(0.0, 0.0, 0.0); bricks.len()];
    let mut keep: Vec<f32> = Vec::new();
    // The cells' weights: each brick's voxels dilated on their own (from the weights around it) and summed
    // per cell (in f64; at `cell 1` a cell is a voxel, its weight the voxel's) — no second array of voxel
    // weights.
    let mut emitting = 0;
    let mut cw = crate::alloc::filled(topo.values_len() / 512 * per, 0f32).ok_or_else(too_many)?;
    let mut next = 0;
    for z in 0..layers.len() {
        // When the layer above this is not yet weighed, a batch of layers: up to it, and enough bricks to
        // keep every worker busy (every layer for `escaping`).
        let mut batch: Vec<usize> = Vec::new();
        if next < z + 2 {
            while next < layers.len() && (escaping || next < z + 2 || batch.len() < workers * 256) {
                batch.extend(&layers[next]);
                next += 1;
            }
        }
        // In rounds of 512 bricks per worker (a worker's blocks held until its round is placed).
        for round in batch.chunks(workers * 512) {
            for (&i, (sums, block)) in round.iter().zip(in_parts(round, workers, run)) {
                found[i] = sums;
                w[slot_of(&bricks[i])] = block;
            }
        }
        if escaping && z == 0 {
            let extinction: Vec<f64> = found.iter().map(|f| f.2).collect();
            keep = escape_fractions(topo, bricks, &extinction, voxel * 8.0, vol.spare_bytes())
                .ok_or_else(too_many)?
                .into_iter()
                .map(|f| (ESCAPE_FLOOR + (1.0 - ESCAPE_FLOOR) * f) as f32)
                .collect();
        }
        let weight = |n: usize| w[n / 512].as_ref().map_or(0.0, |b| b[n % 512]);
        // Each brick of the layer dilated and summed per cell on its own (the workers take a share of the layer
        // each), then placed: its slot, its cells' weights and its emitting voxels.
        let dilated = |part: &[usize]| -> Vec<(usize, Vec<f32>, usize)> {
            part.iter()
                .map(|&i| {
                    let b = &bricks[i];
                    let slot = slot_of(b);
                    let mut ws = [0f32; 512];
                    if trilinear {
                        dilate_brick(weight, topo, *b, 0.125, &mut ws);
                    } else if let Some(block) = &w[slot] {
                        ws = **block;
                    }
                    if let Some(&k) = keep.get(i) {
                        ws.iter_mut().for_each(|v| *v *= k);
                    }
                    let (mut sums, mut count) = ([0f64; 512], 0);
                    for (l, &v) in ws.iter().enumerate() {
                        if v > 0.0 {
                            count += 1;
                            let c = (l % 8) / cell
                                + side * ((l / 8 % 8) / cell + side * ((l / 64) / cell));
                            sums[c] += v as f64;
                        }
                    }
                    (slot, sums[..per].iter().map(|&v| v as f32).collect(), count)
                })
                .collect()
        };
        let layer = &layers[z];
        let shared = if layer.len() < 64 { 1 } else { workers };
        for (slot, cells, count) in in_parts(layer, shared, &dilated) {
            cw[slot * per..(slot + 1) * per].copy_from_slice(&cells);
            emitting += count;
        }
        if !escaping && z > 0 {
            for &i in &layers[z - 1] {
                w[slot_of(&bricks[i])] = None;
            }
        }
    }
    Ok((cw, found, emitting))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dilation_brick_by_brick_is_the_27_neighbour_maximum() {
        // A lattice whose bricks are offset from its origin and cut at its far faces, some bricks missing (their
        // voxels count as 0), sparse weights — each where its 26 neighbours are covered, as the light's bricks
        // around the data are —: every covered voxel's dilated weight is max(w, f · the largest of its 26
        // neighbours and itself), computed here voxel by voxel.
        let dims = [21, 14, 19];
        let off = [3, 5, 1];
        let missing = |b: [usize; 3]| b == [1, 1, 1] || b == [0, 2, 2];
        let topo = crate::grid::Topology::build_offset(dims, off, |b| !missing(b)).unwrap();
        let mut bricks = Vec::new();
        topo.for_each_slot(|b, _| bricks.push(b));
        let covered = |v: [usize; 3]| !missing(topo.brick_of(v));
        let mut w = vec![0f32; topo.values_len()];
        let mut rng = firemedium_core::rng::Rng::new(5);
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let around = (0..27).all(|n| {
                        let q = [i + n % 3, j + n / 3 % 3, k + n / 9];
                        q.contains(&0)
                            || (0..3).any(|a| q[a] > dims[a])
                            || covered(q.map(|x| x - 1))
                    });
                    if around && rng.next_f64() < 0.05 {
                        w[topo.index(i, j, k)] = (1.0 + 9.0 * rng.next_f64()) as f32;
                    }
                }
            }
        }
        // Brick by brick, from the weights around each.
        let mut d = vec![0f32; w.len()];
        for b in &bricks {
            let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
            let slot = topo.index(span[0].0, span[1].0, span[2].0) / 512;
            let mut out = [0f32; 512];
            dilate_brick(|n| w[n], &topo, *b, 0.125, &mut out);
            d[slot * 512..(slot + 1) * 512].copy_from_slice(&out);
        }
        let at = |v: [i64; 3]| -> f32 {
            if (0..3).any(|a| v[a] < 0 || v[a] >= dims[a] as i64) {
                return 0.0;
            }
            let v = v.map(|x| x as usize);
            if covered(v) {
                w[topo.index(v[0], v[1], v[2])]
            } else {
                0.0
            }
        };
        let (mut checked, mut raised) = (0, 0);
        for k in 0..dims[2] as i64 {
            for j in 0..dims[1] as i64 {
                for i in 0..dims[0] as i64 {
                    let v = [i, j, k].map(|x| x as usize);
                    if !covered(v) {
                        continue;
                    }
                    let mut m = 0f32;
                    for dk in -1..=1 {
                        for dj in -1..=1 {
                            for di in -1..=1 {
                                m = m.max(at([i + di, j + dj, k + dk]));
                            }
                        }
                    }
                    let own = at([i, j, k]);
                    let want = own.max(0.125 * m);
                    assert_eq!(d[topo.index(v[0], v[1], v[2])], want, "{v:?}");
                    checked += 1;
                    raised += usize::from(want > own);
                }
            }
        }
        assert!(checked > 4000 && raised > 1000, "{checked} {raised}");
    }
}
