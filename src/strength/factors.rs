//! Generic effects of recorded factors: what a strength dataset's own columns can do to the
//! Weibull law, whatever the specimens (particles, pellets, bend bars, fibres).
//!
//! A strength file declares a size measure and factor columns ([`FactorSpec`],
//! [`SizeSpec`]); each becomes one or two candidate effects of the naming loop, acting on the
//! Weibull scale of specimen i or, for `moduli`, on its modulus:
//!
//! | form | column | equation | parameter reported | source |
//! |---|---|---|---|---|
//! | `linear(x)` | numeric x | ln σ_θ,i = μ + β (x_i − x̄) | β (ln-scale change per unit of x) | Weibull regression, Lawless (2003) *Statistical Models and Methods for Lifetime Data* §6.3 |
//! | `power(x)` | numeric x > 0 | σ_θ,i ∝ x_i^β: ln σ_θ,i = μ + β ln(x_i/x̃) | β (exponent) | same, on ln x |
//! | `levels(g)` | categorical g with L levels | ln σ_θ,i = μ + δ_g(i), δ = 0 for the reference level (the largest) | scale of each level relative to the reference, max/min ratio | same, treatment coding (L − 1 parameters) |
//! | `moduli(g)` | categorical g with L levels | 1/m_i = (1/m) e^(γ_g(i)), γ = 0 for the reference level; the scale as the rest of the model has it | modulus of each level, max/min ratio | Lawless (2003) §6.3.3 (scale depending on covariates); L − 1 parameters |
//! | `size(s)` | size measure s > 0 | σ_θ(s) = σ_θ(s̃)(s/s̃)^(−α) | α, tested against the weakest-link exponent k/m | Weibull (1939); Bazant & Planas (1998) §12 |
//!
//! x̄ is the mean and x̃, s̃ the median over the fitted data. The weakest-link law gives
//! P_f = 1 − exp[−(s/s₀)^k (σ/σ₀)^m], so σ_θ ∝ s^(−k/m): k = 1 when s is the effective volume,
//! the effective area or the gauge length of fibres of one diameter (volume and surface both ∝
//! L), k = 3 (volume flaws) or 2 (surface flaws) when s is a diameter. The **weakest-link
//! test** ([`weakest_link`]) fits the model with α tied to k/m (one parameter fewer) and
//! compares it with α free by the likelihood ratio (the other effects refitted under the tie),
//! χ²₁ under the relation (Wilks): the
//! relation is *supported* when p ≥ 0.05 and *rejected* otherwise, with the direction (size
//! effect weaker or stronger than weakest-link theory allows).
//!
//! A categorical factor needs at least [`MIN_PER_LEVEL`] specimens in every level for a scale
//! per level of its own; when a level has fewer, the levels' scales are **partially pooled**
//! ([`pooled_columns`]): ln σ_θ,i = μ + δ_g(i) with δ ~ N(0, τ²) over the levels, τ estimated by
//! the Laplace approximation of the marginal likelihood and the δ at their posterior mode given
//! τ (a random-effects Weibull model; Gelman & Hill (2007) §12 for the pooling, Lawless (2003) §6
//! for the law) — a level of one or two specimens borrows strength from the others instead of
//! being dropped. A modulus per level needs [`MIN_PER_LEVEL_MODULUS`] in every level; a numeric
//! factor with few distinct values (whole numbers, at most [`FEW_LEVELS`]) must be declared
//! `numeric` or `categorical` by the study — it is never guessed.
//!
//! Verified by `tests/strength_factors.rs` (hidden effects named through the generator,
//! parameters inside their bands, no false naming with irrelevant or shuffled factors) and
//! the unit tests below (the weakest-link fit against a direct maximisation).

use serde::{Deserialize, Serialize};

/// Fewest specimens a level of a categorical factor needs to get its own scale.
pub const MIN_PER_LEVEL: usize = 3;

/// Fewest specimens a level needs to get its own Weibull modulus (the modulus of fewer is
/// hardly estimable: its maximum-likelihood value from 3 specimens is biased by a factor ~2).
pub const MIN_PER_LEVEL_MODULUS: usize = 5;

pub use crate::intake::factors::{FEW_LEVELS, FactorType};

/// How a factor enters the strength law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Form {
    /// ln σ_θ linear in the value.
    Linear,
    /// σ_θ a power of the value.
    Power,
    /// One scale per level.
    Levels,
    /// One Weibull modulus per level.
    Moduli,
    /// Weakest-link size effect of a size measure.
    Size(SizeMeasure),
}

/// What a size column measures, and so the weakest-link exponent k in σ_θ ∝ s^(−k/m).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SizeMeasure {
    /// Effective volume (k = 1).
    EffectiveVolume,
    /// Effective surface area (k = 1).
    EffectiveArea,
    /// Gauge length of fibres or rods of one cross-section (k = 1).
    GaugeLength,
    /// Diameter, volume flaws (k = 3).
    DiameterVolume,
    /// Diameter, surface flaws (k = 2).
    DiameterSurface,
}

