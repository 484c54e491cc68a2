//! The fires' fuel: cells on the logs, the pool, the wick, the torch head; each kind's model.

use super::*;

/// Cells over a cylinder's side (`along` × `around`; `upper_only`: those facing more up than down), and the
/// links between neighbours along and around it, their conductance the geometry's w/Δx (× the fuel's k·d later).
fn cylinder_cells(
    a: DVec3,
    b: DVec3,
    r: f64,
    along: usize,
    around: usize,
    upper_only: bool,
) -> (Vec<Cell>, Vec<Link>) {
    let axis = (b - a).normalize();
    let u = if axis.z.abs() < 0.9 {
        axis.cross(DVec3::Z).normalize()
    } else {
        axis.cross(DVec3::X).normalize()
    };
    let v = axis.cross(u);
    let len = (b - a).length();
    let (dl, dphi) = (
        len / along as f64,
        2.0 * std::f64::consts::PI * r / around as f64,
    );
    let mut cells = Vec::new();
    let mut index = vec![None; along * around];
    for i in 0..along {
        for j in 0..around {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / around as f64;
            let n = u * phi.cos() + v * phi.sin();
            if upper_only && n.z < -0.2 {
                continue;
            }
            index[i * around + j] = Some(cells.len());
            cells.push(Cell {
                p: a + axis * (len * (i as f64 + 0.5) / along as f64) + n * r,
                normal: n,
                area: dl * dphi,
                load: 0.0,
                t: T_AMB,
            });
        }
    }
    let mut links = Vec::new();
    for i in 0..along {
        for j in 0..around {
            let Some(here) = index[i * around + j] else {
                continue;
            };
            let next_along = (i + 1 < along)
                .then(|| index[(i + 1) * around + j])
                .flatten();
            let next_around = (around > 2)
                .then(|| index[i * around + (j + 1) % around])
                .flatten();
            for (there, g) in [(next_along, dphi / dl), (next_around, dl / dphi)] {
                if let Some(b) = there {
                    links.push(Link {
                        a: here,
                        b,
                        conductance: g,
                    });
                }
            }
        }
    }
    (cells, links)
}

fn disk_cells(centre: DVec3, r: f64, rings: usize) -> Vec<Cell> {
    let mut cells = Vec::new();
    for i in 0..rings {
        let (r0, r1) = (
            r * i as f64 / rings as f64,
            r * (i + 1) as f64 / rings as f64,
        );
        let n = (6 * i).max(1);
        for j in 0..n {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n as f64;
            let rm = 0.5 * (r0 + r1);
            cells.push(Cell {
                p: centre + DVec3::new(rm * phi.cos(), rm * phi.sin(), 0.0),
                normal: DVec3::Z,
                area: std::f64::consts::PI * (r1 * r1 - r0 * r0) / n as f64,
                load: 0.0,
                t: T_AMB,
            });
        }
    }
    cells
}

impl Kind {
    /// The model constants, fuel surfaces and their links (conductances in W/K) of this kind.
    pub fn setup(self) -> (Model, Vec<Cell>, Vec<Link>) {
        let (m, cells, mut links) = self.surfaces();
        for l in &mut links {
            l.conductance *= m.fuel_conduction;
        }
        (m, cells, links)
    }

