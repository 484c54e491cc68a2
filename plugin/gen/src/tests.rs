use super::*;

#[test]
fn embers_are_thrown_at_their_rate_and_kept_while_they_glow_inside_the_domain() {
    let (rate, t) = (60.0, 1.0);
    let mut sim = Sim::new(Kind::Campfire, 3);
    sim.ember_rate = Some(rate);
    sim.run_to(t);
    // About rate × t: each step that burns fuel throws floor(U + rate·dt) embers (none before the first
    // cell burns).
    let n = sim.embers_born as f64;
    assert!(n > 0.5 * rate * t && n < 1.05 * rate * t, "{n} thrown");
    let m = &sim.model;
    assert!(!sim.embers.is_empty() && sim.embers.len() < sim.embers_born);
    for e in &sim.embers {
        assert!(e.x.z >= 0.0 && e.x.z <= m.height && e.x.x.abs() <= m.half_width);
        // (Burning, a small spark may run hotter than it was born; it is never cold.)
        assert!(e.temperature() > EMBER_DEAD_K && e.temperature() < 2500.0);
        assert!(e.age > 0.0 && e.age <= t + 1e-9);
        assert!((0.5e-3..=3.0e-3).contains(&e.r));
    }
    // The same seed, the same embers; and the blobs do not see them.
    let mut again = Sim::new(Kind::Campfire, 3);
    again.ember_rate = Some(rate);
    again.run_to(t);
    assert_eq!(again.embers, sim.embers);
    let mut none = Sim::new(Kind::Campfire, 3);
    none.run_to(t);
    assert_eq!(none.blobs.len(), sim.blobs.len());
    assert!(none
        .blobs
        .iter()
        .zip(&sim.blobs)
        .all(|(a, b)| a.x == b.x && a.t == b.t));
    // The PLY the plugin reads: a header and 36 bytes per ember.
    let ply = embers_ply(&sim.embers);
    let head = ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    assert_eq!(ply.len() - head, 36 * sim.embers.len());
}

#[test]
fn an_ember_in_still_air_falls_as_quadratic_drag_says() {
    // Gravity against quadratic drag from rest: v(t) = v_t tanh(g' t / v_t), g' = g (1 − ρ_a/ρ_p),
    // v_t = sqrt(8 ρ_p r g' / (3 C_d ρ_a)), air at 293.15 K (no blobs: the gas is ambient and still).
    let mut sim = Sim::new(Kind::Campfire, 1);
    sim.model.turbulence = 0.0;
    sim.model.dt = 1e-3;
    // (Its char not burning: the radius the closed form assumes stays.)
    sim.ember_char.oxygen = 0.0;
    let r = 1e-3;
    sim.embers.push(Ember {
        x: DVec3::new(0.0, 0.0, 1.55),
        v: DVec3::ZERO,
        r,
        t0: 5000.0,
        age: 0.0,
        now: (5000.0, r),
    });
    for _ in 0..300 {
        sim.step_embers(0.0, &[]);
    }
    let rho_a = 353.0 / T_AMB;
    let rho_p = firemedium_core::ember::CHAR_DENSITY;
    let g = 9.81 * (1.0 - rho_a / rho_p);
    let vt = (8.0 * rho_p * r * g / (3.0 * 0.47 * rho_a)).sqrt();
    let want = vt * (g * 0.3 / vt).tanh();
    let e = sim.embers.first().expect("still falling");
    assert!((-e.v.z / want - 1.0).abs() < 1e-4, "{} vs {want}", -e.v.z);
}

