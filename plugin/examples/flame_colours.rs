//! Flame-test colours: the chromaticity (CIE 1931) of the radiance through a 1 m slab at 2200 K seeded with one
//! species, for each species with shipped lines (and bands), at three number densities, without soot. Results are
//! in docs/results/log.md, "Flame-test colours" and "Molecular bands".
//!
//!     cargo run --release -p firemedium-plugin --example flame_colours

use firemedium_plugin::params::Param;
use firemedium_plugin::volume::{FireVolume, Ray};
use glam::DVec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::temp_dir().join(format!("firemedium-flame-colours-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    // A 4³ grid of one value (the thesis's ASCII format), over the unit cube.
    let grid = |name: &str, v: f64| -> std::io::Result<String> {
        let p = dir.join(name);
        let body: Vec<String> = (0..64).map(|_| v.to_string()).collect();
        std::fs::write(&p, format!("4 4 4\n{}\n", body.join(" ")))?;
        Ok(p.display().to_string())
    };
    let (d, t, s) = (
        grid("d.txt", 0.0)?,
        grid("t.txt", 2200.0)?,
        grid("s.txt", 1.0)?,
    );
    for sym in ["Li", "Na", "K", "Ca", "Sr", "Ba", "Cu"] {
        let mut line = format!("{sym}:");
        for n in [1e16, 1e18, 1e20] {
            let list = vec![
                Param::string("densityfile", &d),
                Param::string("temperaturefile", &t),
                Param::strings("species", &[sym]),
                Param::strings("speciesfiles", &[&s]),
                Param::float("speciesscale", n),
                Param::string("interpolation", "nearest"),
                Param::int("bins", 40),
                Param::float("lambdamin", 380.0),
                Param::float("lambdamax", 780.0),
            ];
            let v = FireVolume::new(&list)?;
            let c = v.channels();
            let (mut l, mut tr) = (vec![0.0; c], vec![0.0; c]);
            let ray = Ray {
                o: DVec3::new(-0.5, 0.5, 0.5),
                d: DVec3::X,
                t0: 0.0,
                t1: 3.0,
                seed: 1,
                first: None,
            };
            v.integrate(&ray, &mut l, &mut tr);
            let w = v.channel_xyz();
            let xyz = (0..c).fold(DVec3::ZERO, |acc, ch| acc + w[ch] * l[ch]);
            let sum = xyz.x + xyz.y + xyz.z;
            line += &format!(
                "  N {n:.0e}: xy ({:.3}, {:.3}) Y {:.3e}",
                xyz.x / sum,
                xyz.y / sum,
                xyz.y
            );
        }
        println!("{line}");
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}
