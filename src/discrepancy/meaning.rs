//! What a fitted candidate's parameter means, in the units a report gives it: the symbol, value
//! and standard error of its parameter, a sentence on what it does to the strength (a scale per
//! level, a modulus per level, a partially pooled spread, a two-population law, a power or a
//! rate), and for a size measure the weakest-link test. The naming loop
//! ([`super::workflow`]) asks it for every candidate it reports and every band it converts.

use crate::obs::Obs;
use crate::strength::factors::{Factor, Form, WeakestLink, weakest_link};
use crate::strength::{Effect, ModelFit, Term};

/// A band of β in the reported parameter's units, lower first (α = −β flips it).
pub(super) fn natural_band(c: &Effect, (a, b): (f64, f64)) -> (f64, f64) {
    let (a, b) = (c.natural(a), c.natural(b));
    (a.min(b), a.max(b))
}

/// The reported parameter of a fitted candidate (symbol, value, standard error), what it
/// means, and for a size measure the weakest-link test.
pub(super) fn describe(c: &Effect, t: &Term, m: &ModelFit, x: Obs) -> ((String, f64, f64), String, Option<WeakestLink>) {
    if let (Some(law), Effect::Populations(_)) = (&m.law, c) {
        let what = match &law.identifiable {
            Ok(()) => law.describe(),
            Err(why) => format!("{} — not identified: {why}", law.describe()),
        };
        let (sym, v) = match law.kind {
            crate::strength::flaws::Populations::Mixture => ("weaker_fraction", law.p),
            crate::strength::flaws::Populations::Competing => ("m_weaker", law.first.1),
            crate::strength::flaws::Populations::Threshold => ("threshold_pa", law.threshold),
        };
        return ((sym.into(), v, f64::NAN), what, None);
    }
    let range = m.beta_range(c);
    if let Term::Levels { levels, reference, .. } = t {
        let beta: Vec<f64> = range.map(|r| m.beta()[r].to_vec()).unwrap_or_default();
        let others = levels.iter().filter(|l| *l != reference);
        let mut scales: Vec<(String, f64)> = vec![(reference.clone(), 1.0)];
        scales.extend(others.zip(&beta).map(|(l, b)| (l.clone(), b.exp())));
        let (lo, hi) = scales.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), (_, s)| (lo.min(*s), hi.max(*s)));
        let list: Vec<String> = scales.iter().map(|(l, s)| format!("{l} ×{s:.3}")).collect();
        let meaning = format!("σ_θ of each level of `{}` relative to \"{reference}\" (the level with the most specimens; among equals the first in the file): {}", c.covariate(), list.join(", "));
        // Two levels: the one ratio, whose band the evidence gives (`scale_B/A`); more: the
        // spread of the levels' scales (no band).
        if let [_, (other, ratio)] = scales.as_slice() {
            return ((format!("scale_{other}/{reference}"), *ratio, f64::NAN), meaning, None);
        }
        return (("scale_ratio_max_min".into(), hi / lo, f64::NAN), meaning, None);
    }
    if let Term::Pooled { levels, columns } = t {
        let range = range.unwrap_or(0..0);
        let delta = &m.reg.beta[range.clone()];
        let tau = m.penalty.get(range.start).map_or(f64::NAN, |l| 1.0 / l.sqrt());
        let scales: Vec<f64> = delta.iter().map(|d| d.exp()).collect();
        let (lo, hi) = scales.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| (lo.min(*s), hi.max(*s)));
        let list: Vec<String> = levels.iter().zip(&scales).zip(columns).map(|((l, s), z)| format!("{l} ×{s:.3} ({})", z.iter().sum::<f64>() as usize)).collect();
        let meaning = format!("σ_θ of each level of `{}` relative to the population of levels, partially pooled (spread τ = {tau:.3} in ln σ_θ; specimens in brackets; the levels span ×{:.3}): {}", c.covariate(), hi / lo, list.join(", "));
        return (("tau".into(), tau, f64::NAN), meaning, None);
    }
    if let Term::Moduli { levels, reference, .. } = t {
        let gamma: Vec<f64> = m.gamma_range(c).map(|r| m.reg.gamma[r].to_vec()).unwrap_or_default();
        let others = levels.iter().filter(|l| *l != reference);
        let mut moduli: Vec<(String, f64)> = vec![(reference.clone(), m.reg.shape())];
        moduli.extend(others.zip(&gamma).map(|(l, g)| (l.clone(), m.reg.shape() * (-g).exp())));
        let (lo, hi) = moduli.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), (_, s)| (lo.min(*s), hi.max(*s)));
        let list: Vec<String> = moduli.iter().map(|(l, s)| format!("{l} {s:.2}")).collect();
        let meaning = format!("Weibull modulus of each level of `{}`: {}", c.covariate(), list.join(", "));
        return (("modulus_ratio_max_min".into(), hi / lo, f64::NAN), meaning, None);
    }
    let (beta, se) = m.coefficient(c).unwrap_or((f64::NAN, f64::NAN));
    let (sym, val, mut meaning) = c.parameter(beta, m.shape());
    // Delta method by a central difference of the reported parameter in β.
    let val_se = if *c == Effect::Damage { f64::NAN } else { 0.5 * (c.parameter(beta + se, m.shape()).1 - c.parameter(beta - se, m.shape()).1).abs() };
    let mut wl = None;
    // (Beside a two-population law there is no one modulus to test the size exponent against.)
    if let (Effect::Factor(Factor { form: Form::Size(measure), .. }), Term::Linear(z), None) = (c, t, &m.law) {
        // The other effects' columns (and a damage offset at its fitted ratio), refitted under the tie.
        let skip = m.beta_range(c).unwrap_or(0..0);
        let others: Vec<Vec<f64>> = m.columns.iter().enumerate().filter(|(j, _)| !skip.contains(j)).map(|(_, col)| col.clone()).collect();
        let penalty: Vec<f64> = m.penalty.iter().enumerate().filter(|(j, _)| !skip.contains(j)).map(|(_, l)| *l).collect();
        let design = crate::strength::regress::Design { columns: &others, offset: m.offset.as_deref(), scale_columns: &m.scale_columns, penalty: &penalty };
        let test = weakest_link(x, z, &design, measure.k(), m.loglik(), val, val_se, m.shape());
        meaning = format!("{meaning}; weakest-link test: {}", test.sentence(measure.k()));
        wl = Some(test);
    }
    ((sym.to_string(), val, val_se), meaning, wl)
}