#[test]
fn flame_production_equals_fuel_consumption_every_step() {
    for kind in Kind::ALL {
        let mut sim = Sim::new(kind, 3);
        let total0: f64 = sim.cells.iter().map(|c| c.load * c.area).sum();
        let mut consumed = 0.0;
        let mut removed = 0.0;
        let mut decayed = 0.0;
        for _ in 0..120 {
            let before: f64 = sim.cells.iter().map(|c| c.load * c.area).sum();
            let l = sim.step();
            let after: f64 = sim.cells.iter().map(|c| c.load * c.area).sum();
            // The fuel that left the cells is the flame that entered the blobs, to 1e-6 relative.
            assert!(
                ((before - after) - l.flame_produced).abs()
                    <= 1e-6 * l.flame_produced.max(1e-300) + 1e-18,
                "{kind:?}: fuel −{} vs flame +{}",
                before - after,
                l.flame_produced
            );
            // And it is in the blobs born this step (age 0, appended after the others moved), counted from
            // the blobs themselves rather than from the ledger.
            let born: f64 = sim
                .blobs
                .iter()
                .filter(|b| b.age == 0.0)
                .map(|b| b.m_flame)
                .sum();
            assert!(
                ((before - after) - born).abs() <= 1e-6 * born.max(1e-300) + 1e-18,
                "{kind:?}: fuel −{} vs new blobs {born}",
                before - after
            );
            consumed += l.fuel_consumed;
            removed += l.removed;
            decayed += l.smoke_decayed;
        }
        // Whole run: fuel left + blob mass + smoke decayed + mass that left the domain = initial fuel.
        let left: f64 = sim.cells.iter().map(|c| c.load * c.area).sum();
        let in_blobs: f64 = sim.blobs.iter().map(|b| b.m_flame + b.m_smoke).sum();
        let books = left + in_blobs + decayed + removed;
        assert!(
            (books / total0 - 1.0).abs() < 1e-9,
            "{kind:?}: {books} vs {total0} (consumed {consumed})"
        );
        assert!(
            consumed > 0.0 && !sim.blobs.is_empty(),
            "{kind:?} did not burn"
        );
        // Temperatures stay physical: blobs between ambient and the hottest birth temperature.
        let t_max = sim.cells.iter().map(|c| c.t).fold(0.0, f64::max) + sim.model.release;
        for b in &sim.blobs {
            assert!(
                b.t >= T_AMB && b.t <= t_max && b.t < 3000.0,
                "{kind:?}: {}",
                b.t
            );
        }
    }
}

