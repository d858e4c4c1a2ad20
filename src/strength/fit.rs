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
//! A partially pooled categorical factor's spread is searched in [`super::pooling`].

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::effects::{Effect, Term, damage_offset};
use super::regress::{Design, RegFit, fit, fit_from};
use crate::contact::{ContactOptions, ContactState, ContactStress, Elastic, Hertz, TensileZone};
use crate::data::CrushData;
use crate::error::{Error, Result};
use crate::stats::golden_max;
use crate::lifetime::damage::tk_ratio_path;

/// Strengths and covariates of one sample: a crush sample reduced to σ̄ at break, or a
/// strength file's specimens with their recorded factors.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sample {
    /// Where it came from (for messages).
    pub source: String,
    /// σ̄ at break, or the specimen strength (Pa), per specimen.
    pub strength: Vec<f64>,
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
            strength: rows.iter().map(|&i| self.strength[i]).collect(),
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
    let zone = TensileZone::new(elastic.poisson_ratio);
    data.records
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let radius = 0.5 * r.diameter_m;
            let hertz = Hertz::sphere_on_flat(elastic, &contact.platen, radius);
            let state = ContactStress { hertz, zone, domain: contact.averaging, particle_radius: radius }.at_force(r.crush_force_n)?;
            if let Some(rule) = crate::data::SIGMA_BAR.broken(state.mean_tensile) {
                return Err(data.error(k, "crush_force_n", format!("{rule}, from F = {} N, d = {} m and E = {} Pa: check the force and diameter units", r.crush_force_n, r.diameter_m, elastic.youngs_modulus_pa)));
            }
            Ok(state)
        })
        .collect()
}