impl SizeMeasure {
    /// k: the weakest-link exponent is α = k/m.
    pub fn k(self) -> f64 {
        match self {
            SizeMeasure::DiameterVolume => 3.0,
            SizeMeasure::DiameterSurface => 2.0,
            _ => 1.0,
        }
    }

    /// Words for the measure.
    pub fn describe(self) -> &'static str {
        match self {
            SizeMeasure::EffectiveVolume => "effective volume",
            SizeMeasure::EffectiveArea => "effective area",
            SizeMeasure::GaugeLength => "gauge length",
            SizeMeasure::DiameterVolume => "diameter (volume flaws)",
            SizeMeasure::DiameterSurface => "diameter (surface flaws)",
        }
    }
}

/// An effect of a recorded factor: its column and form.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Factor {
    /// The column (as the study names it).
    pub column: String,
    /// How it enters.
    pub form: Form,
}

impl Factor {
    /// Key in tables and verdict.json: `linear(rate)`, `power(rate)`, `levels(batch)`,
    /// `size(gauge_length)`.
    pub fn name(&self) -> String {
        let f = match self.form {
            Form::Linear => "linear",
            Form::Power => "power",
            Form::Levels => "levels",
            Form::Moduli => "moduli",
            Form::Size(_) => "size",
        };
        format!("{f}({})", self.column)
    }

    /// Words.
    pub fn label(&self) -> String {
        let c = &self.column;
        match self.form {
            Form::Linear => format!("`{c}` on the scale (ln-linear)"),
            Form::Power => format!("`{c}` on the scale (power law)"),
            Form::Levels => format!("one scale per level of `{c}`"),
            Form::Moduli => format!("one Weibull modulus per level of `{c}`"),
            Form::Size(s) => format!("size effect of the {} `{c}` (weakest link, exponent free)", s.describe()),
        }
    }

    /// Its equation.
    pub fn equation(&self) -> String {
        let c = &self.column;
        match self.form {
            Form::Linear => format!("ln σ_θ,i = μ + β ({c}_i − mean {c})"),
            Form::Power => format!("σ_θ,i ∝ {c}_i^β; ln σ_θ,i = μ + β ln({c}_i/median {c})"),
            Form::Levels => format!("ln σ_θ,i = μ + δ_level(i), one δ per level of {c} (0 for the reference level)"),
            Form::Moduli => format!("1/m_i = (1/m) e^(γ_level(i)), one γ per level of {c} (0 for the reference level)"),
            Form::Size(s) => format!("σ_θ(s) = σ_θ(s̃)(s/s̃)^(−α), s = {c}, s̃ its median; weakest link: α = {}/m", s.k()),
        }
    }

    /// Whether the value enters through its logarithm (power law, size).
    pub fn logarithmic(&self) -> bool {
        matches!(self.form, Form::Power | Form::Size(_))
    }
}

/// The candidate effects of a declared factor column: numeric → linear, and power when every
/// value is > 0; categorical → levels and moduli.
pub fn candidates_of(column: &str, kind: FactorType, all_positive: bool) -> Vec<Factor> {
    match kind {
        FactorType::Numeric if all_positive => vec![Factor { column: column.into(), form: Form::Linear }, Factor { column: column.into(), form: Form::Power }],
        FactorType::Numeric => vec![Factor { column: column.into(), form: Form::Linear }],
        FactorType::Categorical => vec![Factor { column: column.into(), form: Form::Levels }, Factor { column: column.into(), form: Form::Moduli }],
    }
}

/// Treatment-coded columns of a categorical factor: the levels in order of appearance, the
/// reference level (most specimens; the first such), and one 0/1 column per other level. Or
/// why it cannot be fitted: every level needs `min` specimens.
pub fn level_columns(values: &[String], min: usize) -> std::result::Result<(Vec<String>, String, Vec<Vec<f64>>), String> {
    let mut levels: Vec<(String, usize)> = Vec::new();
    for v in values {
        match levels.iter_mut().find(|(l, _)| l == v) {
            Some(e) => e.1 += 1,
            None => levels.push((v.clone(), 1)),
        }
    }
    if levels.len() < 2 {
        return Err(format!("one level only (\"{}\"): no contrast to fit", levels.first().map_or("", |l| l.0.as_str())));
    }
    if let Some((l, k)) = levels.iter().find(|(_, k)| *k < min) {
        let what = if min >= MIN_PER_LEVEL_MODULUS { "modulus" } else { "scale" };
        return Err(format!("level \"{l}\" has {k} specimen{}: at least {min} per level are needed to give it its own {what}", if *k == 1 { "" } else { "s" }));
    }
    let reference = levels.iter().fold(&levels[0], |b, l| if l.1 > b.1 { l } else { b }).0.clone();
    let names: Vec<String> = levels.iter().map(|l| l.0.clone()).collect();
    let columns = names.iter().filter(|l| **l != reference).map(|l| values.iter().map(|v| f64::from(u8::from(v == l))).collect()).collect();
    Ok((names, reference, columns))
}

