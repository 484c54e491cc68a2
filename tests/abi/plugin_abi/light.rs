//! The fire light through the ABI: its samples, densities and power, and its line estimate.

use super::*;

#[test]
fn the_fire_light_samples_through_the_abi() {
    let p = plugin();
    let v = p.create_volume(&fire_params()).unwrap();
    let light = v.create_light(None).unwrap();
    let lum = v.create_light(Some("luminance")).unwrap();
    // The volume handle may go first: the light holds its own reference.
    drop(v);
    let info = light.info();
    assert_eq!(info.weighting, firemedium_abi::FM_WEIGHTING_POWER);
    assert_eq!(lum.info().weighting, firemedium_abi::FM_WEIGHTING_LUMINANCE);
    assert!(info.voxels > 1000 && info.power_w > 0.0 && info.power_lm > 0.0);
    // Both weightings describe the same fire: the same total power.
    assert_eq!(info.power_w, lum.info().power_w);

    let n = 2000;
    let mut rng = firemedium_plugin::rng::Rng::new(7);
    let u: Vec<[f64; 6]> = (0..n).map(|_| [(); 6].map(|_| rng.next_f64())).collect();
    let (mut pts, mut pdf, mut em) = (vec![[0.0; 3]; n], vec![0.0; n], vec![0f32; n * 32]);
    light.sample(&u, &mut pts, &mut pdf, Some(&mut em)).unwrap();
    let mut again = vec![0.0; n];
    light.pdf(&pts, &mut again).unwrap();
    for i in 0..n {
        assert!(
            pdf[i] > 0.0 && (again[i] / pdf[i] - 1.0).abs() < 1e-5,
            "{} vs {}",
            pdf[i],
            again[i]
        );
        assert!(
            pts[i].iter().all(|c| (-0.01..3.01).contains(c)),
            "{:?}",
            pts[i]
        );
        assert!(em[i * 32..(i + 1) * 32]
            .iter()
            .all(|e| e.is_finite() && *e >= 0.0));
    }
    // Seen from beside the fire, the direction of a sampled point has positive density; away from it, zero.
    let o = [[1.0, -2.0, 1.0]];
    let toward = [[pts[0][0] - 1.0, pts[0][1] + 2.0, pts[0][2] - 1.0]];
    let mut pd = [0.0];
    light.pdf_direction(&o, &toward, &mut pd).unwrap();
    assert!(pd[0] > 0.0);
    light
        .pdf_direction(&o, &[[0.0, -1.0, 0.0]], &mut pd)
        .unwrap();
    assert_eq!(pd[0], 0.0);

    let e = p
        .create_volume(&fire_params())
        .unwrap()
        .create_light(Some("brightest"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("weighting") && e.contains("brightest") && e.contains("power"),
        "{e}"
    );
    let mut short = vec![0.0; 1];
    assert!(matches!(
        light.sample(&u[..2], &mut pts[..2], &mut short, None),
        Err(Error::Buffer(_))
    ));
}

#[test]
fn the_fire_lights_line_estimate_through_the_abi() {
    // `light_integrate_at`: at the volume's own step, the volume's march bit for bit; with a coarse step, the
    // same fire to within the march's discretisation; with the correction always taken (probability 1), the
    // volume's march again (coarse + (fine − coarse) / 1); bad parameters named.
    let p = plugin();
    let v = p.create_volume(&fire_params()).unwrap();
    let c = v.info().channels as usize;
    let rs = rays(64);
    let (mut lv, mut tv) = (vec![0f32; rs.len() * c], vec![0f32; rs.len() * c]);
    v.integrate_at(&rs, None, &mut lv, Some(&mut tv), None)
        .unwrap();
    let light_with = |extra: &[Param]| {
        let mut list = vec![Param::string("weighting", "power")];
        list.extend_from_slice(extra);
        v.create_light_with(&list)
    };
    let run = |light: &firemedium_loader::Light| {
        let (mut l, mut t) = (vec![0f32; rs.len() * c], vec![0f32; rs.len() * c]);
        light.integrate_at(&rs, None, &mut l, Some(&mut t)).unwrap();
        (l, t)
    };
    // The volume's step (the default stepsize, ½ voxel) is below this fire's longest side / 64 (96 voxels:
    // 1.5): `linestep` 0.5 is the volume's own march.
    let same = light_with(&[Param::float("linestep", 0.5)]).unwrap();
    assert_eq!(run(&same), (lv.clone(), tv.clone()));
    let total = |l: &[f32]| l.iter().map(|&x| x as f64).sum::<f64>();
    let coarse = light_with(&[]).unwrap();
    let (lc, tc) = run(&coarse);
    assert_ne!(
        lc, lv,
        "the default step (longest side / 64) is coarser here"
    );
    assert!(tc.iter().all(|t| (0.0..=1.0).contains(t)));
    // Its expectation (each ray with 64 seeds: the march's jitter averaged out) against the volume's march's.
    let mean = |light: Option<&firemedium_loader::Light>| {
        let mut sum = 0.0;
        for k in 0..64u64 {
            let rk: Vec<Ray> = rs
                .iter()
                .map(|r| Ray {
                    seed: r.seed.wrapping_mul(7919).wrapping_add(k),
                    ..*r
                })
                .collect();
            let mut l = vec![0f32; rk.len() * c];
            match light {
                Some(lt) => lt.integrate_at(&rk, None, &mut l, None).unwrap(),
                None => v.integrate_at(&rk, None, &mut l, None, None).unwrap(),
            }
            sum += total(&l);
        }
        sum
    };
    let rel = mean(Some(&coarse)) / mean(None) - 1.0;
    eprintln!("coarse line estimate against the volume's march: {rel:+.3e}");
    assert!(rel.abs() < 0.01, "coarse line estimate off by {rel}");
    // This thick fire's copy of 2³ blocks strays (its build-time check refuses it): the default line marches
    // the fire's own voxels, as `lineblock` 1 asks; `lineblock` 2 forces the copy, several per cent off.
    let own = light_with(&[Param::int("lineblock", 1)]).unwrap();
    assert_eq!(run(&own), (lc.clone(), tc.clone()));
    let copy = light_with(&[Param::int("lineblock", 2)]).unwrap();
    let rel_copy = mean(Some(&copy)) / mean(None) - 1.0;
    eprintln!("through the copy of 2³ blocks: {rel_copy:+.3e}");
    assert!(rel_copy < -0.02, "{rel_copy}");
    // The light says which (ABI 0.9: `FmLightInfo::line_block`).
    let blocks = |l: &firemedium_loader::Light| l.info().line_block;
    assert_eq!((blocks(&coarse), blocks(&own), blocks(&copy)), (1, 1, 2));
    // And in how many of the volume's channels (ABI 0.10): this thick fire's line in every bin (its build-time
    // check refuses the line in 8, whose X, Y or Z strays by more than 0.2 % on its rays); in 8 when asked, its
    // luminance then within 0.2 % of every bin's on these rays.
    let few = light_with(&[Param::int("linechannels", 8)]).unwrap();
    assert_eq!(coarse.line_channels().unwrap() as usize, c);
    assert_eq!(few.line_channels().unwrap(), 8);
    let (la, _) = run(&few);
    let y = |l: &[f32]| {
        let xyz = v.channel_xyz().unwrap();
        l.chunks(c)
            .map(|r| (0..c).map(|k| r[k] as f64 * xyz[k][1]).sum::<f64>())
            .sum::<f64>()
    };
    let rel_y = y(&la) / y(&lc) - 1.0;
    eprintln!("the line in 8 bins against every bin, Y: {rel_y:+.3e}");
    assert!(rel_y.abs() < 2e-3 && la != lc, "{rel_y}");
    let corrected = light_with(&[Param::float("linecorrection", 1.0)]).unwrap();
    let (lq, tq) = run(&corrected);
    for k in 0..lq.len() {
        assert!(
            (lq[k] - lv[k]).abs() <= 1e-5 * lv[k].abs() + 1e-30,
            "{k}: {} vs {}",
            lq[k],
            lv[k]
        );
        assert!((tq[k] - tv[k]).abs() <= 1e-6, "{k}");
    }
    for (name, value, want) in [
        ("linecorrection", 1.5, "linecorrection"),
        ("linestep", -1.0, "linestep"),
        ("cell", 3.0, "cell"),
        ("lineblock", 3.0, "lineblock"),
    ] {
        let param = if name == "cell" || name == "lineblock" {
            Param::int(name, value as i64)
        } else {
            Param::float(name, value)
        };
        let e = light_with(&[param]).unwrap_err().to_string();
        assert!(e.contains(want), "{name} = {value}: {e}");
    }
    let mut short = vec![0f32; 3];
    assert!(matches!(
        coarse.integrate_at(&rs, None, &mut short, None),
        Err(Error::Buffer(_))
    ));
}
