//! Shapes and their BVH: triangles (from `trianglemesh`, `bilinearmesh`, `plymesh`), and analytic `sphere`,
//! `disk` and `cylinder` in their object space. The BVH is obvhs's BVH2 (PLOC build) over primitive boxes.
//! Object instances are one primitive each that points at their object's own BVH (shared, never copied), with
//! the instance's transform: pbrt-v4's two-level scheme, so memory grows with the objects, not the instances.

use glam::{Affine3A, Vec2, Vec3A};
use obvhs::{aabb::Aabb, bvh2::Bvh2, ray::Ray as BRay, ray::RayHit, Boundable, BvhBuildParams};
use std::f32::consts::PI;
use std::sync::Arc;

/// Geometry of one primitive.
#[derive(Debug, Clone)]
pub enum Geom {
    Triangle {
        p: [Vec3A; 3],
        n: Option<[Vec3A; 3]>,
        uv: [Vec2; 3],
    },
    Sphere {
        to_world: Affine3A,
        to_obj: Affine3A,
        r: f32,
        /// pbrt-v4's partial sphere: the part with z in [zmin, zmax] and φ in [0, phimax] (whole: −r, r, 2π).
        zmin: f32,
        zmax: f32,
        phimax: f32,
    },
    Disk {
        to_world: Affine3A,
        to_obj: Affine3A,
        h: f32,
        r: f32,
        ri: f32,
        /// The part with φ in [0, phimax] (whole: 2π), as for spheres and cylinders.
        phimax: f32,
    },
    Cylinder {
        to_world: Affine3A,
        to_obj: Affine3A,
        r: f32,
        zmin: f32,
        zmax: f32,
        phimax: f32,
    },
    /// An `ObjectInstance`: the object's primitives under `to_world`, shared by every instance of it.
    Instance {
        to_world: Affine3A,
        to_obj: Affine3A,
        object: Arc<Bvh>,
    },
}

/// A primitive with what the renderer attaches to it.
#[derive(Debug, Clone)]
pub struct Prim {
    pub geom: Geom,
    /// Material index; `None` is pbrt's `interface` (no surface: only a medium boundary).
    pub material: Option<usize>,
    pub area_light: Option<usize>,
    /// (inside, outside) media, when the shape carries a MediumInterface.
    pub media: Option<(Option<usize>, Option<usize>)>,
    /// ReverseOrientation: the normal points the other way.
    pub reverse: bool,
}

/// A surface hit.
#[derive(Debug, Clone, Copy)]
pub struct Hit {
    pub t: f32,
    pub p: Vec3A,
    /// Geometric normal (after ReverseOrientation): "outside" is where it points.
    pub ng: Vec3A,
    /// Shading normal, on the side of `ng`.
    pub ns: Vec3A,
    pub uv: Vec2,
    /// The scene's primitive that was hit (an instance, for a hit inside one)...
    pub prim: usize,
    /// ...and, inside an instance, the object's primitive (see [`Bvh::prim`]).
    pub part: Option<usize>,
}

impl Boundable for Prim {
    fn aabb(&self) -> Aabb {
        match &self.geom {
            Geom::Triangle { p, .. } => {
                let mut b = Aabb::INVALID;
                for v in p {
                    b.extend(*v);
                }
                b
            }
            Geom::Sphere { to_world, r, .. } => {
                box_of(to_world, Vec3A::splat(-*r), Vec3A::splat(*r))
            }
            Geom::Disk { to_world, h, r, .. } => {
                box_of(to_world, Vec3A::new(-r, -r, *h), Vec3A::new(*r, *r, *h))
            }
            Geom::Cylinder {
                to_world,
                r,
                zmin,
                zmax,
                ..
            } => box_of(
                to_world,
                Vec3A::new(-r, -r, *zmin),
                Vec3A::new(*r, *r, *zmax),
            ),
            Geom::Instance {
                to_world, object, ..
            } => {
                let b = object.bounds();
                box_of(to_world, b.min, b.max)
            }
        }
    }
}

