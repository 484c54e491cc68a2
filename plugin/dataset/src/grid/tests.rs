use super::*;

#[test]
fn floor_matches_libm() {
    for x in [
        -3.5,
        -3.0,
        -2.9999999,
        -0.5,
        -1e-300,
        -0.0,
        0.0,
        1e-300,
        0.5,
        1.0,
        2.9999999,
        3.0,
        1e15 + 0.5,
    ] {
        assert_eq!(floor(x), f64::floor(x), "x = {x}");
    }
}

fn ramp() -> Grid {
    // v = i + 10 j + 100 k on 4×3×2.
    let mut d = Vec::new();
    for k in 0..2 {
        for j in 0..3 {
            for i in 0..4 {
                d.push((i + 10 * j + 100 * k) as f32);
            }
        }
    }
    Grid::new([4, 3, 2], d).unwrap()
}

#[test]
fn x_fastest_layout() {
    let g = ramp();
    assert_eq!(g.at(3, 0, 0), 3.0);
    assert_eq!(g.at(0, 2, 0), 20.0);
    assert_eq!(g.at(1, 1, 1), 111.0);
    assert_eq!(g.at(4, 0, 0), 0.0);
    assert_eq!(g.at(-1, 0, 0), 0.0);
    assert!(Grid::new([2, 2, 2], vec![0.0; 7]).is_none());
    assert!(Grid::new([usize::MAX, 2, 2], vec![]).is_none());
}

#[test]
fn trilinear_reproduces_samples_and_linear_fields() {
    let g = ramp();
    // At cell centres the sample itself.
    let c = |i: f64, j: f64, k: f64| [(i + 0.5) / 4.0, (j + 0.5) / 3.0, (k + 0.5) / 2.0];
    assert_eq!(g.lookup(c(2.0, 1.0, 1.0), Interpolation::Trilinear), 112.0);
    // Between centres, exactly linear (the field is linear).
    let v = g.lookup(c(1.25, 0.5, 0.5), Interpolation::Trilinear);
    assert!((v - (1.25 + 5.0 + 50.0)).abs() < 1e-4, "{v}");
}

#[test]
fn last_half_voxel_fades_to_half_at_the_bounds() {
    // pbrt convention: on the face the value is half the edge sample; outside, zero.
    let g = Grid::new([2, 1, 1], vec![4.0, 8.0]).unwrap();
    let y = 0.5;
    let z = 0.5;
    // y, z at the single centre: the x profile.
    assert_eq!(g.lookup([1.0, y, z], Interpolation::Trilinear), 4.0);
    assert_eq!(g.lookup([0.0, y, z], Interpolation::Trilinear), 2.0);
    assert_eq!(g.lookup([0.75, y, z], Interpolation::Trilinear), 8.0);
    assert_eq!(g.lookup([1.0001, y, z], Interpolation::Trilinear), 0.0);
    assert_eq!(g.lookup([f64::NAN, y, z], Interpolation::Trilinear), 0.0);
    // Along y (one sample): at the centre 4, at the face 2 (x at sample 0's centre).
    assert_eq!(g.lookup([0.25, 0.0, 0.5], Interpolation::Trilinear), 2.0);
}

#[test]
fn nearest_picks_the_cell() {
    let g = ramp();
    assert_eq!(g.lookup([0.99, 0.99, 0.99], Interpolation::Nearest), 123.0);
    assert_eq!(g.lookup([1.0, 1.0, 1.0], Interpolation::Nearest), 123.0);
    assert_eq!(g.lookup([0.0, 0.0, 0.0], Interpolation::Nearest), 0.0);
    assert_eq!(g.lookup([0.26, 0.0, 0.0], Interpolation::Nearest), 1.0);
    assert_eq!(g.lookup([1.1, 0.0, 0.0], Interpolation::Nearest), 0.0);
}

#[test]
fn stencil_agrees_with_lookup() {
    let g = ramp();
    let mut x = 0.013;
    for _ in 0..2000 {
        x = (x * 3.7 + 0.123) % 1.0;
        let p = [x, (x * 7.1) % 1.0, (x * 13.3) % 1.0];
        for interp in [Interpolation::Trilinear, Interpolation::Nearest] {
            let st = Stencil::new(g.topology(), p, interp).unwrap();
            assert!((g.eval(&st) - g.lookup(p, interp)).abs() < 1e-4, "{p:?}");
        }
    }
    assert!(Stencil::new(g.topology(), [1.5, 0.5, 0.5], Interpolation::Trilinear).is_none());
}

