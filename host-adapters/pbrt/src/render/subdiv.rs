//! pbrt-v4's `loopsubdiv` shape: Loop subdivision of a triangle mesh (C. Loop, *Smooth Subdivision Surfaces Based
//! on Triangles*, M.S. thesis, University of Utah, 1987; the rules as pbrt-v4's `LoopSubdivide`,
//! `src/pbrt/util/mesh.cpp`, and Pharr, Jakob & Humphreys, *PBR* 3rd ed., §3.8).
//!
//! Each level splits every triangle in four. An old ("even") vertex of valence n moves to
//! (1 − nβ) v + β Σ neighbours, with β = 3/16 for n = 3 and 3/(8n) otherwise; on a boundary to
//! ¾ v + ⅛ (its two boundary neighbours). A new ("odd") vertex on an interior edge v₀v₁ is
//! ⅜ (v₀ + v₁) + ⅛ (the two opposite vertices); on a boundary edge the midpoint. After the last level every vertex is
//! pushed to its limit position: (1 − nγ) v + γ Σ neighbours with γ = 1 / (n + 3/(8β)); on a boundary
//! ⅗ v + ⅕ (its two boundary neighbours). An edge shared by more than two faces and a boundary vertex
//! without exactly two boundary neighbours are treated as pbrt-v4 cannot: they stay where they are (no smoothing
//! across a non-manifold seam).
//!
//! Normals: pbrt-v4 takes the limit surface's tangents from each vertex's ordered ring; here each vertex's normal
//! is the area-weighted mean of its faces' normals on the subdivided limit mesh, which converges to the limit
//! normal as the levels grow (at pbrt-v4's default 3 levels they differ by well under a degree on smooth parts).

use std::collections::{BTreeMap, HashMap};

/// The most levels a scene may ask for (each multiplies the triangles by 4: 4¹⁶ ≈ 4·10⁹).
pub const MAX_LEVELS: u32 = 16;

/// A triangle mesh: positions and triangles (counter-clockwise as given).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub p: Vec<[f64; 3]>,
    pub tris: Vec<[u32; 3]>,
}

/// The faces opposite an edge (sorted vertex pair): the third vertex of each face that holds it. Ordered, so the
/// new vertices' numbering and every sum's order are the same on every run (same scene, same bits).
type EdgeMap = BTreeMap<(u32, u32), Vec<u32>>;

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

fn edges(tris: &[[u32; 3]]) -> EdgeMap {
    let mut m: EdgeMap = BTreeMap::new();
    for t in tris {
        for k in 0..3 {
            m.entry(key(t[k], t[(k + 1) % 3]))
                .or_default()
                .push(t[(k + 2) % 3]);
        }
    }
    m
}

/// Each vertex's neighbours: all of them (interior), or its boundary neighbours and a flag.
struct Rings {
    all: Vec<Vec<u32>>,
    boundary: Vec<Vec<u32>>,
    /// On an edge with other than two faces.
    on_boundary: Vec<bool>,
}

fn rings(n: usize, e: &EdgeMap) -> Rings {
    let mut r = Rings {
        all: vec![Vec::new(); n],
        boundary: vec![Vec::new(); n],
        on_boundary: vec![false; n],
    };
    for (&(a, b), faces) in e {
        r.all[a as usize].push(b);
        r.all[b as usize].push(a);
        if faces.len() != 2 {
            r.boundary[a as usize].push(b);
            r.boundary[b as usize].push(a);
            r.on_boundary[a as usize] = true;
            r.on_boundary[b as usize] = true;
        }
    }
    r
}

fn beta(n: usize) -> f64 {
    if n == 3 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * n as f64)
    }
}