/// Strengths (σ̄ at break) and covariates of a crush dataset, with the factor columns its study
/// declares (numeric ones beside the particle covariates, categorical ones as levels) and their
/// candidate effects.
pub fn sample_of(data: &CrushData, elastic: &Elastic, contact: &ContactOptions) -> Result<Sample> {
    let at = contact_at_break(data, elastic, contact)?;
    let r = &data.records;
    let mut s = Sample {
        source: data.path.display().to_string(),
        strength: at.iter().map(|c| c.mean_tensile).collect(),
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

/// A fitted model: the base Weibull plus zero or more effects.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelFit {
    /// The effects, in the order they were added.
    pub effects: Vec<Effect>,
    /// Regression columns of each effect, in the order of `effects` (1 for a linear effect,
    /// L − 1 for the levels of a categorical factor, 0 for damage and for a modulus per level).
    pub widths: Vec<usize>,
    /// Scale columns of each effect, in the order of `effects` (L − 1 for a modulus per level,
    /// 0 for the others).
    pub scale_widths: Vec<usize>,
    /// The scale columns (ln b_i = ln b + Σ γ_j v_ij), in the order of the moduli effects.
    pub scale_columns: Vec<Vec<f64>>,
    /// Ridge precision 1/τ² of each regression column (0 unless partially pooled).
    pub penalty: Vec<f64>,
    /// The regression (β in the order of the linear effects).
    pub reg: RegFit,
    /// Linear columns, in the order of the linear effects.
    pub columns: Vec<Vec<f64>>,
    /// The damage offset at the fitted ratio, if damage is an effect.
    pub offset: Option<Vec<f64>>,
    /// Fitted Tavares–King ratio x, if damage is an effect.
    pub damage_ratio: Option<f64>,
    /// Number of particles fitted.
    pub n: usize,
    /// A two-population law in place of the Weibull law (then `reg` is the plain two-parameter
    /// fit, kept for the reference scale, and the likelihood, CDF and draws are the law's).
    pub law: Option<crate::strength::flaws::FlawFit>,
}

impl ModelFit {
    /// The regression design of the fitted model.
    pub fn design(&self) -> Design<'_> {
        Design { columns: &self.columns, offset: self.offset.as_deref(), scale_columns: &self.scale_columns, penalty: &self.penalty }
    }

    /// Number of parameters: μ, b, and each effect's (one; L − 1 for levels or moduli, also
    /// when partially pooled); a two-population law's own (4 or 5).
    pub fn parameters(&self) -> usize {
        if let Some(l) = &self.law {
            return l.kind.parameters();
        }
        2 + self.widths.iter().zip(&self.effects).map(|(w, e)| if *e == Effect::Damage { 1 } else { *w }).sum::<usize>() + self.scale_columns.len() - self.pooled_effects()
    }

    /// [`ModelFit::parameters`] with each partially pooled factor counted at its effective
    /// degrees of freedom (between 0 and L − 1) instead of L − 1: what ΔBIC charges.
    pub fn effective_parameters(&self) -> f64 {
        let pooled_columns = self.penalty.iter().filter(|l| **l > 0.0).count();
        if self.law.is_some() || pooled_columns == 0 {
            return self.parameters() as f64;
        }
        // parameters() counts each pooled factor at L − 1: take its columns out, its edf in.
        (self.parameters() + self.pooled_effects() - pooled_columns) as f64 + self.reg.edf_penalised
    }

    /// ln τ of each partially pooled factor, in the order of the effects.
    pub fn pooled_ln_tau(&self) -> Vec<f64> {
        self.effects.iter().filter_map(|e| self.beta_range(e)).filter(|r| !r.is_empty()).filter_map(|r| self.penalty.get(r.start).copied()).filter(|l| *l > 0.0).map(|l| -0.5 * l.ln()).collect()
    }

    /// Number of partially pooled factors.
    fn pooled_effects(&self) -> usize {
        self.effects.iter().filter(|e| self.beta_range(e).is_some_and(|r| !r.is_empty() && self.penalty.get(r.start).is_some_and(|l| *l > 0.0))).count()
    }

    /// Weibull modulus (of the reference level when a factor has a modulus per level; NaN for a
    /// two-population law, which has two).
    pub fn shape(&self) -> f64 {
        if self.law.is_some() { f64::NAN } else { self.reg.shape() }
    }

    /// The smallest and largest Weibull modulus over the fitted specimens: (m, m) with one
    /// modulus, the range over the levels with a modulus per level, the two populations'
    /// moduli for a two-population law.
    pub fn modulus_range(&self) -> (f64, f64) {
        if let Some(l) = &self.law {
            return (l.first.1.min(l.second.1), l.first.1.max(l.second.1));
        }
        let d = self.design();
        (0..self.n).map(|i| 1.0 / self.reg.b_at(&d, i)).fold((self.reg.shape(), self.reg.shape()), |(lo, hi), m| (lo.min(m), hi.max(m)))
    }

    /// Maximised log-likelihood.
    pub fn loglik(&self) -> f64 {
        self.law.as_ref().map_or(self.reg.loglik, |l| l.loglik)
    }

    /// Fitted CDF of specimen i at x.
    pub fn cdf(&self, i: usize, x: f64) -> f64 {
        match &self.law {
            Some(l) => l.cdf(x),
            None => self.reg.cdf(&self.design(), i, x),
        }
    }

    /// The linear effects, in the order of β.
    pub fn linear(&self) -> Vec<Effect> {
        self.effects.iter().zip(&self.widths).filter(|(e, w)| **e != Effect::Damage && **w > 0).map(|(e, _)| e.clone()).collect()
    }

    /// The positions in γ (the scale coefficients) of a modulus-per-level effect.
    pub fn gamma_range(&self, c: &Effect) -> Option<std::ops::Range<usize>> {
        let k = self.effects.iter().position(|e| e == c)?;
        let start: usize = self.scale_widths[..k].iter().sum();
        Some(start..start + self.scale_widths[k])
    }

    /// The positions in β of an effect's coefficients.
    pub fn beta_range(&self, c: &Effect) -> Option<std::ops::Range<usize>> {
        let k = self.effects.iter().position(|e| e == c)?;
        let start: usize = self.widths[..k].iter().sum();
        Some(start..start + self.widths[k])
    }

    /// The profile-likelihood interval at `level` of a single-column effect's β (`x`: the
    /// fitted strengths; [`super::regress::profile_interval`]); None for a categorical factor, a
    /// modulus per level, damage and a two-population law.
    pub fn profile_band(&self, x: &[f64], c: &Effect, level: f64) -> Option<(f64, f64)> {
        if self.law.is_some() || self.damage_ratio.is_some() {
            return None;
        }
        let r = self.beta_range(c)?;
        if r.len() != 1 {
            return None;
        }
        super::regress::profile_interval(x, &self.design(), &self.reg, r.start, level)
    }

    /// β of a linear effect (or the ratio x for damage), with its standard error (NaN for
    /// damage); the first coefficient of a categorical factor's levels; the first γ (ln of the
    /// level's 1/m over the reference's) of a modulus per level.
    pub fn coefficient(&self, c: &Effect) -> Option<(f64, f64)> {
        if *c == Effect::Damage {
            return self.damage_ratio.map(|x| (x, f64::NAN));
        }
        if let Some(r) = self.gamma_range(c).filter(|r| !r.is_empty()) {
            return Some((*self.reg.gamma.get(r.start)?, self.reg.gamma_se[r.start]));
        }
        let j = self.beta_range(c)?.start;
        Some((*self.reg.beta.get(j)?, self.reg.beta_se[j]))
    }

    /// Parametric-bootstrap replicate `r` (its own ChaCha8 stream of `seed`): strengths drawn
    /// from this model at the sample's covariates, refitted with `terms` (the model's own terms
    /// or more). None if the refit fails.
    pub fn bootstrap_refit(&self, terms: &[(Effect, Term)], seed: u64, r: usize) -> Option<(Vec<f64>, ModelFit)> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let xs = match &self.law {
            Some(l) => (0..self.n).map(|_| l.sample(&mut rng)).collect(),
            None => self.reg.sample(&self.design(), self.n, &mut rng),
        };
        let refit = fit_model_near(&xs, terms, Some(self)).ok()?;
        Some((xs, refit))
    }
}

