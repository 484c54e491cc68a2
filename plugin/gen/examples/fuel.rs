//! The campfire's fuel over time: how many cells burn, how hot, how much fuel is left, the flames' mass; then,
//! at the end, where a cell's heat comes from and where it goes, and the flames' radiated power (what the
//! renderer's fire light measures on the same frame). docs/results/log.md, "A campfire that burns on its own".
//!
//!     cargo run --release -p firemedium-gen --example fuel -- 60

use firemedium_gen::{Kind, Sim, T_AMB};

fn main() {
    let until: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(30.0);
    let mut sim = Sim::new(Kind::Campfire, 1);
    println!(
        "t (s) | cells > 500 K | their mean T (K) | fuel left | flame mass (kg) | hottest blob (K)"
    );
    for t in [1.0, 5.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 90.0, 120.0] {
        if t > until {
            break;
        }
        sim.run_to(t);
        let (hot, _, mean, left) = sim.fuel_summary();
        let flame: f64 = sim.blobs.iter().map(|b| b.m_flame).sum();
        let hottest = sim.blobs.iter().map(|b| b.t).fold(0.0, f64::max);
        println!(
            "{t} | {hot} | {mean:.0} | {:.1} % | {flame:.2e} | {hottest:.0}",
            100.0 * left
        );
    }
    let m = sim.model.clone();
    let (heat, exchange) = (sim.fuel_heating(), sim.fuel_exchange());
    let n = sim.cells.len() as f64;
    let mut terms = [0.0; 5];
    for (i, c) in sim.cells.iter().enumerate() {
        let k = m.nu_a * (-m.t_a / c.t).exp();
        let each = [
            m.flame_contact * (heat[i].1 - c.t),
            m.fuel_absorptance * heat[i].0,
            m.fuel_absorptance * exchange[i],
            m.fuel_absorptance * 5.670374419e-8 * (c.t.powi(4) - T_AMB.powi(4)),
            m.gasification * c.load * k,
        ];
        for (t, e) in terms.iter_mut().zip(each) {
            *t += e / n;
        }
    }
    let power: f64 = sim.blobs.iter().map(|b| sim.blob_power(b)).sum();
    println!(
        "at {} s, per cell (W/m²): gas touching it {:.0}, flames' radiation {:.0}, other logs {:.0}; \
         its own radiation −{:.0}, gasifying wood −{:.0}. The flames radiate {power:.0} W.",
        sim.time, terms[0], terms[1], terms[2], terms[3], terms[4]
    );
}