    fn surfaces(self) -> (Model, Vec<Cell>, Vec<Link>) {
        let base = Model {
            half_width: 0.6,
            height: 1.6,
            fuel_load: 20.0,
            nu_a: 3.0e3,
            t_a: 1.0e4,
            release: 750.0,
            heat_capacity: 2.1e4,
            mixing_time: 0.35,
            fuel_absorptance: 0.9,
            flame_contact: 20.0,
            // Wood, 0.12 W/(m K), over the 5 mm a heat capacity of 4 kJ/(m² K) holds (ρc ≈ 7.5e5 J/(m³ K)).
            fuel_conduction: 0.12 * 5.3e-3,
            fuel_heat_capacity: 4.0e3,
            boiling: 0.0,
            gasification: 1.8e6,
            nu_b: 3.0,
            t_s: 600.0,
            smoke_decay: 0.8,
            sigma0: 0.015,
            kappa: 4.0e-4,
            buoyancy: 2.5,
            turbulence: 1.2,
            turbulence_scale: 0.15,
            soot_yield: 0.015,
            // A match (kindling) under the logs' raised tips, for its first seconds: the rest catches from it.
            match_at: DVec3::new(0.0, 0.0, 0.1),
            match_radius: 0.25,
            t_match: 900.0,
            match_seconds: 5.0,
            dt: 1.0 / 120.0,
        };
        match self {
            Kind::Campfire => {
                // Four logs (r 6 cm, 70 cm) lying as a cross on the ground, tips raised towards the centre.
                let (mut cells, mut links) = (Vec::new(), Vec::new());
                for k in 0..4 {
                    let a = std::f64::consts::FRAC_PI_4 + k as f64 * std::f64::consts::FRAC_PI_2;
                    let dir = DVec3::new(a.cos(), a.sin(), 0.0);
                    let (c, l) = cylinder_cells(
                        dir * 0.42 + DVec3::Z * 0.06,
                        dir * 0.04 + DVec3::Z * 0.16,
                        0.06,
                        14,
                        10,
                        true,
                    );
                    let first = cells.len();
                    links.extend(l.into_iter().map(|l| Link {
                        a: l.a + first,
                        b: l.b + first,
                        ..l
                    }));
                    cells.extend(c);
                }
                // Wood's flames hold about a tenth of the fuel they burn as soot before their tips oxidise it (the
                // smoke keeps little of it): peak volume fractions near 1e-7 and a fifth of the heat radiated.
                let m = Model {
                    soot_yield: 0.1,
                    ..base
                };
                (m, cells, links)
            }
            Kind::Candle => {
                // A wick 1 cm tall (r 1 mm) above a 2 cm wax column; laminar, small, hot, little soot.
                let (cells, links) = cylinder_cells(
                    DVec3::new(0.0, 0.0, 0.02),
                    DVec3::new(0.0, 0.0, 0.03),
                    0.001,
                    4,
                    8,
                    false,
                );
                let m = Model {
                    half_width: 0.025,
                    height: 0.1,
                    fuel_load: 50.0,
                    release: 1200.0,
                    heat_capacity: 1.07e4,
                    mixing_time: 0.03,
                    // The wick is fed by the molten wax and held at its temperature: nothing heats or cools it.
                    fuel_absorptance: 0.0,
                    flame_contact: 0.0,
                    t_s: 500.0,
                    nu_b: 1.0,
                    smoke_decay: 5.0,
                    sigma0: 0.0012,
                    kappa: 2.0e-6,
                    buoyancy: 0.35,
                    turbulence: 0.004,
                    turbulence_scale: 0.02,
                    soot_yield: 0.01,
                    match_at: DVec3::new(0.0, 0.0, 0.025),
                    match_radius: 0.02,
                    t_match: 640.0,
                    match_seconds: 1e9,
                    dt: 1.0 / 480.0,
                    ..base
                };
                (m, cells, links)
            }
            Kind::Pool => {
                // A heptane pool of radius 0.5 m, lit over its whole surface by a pilot flame; sooty, turbulent.
                // (A liquid: no conduction between cells; its surface held at its boiling point, 371.6 K.)
                let (cells, links) = (disk_cells(DVec3::new(0.0, 0.0, 0.005), 0.5, 12), Vec::new());
                let m = Model {
                    half_width: 1.0,
                    height: 3.0,
                    release: 900.0,
                    heat_capacity: 3.56e4,
                    mixing_time: 0.6,
                    sigma0: 0.04,
                    kappa: 3.0e-3,
                    buoyancy: 3.5,
                    turbulence: 1.0,
                    turbulence_scale: 0.4,
                    soot_yield: 0.037,
                    match_radius: 1.0,
                    // Heptane: boiling at 371.6 K; its heat of gasification (latent heat and the sensible heat
                    // to boiling) 0.48 MJ/kg (Drysdale, after Tewarson).
                    boiling: 371.6,
                    gasification: 0.48e6,
                    ..base
                };
                (m, cells, links)
            }
            Kind::Torch => {
                // A rag head (r 4 cm, 10 cm tall) on a stick, lit at once.
                let (cells, links) = cylinder_cells(
                    DVec3::new(0.0, 0.0, 0.12),
                    DVec3::new(0.0, 0.0, 0.22),
                    0.04,
                    8,
                    12,
                    false,
                );
                let m = Model {
                    half_width: 0.2,
                    height: 0.9,
                    release: 700.0,
                    mixing_time: 0.2,
                    sigma0: 0.012,
                    kappa: 5.0e-4,
                    buoyancy: 1.6,
                    turbulence: 0.25,
                    turbulence_scale: 0.08,
                    match_at: DVec3::new(0.0, 0.0, 0.17),
                    match_radius: 0.2,
                    ..base
                };
                (m, cells, links)
            }
        }
    }
}
