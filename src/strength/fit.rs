//! Fitting the strength model to one material's crush data: the reduction of each test to σ̄
//! at break, the maximum-likelihood fit of the Weibull regression with the model's effects
//! ([`fit_model`]), and cross-validated pointwise log scores ([`cv_pointwise`]) for model
//! comparison.
//!
//! The reduction is the deliverable's: a sphere of radius R = d/2 on the platen, the Hertz
//! contact at the force at break, σ̄ averaged over the study's domain ([`contact_at_break`]).
//! Contact-geometry effects are regression terms on this σ̄ (see [`super::effects`]), which
//! for a domain with σ̄ ∝ p0 is the same as reducing each test with its own R_c.
//!
//! The fitted model and its fit at given terms are [`super::mle`]; a partially pooled
//! categorical factor's spread is searched in [`super::pooling`].

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::effects::{Effect, Term, damage_offset};
pub use super::mle::ModelFit;
use super::mle::fit_at;
use crate::contact::{ContactOptions, ContactState, ContactStress, Elastic, Hertz, TensileZone};
use crate::data::CrushData;
use crate::error::{Error, Result};
use crate::obs::{Obs, Observations};

/// Strengths and covariates of one sample: a crush sample reduced to σ̄ at break, or a
/// strength file's specimens with their recorded factors.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sample {
    /// Where it came from (for messages).
    pub source: String,
    /// σ̄ at break, or the specimen strength (Pa), per specimen, with what each row says of it
    /// (broke at it; did not break by it; broke within a class — [`crate::obs`]).
    pub strength: Observations,
    /// Numeric covariate columns by name (`None`: empty cell).
    pub covariates: Vec<(String, Vec<Option<f64>>)>,
    /// Categorical factor columns by name: each specimen's level.
    pub levels: Vec<(String, Vec<String>)>,
    /// The generic candidate effects the data's study declares (factors, size measure); the
    /// five particle effects are candidates only of crush samples (`particles`).
    pub factors: Vec<crate::strength::factors::Factor>,
    /// Whether the specimens are crushed particles (the particle effects apply).
    pub particles: bool,
    /// Two-population laws the data's study offers as candidates (strength files).
    pub populations: Vec<crate::strength::flaws::Populations>,
}

impl Sample {
    /// Every candidate of the naming loop for this sample: the configured particle effects
    /// (crush samples only), then the data's declared factors.
    pub fn candidates(&self, particle_effects: &[Effect]) -> Vec<Effect> {
        let particle = if self.particles { particle_effects.to_vec() } else { Vec::new() };
        particle.into_iter().chain(self.factors.iter().cloned().map(Effect::Factor)).chain(self.populations.iter().copied().map(Effect::Populations)).collect()
    }

    /// The term of effect `e` in this sample, or why it cannot be fitted
    /// ([`Effect::term`] on the sample's columns).
    pub fn term(&self, e: &Effect, gamma: f64) -> std::result::Result<Term, String> {
        e.term(&self.covariates, &self.levels, gamma)
    }

    /// Adds a file's factor columns: numeric ones to the covariates, categorical ones to the
    /// levels, and their candidate effects (linear and, where every value is > 0, power; levels
    /// and moduli).
    pub fn add_factors(&mut self, columns: &crate::intake::factors::FactorColumns) {
        use crate::intake::factors::FactorValues;
        use crate::strength::factors::{FactorType, candidates_of};
        for (name, values) in columns {
            match values {
                FactorValues::Numeric(v) => {
                    self.covariates.push((name.clone(), v.iter().map(|x| Some(*x)).collect()));
                    self.factors.extend(candidates_of(name, FactorType::Numeric, v.iter().all(|x| *x > 0.0)));
                }
                FactorValues::Levels(v) => {
                    self.levels.push((name.clone(), v.clone()));
                    self.factors.extend(candidates_of(name, FactorType::Categorical, false));
                }
            }
        }
    }