/// Indicator columns of every level of a categorical factor for partial pooling (levels in
/// order of appearance, one 0/1 column each, no reference): used when a level has fewer than
/// [`MIN_PER_LEVEL`] specimens. At least two levels need [`MIN_PER_LEVEL`] specimens, so that
/// the spread of the levels' scales is estimable from within-level scatter.
pub fn pooled_columns(values: &[String]) -> std::result::Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let mut levels: Vec<(String, usize)> = Vec::new();
    for v in values {
        match levels.iter_mut().find(|(l, _)| l == v) {
            Some(e) => e.1 += 1,
            None => levels.push((v.clone(), 1)),
        }
    }
    let full = levels.iter().filter(|(_, k)| *k >= MIN_PER_LEVEL).count();
    if levels.len() < 2 {
        return Err(format!("one level only (\"{}\"): no contrast to fit", levels.first().map_or("", |l| l.0.as_str())));
    }
    if full < 2 {
        return Err(format!("{full} of its {} levels ha{} {MIN_PER_LEVEL} or more specimens: at least two are needed to pool the small ones", levels.len(), if full == 1 { "s" } else { "ve" }));
    }
    let names: Vec<String> = levels.into_iter().map(|l| l.0).collect();
    let columns = names.iter().map(|l| values.iter().map(|v| f64::from(u8::from(v == l))).collect()).collect();
    Ok((names, columns))
}

/// The weakest-link test of a size effect.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WeakestLink {
    /// α with the exponent free.
    pub alpha: f64,
    /// Its standard error.
    pub alpha_se: f64,
    /// k/m of the free fit: the exponent weakest-link theory predicts for that modulus.
    pub predicted: f64,
    /// Weibull modulus of the model with α = k/m.
    pub shape_tied: f64,
    /// Log-likelihood with α = k/m.
    pub loglik_tied: f64,
    /// Likelihood ratio 2(ℓ_free − ℓ_tied).
    pub lr: f64,
    /// Its χ²₁ p-value.
    pub p: f64,
    /// p ≥ 0.05.
    pub supported: bool,
}

impl WeakestLink {
    /// One sentence: supported or rejected, with the evidence.
    pub fn sentence(&self, k: f64) -> String {
        let verdict = if self.supported {
            "consistent with weakest-link scaling"
        } else if self.alpha < self.predicted {
            "weaker than weakest-link scaling allows: rejected"
        } else {
            "stronger than weakest-link scaling allows: rejected"
        };
        let p = if self.p < 1e-3 { format!("{:.1e}", self.p) } else { format!("{:.3}", self.p) };
        format!(
            "α = {:.3} ± {:.3} against {k}/m = {:.3}, {verdict} (likelihood ratio {:.2}, χ²₁ p = {p}; with α tied to {k}/m the modulus is {:.2})",
            self.alpha, self.alpha_se, self.predicted, self.lr, self.shape_tied
        )
    }
}