fn box_of(m: &Affine3A, lo: Vec3A, hi: Vec3A) -> Aabb {
    let mut b = Aabb::INVALID;
    for i in 0..8 {
        let c = Vec3A::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let _ = b.extend(m.transform_point3a(c));
    }
    // Padding keeps flat boxes (disks, axis-aligned triangles) traversable.
    b.min -= Vec3A::splat(1e-6);
    b.max += Vec3A::splat(1e-6);
    b
}

/// The ray parameter of the nearest hit of `g` in (tmin, tmax), or infinity.
pub fn intersect_t(g: &Geom, o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> f32 {
    let ok = |t: f32| t > tmin && t < tmax;
    match g {
        Geom::Triangle { p, .. } => {
            // Möller–Trumbore.
            let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
            let pv = d.cross(e2);
            let det = e1.dot(pv);
            if det.abs() < 1e-12 {
                return f32::INFINITY;
            }
            let inv = 1.0 / det;
            let tv = o - p[0];
            let u = tv.dot(pv) * inv;
            if !(0.0..=1.0).contains(&u) {
                return f32::INFINITY;
            }
            let qv = tv.cross(e1);
            let v = d.dot(qv) * inv;
            if v < 0.0 || u + v > 1.0 {
                return f32::INFINITY;
            }
            let t = e2.dot(qv) * inv;
            if ok(t) {
                t
            } else {
                f32::INFINITY
            }
        }
        Geom::Sphere {
            to_obj,
            r,
            zmin,
            zmax,
            phimax,
            ..
        } => {
            let (oo, dd) = (to_obj.transform_point3a(o), to_obj.transform_vector3a(d));
            let (a, b, c) = (dd.dot(dd), 2.0 * oo.dot(dd), oo.dot(oo) - r * r);
            let disc = b * b - 4.0 * a * c;
            if disc < 0.0 {
                return f32::INFINITY;
            }
            let q = disc.sqrt();
            let (t0, t1) = ((-b - q) / (2.0 * a), (-b + q) / (2.0 * a));
            let whole = *zmin <= -r && *zmax >= *r && *phimax >= 2.0 * PI;
            let kept = |t: f32| {
                if whole {
                    return true;
                }
                let p = oo + dd * t;
                p.z >= *zmin && p.z <= *zmax && within_phi(p, *phimax)
            };
            if ok(t0) && kept(t0) {
                t0
            } else if ok(t1) && kept(t1) {
                t1
            } else {
                f32::INFINITY
            }
        }
        Geom::Disk {
            to_obj,
            h,
            r,
            ri,
            phimax,
            ..
        } => {
            let (oo, dd) = (to_obj.transform_point3a(o), to_obj.transform_vector3a(d));
            if dd.z == 0.0 {
                return f32::INFINITY;
            }
            let t = (h - oo.z) / dd.z;
            let q = oo + dd * t;
            let r2 = q.x * q.x + q.y * q.y;
            if ok(t) && r2 <= r * r && r2 >= ri * ri && within_phi(q, *phimax) {
                t
            } else {
                f32::INFINITY
            }
        }
        Geom::Cylinder {
            to_obj,
            r,
            zmin,
            zmax,
            phimax,
            ..
        } => {
            let (oo, dd) = (to_obj.transform_point3a(o), to_obj.transform_vector3a(d));
            let a = dd.x * dd.x + dd.y * dd.y;
            if a == 0.0 {
                return f32::INFINITY;
            }
            let b = 2.0 * (dd.x * oo.x + dd.y * oo.y);
            let c = oo.x * oo.x + oo.y * oo.y - r * r;
            let disc = b * b - 4.0 * a * c;
            if disc < 0.0 {
                return f32::INFINITY;
            }
            let q = disc.sqrt();
            for t in [(-b - q) / (2.0 * a), (-b + q) / (2.0 * a)] {
                let z = oo.z + dd.z * t;
                if ok(t) && z >= *zmin && z <= *zmax && within_phi(oo + dd * t, *phimax) {
                    return t;
                }
            }
            f32::INFINITY
        }
        Geom::Instance { to_obj, object, .. } => {
            // The object-space ray keeps the parameter t (its direction is not renormalised).
            let (oo, dd) = (to_obj.transform_point3a(o), to_obj.transform_vector3a(d));
            object
                .nearest(oo, dd, tmin, tmax)
                .map_or(f32::INFINITY, |(t, _)| t)
        }
    }
}

/// Whether object-space point `p` lies at φ ≤ `phimax` (always, for a whole turn).
fn within_phi(p: Vec3A, phimax: f32) -> bool {
    phimax >= 2.0 * PI || p.y.atan2(p.x).rem_euclid(2.0 * PI) <= phimax
}

/// Hit details at parameter t; `part` is the object's primitive when `prims[id]` is an instance.
pub fn hit_at(prims: &[Prim], id: usize, part: Option<usize>, o: Vec3A, d: Vec3A, t: f32) -> Hit {
    let pr = &prims[id];
    let p = o + d * t;
    let (mut ng, mut ns, uv) = match &pr.geom {
        Geom::Instance { to_obj, object, .. } => {
            let (oo, dd) = (to_obj.transform_point3a(o), to_obj.transform_vector3a(d));
            let inner = hit_at(&object.prims, part.unwrap_or(0), None, oo, dd, t);
            return Hit {
                t,
                p,
                ng: normal_to_world(to_obj, inner.ng),
                ns: normal_to_world(to_obj, inner.ns),
                uv: inner.uv,
                prim: id,
                part: Some(inner.prim),
            };
        }
        Geom::Triangle { p: v, n, uv } => {
            let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            // Barycentrics of p.
            let (e1, e2, ep) = (v[1] - v[0], v[2] - v[0], p - v[0]);
            let (d00, d01, d11, d20, d21) =
                (e1.dot(e1), e1.dot(e2), e2.dot(e2), ep.dot(e1), ep.dot(e2));
            let den = (d00 * d11 - d01 * d01).max(1e-30);
            let b1 = (d11 * d20 - d01 * d21) / den;
            let b2 = (d00 * d21 - d01 * d20) / den;
            let b0 = 1.0 - b1 - b2;
            let ns = n
                .map(|n| (n[0] * b0 + n[1] * b1 + n[2] * b2).normalize_or_zero())
                .unwrap_or(ng);
            let uv = uv[0] * b0 + uv[1] * b1 + uv[2] * b2;
            // pbrt: the geometric normal follows the shading normal's side when normals are given.
            let ng = if n.is_some() && ng.dot(ns) < 0.0 {
                -ng
            } else {
                ng
            };
            (ng, ns, uv)
        }
        Geom::Sphere {
            to_world, to_obj, ..
        } => {
            let q = to_obj.transform_point3a(p);
            let n = normal_to_world(to_obj, q);
            let phi = q.y.atan2(q.x).rem_euclid(2.0 * PI);
            let _ = to_world;
            (
                n,
                n,
                Vec2::new(
                    phi / (2.0 * PI),
                    (q.z / q.length().max(1e-30)).clamp(-1.0, 1.0).acos() / PI,
                ),
            )
        }
        Geom::Disk { to_obj, r, .. } => {
            let q = to_obj.transform_point3a(p);
            let n = normal_to_world(to_obj, Vec3A::Z);
            let rr = (q.x * q.x + q.y * q.y).sqrt();
            (
                n,
                n,
                Vec2::new(
                    q.y.atan2(q.x).rem_euclid(2.0 * PI) / (2.0 * PI),
                    1.0 - rr / r,
                ),
            )
        }
        Geom::Cylinder {
            to_obj, zmin, zmax, ..
        } => {
            let q = to_obj.transform_point3a(p);
            let n = normal_to_world(to_obj, Vec3A::new(q.x, q.y, 0.0));
            (
                n,
                n,
                Vec2::new(
                    q.y.atan2(q.x).rem_euclid(2.0 * PI) / (2.0 * PI),
                    (q.z - zmin) / (zmax - zmin),
                ),
            )
        }
    };
    if pr.reverse {
        ng = -ng;
        ns = -ns;
    }
    Hit {
        t,
        p,
        ng,
        ns,
        uv,
        prim: id,
        part: None,
    }
}

pub(super) fn normal_to_world(to_obj: &Affine3A, n_obj: Vec3A) -> Vec3A {
    // Normals transform by the inverse transpose of object→world, i.e. the transpose of world→object.
    to_obj
        .matrix3
        .transpose()
        .mul_vec3a(n_obj)
        .normalize_or_zero()
}

/// Primitives with their BVH.
pub struct Bvh {
    pub prims: Vec<Prim>,
    bvh: Option<Bvh2>,
    /// The BVH's entries when primitives share boxes ([`Shared`]); `None`: one entry per primitive.
    shared: Option<Shared>,
}

/// Primitives whose boxes are equal bit for bit, `SHARED` or more of them, as one BVH entry: no split can part
/// them, and a builder that tries (PLOC's nearest-neighbour search among ties) takes quadratic time — 32 000
/// coincident triangles built in 26.8 s, 100 000 instances of one sphere in 262 s.
struct Shared {
    /// Per entry, its box.
    boxes: Vec<Aabb>,
    /// Entry e's primitives are `members[start[e]..start[e + 1]]`, in scene order.
    start: Vec<u32>,
    members: Vec<u32>,
}

/// Whether PLOC would merge `boxes` a pair at a time: nested or collinear boxes (each inside the next, or along
/// one line) sorted along the Morton curve have merge costs that grow along the order, so each pass finds one
/// mutual pair and the build is quadratic (32 000 nested triangles: 26 s). Its first passes are simulated with
/// the nearest neighbour on either side (O(n) a pass): input where a pass merges fewer than 1 in 64 is chained.
fn chained(boxes: &[Aabb]) -> bool {
    const SMALL: usize = 4096;
    if boxes.len() <= SMALL {
        return false;
    }
    let mut bounds = Aabb::INVALID;
    for b in boxes {
        bounds.extend(b.center());
    }
    let extent = (bounds.max - bounds.min).max(Vec3A::splat(f32::MIN_POSITIVE));
    // 10 bits per axis, interleaved.
    let spread = |v: u32| {
        let mut x = v & 0x3ff;
        x = (x | x << 16) & 0x030000ff;
        x = (x | x << 8) & 0x0300f00f;
        x = (x | x << 4) & 0x030c30c3;
        (x | x << 2) & 0x09249249
    };
    let morton = |b: &Aabb| {
        let q =
            ((b.center() - bounds.min) / extent * 1023.0).clamp(Vec3A::ZERO, Vec3A::splat(1023.0));
        spread(q.x as u32) << 2 | spread(q.y as u32) << 1 | spread(q.z as u32)
    };
    let mut order: Vec<(u32, usize)> = boxes
        .iter()
        .enumerate()
        .map(|(i, b)| (morton(b), i))
        .collect();
    order.sort_unstable();
    let mut nodes: Vec<Aabb> = order.iter().map(|&(_, i)| boxes[i]).collect();
    while nodes.len() > SMALL {
        let n = nodes.len();
        let cost: Vec<f32> = (0..n - 1)
            .map(|i| nodes[i].union(&nodes[i + 1]).half_area())
            .collect();
        // Node i prefers its right neighbour when that union is no dearer than the left one.
        let right = |i: usize| i + 1 < n && (i == 0 || cost[i] <= cost[i - 1]);
        let mut next = Vec::with_capacity(n);
        let mut i = 0;
        while i < n {
            if right(i) && !right(i + 1) {
                next.push(nodes[i].union(&nodes[i + 1]));
                i += 2;
            } else {
                next.push(nodes[i]);
                i += 1;
            }
        }
        if (n - next.len()) * 64 < n {
            return true;
        }
        nodes = next;
    }
    false
}

/// A BVH of `boxes` by median splits of their centres along the widest axis (leaves of at most 2): O(n log n)
/// whatever the input, for the chained input PLOC builds in quadratic time.
fn median_bvh(boxes: &[Aabb]) -> Bvh2 {
    use obvhs::bvh2::node::Bvh2Node;
    let mut index: Vec<u32> = (0..boxes.len() as u32).collect();
    let mut nodes = vec![Bvh2Node::default()];
    let mut stack = vec![(0usize, 0usize, boxes.len(), 1usize)];
    let mut depth = 1;
    while let Some((node, a, b, d)) = stack.pop() {
        depth = depth.max(d);
        let mut bb = Aabb::INVALID;
        let mut centres = Aabb::INVALID;
        for &i in &index[a..b] {
            bb = bb.union(&boxes[i as usize]);
            centres.extend(boxes[i as usize].center());
        }
        if b - a <= 2 {
            nodes[node] = Bvh2Node::new(bb, (b - a) as u32, a as u32);
            continue;
        }
        let axis = centres.largest_axis();
        let mid = (a + b) / 2;
        let key = |i: &u32| boxes[*i as usize].center_axis(axis);
        index[a..b]
            .select_nth_unstable_by(mid - a, |p, q| key(p).total_cmp(&key(q)).then(p.cmp(q)));
        let first = nodes.len();
        nodes.push(Bvh2Node::default());
        nodes.push(Bvh2Node::default());
        nodes[node] = Bvh2Node::new(bb, 0, first as u32);
        stack.push((first, a, mid, d + 1));
        stack.push((first + 1, mid, b, d + 1));
    }
    Bvh2 {
        nodes,
        primitive_indices: index,
        // (A traversal stack deep enough for the tree.)
        max_depth: (depth + 2).max(obvhs::bvh2::DEFAULT_MAX_STACK_DEPTH),
        ..Default::default()
    }
}

/// How many primitives must share a box to be one entry (below it the builder's leaves of two hold them: a
/// quad's two triangles share a box and stay as they were, so scenes without such ties build the same BVH).
const SHARED: usize = 4;

impl Shared {
    /// The entries of `boxes`, or `None` when no box repeats `SHARED` times.
    fn of(boxes: &[Aabb]) -> Option<Shared> {
        let key =
            |b: &Aabb| [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits);
        let mut count: std::collections::HashMap<[u32; 6], (u32, u32)> = Default::default();
        for b in boxes {
            count.entry(key(b)).or_insert((0, u32::MAX)).0 += 1;
        }
        if count.values().all(|&(n, _)| (n as usize) < SHARED) {
            return None;
        }
        // Entries in the order of their first primitive; a tied box's primitives all in its one entry.
        let mut entry_of = Vec::with_capacity(boxes.len());
        let mut entry_boxes = Vec::new();
        for b in boxes {
            let c = count.get_mut(&key(b)).expect("counted");
            let e = if (c.0 as usize) < SHARED || c.1 == u32::MAX {
                entry_boxes.push(*b);
                let e = entry_boxes.len() as u32 - 1;
                if c.0 as usize >= SHARED {
                    c.1 = e;
                }
                e
            } else {
                c.1
            };
            entry_of.push(e);
        }
        let mut start = vec![0u32; entry_boxes.len() + 1];
        for &e in &entry_of {
            start[e as usize + 1] += 1;
        }
        for e in 0..entry_boxes.len() {
            start[e + 1] += start[e];
        }
        let mut next = start.clone();
        let mut members = vec![0u32; boxes.len()];
        for (p, &e) in entry_of.iter().enumerate() {
            members[next[e as usize] as usize] = p as u32;
            next[e as usize] += 1;
        }
        Some(Shared {
            boxes: entry_boxes,
            start,
            members,
        })
    }

    fn members(&self, e: usize) -> &[u32] {
        &self.members[self.start[e] as usize..self.start[e + 1] as usize]
    }
}

impl std::fmt::Debug for Bvh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Bvh({} primitives)", self.prims.len())
    }
}

