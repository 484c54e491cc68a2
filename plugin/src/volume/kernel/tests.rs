use super::*;
use crate::grid::{Grid, Interpolation, Stencil};

/// A grid of `dims` whose values are `f` of uniform numbers in [0, 1).
fn random_grid(dims: [usize; 3], rng: &mut crate::rng::Rng, f: impl Fn(f32) -> f32) -> Grid {
    let n = dims[0] * dims[1] * dims[2];
    let v: Vec<f32> = (0..n).map(|_| f(rng.next_f64() as f32)).collect();
    Grid::new(dims, v).expect("dims match")
}

/// Every read of `lat` (over the grids `d`, `t`, `les`) at 20 000 points from a voxel below the lower bound
/// to one above the upper, some exactly on a face, equals the grids' own lookup (pbrt-v4's fade at the
/// faces, continued by nanovdb's margin) to the rounding of the two orders of lerps; returns the points
/// checked and how many lay on a face.
fn reads_equal_the_grids(
    lat: &Lattice,
    d: &Grid,
    t: &Grid,
    les: &Grid,
    seed: u64,
) -> (usize, usize) {
    let dims = d.dims();
    let lay = Layout::new(lat, true, dims);
    let mut rng = crate::rng::Rng::new(seed);
    let (mut worst, mut checked, mut faces) = (0f64, 0, 0);
    for i in 0..20_000 {
        let mut g = [0f64; 3];
        for a in 0..3 {
            let m = dims[a] as f64;
            g[a] = -1.5 + rng.next_f64() * (m + 2.0);
            if i % 7 == a {
                g[a] = if i % 2 == 0 { -0.5 } else { m - 0.5 };
                faces += 1;
            }
        }
        let unit = [0, 1, 2].map(|a| (g[a] + 0.5) / dims[a] as f64);
        let Some(st) = Stencil::with_margin(d.topology(), unit, Interpolation::Trilinear, 0.5)
        else {
            continue;
        };
        let mut dt = [[0f32; 2]; BATCH];
        let mut x = Extras {
            les: [1.0; BATCH],
            n: [[0.0; BATCH]; MAX_SPECIES],
        };
        let (i, f) = match lay.bricks {
            None => cell::<false>(&lay, g),
            Some((topo, off, n)) => cell_in_bricks::<false>(topo, off, n, g),
        };
        assert!(
            read::<false>(&lay, i, f, &[], 3, &mut dt, &mut x),
            "every point within the margin has its cell in the lattice: {g:?}"
        );
        for (got, grid) in [(dt[3][0], d), (dt[3][1], t), (x.les[3], les)] {
            // (The data is of order 1: the two orders of f32 lerps differ by its rounding.)
            let want = grid.eval(&st);
            let e = (got - want).abs() as f64;
            worst = worst.max(e);
            assert!(e < 1e-6, "{g:?}: lattice {got} vs grid {want}");
        }
        checked += 1;
    }
    assert!(
        worst > 0.0,
        "the two orders of lerps cannot agree to the bit everywhere"
    );
    (checked, faces)
}

#[test]
fn lattice_reads_equal_the_grid_lookup_up_to_and_beyond_the_faces() {
    // Data non-zero up to the faces, so that pbrt-v4's fade (half the edge sample on a face, zero half a
    // voxel out, continued to the next voxel centre by nanovdb's margin) is what the zero padding must give.
    let dims = [5, 4, 3];
    let mut rng = crate::rng::Rng::new(11);
    let mut grid = || random_grid(dims, &mut rng, |u| 0.5 + u);
    let (d, t, les) = (grid(), grid(), grid());
    let (lat, _) = Lattice::build(&d, Some(&t), &[&les], 4, u64::MAX).expect("a small lattice");
    let (checked, faces) = reads_equal_the_grids(&lat, &d, &t, &les, 12);
    assert!(
        checked > 5000 && faces > 1000,
        "{checked} points, {faces} on faces"
    );
    // The brick layout of the same grids reads the same.
    let lat = Lattice::build_bricks(&d, Some(&t), &[&les], u64::MAX).expect("small");
    reads_equal_the_grids(&lat, &d, &t, &les, 12);
}