/// Fits the base model plus `terms` to the strengths `x`.
pub fn fit_model(x: &[f64], terms: &[(Effect, Term)]) -> Result<ModelFit> {
    fit_model_near(x, terms, None)
}

/// [`fit_model`] near a fit to similar data (a bootstrap refit): the damage ratio's profile
/// search and each pooled factor's τ search then start at the hint's values, which is several
/// times faster (the full search runs when the optimum leaves the local bracket).
pub fn fit_model_near(x: &[f64], terms: &[(Effect, Term)], hint: Option<&ModelFit>) -> Result<ModelFit> {
    let ratio = hint.and_then(|h| h.damage_ratio);
    let pooled = terms.iter().filter(|(_, t)| matches!(t, Term::Pooled { .. })).count();
    if pooled == 0 {
        return fit_at(x, terms, ratio, &[], None);
    }
    super::pooling::fit_pooled(x, terms, ratio, hint, pooled)
}

/// [`fit_model_near`] with each pooled factor's spread fixed at e^(ln_tau).
pub(super) fn fit_at(x: &[f64], terms: &[(Effect, Term)], hint: Option<f64>, ln_tau: &[f64], start: Option<&RegFit>) -> Result<ModelFit> {
    let mut columns = Vec::new();
    let mut damage = None;
    let mut effects = Vec::new();
    let mut widths = Vec::new();
    let mut penalty = Vec::new();
    let mut pooled = 0;
    if let Some(kind) = terms.iter().find_map(|(_, t)| if let Term::Populations(k) = t { Some(*k) } else { None }) {
        if terms.len() > 1 {
            return Err(Error::numerical("two flaw populations", "a two-population law is fitted against the base law only, not beside other effects"));
        }
        let law = crate::strength::flaws::fit(kind, x)?;
        let reg = fit(x, &Design::default())?;
        return Ok(ModelFit { effects: vec![terms[0].0.clone()], widths: vec![0], scale_widths: vec![0], scale_columns: Vec::new(), penalty: Vec::new(), reg, columns: Vec::new(), offset: None, damage_ratio: None, n: x.len(), law: Some(law) });
    }
    let mut scale_columns = Vec::new();
    let mut scale_widths = Vec::new();
    for (c, t) in terms {
        effects.push(c.clone());
        match t {
            Term::Linear(z) => {
                columns.push(z.clone());
                widths.push(1);
                penalty.push(0.0);
            }
            Term::Levels { columns: z, .. } => {
                columns.extend(z.iter().cloned());
                widths.push(z.len());
                penalty.extend(std::iter::repeat_n(0.0, z.len()));
            }
            Term::Pooled { columns: z, .. } => {
                let tau = ln_tau.get(pooled).copied().unwrap_or((0.1f64).ln()).exp();
                pooled += 1;
                columns.extend(z.iter().cloned());
                widths.push(z.len());
                penalty.extend(std::iter::repeat_n(1.0 / (tau * tau), z.len()));
            }
            Term::Moduli { columns: v, .. } => {
                scale_columns.extend(v.iter().cloned());
                widths.push(0);
            }
            Term::Damage { impacts, gamma } => {
                damage = Some((impacts, *gamma));
                widths.push(0);
            }
            Term::Populations(_) => unreachable!("handled above"),
        }
        scale_widths.push(if let Term::Moduli { columns: v, .. } = t { v.len() } else { 0 });
    }
    // Linear effects first in `effects`' β order; damage (if any) is profiled.
    let Some((impacts, gamma)) = damage else {
        let reg = fit_from(x, &Design { columns: &columns, offset: None, scale_columns: &scale_columns, penalty: &penalty }, start)?;
        return Ok(ModelFit { effects, widths, scale_widths, scale_columns, penalty, reg, columns, offset: None, damage_ratio: None, n: x.len(), law: None });
    };
    let n_max = impacts.iter().copied().max().unwrap_or(0);
    // One Tavares–King trajectory per trial ratio serves every particle.
    let offsets = |lx: f64| -> Option<Vec<f64>> {
        let path = tk_ratio_path(lx.exp(), gamma, n_max)?;
        Some(impacts.iter().map(|&n| (lx - path[n as usize]) / 5.0).collect())
    };
    let profile = |lx: f64| -> f64 {
        offsets(lx)
            .and_then(|o| fit(x, &Design { columns: &columns, offset: Some(&o), scale_columns: &scale_columns, penalty: &penalty }).ok())
            .map_or(f64::NEG_INFINITY, |r| r.loglik)
    };
    let (lo, hi) = ((1e-4f64).ln(), (0.99f64).ln());
    let golden = |a: f64, b: f64, tol: f64| golden_max(&profile, a, b, tol);
    // Near a hint (a bootstrap refit of a fitted ratio): golden section on ln x ± 1, kept
    // unless the optimum sits at the edge of that bracket.
    let local = hint.filter(|h| h.is_finite() && *h > 0.0).map(|h| {
        let (a, b) = ((h.ln() - 1.0).max(lo), (h.ln() + 1.0).min(hi));
        let lx = golden(a, b, 1e-3);
        let inside = (lx - a > 1e-2 || a == lo) && (b - lx > 1e-2 || b == hi);
        (lx, inside && profile(lx).is_finite())
    });
    let lx = match local {
        Some((lx, true)) => lx,
        _ => {
            // Coarse scan of ln x over [ln 10⁻⁴, ln 0.99] (ratios that break a particle score
            // −∞), then golden section around the best point to 10⁻⁴ in ln x.
            let grid: Vec<f64> = (0..=16).map(|k| lo + (hi - lo) * k as f64 / 16.0).collect();
            let vals: Vec<f64> = grid.iter().map(|&g| profile(g)).collect();
            let best = (0..grid.len()).max_by(|&a, &b| vals[a].total_cmp(&vals[b])).unwrap_or(0);
            if !vals[best].is_finite() {
                return Err(Error::numerical("damage effect", "every trial damage ratio breaks a particle or fails to fit"));
            }
            golden(grid[best.saturating_sub(1)], grid[(best + 1).min(grid.len() - 1)], 1e-4)
        }
    };
    let off = offsets(lx).ok_or_else(|| Error::numerical("damage effect", "the fitted ratio breaks a particle"))?;
    let reg = fit(x, &Design { columns: &columns, offset: Some(&off), scale_columns: &scale_columns, penalty: &penalty })?;
    // `effects` keeps damage wherever it was added; β follow the linear effects' order.
    Ok(ModelFit { effects, widths, scale_widths, scale_columns, penalty, reg, columns, offset: Some(off), damage_ratio: Some(lx.exp()), n: x.len(), law: None })
}