    /// The rows `rows` of the sample (strengths, covariates and levels), same candidates.
    pub fn rows(&self, rows: &[usize], source: String) -> Sample {
        Sample {
            source,
            strength: self.strength.rows(rows),
            covariates: self.covariates.iter().map(|(c, v)| (c.clone(), rows.iter().map(|&i| v[i]).collect())).collect(),
            levels: self.levels.iter().map(|(c, v)| (c.clone(), rows.iter().map(|&i| v[i].clone()).collect())).collect(),
            factors: self.factors.clone(),
            particles: self.particles,
            populations: self.populations.clone(),
        }
    }
}

/// Hertz contact state of each crushed particle at its force at break: sphere of radius d/2 on
/// the platen, σ̄ over the contact options' averaging domain (the deliverable's reduction).
/// A σ̄ outside [`crate::data::SIGMA_BAR`] is refused naming the particle's row, with the hint
/// to check the force and diameter units.
pub fn contact_at_break(data: &CrushData, elastic: &Elastic, contact: &ContactOptions) -> Result<Vec<ContactState>> {
    data.records
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let state = crush_contact(elastic, contact, r.diameter_m).at_force(r.crush_force_n)?;
            if let Some(rule) = crate::data::SIGMA_BAR.broken(state.mean_tensile) {
                return Err(data.error(k, "crush_force_n", format!("{rule}, from F = {} N, d = {} m and E = {} Pa: check the force and diameter units", r.crush_force_n, r.diameter_m, elastic.youngs_modulus_pa)));
            }
            Ok(state)
        })
        .collect()
}

/// The contact of a crushed particle of diameter `diameter_m`: a sphere of radius d/2 on the
/// platen, σ̄ over the contact options' averaging domain. Its `at_force(F)` gives the particle's
/// σ̄ at a crush force F (at break, at a rig's limit, at a class edge).
pub fn crush_contact(elastic: &Elastic, contact: &ContactOptions, diameter_m: f64) -> ContactStress {
    let radius = 0.5 * diameter_m;
    let hertz = Hertz::sphere_on_flat(elastic, &contact.platen, radius);
    ContactStress { hertz, zone: TensileZone::new(elastic.poisson_ratio), domain: contact.averaging, particle_radius: radius }
}

/// Strengths (σ̄ at break) and covariates of a crush dataset, with the factor columns its study
/// declares (numeric ones beside the particle covariates, categorical ones as levels) and their
/// candidate effects. A particle that did not break by the rig's limit, or broke within a
/// force class, keeps what its row says: its limits and class edges become σ̄ at those forces,
/// particle by particle ([`crate::obs`]).
pub fn sample_of(data: &CrushData, elastic: &Elastic, contact: &ContactOptions) -> Result<Sample> {
    let at = contact_at_break(data, elastic, contact)?;
    let r = &data.records;
    let sigma_at = |k: usize, force: f64| -> f64 {
        if force == r[k].crush_force_n {
            return at[k].mean_tensile;
        }
        crush_contact(elastic, contact, r[k].diameter_m).at_force(force).map_or(f64::NAN, |s| s.mean_tensile)
    };
    let strength = data.observed().map(sigma_at);
    if let Some(c) = &strength.censoring
        && let Some(k) = (0..r.len()).find(|&k| c.kind[k] == crate::obs::Censor::Interval && !(c.upper[k] > strength.x[k]))
    {
        return Err(data.error(k, "crush_force_n", format!("the class's σ̄ at its upper force is not above its σ̄ at its lower force ({} and {} Pa)", c.upper[k], strength.x[k])));
    }
    let mut s = Sample {
        source: data.path.display().to_string(),
        strength,
        covariates: vec![
            ("diameter_m".into(), r.iter().map(|x| Some(x.diameter_m)).collect()),
            ("roundness".into(), r.iter().map(|x| x.roundness).collect()),
            ("sphericity".into(), r.iter().map(|x| x.sphericity).collect()),
            ("temperature_c".into(), r.iter().map(|x| x.temperature_c).collect()),
            ("impacts".into(), r.iter().map(|x| x.impacts.map(|k| k as f64)).collect()),
        ],
        levels: Vec::new(),
        factors: Vec::new(),
        particles: true,
        populations: Vec::new(),
    };
    s.add_factors(&data.factors);
    Ok(s)
}