#[test]
fn stiff_radiative_cooling_is_exact_and_never_overshoots() {
    // dT/dt = −K(T) T⁴ with the soot-derived K: the table's exact step against 100 000 RK4 steps, over one
    // step and over a second; a stiff step never passes ambient; the map is monotone in T and in dt.
    let (m, ..) = Kind::Campfire.setup();
    let cool = Cooling::new(m.soot_yield, m.heat_capacity);
    let rate = |t: f64| -cool.k(t) * t.powi(4);
    for (t0, span) in [(1800.0f64, 1.0 / 120.0), (2400.0, 1.0), (900.0, 10.0)] {
        let n = 100_000;
        let h = span / n as f64;
        let mut t = t0;
        for _ in 0..n {
            let k1 = rate(t);
            let k2 = rate(t + 0.5 * h * k1);
            let k3 = rate(t + 0.5 * h * k2);
            let k4 = rate(t + h * k3);
            t += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        let exact = cool.step(t0, span);
        assert!(
            ((exact - t) / (t0 - t)).abs() < 1e-4,
            "T0 {t0}, {span} s: table {exact} vs RK4 {t} (drop {})",
            t0 - t
        );
    }
    let mut last = f64::INFINITY;
    for dt in [1e-4, 1e-2, 1.0, 1e3, 1e9] {
        let t1 = cool.step(2500.0, dt);
        assert!(
            t1.is_finite() && (T_AMB..2500.0).contains(&t1) && t1 <= last,
            "{dt}: {t1}"
        );
        last = t1;
    }
    assert!(cool.step(1500.0, 0.01) < cool.step(1600.0, 0.01));
    assert_eq!(cool.step(f64::NAN, 1.0), T_AMB);
    assert_eq!(cool.step(250.0, 1.0), T_AMB);
}

#[test]
fn a_flame_radiates_what_the_renderer_renders_its_soot_emitting() {
    // The power a blob's cooling removes is what the plugin's soot of the same volume fraction emits: 4π ∫ σ_a
    // B_λ dλ over the blob's volume, here by a plain trapezoid in λ (10 nm to 0.1 mm in 0.05 nm steps), for every
    // kind's constants — the heat the flames lose and the light the renderer draws are the same number.
    use firemedium_core::blackbody::spectral_radiance;
    use firemedium_core::soot::{SootOptics, HOTTEL_ALPHA};
    let soot = SootOptics::propane();
    for kind in Kind::ALL {
        let (m, ..) = kind.setup();
        let cool = Cooling::new(m.soot_yield, m.heat_capacity);
        let mass = 1e-4;
        // (Any volume: f_v = Y_s ρ / ρ_s, σ_a = f_v κ(λ), so σ_a V = κ(λ) Y_s m / ρ_s.)
        let fv_volume = m.soot_yield * mass / super::RHO_SOOT;
        for t in [800.0, 1400.0, 2200.0] {
            let (mut sum, mut l) = (0.0, 10.0);
            let h = 0.05;
            let f = |l: f64| soot.kappa(l, 1.0, HOTTEL_ALPHA) * spectral_radiance(t, l);
            while l < 1e5 {
                sum += 0.5 * h * (f(l) + f(l + h));
                l += h;
            }
            let emitted = 4.0 * std::f64::consts::PI * fv_volume * sum;
            let lost = cool.power(t, mass, m.heat_capacity);
            assert!(
                (lost / emitted - 1.0).abs() < 2e-3,
                "{kind:?} at {t} K: cooling {lost} W vs soot emitting {emitted} W"
            );
        }
    }
}

#[test]
fn the_fuel_step_balances_its_surface_exactly() {
    let s = FuelBalance {
        flux: 2e4,
        h: 20.0,
        t_gas: 1300.0,
        emissivity: 0.9,
        heat_capacity: 4e3,
        load: 20.0,
        nu_a: 3e3,
        t_a: 1e4,
        gasification: 1.8e6,
    };
    // The step satisfies its equation, for short and stiff steps.
    for (t0, dt) in [
        (300.0, 1.0 / 120.0),
        (900.0, 1.0 / 120.0),
        (600.0, 10.0),
        (2000.0, 1e6),
    ] {
        let t = implicit_fuel_temperature(t0, &s, dt);
        let residual = s.heat_capacity * (t - t0) / dt - s.flux - s.h * (s.t_gas - t)
            + s.emissivity * SIGMA * (t.powi(4) - T_AMB.powi(4))
            + s.gasification * s.burnt(t, dt) / dt;
        let scale = s.flux + s.h * s.t_gas;
        assert!(
            residual.abs() < 1e-8 * scale,
            "T0 {t0} dt {dt}: T {t}, residual {residual} W/m²"
        );
        assert!(t > T_AMB && t < 2000.0_f64.max(t0) + 1.0, "{t}");
    }
    // Without gasification or contact, a long step reaches the radiative equilibrium ε σ (T⁴ − T_amb⁴) = flux.
    let bare = FuelBalance {
        h: 0.0,
        gasification: 0.0,
        ..s
    };
    let eq = implicit_fuel_temperature(300.0, &bare, 1e12);
    let want = (3e4_f64.min(2e4) / (0.9 * SIGMA) + T_AMB.powi(4)).powf(0.25);
    assert!((eq / want - 1.0).abs() < 1e-9, "{eq} vs {want}");
    // Gasification holds a burning surface down: the same heating, with the fuel taking 1.8 MJ/kg to gasify,
    // settles well below the bare equilibrium.
    let held = implicit_fuel_temperature(300.0, &FuelBalance { h: 0.0, ..s }, 1e3);
    assert!(held < eq - 50.0 && held > 500.0, "{held} vs {eq}");
    assert!(implicit_fuel_temperature(300.0, &FuelBalance { flux: 3e4, ..bare }, 1e-3) < 301.0);
}

#[test]
fn conduction_along_a_log_decays_a_ring_mode_as_diffusion_says() {
    // A ring of cells around a log (links' conductance G = k·d·w/Δx): a temperature mode cos(2πj/n) decays at
    // the discrete rate 2G(1 − cos(2π/n))/(C A) (the fuel map's diffusion, Stam & Fiume §6.1), here against
    // the generator's own links and 2 000 explicit steps.
    let (m, cells, links) = Kind::Torch.setup();
    let around = 12;
    // The torch head's first ring: cells 0..12, linked around.
    let ring: Vec<&Link> = links
        .iter()
        .filter(|l| l.a < around && l.b < around)
        .collect();
    assert_eq!(ring.len(), around);
    let g = ring[0].conductance;
    let ca = m.fuel_heat_capacity * cells[0].area;
    let rate = 2.0 * g * (1.0 - (2.0 * std::f64::consts::PI / around as f64).cos()) / ca;
    let mut t: Vec<f64> = (0..around)
        .map(|j| 600.0 + 100.0 * (2.0 * std::f64::consts::PI * j as f64 / around as f64).cos())
        .collect();
    let (steps, dt) = (2000, 10.0);
    for _ in 0..steps {
        let mut q = vec![0.0; around];
        for l in &ring {
            let flow = l.conductance * (t[l.b] - t[l.a]);
            q[l.a] += flow;
            q[l.b] -= flow;
        }
        for j in 0..around {
            t[j] += dt * q[j] / ca;
        }
    }
    let amplitude = t[0] - 600.0;
    let want = 100.0 * (-rate * dt * steps as f64).exp();
    assert!(
        (amplitude / want - 1.0).abs() < 0.01,
        "{amplitude} vs {want} (rate {rate} 1/s)"
    );
    assert!(want < 99.0, "the mode barely moved: {want}");
}

#[test]
fn the_campfire_catches_from_its_kindling_and_burns_on_without_it() {
    // The kindling lights the logs' raised tips (within 25 cm of the centre) for 5 s; the logs' own flames
    // then keep those cells burning, heated by the flames' radiation and the gas touching them against their
    // emission and the heat their wood takes to gasify, and heat the next cells. 15 s after the kindling is
    // out, every cell it lit still burns, near the surface temperatures of burning wood, at wood's burning
    // rate (5–20 g/(m² s)).
    let mut sim = Sim::new(Kind::Campfire, 1);
    let m = sim.model.clone();
    let lit: Vec<usize> = (0..sim.cells.len())
        .filter(|&i| (sim.cells[i].p - m.match_at).length() < m.match_radius)
        .collect();
    assert!(
        lit.len() > 50 && lit.len() < sim.cells.len(),
        "{}",
        lit.len()
    );
    sim.run_to(m.match_seconds + 15.0);
    let load0: Vec<f64> = sim.cells.iter().map(|c| c.load).collect();
    sim.run_to(m.match_seconds + 20.0);
    for &i in &lit {
        let c = &sim.cells[i];
        assert!((560.0..760.0).contains(&c.t), "cell {i}: {} K", c.t);
        let rate = (load0[i] - c.load) / 5.0;
        assert!((5e-3..2e-2).contains(&rate), "cell {i}: {rate} kg/(m² s)");
    }
    // The flames have begun to heat the cells beyond the kindling, and the fire is not out.
    let beyond = (0..sim.cells.len())
        .filter(|i| !lit.contains(i))
        .map(|i| sim.cells[i].t)
        .fold(0.0, f64::max);
    assert!(beyond > 400.0, "{beyond}");
    assert!(sim.blobs.iter().any(|b| b.t > 1300.0));
}

#[test]
fn the_same_seed_gives_the_same_fields_and_another_seed_does_not() {
    let run = |seed| {
        let mut sim = Sim::new(Kind::Torch, seed);
        sim.run_to(0.5);
        let f = voxelise(&sim, 24, false);
        f.density
            .iter()
            .chain(&f.temperature)
            .fold(0xcbf2_9ce4_8422_2325u64, |h, v| {
                (h ^ v.to_bits() as u64).wrapping_mul(0x100_0000_01b3)
            })
    };
    assert_eq!(run(7), run(7));
    assert_ne!(run(7), run(8));
}

#[test]
fn warped_blobs_keep_their_mass_and_change_their_shape() {
    // §4's warp through the campfire's turbulent wind (t₀ = 0.1 s: ~0.1 m at its ~1 m/s): the kernels are
    // evaluated at back-traced points and scaled by the back-trace's Jacobian — the fire's total flame mass
    // stays within 7 % of the round blobs' (5.4 %: the round kernels are cut at a 3σ box, the warped at
    // 6σ; 3.6 % with the wider fire of the generator before its kindling was local), while the field itself changes (blobs stretched along the wind: 17 % of the mass moves; asserted
    // > 10 %). Through a still wind the warp is the identity.
    let mut sim = Sim::new(Kind::Campfire, 3);
    sim.run_to(0.75);
    let total = |f: &Fields| f.flame.iter().map(|&v| v as f64).sum::<f64>();
    let round = voxelise(&sim, 40, false);
    sim.warp = Some((0.1, 0.0));
    let warped = voxelise(&sim, 40, false);
    let (a, b) = (total(&round), total(&warped));
    assert!(
        a > 0.0 && (b / a - 1.0).abs() < 0.07,
        "mass {a} round, {b} warped"
    );
    let moved: f64 = round
        .flame
        .iter()
        .zip(&warped.flame)
        .map(|(&x, &y)| (x as f64 - y as f64).abs())
        .sum::<f64>()
        / (2.0 * a);
    assert!(
        moved > 0.1,
        "fraction of the mass moved by the warp: {moved}"
    );
    // η shrinks the kernels: denser, the same mass.
    sim.warp = Some((0.1, 0.2));
    let tight = voxelise(&sim, 40, false);
    // (Concentration: Σ ρ², which a narrower kernel of the same mass raises: +2.4 % here, most kernels at
    // the half-voxel floor already.)
    let conc = |f: &Fields| f.flame.iter().map(|&v| (v as f64).powi(2)).sum::<f64>();
    let (c1, c0) = (conc(&tight), conc(&warped));
    assert!(
        c1 > 1.01 * c0 && (total(&tight) / a - 1.0).abs() < 0.07,
        "concentration {c1} vs {c0}, mass {} vs {a}",
        total(&tight)
    );
    // A still wind: the identity (to rounding, and the e⁻¹⁸ beyond the warped kernels' 6σ cut).
    sim.model.turbulence = 0.0;
    sim.warp = None;
    let still = voxelise(&sim, 40, false);
    sim.warp = Some((0.3, 0.0));
    let still_warped = voxelise(&sim, 40, false);
    let top = still.flame.iter().copied().fold(0f32, f32::max);
    for (x, y) in still.flame.iter().zip(&still_warped.flame) {
        assert!((x - y).abs() <= 1e-5 * x + 1e-7 * top, "{x} vs {y}");
    }
}

#[test]
fn the_wind_is_divergence_free_apart_from_buoyancy() {
    let n = Noise { seed: 5 };
    let h = 1e-2;
    for p in [DVec3::new(0.3, 1.7, -2.2), DVec3::new(5.1, 0.2, 0.9)] {
        let div = (n.curl(p + DVec3::X * h).x - n.curl(p - DVec3::X * h).x
            + n.curl(p + DVec3::Y * h).y
            - n.curl(p - DVec3::Y * h).y
            + n.curl(p + DVec3::Z * h).z
            - n.curl(p - DVec3::Z * h).z)
            / (2.0 * h);
        let scale = n.curl(p).length();
        assert!(div.abs() < 1e-2 * scale.max(1.0), "div {div} at {p}");
    }
}

#[test]
fn the_reaction_field_holds_the_heat_the_young_blobs_release() {
    // Σ reaction · voxel volume over the grid = Σ over blobs of (m_f + m_s) H / τ_r e^(−age/τ_r) — the
    // blobs' own sum, not the splat — to the kernels' truncation at 3σ and the domain's edges.
    let mut sim = Sim::new(Kind::Torch, 5);
    sim.run_to(1.0);
    let f = voxelise(&sim, 48, false);
    let on_grid: f64 = f.reaction.iter().map(|&q| q as f64).sum::<f64>() * f.voxel.powi(3);
    let from_blobs: f64 = sim
        .blobs
        .iter()
        .map(|b| {
            (b.m_flame + b.m_smoke) * HEAT_OF_COMBUSTION / REACTION_TIME
                * (-b.age / REACTION_TIME).exp()
        })
        .sum();
    assert!(from_blobs > 0.0);
    assert!(
        (on_grid / from_blobs - 1.0).abs() < 0.05,
        "{on_grid} W on the grid vs {from_blobs} W from the blobs"
    );
}

#[test]
fn a_liquid_surface_stays_at_its_boiling_point_and_evaporates_the_heat_beyond() {
    let t_b = 371.6;
    let s = FuelBalance {
        flux: 2e4,
        h: 20.0,
        t_gas: 1200.0,
        emissivity: 0.9,
        heat_capacity: 4e3,
        load: 20.0,
        nu_a: 3e3,
        t_a: 1e4,
        gasification: 0.48e6,
    };
    // At its boiling point, a step evaporates what reaches the surface beyond its own radiation, at L.
    let dt = 1.0 / 120.0;
    let (t, burnt) = liquid_fuel_step(t_b, &s, t_b, dt);
    let net = 2e4 + 20.0 * (1200.0 - t_b) - 0.9 * SIGMA * (t_b.powi(4) - T_AMB.powi(4));
    assert_eq!(t, t_b);
    assert!((burnt / (net * dt / 0.48e6) - 1.0).abs() < 1e-12, "{burnt}");
    // From below, the heat that warms it to boiling is taken first (over a step long enough to reach it); a cold
    // surface under a weak flux only warms.
    let (t, burnt) = liquid_fuel_step(360.0, &s, t_b, 10.0);
    assert!(
        (burnt / ((net * 10.0 - 4e3 * (t_b - 360.0)) / 0.48e6) - 1.0).abs() < 1e-12 && t == t_b
    );
    let (t, burnt) = liquid_fuel_step(360.0, &s, t_b, dt);
    assert!(burnt == 0.0 && t > 360.0 && t < t_b, "{t} {burnt}");
    let weak = FuelBalance {
        flux: 100.0,
        h: 0.0,
        ..s
    };
    let (t, burnt) = liquid_fuel_step(300.0, &weak, t_b, dt);
    assert!(burnt == 0.0 && t > 300.0 && t < 301.0, "{t} {burnt}");
    // Never more than the load.
    let (_, burnt) = liquid_fuel_step(t_b, &FuelBalance { load: 1e-6, ..s }, t_b, 10.0);
    assert_eq!(burnt, 1e-6);
}

/// The heptane pool (1 m across) burns at the rate large pool fires do: Babrauskas' correlation
/// ṁ″ = ṁ″∞ (1 − e^{−kβ D}), heptane ṁ″∞ = 0.101 kg/(m² s), kβ = 1.1 m⁻¹ (SFPE Handbook) — 0.0675 kg/(m² s) — within
/// 25 %, its surface at its boiling point, and burning on at the same rate once the pilot flame is gone.
#[test]
fn a_heptane_pool_burns_at_the_rate_large_pool_fires_do() {
    let mut sim = Sim::new(Kind::Pool, 1);
    let area: f64 = sim.cells.iter().map(|c| c.area).sum();
    let fuel = |sim: &Sim| sim.cells.iter().map(|c| c.area * c.load).sum::<f64>();
    let rate = |sim: &mut Sim, from: f64, to: f64| {
        sim.run_to(from);
        let before = fuel(sim);
        sim.run_to(to);
        (before - fuel(sim)) / ((to - from) * area)
    };
    let lit = rate(&mut sim, 2.0, 4.0);
    let pilot = sim.model.match_seconds;
    let on = rate(&mut sim, pilot + 1.0, pilot + 4.0);
    let want = 0.101 * (1.0 - (-1.1_f64 * 1.0).exp());
    assert!(
        (lit / want - 1.0).abs() < 0.25,
        "{lit} kg/(m² s) against {want}"
    );
    assert!(
        (on / lit - 1.0).abs() < 0.1,
        "{on} after the pilot, {lit} with it"
    );
    assert!(
        sim.cells.iter().all(|c| (c.t - 371.6).abs() < 1e-9),
        "the surface boils"
    );
}