fn add(a: [f64; 3], b: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Vertex `v` moved by the mask (1 − nw) v + w Σ ring (interior) or (1 − 2wb) v + wb Σ boundary ring.
fn masked(m: &Mesh, r: &Rings, v: usize, w: impl Fn(usize) -> f64, wb: f64) -> [f64; 3] {
    let p = m.p[v];
    let (ring, wt) = if r.on_boundary[v] {
        if r.boundary[v].len() != 2 {
            return p;
        }
        (&r.boundary[v], wb)
    } else {
        if r.all[v].is_empty() {
            return p;
        }
        (&r.all[v], w(r.all[v].len()))
    };
    let mut out = scale(p, 1.0 - ring.len() as f64 * wt);
    for &q in ring {
        out = add(out, m.p[q as usize], wt);
    }
    out
}

/// The mesh after `levels` Loop subdivisions, pushed to the limit surface (pbrt-v4 pushes even at level 0).
/// The caller bounds `levels` and checks the result's size (4^levels × the triangles) before calling.
pub fn subdivide(mesh: &Mesh, levels: u32) -> Mesh {
    let mut m = mesh.clone();
    for _ in 0..levels {
        let e = edges(&m.tris);
        let r = rings(m.p.len(), &e);
        let mut p: Vec<[f64; 3]> = (0..m.p.len())
            .map(|v| masked(&m, &r, v, beta, 1.0 / 8.0))
            .collect();
        // Odd vertices, one per edge, numbered after the even ones.
        let mut odd: HashMap<(u32, u32), u32> = HashMap::with_capacity(e.len());
        for (&(a, b), faces) in &e {
            let (pa, pb) = (m.p[a as usize], m.p[b as usize]);
            let v = if faces.len() == 2 {
                add(
                    scale(add(pa, pb, 1.0), 3.0 / 8.0),
                    add(m.p[faces[0] as usize], m.p[faces[1] as usize], 1.0),
                    1.0 / 8.0,
                )
            } else {
                scale(add(pa, pb, 1.0), 0.5)
            };
            odd.insert((a, b), p.len() as u32);
            p.push(v);
        }
        let mut tris = Vec::with_capacity(m.tris.len() * 4);
        for t in &m.tris {
            let [a, b, c] = *t;
            let (ab, bc, ca) = (odd[&key(a, b)], odd[&key(b, c)], odd[&key(c, a)]);
            tris.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        m = Mesh { p, tris };
    }
    let r = rings(m.p.len(), &edges(&m.tris));
    let gamma = |n: usize| 1.0 / (n as f64 + 3.0 / (8.0 * beta(n)));
    let p = (0..m.p.len())
        .map(|v| masked(&m, &r, v, gamma, 1.0 / 5.0))
        .collect();
    Mesh { p, tris: m.tris }
}

/// Per-vertex normals: the area-weighted mean of the faces' normals, unit length (zero where no face has area).
pub fn normals(m: &Mesh) -> Vec<[f64; 3]> {
    let mut n = vec![[0.0; 3]; m.p.len()];
    for t in &m.tris {
        let [a, b, c] = t.map(|i| m.p[i as usize]);
        let (u, v) = (add(b, a, -1.0), add(c, a, -1.0));
        // The cross product's length is twice the area: area weighting for free.
        let f = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        for &i in t {
            n[i as usize] = add(n[i as usize], f, 1.0);
        }
    }
    n.iter()
        .map(|v| {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 0.0 {
                scale(*v, 1.0 / l)
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn octahedron() -> Mesh {
        Mesh {
            p: vec![
                [1.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0],
            ],
            tris: vec![
                [0, 2, 4],
                [2, 1, 4],
                [1, 3, 4],
                [3, 0, 4],
                [2, 0, 5],
                [1, 2, 5],
                [3, 1, 5],
                [0, 3, 5],
            ],
        }
    }

    fn len(v: [f64; 3]) -> f64 {
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    }

    #[test]
    fn an_octahedrons_corners_reach_their_limit_at_every_level() {
        // A corner of the unit octahedron has valence 4: β = 3/32, γ = 1/(4 + 4) = 1/8, so its limit point is
        // ½ v + ⅛ Σ (the four neighbours, summing to 0) = v/2 — the same whatever the level it is computed from.
        for levels in 0..=5 {
            let m = subdivide(&octahedron(), levels);
            assert_eq!(m.tris.len(), 8 << (2 * levels));
            for (v, want) in octahedron().p.iter().enumerate() {
                let got = m.p[v];
                for k in 0..3 {
                    assert!(
                        (got[k] - want[k] / 2.0).abs() < 1e-12,
                        "level {levels}, corner {v}: {got:?}"
                    );
                }
            }
            // The corners are the surface's farthest points (radius ½) and the faces' centres its nearest: the
            // nearest vertex at levels 2…6 is 0.4248, 0.4174, 0.4162, 0.4158, 0.4157, its steps shrinking by
            // about 4 per level (the spacing of the samples halves; the surface is C² there). Every vertex lies
            // between.
            if levels >= 2 {
                let nearest = m.p.iter().map(|p| len(*p)).fold(f64::MAX, f64::min);
                let farthest = m.p.iter().map(|p| len(*p)).fold(0.0, f64::max);
                assert!(
                    (farthest - 0.5).abs() < 1e-12,
                    "level {levels}: farthest {farthest}"
                );
                assert!(
                    (0.4155..0.425).contains(&nearest),
                    "level {levels}: nearest {nearest}"
                );
                // Normals point outwards, near the radial direction of a nearly round surface.
                for (p, n) in m.p.iter().zip(normals(&m)) {
                    let cos = (p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / len(*p);
                    assert!(cos > 0.95, "normal {n:?} at {p:?}");
                }
            }
        }
    }

    #[test]
    fn a_flat_sheet_stays_flat_and_keeps_its_linear_interior() {
        // Loop subdivision reproduces affine functions on a regular (valence-6) interior: a planar grid stays in
        // its plane, and its interior vertices stay where they were (their ring is symmetric about them).
        let n = 6;
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push([i as f64 + 0.5 * j as f64, j as f64 * 0.75f64.sqrt(), 2.0]);
            }
        }
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let v = (j * (n + 1) + i) as u32;
                let w = (n + 1) as u32;
                tris.push([v, v + 1, v + w]);
                tris.push([v + 1, v + w + 1, v + w]);
            }
        }
        let sheet = Mesh { p, tris };
        let m = subdivide(&sheet, 2);
        assert!(m.p.iter().all(|q| (q[2] - 2.0).abs() < 1e-12));
        // An interior vertex of the original grid (valence 6 everywhere around it) is a fixed point.
        let centre = 3 * (n + 1) + 3;
        for k in 0..2 {
            assert!((m.p[centre][k] - sheet.p[centre][k]).abs() < 1e-12);
        }
        // A boundary vertex moves along its boundary only: ⅗ v + ⅕ (neighbours on a straight edge) = v.
        assert!((m.p[3][1]).abs() < 1e-12);
        assert!(normals(&m).iter().all(|q| (q[2] - 1.0).abs() < 1e-12));
    }

    #[test]
    fn a_lone_triangle_and_a_nonmanifold_fan_stay_finite() {
        let tri = Mesh {
            p: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            tris: vec![[0, 1, 2]],
        };
        let m = subdivide(&tri, 3);
        assert_eq!(m.tris.len(), 64);
        assert!(m.p.iter().flatten().all(|v| v.is_finite()));
        // Three triangles on one edge: the edge is a seam, its vertices stay put.
        let fan = Mesh {
            p: vec![
                [0.0; 3],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [-1.0, -1.0, 0.0],
            ],
            tris: vec![[0, 1, 2], [0, 1, 3], [0, 1, 4]],
        };
        let m = subdivide(&fan, 2);
        assert!(m.p.iter().flatten().all(|v| v.is_finite()));
        assert_eq!(m.p[0], [0.0; 3]);
    }
}