impl ModelFit {
    /// Parametric-bootstrap replicate `r` (its own ChaCha8 stream of `seed`): strengths drawn
    /// from this model at the sample's covariates, censored as the campaign censored each row
    /// of `x` (the observations fitted: [`Obs::censor`]), refitted with `terms` (the model's
    /// own terms or more). None if the refit fails.
    pub fn bootstrap_refit(&self, x: Obs, terms: &[(Effect, Term)], seed: u64, r: usize) -> Option<(Observations, ModelFit)> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let drawn = match &self.law {
            Some(l) => (0..self.n).map(|i| l.sample(&mut rng) * l.shift(&self.columns, i).exp()).collect(),
            None => self.reg.sample(&self.design(), self.n, &mut rng),
        };
        let xs = x.censor(drawn, &mut rng);
        let refit = fit_model_near(xs.view(), terms, Some(self)).ok()?;
        Some((xs, refit))
    }
}

/// Fits the base model plus `terms` to the strengths `x`.
pub fn fit_model(x: Obs, terms: &[(Effect, Term)]) -> Result<ModelFit> {
    fit_model_near(x, terms, None)
}

/// [`fit_model`] near a fit to similar data (a bootstrap refit): the damage ratio's profile
/// search and each pooled factor's τ search then start at the hint's values, which is several
/// times faster (the full search runs when the optimum leaves the local bracket).
pub fn fit_model_near(x: Obs, terms: &[(Effect, Term)], hint: Option<&ModelFit>) -> Result<ModelFit> {
    let ratio = hint.and_then(|h| h.damage_ratio);
    let pooled = terms.iter().filter(|(_, t)| matches!(t, Term::Pooled { .. })).count();
    if pooled == 0 {
        return fit_at(x, terms, ratio, &[], None);
    }
    super::pooling::fit_pooled(x, terms, ratio, hint, pooled)
}

/// ln σ_i of particle `i` under a model fitted on other rows: its linear terms' columns at row
/// i and the damage offset at the fitted ratio.
pub fn predict_ln_scale(fit: &ModelFit, terms: &[(Effect, Term)], i: usize) -> f64 {
    fit.reg.mu + linear_predictor(&fit.reg.beta, fit, terms, i)
}

/// Σ β_j z_j,i over the regression columns of `terms` at row i (β in the order of the columns),
/// plus a damage offset at the fit's ratio.
fn linear_predictor(beta: &[f64], fit: &ModelFit, terms: &[(Effect, Term)], i: usize) -> f64 {
    let mut s = 0.0;
    let mut j = 0;
    for (_, t) in terms {
        match t {
            Term::Linear(z) => {
                s += beta[j] * z[i];
                j += 1;
            }
            Term::Levels { columns, .. } | Term::Pooled { columns, .. } => {
                for z in columns {
                    s += beta[j] * z[i];
                    j += 1;
                }
            }
            Term::Damage { impacts, gamma } => {
                let x0 = fit.damage_ratio.unwrap_or(0.0);
                s += damage_offset(x0, *gamma, impacts[i]).unwrap_or(f64::NEG_INFINITY);
            }
            Term::Moduli { .. } | Term::Populations(_) => {}
        }
    }
    s
}

/// b_i = 1/m_i of particle `i` under a model fitted on other rows: the reference b times its
/// level's e^γ for every modulus-per-level term.
pub fn predict_b(fit: &ModelFit, terms: &[(Effect, Term)], i: usize) -> f64 {
    let mut ln_b = fit.reg.b.ln();
    let mut j = 0;
    for (_, t) in terms {
        if let Term::Moduli { columns, .. } = t {
            for v in columns {
                ln_b += fit.reg.gamma[j] * v[i];
                j += 1;
            }
        }
    }
    ln_b.exp()
}

/// ln P(row i of `x`) under a model fitted on other rows (its law's, or the Weibull
/// regression's at [`predict_ln_scale`]): the log density of an exact row, the log probability
/// of what a censored or interval row says ([`Obs::ln_prob`]).
pub fn predict_ln_prob(fit: &ModelFit, terms: &[(Effect, Term)], x: Obs, i: usize) -> f64 {
    match &fit.law {
        Some(l) => {
            let eta = linear_predictor(&l.beta, fit, terms, i);
            x.ln_prob(i, |v| l.ln_pdf(v * (-eta).exp()) - eta, |v| l.ln_sf(v * (-eta).exp()))
        }
        None => super::regress::ln_prob(x, i, predict_ln_scale(fit, terms, i), predict_b(fit, terms, i)),
    }
}

