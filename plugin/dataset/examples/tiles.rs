use firemedium_dataset::vdb::write_tiled;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: i32 = args[1].parse().unwrap();
    let mut d = Vec::new();
    let mut t = Vec::new();
    for k in 0..n {
        for j in 0..8 {
            for i in 0..8 {
                d.push(([128 * i, 128 * j, 128 * k], 128, 1e-4f32));
                t.push(([128 * i, 128 * j, 128 * k], 128, 1500f32));
            }
        }
    }
    let b = write_tiled(
        &[("density", vec![], d), ("temperature", vec![], t)],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.01),
    );
    std::fs::write(&args[2], b).unwrap();
}
