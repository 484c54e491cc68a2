use super::*;

#[test]
fn written_grids_read_back_voxel_for_voxel() {
    // Two 21×13×140 grids (not multiples of 8; two 128-voxel internal nodes along z) with a
    // blob of non-zero values, negative and tiny ones included, and a corner voxel set.
    let dims = [21usize, 13, 140];
    let n = dims[0] * dims[1] * dims[2];
    let mut a = vec![0f32; n];
    let mut b = vec![0f32; n];
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let i = x + dims[0] * (y + dims[1] * z);
                let r2 = ((x as f32 - 10.0).powi(2) + (y as f32 - 6.0).powi(2)) / 20.0
                    + ((z as f32 - 70.0) / 40.0).powi(2);
                if r2 < 1.0 {
                    a[i] = 1.0 - r2;
                    b[i] = 300.0 + 1500.0 * (1.0 - r2) * if x % 3 == 0 { -1e-3 } else { 1.0 };
                }
            }
        }
    }
    a[n - 1] = 1e-30;
    let p0 = DVec3::new(-0.5, 0.25, 0.0);
    let voxel = DVec3::new(0.01, 0.02, 0.015);
    let bytes = write(
        &[("density", dims, &a), ("temperature", dims, &b)],
        p0,
        voxel,
    );
    let header = read_header("t.vdb", &bytes).unwrap();
    assert_eq!(header.grids.len(), 2);
    let got = read(
        "t.vdb",
        Bytes::Slice(&bytes),
        &["density", "temperature"],
        u64::MAX,
    )
    .unwrap();
    // The union of the active boxes: from the blob's lowest voxel to the corner.
    let lo = [0usize, 1, 2].map(|k| {
        (0..n)
            .filter(|&i| a[i] != 0.0 || b[i] != 0.0)
            .map(|i| {
                [
                    i % dims[0],
                    (i / dims[0]) % dims[1],
                    i / (dims[0] * dims[1]),
                ][k]
            })
            .min()
            .unwrap()
    });
    let d = got[0].dims;
    assert_eq!(d, [dims[0] - lo[0], dims[1] - lo[1], dims[2] - lo[2]]);
    let [q0, q1] = got[0].bounds.unwrap();
    let want0 = p0 + DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64) * voxel;
    assert!(
        (q0 - want0).length() < 1e-12
            && (q1 - (p0 + DVec3::new(21.0, 13.0, 140.0) * voxel)).length() < 1e-12,
        "{q0} {q1}"
    );
    for (g, src) in got.iter().zip([&a, &b]) {
        for z in 0..d[2] {
            for y in 0..d[1] {
                for x in 0..d[0] {
                    let s = src[(x + lo[0]) + dims[0] * ((y + lo[1]) + dims[1] * (z + lo[2]))];
                    let b = g.bricks.as_ref().expect("bricks");
                    assert_eq!(b.at(x as i64, y as i64, z as i64), s);
                }
            }
        }
    }
}

#[test]
fn each_grid_carries_the_metadata_readers_list_it_by() {
    // OpenVDB's own readers (Blender, Houdini) name a grid and place it by its metadata before loading voxels:
    // `name`, and the active voxels' index bounds and count.
    let dims = [10, 9, 20];
    let mut v = vec![0f32; 10 * 9 * 20];
    v[3 + 10 * (2 + 9 * 5)] = 1.0; // voxel (3, 2, 5)
    v[9 + 10 * (8 + 9 * 17)] = 2.0; // voxel (9, 8, 17)
    let bytes = write(&[("flame", dims, &v)], DVec3::ZERO, DVec3::ONE);
    let find = |key: &str, ty: &str| {
        let mut pat = (key.len() as u32).to_le_bytes().to_vec();
        pat.extend_from_slice(key.as_bytes());
        pat.extend_from_slice(&(ty.len() as u32).to_le_bytes());
        pat.extend_from_slice(ty.as_bytes());
        let at = bytes
            .windows(pat.len())
            .position(|w| w == pat)
            .unwrap_or_else(|| panic!("no {key}"));
        let size = u32::from_le_bytes(
            bytes[at + pat.len()..at + pat.len() + 4]
                .try_into()
                .unwrap(),
        ) as usize;
        bytes[at + pat.len() + 4..at + pat.len() + 4 + size].to_vec()
    };
    assert_eq!(find("name", "string"), b"flame");
    let vec3i =
        |b: Vec<u8>| [0, 1, 2].map(|k| i32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap()));
    assert_eq!(vec3i(find("file_bbox_min", "vec3i")), [3, 2, 5]);
    assert_eq!(vec3i(find("file_bbox_max", "vec3i")), [9, 8, 17]);
    assert_eq!(
        i64::from_le_bytes(find("file_voxel_count", "int64").try_into().unwrap()),
        2
    );
}