#[test]
fn brick_copies_read_as_sparse_grids_with_offsets_and_backgrounds() {
    // Random sparse topologies (about a third of the bricks stored, sample 0 anywhere in its brick), data
    // in the stored bricks, and a background that is 0 or not: every read of the brick layout equals the
    // grids' lookup, and copies exist only around stored bricks (plus the faces for a non-zero background).
    let mut rng = crate::rng::Rng::new(31);
    for case in 0..12 {
        let dims = [0, 1, 2].map(|_| 3 + (rng.next_f64() * 30.0) as usize);
        let off = [0, 1, 2].map(|_| (rng.next_f64() * 8.0) as usize);
        let nb = [0, 1, 2].map(|a| (dims[a] + off[a]).div_ceil(8));
        let keep: Vec<bool> = (0..nb[0] * nb[1] * nb[2])
            .map(|_| rng.next_f64() < 0.35)
            .collect();
        let topo = std::sync::Arc::new(
            crate::grid::Topology::build_offset(dims, off, |b| {
                keep[b[0] + nb[0] * (b[1] + nb[1] * b[2])]
            })
            .expect("small"),
        );
        let background = if case % 3 == 0 { 0.25 } else { 0.0 };
        let n = dims[0] * dims[1] * dims[2];
        let mut grid = || {
            let v: Vec<f32> = (0..n).map(|_| 0.5 + rng.next_f64() as f32).collect();
            Grid::from_dense(topo.clone(), &v, background).expect("dims match")
        };
        let (d, t, les) = (grid(), grid(), grid());
        let lat = Lattice::build_bricks(&d, Some(&t), &[&les], u64::MAX).expect("small");
        let copies = lat.bricks().expect("bricks").active_bricks();
        assert!(
            background != 0.0 || copies <= 8 * topo.active_bricks(),
            "{copies} copies for {} stored bricks",
            topo.active_bricks()
        );
        reads_equal_the_grids(&lat, &d, &t, &les, 100 + case);
    }
}

#[test]
fn the_lattice_gathers_each_grids_brick_ranges() {
    // The ranges gathered slab by slab as the lattice is copied (split over the threads) are the majorant's.
    let dims = [13, 9, 37];
    let mut rng = crate::rng::Rng::new(21);
    let mut grid = || random_grid(dims, &mut rng, |u| if u < 0.4 { 0.0 } else { u - 0.45 });
    let (d, t, e1, e2) = (grid(), grid(), grid(), grid());
    for brick in [1, 3, 4, 8, 64] {
        let (_, ranges) =
            Lattice::build(&d, Some(&t), &[&e1, &e2], brick, u64::MAX).expect("small");
        assert_eq!(ranges.len(), 4);
        for (r, g) in ranges.iter().zip([&d, &t, &e1, &e2]) {
            assert_eq!(
                r,
                &crate::majorant::brick_ranges(&g.to_dense(), dims, brick),
                "brick {brick}"
            );
        }
        let (_, only_d) = Lattice::build(&d, None, &[], brick, u64::MAX).expect("small");
        assert_eq!(
            only_d,
            vec![crate::majorant::brick_ranges(&d.to_dense(), dims, brick)]
        );
    }
}

#[test]
fn a_lattice_too_large_for_32_bit_offsets_is_refused() {
    // [d, T] per padded voxel, fewer than u32::MAX floats: 2 × 1293² × 1284 = 4 293 308 232 fits,
    // 2 × 1293² × 1285 = 4 296 651 930 does not.
    assert_eq!(
        Lattice::padded([1291, 1291, 1282]),
        Some([1293, 1293, 1284])
    );
    assert_eq!(Lattice::padded([1291, 1291, 1283]), None);
    assert_eq!(Lattice::padded([usize::MAX, 2, 2]), None);
    assert_eq!(Lattice::padded([256, 256, 256]), Some([258, 258, 258]));
}