/// ln σ_i of particle `i` under a model fitted on other rows: its linear terms' columns at row
/// i and the damage offset at the fitted ratio.
pub fn predict_ln_scale(fit: &ModelFit, terms: &[(Effect, Term)], i: usize) -> f64 {
    let mut s = fit.reg.mu;
    let mut j = 0;
    for (_, t) in terms {
        match t {
            Term::Linear(z) => {
                s += fit.reg.beta[j] * z[i];
                j += 1;
            }
            Term::Levels { columns, .. } | Term::Pooled { columns, .. } => {
                for z in columns {
                    s += fit.reg.beta[j] * z[i];
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

/// Log density of specimen i's strength x under a model fitted on other rows (its law's, or the
/// Weibull regression's at [`predict_ln_scale`]).
pub fn predict_ln_density(fit: &ModelFit, terms: &[(Effect, Term)], i: usize, x: f64) -> f64 {
    match &fit.law {
        Some(l) => l.ln_pdf(x),
        None => fit.reg.ln_density_with(predict_ln_scale(fit, terms, i), predict_b(fit, terms, i), x),
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
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut idx: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        idx.swap(i, rand::Rng::random_range(&mut rng, 0..=i));
    }
    let mut f = vec![0; n];
    for (pos, &i) in idx.iter().enumerate() {
        f[i] = pos % k;
    }
    f
}

/// K-fold cross-validated log density of every particle: particle i scored under the model with
/// `terms` fitted to the other folds (plug-in maximum likelihood). None if a training fit fails.
pub fn cv_pointwise(x: &[f64], terms: &[(Effect, Term)], folds: &[usize], k: usize) -> Option<Vec<f64>> {
    let mut out = vec![f64::NAN; x.len()];
    for f in 0..k {
        let train: Vec<usize> = (0..x.len()).filter(|&i| folds[i] != f).collect();
        let xt: Vec<f64> = train.iter().map(|&i| x[i]).collect();
        let fit = fit_model(&xt, &subset(terms, &train)).ok()?;
        for i in (0..x.len()).filter(|&i| folds[i] == f) {
            out[i] = predict_ln_density(&fit, terms, i, x[i]);
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
    /// The fitted strengths σ̄ at break (Pa).
    pub data: Vec<f64>,
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
        let model = fit_model(&sample.strength, &terms).map_err(|err| Error::Data {
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
                        out.push(format!("{} = {}", e.covariate(), four_significant(v)));
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
        let m = fit_model(&x, &[(Effect::Damage, t)]).unwrap();
        let r = m.damage_ratio.unwrap();
        assert!((r / 0.05 - 1.0).abs() < 0.25, "x = {r}");
        assert!((m.shape() - 15.0).abs() < 1.5);
    }

    #[test]
    fn a_missing_covariate_names_material_file_and_column() {
        let s = Sample { source: "d.csv".into(), strength: vec![1e9; 12], covariates: vec![("roundness".into(), vec![None; 12])], ..Sample::default() };
        let e = StrengthFit::new(&s, &[Effect::Roundness], 5.0, "gen4").unwrap_err().to_string();
        assert!(e.contains("d.csv") && e.contains("column roundness") && e.contains("gen4"), "{e}");
    }
}