/// The weakest-link test: the model with α tied to k/m — the other effects' columns and offset
/// (`others`) refitted under the tie ([`crate::strength::regress::fit_tied`]) — against the free
/// fit's ℓ and α ± se. The likelihood ratio has one degree of freedom (α free against α = k/m).
#[allow(clippy::too_many_arguments)]
pub fn weakest_link(x: crate::obs::Obs, z: &[f64], others: &crate::strength::regress::Design, k: f64, free_loglik: f64, alpha: f64, alpha_se: f64, free_shape: f64) -> WeakestLink {
    let (loglik_tied, shape_tied) = match crate::strength::regress::fit_tied(x, others, (z, k)) {
        Ok(r) => (r.loglik, r.shape()),
        Err(_) => (f64::NAN, f64::NAN),
    };
    let lr = (2.0 * (free_loglik - loglik_tied)).max(0.0);
    let p = if lr.is_finite() { crate::stats::chi2_upper_tail(lr, 1.0) } else { f64::NAN };
    WeakestLink { alpha, alpha_se, predicted: k / free_shape, shape_tied, loglik_tied, lr, p, supported: p >= 0.05 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obs::Obs;
    use crate::strength::regress::{Design, fit};
    use crate::weibull::Weibull;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// ℓ of the weakest-link model without other effects at modulus m, σ_θ profiled in closed
    /// form: P(X_i ≤ x) = 1 − exp[−e^(t_i − ln S)], t_i = m y_i + k z_i, S = σ_θ^m, optimum
    /// S = mean e^(t_i), ℓ(m) = Σ[ln m − y_i + t_i − ln S] − n. An independent reference for
    /// `regress::fit_tied`.
    fn tied_profile(y: &[f64], z: &[f64], k: f64, m: f64) -> f64 {
        let n = y.len() as f64;
        let t: Vec<f64> = (0..y.len()).map(|i| m * y[i] + k * z[i]).collect();
        let tmax = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let ln_s = tmax + (t.iter().map(|v| (v - tmax).exp()).sum::<f64>() / n).ln();
        t.iter().zip(y).map(|(ti, yi)| m.ln() + ti - ln_s - yi).sum::<f64>() - n
    }

    #[test]
    fn the_tied_fit_is_the_profile_maximum_and_never_above_the_free_fit() {
        // At any m, ℓ_tied(m) equals the regression log-likelihood with β = −k/m, b = 1/m and
        // μ at its optimum; and the free fit is never below the tied one.
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let n = 200;
        let s: Vec<f64> = (0..n).map(|i| [1.0, 10.0, 50.0][i % 3]).collect();
        let z: Vec<f64> = s.iter().map(|v| (v / 10.0f64).ln()).collect();
        let x: Vec<f64> = z.iter().map(|&zi| Weibull::new(6.0, 3.0 * (-zi / 6.0).exp()).unwrap().sample(&mut rng)).collect();
        let y: Vec<f64> = x.iter().map(|v| v.ln()).collect();
        for m in [3.0, 6.0, 11.0] {
            let l = tied_profile(&y, &z, 1.0, m);
            // Direct: scan μ finely around its closed form.
            let lnsig = |mu: f64| -> f64 {
                (0..n)
                    .map(|i| {
                        let ls = mu - z[i] / m;
                        crate::strength::regress::ln_density_of_log(y[i], ls, 1.0 / m) - y[i]
                    })
                    .sum()
            };
            let best = (0..8001).map(|j| lnsig(0.5 + 1.5 * j as f64 / 8000.0)).fold(f64::NEG_INFINITY, f64::max);
            assert!((l - best).abs() < 1e-3, "m = {m}: {l} vs {best}");
        }
        // The tied regression reaches the maximum of the profile over m (scanned finely).
        let best_profile = (0..20001).map(|j| tied_profile(&y, &z, 1.0, 2.0 + 10.0 * j as f64 / 20000.0)).fold(f64::NEG_INFINITY, f64::max);
        let cols = vec![z.clone()];
        let free = fit(Obs::exact(&x), &Design { columns: &cols, ..Design::default() }).unwrap();
        let w = weakest_link(Obs::exact(&x), &z, &Design::default(), 1.0, free.loglik, -free.beta[0], free.beta_se[0], free.shape());
        assert!((w.loglik_tied - best_profile).abs() < 1e-6, "tied fit {} vs profile maximum {best_profile}", w.loglik_tied);
        assert!(w.loglik_tied <= free.loglik + 1e-9 && w.supported, "{w:?}");
        // Data with α = 3/m at k = 1 reject the relation.
        let x3: Vec<f64> = z.iter().map(|&zi| Weibull::new(6.0, 3.0 * (-3.0 * zi / 6.0).exp()).unwrap().sample(&mut rng)).collect();
        let free = fit(Obs::exact(&x3), &Design { columns: &cols, ..Design::default() }).unwrap();
        let w = weakest_link(Obs::exact(&x3), &z, &Design::default(), 1.0, free.loglik, -free.beta[0], free.beta_se[0], free.shape());
        assert!(!w.supported && w.alpha > w.predicted, "{w:?}");
        assert!(w.sentence(1.0).contains("stronger than weakest-link"));
    }

    #[test]
    fn levels_are_treatment_coded_against_the_largest_level() {
        let v: Vec<String> = ["a", "b", "b", "c", "b", "a", "c", "a", "c", "b"].iter().map(|s| s.to_string()).collect();
        let (names, reference, cols) = level_columns(&v, MIN_PER_LEVEL).unwrap();
        assert_eq!(names, ["a", "b", "c"]);
        assert_eq!(reference, "b");
        assert_eq!(cols.len(), 2);
        assert_eq!(cols[0], [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0]);
        let few: Vec<String> = ["a", "a", "a", "b", "b"].iter().map(|s| s.to_string()).collect();
        assert!(level_columns(&few, MIN_PER_LEVEL).unwrap_err().contains("level \"b\" has 2 specimens"));
        assert!(level_columns(&few[..3], MIN_PER_LEVEL).unwrap_err().contains("one level only"));
        assert!(level_columns(&v, MIN_PER_LEVEL_MODULUS).unwrap_err().contains("at least 5 per level are needed to give it its own modulus"));
    }
}
