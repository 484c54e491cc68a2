//! What a volume's build found that a user should hear, whatever host renders it: species whose strong lines fall
//! outside the channels, species whose photographed colour the model does not hold (barium's and copper's
//! chloride bands, potassium's lilac), and band-forming metals in a fire hotter than the bands' strengths hold for. Read through the ABI's `volume_note_count`/`volume_note`; the renderer prints
//! them as warnings at the medium's statement.

use crate::constants::{BOLTZMANN, PLANCK, SPEED_OF_LIGHT};
use crate::species::bands::T_REF;
use crate::species::{colour_note, Element, Line};

/// The notes about a fire's `species` ((symbol, element, scale)), at its hottest temperature `t_hot` (K; 2000 K
/// when it has no temperature grid), for channels over `range` nm.
pub(super) fn species(
    species: &[(String, Element, f64)],
    t_hot: f64,
    range: (f64, f64),
) -> Vec<String> {
    let mut out = Vec::new();
    for (sym, e, _) in species {
        if let Some(m) = lines_outside(sym, e, t_hot, range) {
            out.push(m);
        }
        if let Some(note) = colour_note(sym) {
            out.push(format!("species {sym}: {note}"));
        }
        if let Some(m) = dissociated(sym, t_hot) {
            out.push(m);
        }
    }
    out
}

/// The hottest a fire may be before [`dissociated`] warns, K: the band strengths hold for a gas flame near
/// [`T_REF`].
const HOT_FOR_BANDS: f64 = 2300.0;

/// Ca–OH, Sr–OH, Ba–OH dissociation energies, eV: 4–4.5 (a review's range; 4.3 taken), which makes the molecules
/// per free atom fall as exp(−D₀/kT) at a fixed OH share.
const D0_HYDROXIDE_EV: f64 = 4.3;

/// When species `sym` carries hydroxide bands and the fire is hotter than [`HOT_FOR_BANDS`]: the bands' strength
/// per free atom is a 2 000 K flame's, where M–OH ⇌ M + OH leaves a hotter flame far fewer molecules per free atom
/// (why flame photometry reads Ca, Sr and Ba on their lines in hot flames): how many fewer at `t` K.
fn dissociated(sym: &str, t: f64) -> Option<String> {
    if !["Ca", "Sr", "Ba"].contains(&sym) || t <= HOT_FOR_BANDS {
        return None;
    }
    let ev = 1.602_176_634e-19;
    let fewer = (D0_HYDROXIDE_EV * ev / BOLTZMANN * (1.0 / T_REF - 1.0 / t)).exp();
    Some(format!(
        "species {sym}: its bands are held at the molecules per free atom of a {T_REF:.0} K gas flame; at this fire's hottest, {t:.0} K, a flame in equilibrium (M–OH ⇌ M + OH, D₀ ≈ {D0_HYDROXIDE_EV} eV, its OH share the same) holds about {fewer:.0}× fewer, and its atomic lines outshine its bands: the band colour is overstated where the fire is hotter than {HOT_FOR_BANDS:.0} K"
    ))
}

/// When species `sym`'s lines outside the channels `lo`–`hi` nm carry more than a tenth of its visible line
/// emission at `t` K (each line's power g_k A_ki e^(−E_k/kT) hc/λ, weighted by the eye's ȳ): what is lost, and how
/// to keep it.
fn lines_outside(sym: &str, e: &Element, t: f64, (lo, hi): (f64, f64)) -> Option<String> {
    let lum = |l: &Line| {
        let power =
            l.g_k as f64 * l.a_ki * (-l.e_k / (BOLTZMANN * t)).exp() * PLANCK * SPEED_OF_LIGHT
                / (l.lambda_nm * 1e-9);
        power * crate::cie::cmf(l.lambda_nm).y
    };
    let total: f64 = e.lines().iter().map(lum).sum();
    let mut out: Vec<&Line> = e
        .lines()
        .iter()
        .filter(|l| (l.lambda_nm < lo || l.lambda_nm > hi) && lum(l) > 0.0)
        .collect();
    let lost: f64 = out.iter().map(|l| lum(l)).sum();
    if !(total > 0.0 && lost > 0.1 * total) {
        return None;
    }
    out.sort_by(|a, b| lum(b).total_cmp(&lum(a)));
    let names: Vec<String> = out
        .iter()
        .take(3)
        .map(|l| format!("{:.1}", l.lambda_nm))
        .collect();
    Some(format!(
        "species {sym}: its lines at {} nm carry {:.0} % of its visible line emission (luminance-weighted at {t:.0} K) and lie outside the render's bins, {lo:.0}–{hi:.0} nm: they are left out (widen the bins with \"float lambdamin\" / \"float lambdamax\", up to 380–780 nm)",
        names.join(", "),
        100.0 * lost / total
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn species_lines_outside_the_bins_are_noted() {
        // Potassium's resonance doublet (766.7, 770.1 nm) outside 400–700 nm: nearly all its visible light.
        let k = Element::by_symbol("K").unwrap();
        let m = lines_outside("K", &k, 2000.0, (400.0, 700.0)).expect("a note");
        let pct: f64 = m
            .split(" carry ")
            .nth(1)
            .and_then(|r| r.split(" %").next())
            .and_then(|v| v.parse().ok())
            .unwrap();
        assert!(
            m.contains("766.") && m.contains("770.") && pct > 90.0,
            "{m}"
        );
        // Inside 400–780 nm, and sodium's D lines inside 400–700: nothing to say.
        assert!(lines_outside("K", &k, 2000.0, (400.0, 780.0)).is_none());
        let na = Element::by_symbol("Na").unwrap();
        assert!(lines_outside("Na", &na, 2000.0, (400.0, 700.0)).is_none());
        // Sodium's colour is its lines and strontium's its bands; copper's chloride blue is not held, and says so.
        let all = species(
            &[
                ("Na".into(), na, 1.0),
                ("Sr".into(), Element::by_symbol("Sr").unwrap(), 1.0),
                ("Cu".into(), Element::by_symbol("Cu").unwrap(), 1.0),
            ],
            2000.0,
            (380.0, 780.0),
        );
        assert_eq!(all.len(), 1, "{all:?}");
        assert!(
            all[0].starts_with("species Cu: its bands here are CuOH's and CuO's")
                && all[0].contains("CuCl"),
            "{all:?}"
        );
    }
}