impl Bvh {
    pub fn new(prims: Vec<Prim>) -> Bvh {
        // Leaves of at most 2 primitives, not obvhs's 8 (sized for SIMD leaf tests): the traversal here tests a
        // leaf's primitives one by one. On the fire-lit room the traversals' share of a render fell from 15.4 %
        // to 12.3–13.6 %, the images the same bit for bit (docs/results/log.md).
        fn build<T: Boundable>(items: &[T]) -> Option<Bvh2> {
            (!items.is_empty()).then(|| {
                obvhs::bvh2::builder::build_bvh2(
                    items,
                    BvhBuildParams {
                        max_prims_per_leaf: 2,
                        ..BvhBuildParams::medium_build()
                    },
                    &mut std::time::Duration::default(),
                )
            })
        }
        let boxes: Vec<Aabb> = prims.iter().map(Boundable::aabb).collect();
        let shared = Shared::of(&boxes);
        let entries = shared.as_ref().map_or(&boxes[..], |s| &s.boxes[..]);
        let bvh = if chained(entries) {
            Some(median_bvh(entries))
        } else {
            match &shared {
                Some(s) => build(&s.boxes),
                None => build(&prims),
            }
        };
        Bvh { prims, bvh, shared }
    }

    /// The nearest hit in (tmin, tmax).
    pub fn intersect(&self, o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<Hit> {
        let (t, (pid, part)) = self.nearest_part(o, d, tmin, tmax)?;
        Some(hit_at(&self.prims, pid, part, o, d, t))
    }

    /// The primitive a hit is on: the object's own one for a hit inside an instance, which carries the
    /// material, the medium interface and the orientation.
    pub fn prim(&self, hit: &Hit) -> &Prim {
        match (&self.prims[hit.prim].geom, hit.part) {
            (Geom::Instance { object, .. }, Some(part)) => &object.prims[part],
            _ => &self.prims[hit.prim],
        }
    }

    /// The box around every primitive (empty: a point at the origin).
    pub fn bounds(&self) -> Aabb {
        match &self.bvh {
            Some(b) if !b.nodes.is_empty() => *b.nodes[0].aabb(),
            _ => Aabb {
                min: Vec3A::ZERO,
                max: Vec3A::ZERO,
            },
        }
    }

    /// The box around the primitives whose medium interface names medium `m` (an instance's whole box when its
    /// object holds one), None if none does: a ray that misses it cannot cross into or out of `m`.
    pub fn media_box(&self, m: usize) -> Option<Aabb> {
        let mut b: Option<Aabb> = None;
        for prim in &self.prims {
            let names = match &prim.geom {
                Geom::Instance { object, .. } => object.media_box(m).is_some(),
                _ => prim
                    .media
                    .is_some_and(|(i, o)| i == Some(m) || o == Some(m)),
            };
            if names {
                let pb = prim.aabb();
                b = Some(match b {
                    Some(mut a) => {
                        a.extend(pb.min);
                        a.extend(pb.max);
                        a
                    }
                    None => pb,
                });
            }
        }
        b
    }

    /// The nearest hit's parameter and primitive index.
    fn nearest(&self, o: Vec3A, d: Vec3A, tmin: f32, tmax: f32) -> Option<(f32, usize)> {
        self.nearest_part(o, d, tmin, tmax)
            .map(|(t, (pid, _))| (t, pid))
    }

    /// The nearest hit's parameter, primitive index and, inside an instance, the object's primitive index.
    fn nearest_part(
        &self,
        o: Vec3A,
        d: Vec3A,
        tmin: f32,
        tmax: f32,
    ) -> Option<(f32, (usize, Option<usize>))> {
        let bvh = self.bvh.as_ref()?;
        let mut hit = RayHit::none();
        let ray = BRay::new(o, d, tmin, tmax);
        let prims = &self.prims;
        let mut part = None;
        let one = |pid: usize, tmax: f32, part: &mut Option<usize>| match &prims[pid].geom {
            Geom::Instance { to_obj, object, .. } => {
                let (oo, dd) = (to_obj.transform_point3a(o), to_obj.transform_vector3a(d));
                match object.nearest(oo, dd, tmin, tmax) {
                    // The traversal keeps t exactly when t < r.tmax, and so does this.
                    Some((t, inner)) if t < tmax => {
                        *part = Some(inner);
                        t
                    }
                    _ => f32::INFINITY,
                }
            }
            g => intersect_t(g, o, d, tmin, tmax),
        };
        // The primitive of a shared entry that the nearest hit so far is on.
        let mut member = 0usize;
        let found = bvh.ray_traverse(ray, &mut hit, |r, id| {
            let e = bvh.primitive_indices[id] as usize;
            match &self.shared {
                None => one(e, r.tmax, &mut part),
                Some(s) => {
                    let mut best = f32::INFINITY;
                    for &pid in s.members(e) {
                        let t = one(pid as usize, best.min(r.tmax), &mut part);
                        if t < best.min(r.tmax) {
                            (best, member) = (t, pid as usize);
                        }
                    }
                    best
                }
            }
        });
        if !found || !hit.t.is_finite() {
            return None;
        }
        let pid = match &self.shared {
            None => bvh.primitive_indices[hit.primitive_id as usize] as usize,
            Some(_) => member,
        };
        let part = matches!(prims[pid].geom, Geom::Instance { .. })
            .then_some(part)
            .flatten();
        Some((hit.t, (pid, part)))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn sphere(r: f32, c: Vec3A) -> Prim {
        let m = Affine3A::from_translation(c.into());
        Prim {
            geom: Geom::Sphere {
                to_world: m,
                to_obj: m.inverse(),
                r,
                zmin: -r,
                zmax: r,
                phimax: 2.0 * PI,
            },
            material: Some(0),
            area_light: None,
            media: None,
            reverse: false,
        }
    }

    #[test]
    fn a_mediums_box_holds_every_shape_that_names_it_instances_too() {
        // Medium 0 bounded by two spheres far apart (a ray leaving one may enter the other), medium 1 inside an
        // instanced object's sphere, medium 2 named by nothing; a sphere with no interface counts for none.
        let with = |r: f32, c: Vec3A, media| Prim {
            media: Some(media),
            ..sphere(r, c)
        };
        let object = Arc::new(Bvh::new(vec![with(0.5, Vec3A::ZERO, (Some(1), None))]));
        let m = Affine3A::from_translation(glam::Vec3::new(0.0, 10.0, 0.0));
        let instance = Prim {
            geom: Geom::Instance {
                to_world: m,
                to_obj: m.inverse(),
                object,
            },
            ..sphere(1.0, Vec3A::ZERO)
        };
        let bvh = Bvh::new(vec![
            with(1.0, Vec3A::new(-3.0, 0.0, 0.0), (Some(0), None)),
            sphere(2.0, Vec3A::new(0.0, 0.0, 8.0)),
            with(0.5, Vec3A::new(3.0, 1.0, 0.0), (None, Some(0))),
            instance,
        ]);
        // (A sphere's box is padded by a few ulps.)
        let near = |b: Aabb, lo: [f32; 3], hi: [f32; 3]| {
            b.min.abs_diff_eq(Vec3A::from(lo), 1e-5) && b.max.abs_diff_eq(Vec3A::from(hi), 1e-5)
        };
        let b = bvh.media_box(0).unwrap();
        assert!(near(b, [-4.0, -1.0, -1.0], [3.5, 1.5, 1.0]), "{b:?}");
        let b = bvh.media_box(1).unwrap();
        assert!(near(b, [-0.5, 9.5, -0.5], [0.5, 10.5, 0.5]), "{b:?}");
        assert!(bvh.media_box(2).is_none());
    }

    /// A triangle of material 0, no light, no media.
    fn triangle(p: [Vec3A; 3]) -> Prim {
        Prim {
            geom: Geom::Triangle {
                p,
                n: None,
                uv: [Vec2::ZERO; 3],
            },
            material: Some(0),
            area_light: None,
            media: None,
            reverse: false,
        }
    }

    #[test]
    fn the_nearest_of_primitives_sharing_a_box_is_hit() {
        // Six triangles with the box [0, 1]³ (one BVH entry), planes z = x + s·y, s from 1 down to 1/6, and a
        // sphere elsewhere: a ray along +z at (0.1, 0.1) meets the last one first, at z = 0.1 + 0.1/6.
        let tri = |s: f32| {
            triangle([
                Vec3A::new(0.0, 0.0, 0.0),
                Vec3A::new(1.0, 0.0, 1.0),
                Vec3A::new(0.0, 1.0, s),
            ])
        };
        let mut prims = vec![sphere(1.0, Vec3A::new(5.0, 0.0, 0.0))];
        prims.extend((0..6).map(|k| tri(1.0 - k as f32 / 6.0)));
        let bvh = Bvh::new(prims);
        assert_eq!(bvh.shared.as_ref().map(|s| s.boxes.len()), Some(2));
        let h = bvh
            .intersect(Vec3A::new(0.1, 0.1, -1.0), Vec3A::Z, 1e-4, f32::INFINITY)
            .unwrap();
        assert_eq!(h.prim, 6);
        assert!((h.t - (1.1 + 0.1 / 6.0)).abs() < 1e-5, "{}", h.t);
        // Limited to before it, the next nearest.
        let h = bvh
            .intersect(
                Vec3A::new(0.1, 0.1, -1.0),
                Vec3A::Z,
                1e-4,
                1.1 + 0.1 / 6.0 - 1e-4,
            )
            .map(|h| h.prim);
        assert_eq!(h, None);
        let h = bvh
            .intersect(Vec3A::new(0.1, 0.1, 0.12), Vec3A::Z, 1e-4, f32::INFINITY)
            .unwrap();
        assert_eq!(h.prim, 5);
        let h = bvh
            .intersect(Vec3A::new(5.0, 0.0, -5.0), Vec3A::Z, 1e-4, f32::INFINITY)
            .unwrap();
        assert_eq!(h.prim, 0);
    }

    #[test]
    fn nested_boxes_build_by_median_splits_and_the_nearest_is_hit() {
        // 8 000 triangles each wider and higher than the last (PLOC's chain) are built by median splits; a
        // tessellated plane of as many is not. Rays find the depth brute force finds.
        let tri = triangle;
        let nested: Vec<Prim> = (0..8000)
            .map(|i| {
                let (w, z) = (1.0 + i as f32 * 1e-3, 1.0 + i as f32 * 1e-4);
                tri([
                    Vec3A::new(0.0, 0.0, z),
                    Vec3A::new(w, 0.0, z),
                    Vec3A::new(0.0, w, z),
                ])
            })
            .collect();
        let boxes: Vec<Aabb> = nested.iter().map(Boundable::aabb).collect();
        assert!(chained(&boxes));
        let plane: Vec<Aabb> = (0..8000)
            .map(|i| {
                let (x, y) = ((i % 90) as f32, (i / 90) as f32);
                tri([
                    Vec3A::new(x, y, 0.0),
                    Vec3A::new(x + 1.0, y, 0.0),
                    Vec3A::new(x, y + 1.0, 0.0),
                ])
                .aabb()
            })
            .collect();
        assert!(!chained(&plane));
        let bvh = Bvh::new(nested);
        for k in 0..50 {
            let o = Vec3A::new(0.05 + 0.1 * k as f32, 0.3, 0.0);
            let want = (0..bvh.prims.len())
                .filter_map(|p| {
                    let t = intersect_t(&bvh.prims[p].geom, o, Vec3A::Z, 1e-4, f32::INFINITY);
                    t.is_finite().then_some((t, p))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let got = bvh.intersect(o, Vec3A::Z, 1e-4, f32::INFINITY);
            assert_eq!(got.map(|h| h.t), want.map(|w| w.0), "ray {k}");
        }
    }

    #[test]
    fn hits_and_normals() {
        let bvh = Bvh::new(vec![
            sphere(1.0, Vec3A::new(0.0, 0.0, 5.0)),
            triangle([
                Vec3A::new(-1.0, -1.0, 10.0),
                Vec3A::new(1.0, -1.0, 10.0),
                Vec3A::new(0.0, 1.0, 10.0),
            ]),
        ]);
        let h = bvh
            .intersect(Vec3A::ZERO, Vec3A::Z, 1e-4, f32::INFINITY)
            .unwrap();
        assert!((h.t - 4.0).abs() < 1e-5 && (h.ng - Vec3A::NEG_Z).length() < 1e-5);
        let h = bvh
            .intersect(Vec3A::new(0.0, -0.5, 0.0), Vec3A::Z, 1e-4, f32::INFINITY)
            .unwrap();
        assert!(h.t < 5.0);
        let h = bvh
            .intersect(Vec3A::new(0.0, -0.5, 7.0), Vec3A::Z, 1e-4, f32::INFINITY)
            .unwrap();
        assert!((h.t - 3.0).abs() < 1e-5 && h.prim == 1);
        assert!(bvh
            .intersect(Vec3A::new(5.0, 5.0, 0.0), Vec3A::Z, 1e-4, f32::INFINITY)
            .is_none());
    }
}