/// The terms restricted to `rows`.
pub fn subset(terms: &[(Effect, Term)], rows: &[usize]) -> Vec<(Effect, Term)> {
    terms
        .iter()
        .map(|(c, t)| {
            let t = match t {
                Term::Linear(z) => Term::Linear(rows.iter().map(|&i| z[i]).collect()),
                Term::Levels { columns, levels, reference } => Term::Levels { columns: columns.iter().map(|z| rows.iter().map(|&i| z[i]).collect()).collect(), levels: levels.clone(), reference: reference.clone() },
                Term::Pooled { columns, levels } => Term::Pooled { columns: columns.iter().map(|z| rows.iter().map(|&i| z[i]).collect()).collect(), levels: levels.clone() },
                Term::Moduli { columns, levels, reference } => Term::Moduli { columns: columns.iter().map(|z| rows.iter().map(|&i| z[i]).collect()).collect(), levels: levels.clone(), reference: reference.clone() },
                Term::Damage { impacts, gamma } => Term::Damage { impacts: rows.iter().map(|&i| impacts[i]).collect(), gamma: *gamma },
                Term::Populations(k) => Term::Populations(*k),
            };
            (c.clone(), t)
        })
        .collect()
}

/// A seeded fold assignment of n rows to k folds (balanced, shuffled).
pub fn folds(n: usize, k: usize, seed: u64) -> Vec<usize> {
    deal(&shuffled(n, seed), k)
}

/// [`folds`] stratified by `group` (row i's group): each group's rows, shuffled, dealt over
/// the folds in turn, so a group of r rows puts at most ⌈r/k⌉ in one fold and every training
/// set keeps at least r − ⌈r/k⌉ of them.
pub fn folds_stratified(group: &[String], k: usize, seed: u64) -> Vec<usize> {
    let mut idx = shuffled(group.len(), seed);
    idx.sort_by(|&a, &b| group[a].cmp(&group[b]));
    deal(&idx, k)
}

/// 0..n in a seeded random order (Fisher–Yates).
fn shuffled(n: usize, seed: u64) -> Vec<usize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut idx: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        idx.swap(i, rand::Rng::random_range(&mut rng, 0..=i));
    }
    idx
}

/// Fold of each row when the rows in order `idx` are dealt over k folds in turn.
fn deal(idx: &[usize], k: usize) -> Vec<usize> {
    let mut f = vec![0; idx.len()];
    for (pos, &i) in idx.iter().enumerate() {
        f[i] = pos % k;
    }
    f
}

/// K-fold cross-validated log score of every particle: particle i's row scored
/// ([`predict_ln_prob`]) under the model with `terms` fitted to the other folds (plug-in
/// maximum likelihood). None if a training fit fails.
pub fn cv_pointwise(x: Obs, terms: &[(Effect, Term)], folds: &[usize], k: usize) -> Option<Vec<f64>> {
    let mut out = vec![f64::NAN; x.len()];
    for f in 0..k {
        let train: Vec<usize> = (0..x.len()).filter(|&i| folds[i] != f).collect();
        let xt = x.rows(&train);
        let fit = fit_model(xt.view(), &subset(terms, &train)).ok()?;
        for i in (0..x.len()).filter(|&i| folds[i] == f) {
            out[i] = predict_ln_prob(&fit, terms, x, i);
        }
    }
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The strength model fitted to one material's sample: the regression with the model's
/// effects, the terms it was fitted with (for refits) and each regression column's reference
/// value (median diameter, mean temperature; NaN for a level's indicator) and mean (its centre
/// over the sample).
#[derive(Debug, Clone, PartialEq)]
pub struct StrengthFit {
    /// The fitted regression.
    pub model: ModelFit,
    /// Its terms, in the order of `model.effects`.
    pub terms: Vec<(Effect, Term)>,
    /// Reference value of each regression column's covariate (order of β; NaN for the
    /// indicator of a level).
    pub references: Vec<f64>,
    /// Mean of each regression column over the sample (order of β).
    pub centre: Vec<f64>,
    /// The sample's source (file), for messages.
    pub source: String,
    /// The fitted strengths σ̄ at break (Pa), with what each row says of its value.
    pub data: Observations,
}

/// What one regression (β) or scale (γ) column of a fitted model is: its effect and, for a
/// categorical factor, the level it indicates.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// The effect.
    pub effect: Effect,
    /// The level (categorical factors), None for a linear effect's one column.
    pub level: Option<String>,
}