/// A random grid of `dims` whose 8³ bricks (at offset `off`) each hold data with probability `p`, as dense
/// samples, and the sparse grid storing only those bricks.
fn sparse_pair(dims: [usize; 3], off: [usize; 3], seed: u64, p: f64) -> (Grid, Grid) {
    let mut rng = firemedium_core::rng::Rng::new(seed);
    let probe = Topology::build_offset(dims, off, |_| false).unwrap();
    let nb = probe.bricks();
    let keep: Vec<bool> = (0..nb.iter().product::<usize>())
        .map(|_| rng.next_f64() < p)
        .collect();
    let mut d = vec![0f32; dims.iter().product()];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let b = probe.brick_of([i, j, k]);
                if keep[b[0] + nb[0] * (b[1] + nb[1] * b[2])] {
                    d[i + dims[0] * (j + dims[1] * k)] = rng.next_f64() as f32 * 3.0;
                }
            }
        }
    }
    let dense = Grid::new(dims, d.clone()).unwrap();
    let topo =
        Topology::build_offset(dims, off, |b| keep[b[0] + nb[0] * (b[1] + nb[1] * b[2])]).unwrap();
    let sparse = Grid::from_dense(std::sync::Arc::new(topo), &d, 0.0).unwrap();
    (dense, sparse)
}

#[test]
fn a_topology_from_its_brick_list_is_the_one_built_brick_by_brick() {
    let mut rng = firemedium_core::rng::Rng::new(5);
    for _ in 0..20 {
        let dims = [0, 1, 2].map(|_| 1 + (rng.next_f64() * 300.0) as usize);
        let off = [0, 1, 2].map(|_| (rng.next_f64() * 8.0) as usize);
        let nb = [0, 1, 2].map(|a| (dims[a] + off[a]).div_ceil(BRICK));
        let p = rng.next_f64() * 0.05;
        let keep: Vec<bool> = (0..nb[0] * nb[1] * nb[2])
            .map(|_| rng.next_f64() < p)
            .collect();
        let want =
            Topology::build_offset(dims, off, |b| keep[b[0] + nb[0] * (b[1] + nb[1] * b[2])])
                .unwrap();
        // The list reversed, with repeats and a brick beyond the lattice.
        let mut list: Vec<[usize; 3]> = Vec::new();
        want.for_each_slot(|b, _| list.extend([b, b]));
        list.reverse();
        list.push([nb[0], 0, 0]);
        let got = Topology::from_bricks(dims, off, list).unwrap();
        assert_eq!(got, want);
    }
}

#[test]
fn sparse_grids_look_up_as_dense_ones_bit_for_bit() {
    // Random sparse trees (dims not multiples of 8, every brick offset) against the dense reference: every
    // sample, trilinear and nearest lookups and stencils at random points (faces included), statistics, and
    // the storage following the bricks kept.
    let mut rng = firemedium_core::rng::Rng::new(5);
    for (t, dims) in [[13usize, 9, 21], [8, 8, 8], [1, 17, 3], [30, 2, 11]]
        .into_iter()
        .enumerate()
    {
        for off in [[0, 0, 0], [3, 7, 1], [7, 0, 5]] {
            let (dense, sparse) = sparse_pair(dims, off, 100 + t as u64, 0.5);
            assert_eq!(sparse.to_dense(), dense.to_dense());
            for k in -1..=dims[2] as i64 {
                for j in -1..=dims[1] as i64 {
                    for i in -1..=dims[0] as i64 {
                        assert_eq!(sparse.at(i, j, k).to_bits(), dense.at(i, j, k).to_bits());
                    }
                }
            }
            for _ in 0..3000 {
                let p = [0, 1, 2].map(|_| rng.next_f64() * 1.2 - 0.1);
                for interp in [Interpolation::Trilinear, Interpolation::Nearest] {
                    assert_eq!(
                        sparse.lookup(p, interp).to_bits(),
                        dense.lookup(p, interp).to_bits(),
                        "{p:?}"
                    );
                    let (a, b) = (
                        Stencil::with_margin(sparse.topology(), p, interp, 0.5),
                        Stencil::with_margin(dense.topology(), p, interp, 0.5),
                    );
                    assert_eq!(
                        a.map(|s| sparse.eval(&s).to_bits()),
                        b.map(|s| dense.eval(&s).to_bits()),
                        "{p:?}"
                    );
                }
            }
            let (s0, s1) = (sparse.stats(), dense.stats());
            assert_eq!((s0.min, s0.max), (s1.min, s1.max));
            assert!((s0.mean - s1.mean).abs() <= 1e-12 * s1.mean.abs().max(1.0));
            assert!((s0.nonzero_fraction - s1.nonzero_fraction).abs() < 1e-12);
            let stored = sparse.topology().active_bricks();
            assert_eq!(sparse.bytes(), (stored + 1) * 512 * 4);
        }
    }
}

#[test]
fn stats() {
    let s = ramp().stats();
    assert_eq!((s.min, s.max), (0.0, 123.0));
    assert!((s.mean - 61.5).abs() < 1e-12);
    assert!((s.nonzero_fraction - 23.0 / 24.0).abs() < 1e-12);
}
