use firemedium_dataset::vdb::write_sparse;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let apart: i32 = args[1].parse().unwrap();
    let leaf = |o: [i32; 3]| (o, [u64::MAX; 8], vec![1e-3f32; 512]);
    let t = |o: [i32; 3]| (o, [u64::MAX; 8], vec![1500f32; 512]);
    let b = write_sparse(
        &[
            (
                "density",
                vec![leaf([0, 0, 0]), leaf([apart, apart, apart])],
            ),
            ("temperature", vec![t([0, 0, 0]), t([apart, apart, apart])]),
        ],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.01),
    );
    std::fs::write(&args[2], b).unwrap();
}