impl StrengthFit {
    /// Fits `effects` to `sample`. An effect whose covariate is missing, empty or constant in
    /// the data is an error naming `material`, the file, the column and the rule (a study that
    /// asks for an effect needs its covariate; the naming loop instead skips such candidates).
    pub fn new(sample: &Sample, effects: &[Effect], gamma: f64, material: &str) -> Result<StrengthFit> {
        let mut terms = Vec::new();
        for e in effects {
            let t = sample.term(e, gamma).map_err(|reason| Error::Data {
                file: sample.source.clone(),
                location: format!("column {}", e.covariate()),
                rule: format!("material `{material}`: the strength model's `{}` effect needs this column: {reason}", e.name()),
            })?;
            terms.push((e.clone(), t));
        }
        let model = fit_model(sample.strength.view(), &terms).map_err(|err| Error::Data {
            file: sample.source.clone(),
            location: "all rows".into(),
            rule: format!("material `{material}`: the strength model ({}) could not be fitted: {err}", names(effects)),
        })?;
        Ok(Self::from_model(model, terms, sample))
    }

    /// Wraps a model fitted with `terms` to `sample` (the naming loop's final model).
    pub fn from_model(model: ModelFit, terms: Vec<(Effect, Term)>, sample: &Sample) -> StrengthFit {
        let mut references = Vec::new();
        let mut centre = Vec::new();
        let mean = |z: &[f64]| z.iter().sum::<f64>() / z.len() as f64;
        for (e, t) in &terms {
            match t {
                Term::Linear(z) => {
                    let values: Vec<f64> = sample
                        .covariates
                        .iter()
                        .find(|(n, _)| *n == e.covariate())
                        .map(|(_, c)| c.iter().map(|v| v.unwrap_or(f64::NAN)).collect())
                        .unwrap_or_default();
                    references.push(e.reference(&values));
                    centre.push(mean(z));
                }
                Term::Levels { columns, .. } | Term::Pooled { columns, .. } => {
                    for z in columns {
                        references.push(f64::NAN);
                        centre.push(mean(z));
                    }
                }
                _ => {}
            }
        }
        StrengthFit { model, terms, references, centre, source: sample.source.clone(), data: sample.strength.clone() }
    }

    /// The model's effects, in the order they were added.
    pub fn effects(&self) -> &[Effect] {
        &self.model.effects
    }

    /// The effects with regression columns, in the order of β (a categorical factor once).
    pub fn linear(&self) -> Vec<Effect> {
        self.model.linear()
    }

    /// Each regression column (order of β).
    pub fn beta_columns(&self) -> Vec<Column> {
        let mut out = Vec::new();
        for (e, t) in &self.terms {
            match t {
                Term::Linear(_) => out.push(Column { effect: e.clone(), level: None }),
                Term::Levels { levels, reference, .. } => out.extend(levels.iter().filter(|l| *l != reference).map(|l| Column { effect: e.clone(), level: Some(l.clone()) })),
                Term::Pooled { levels, .. } => out.extend(levels.iter().map(|l| Column { effect: e.clone(), level: Some(l.clone()) })),
                _ => {}
            }
        }
        out
    }

    /// Each scale column (order of γ): the non-reference levels of each modulus-per-level factor.
    pub fn scale_columns(&self) -> Vec<Column> {
        let mut out = Vec::new();
        for (e, t) in &self.terms {
            if let Term::Moduli { levels, reference, .. } = t {
                out.extend(levels.iter().filter(|l| *l != reference).map(|l| Column { effect: e.clone(), level: Some(l.clone()) }));
            }
        }
        out
    }

    /// Where e^μ is the scale, in words: each categorical factor's reference level and each
    /// linear effect's covariate at its reference value (`Charge = K1, temperature_c = 20`);
    /// empty without effects. Contact-geometry effects are at roundness or sphericity 1.
    pub fn reference_words(&self) -> String {
        let mut out: Vec<String> = Vec::new();
        let mut j = 0;
        for (e, t) in &self.terms {
            match t {
                Term::Linear(_) => {
                    let r = self.references[j];
                    j += 1;
                    let v = if e.is_contact_geometry() { 1.0 } else { r };
                    if v.is_finite() && !out.iter().any(|w| w.starts_with(&format!("{} =", e.covariate()))) {
                        // A recorded column's reference is the data's mean or median (a
                        // temperature mean may lie where no particle was tested): said so.
                        let unit = if e.covariate() == "temperature_c" { " °C" } else { "" };
                        let said = match e.reference_said() {
                            "" => String::new(),
                            w => format!(" ({w})"),
                        };
                        out.push(format!("{} = {}{unit}{said}", e.covariate(), four_significant(v)));
                    }
                }
                Term::Levels { levels, reference, .. } => {
                    j += levels.len() - 1;
                    out.push(format!("{} = {reference}", e.covariate()));
                }
                Term::Pooled { levels, .. } => {
                    j += levels.len();
                    out.push(format!("{}: the population of levels", e.covariate()));
                }
                Term::Moduli { reference, .. } => {
                    let w = format!("{} = {reference}", e.covariate());
                    if !out.contains(&w) {
                        out.push(w);
                    }
                }
                Term::Damage { .. } => out.push("impacts = 0".into()),
                Term::Populations(_) => {}
            }
        }
        out.join(", ")
    }

    /// The single-column linear effects with their β index: what a sensitivity analysis can
    /// vary one at a time.
    pub fn scalar_effects(&self) -> Vec<(Effect, usize)> {
        self.beta_columns().into_iter().enumerate().filter(|(_, c)| c.level.is_none()).map(|(j, c)| (c.effect, j)).collect()
    }
}

/// `v` to four significant digits, as a message shows a number.
fn four_significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let d = 10f64.powi(3 - v.abs().log10().floor() as i32);
    crate::intake::columns::shown((v * d).round() / d)
}

/// Effect names joined by `+` (`none` for the deliverable's model).
pub fn names(effects: &[Effect]) -> String {
    if effects.is_empty() { "none".into() } else { effects.iter().map(|e| e.name()).collect::<Vec<_>>().join("+") }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::weibull::Weibull;
    use rand::Rng;

    #[test]
    fn damage_ratio_is_recovered() {
        // Particles crushed after 0–200 prior impacts at x = 0.05 (γ = 5), m = 15.
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let n = 600;
        let impacts: Vec<u64> = (0..n).map(|_| rng.random_range(0..=200)).collect();
        let x: Vec<f64> = impacts
            .iter()
            .map(|&k| {
                let f = damage_offset(0.05, 5.0, k).unwrap().exp();
                Weibull::new(15.0, 2e9 * f).unwrap().sample(&mut rng)
            })
            .collect();
        let c = Sample { covariates: vec![("impacts".to_string(), impacts.iter().map(|&k| Some(k as f64)).collect())], ..Sample::default() };
        let t = c.term(&Effect::Damage, 5.0).unwrap();
        let m = fit_model(Obs::exact(&x), &[(Effect::Damage, t)]).unwrap();
        let r = m.damage_ratio.unwrap();
        assert!((r / 0.05 - 1.0).abs() < 0.25, "x = {r}");
        assert!((m.shape() - 15.0).abs() < 1.5);
    }

    #[test]
    fn a_missing_covariate_names_material_file_and_column() {
        let s = Sample { source: "d.csv".into(), strength: Observations::exact(vec![1e9; 12]), covariates: vec![("roundness".into(), vec![None; 12])], ..Sample::default() };
        let e = StrengthFit::new(&s, &[Effect::Roundness], 5.0, "gen4").unwrap_err().to_string();
        assert!(e.contains("d.csv") && e.contains("column roundness") && e.contains("gen4"), "{e}");
    }
}
