//! The lifetime model of one particle type: contact geometry → strength law → impact →
//! population → breaking probability after N impacts. Every study evaluates this object.
//!
//! # Equations
//!
//! A particle of diameter d (R = d/2) touches a flat (platen or tube) with the radius of
//! curvature
//!
//! ```text
//! R_c = R · roundness^q · sphericity^p          (q = p = 0 unless the model carries the effect)
//! ```
//!
//! in the crush test and in every impact alike. With an averaging domain ending at a multiple of
//! the contact radius, σ̄ = r·p0 and the Hertz relations are power laws in R_c:
//!
//! ```text
//! crush at force F:    p0 ∝ (F E*²/R_c²)^(1/3)              ⇒ σ̄(F, R_c) = σ̄(F, R)·(R_c/R)^(−2/3)
//! impact at V, η:      p0 ∝ E*^(4/5) (ρ d³)^(1/5) (η V²)^(1/5) R_c^(−3/5)
//!                                                          ⇒ σ̄_imp(R_c) = σ̄_imp,sphere·(R_c/R)^(−3/5)
//! ```
//!
//! and σ̄_imp,sphere(η, V) does not depend on d (the mass ∝ d³ and R^(−3/5) cancel), nor does
//! a/R of a sphere's impact, so one reference sphere serves every particle, whatever the
//! domain. The strength law is the Weibull law of σ̄ at break with the particle's own scale,
//! ln σ_θ,i = μ + Σ_strength β_k z_ik (size, temperature; [`super::effects`]); in the σ̄ reduced
//! with R = d/2 the contact effects add β z_ik with β = 2q/3 (z = ln roundness). The
//! single-impact hazard of particle i is then
//!
//! ```text
//! ln H_i = m [ln σ̄_imp,sphere(η, V) − μ − Σ_k κ_k β_k z_ik],   κ = 1 (strength), 0.9 (contact)
//! ```
//!
//! (κ = (3/5)/(2/3): the impact feels R_c^(−3/5) where the crush reduction felt R_c^(−2/3)),
//! P_N,i follows from the damage model ([`crate::lifetime::damage::Law`]) and the population's
//! breaking probability is P_N = Σ_i w_i P_N,i ([`super::population`]). The deliverable's model
//! is the special case without effects: R_c = R, one strength law, every particle alike.
//!
//! For a domain with σ̄ ∝ p0 the impact stress is σ̄_imp,sphere(1, 1)·η^(1/5)·V^(2/5): one
//! logarithm per call ([`LifetimeModel::ln_impact_stress`]; `tests::fast_path_is_the_contact_chain`
//! checks it against the contact module to 1e-12). With L = R the domain formula is evaluated.
//!
//! Recorded factors of the crush file (a powder batch, a sintering temperature) enter the same
//! way: a numeric factor's z and a level's indicator are strength effects (κ = 1), taken from
//! the population's factor values ([`super::population`]: a named level, levels in proportion,
//! a value or a distribution); a modulus per level gives row i its own modulus
//! m_i = m e^(−Σ γ_j v_ij), so ln H_i = m_i [ln σ̄_imp − μ − Σ β_j z_ij] and the damage law of
//! row i is built for m_i.
//!
//! [`LifetimeChain`] is the model as a [`Simulator`]: θ = (m, σ_θ = e^μ, β of each regression
//! column, γ of each scale column, η, V) ↦ (F_max and σ̄ of the reference sphere, P_N of the population for each
//! configured N under independent trials).
//!
//! Verified by the unit tests below (power laws of R_c against direct Hertz computations,
//! diameter independence, fast path) and by `tests/verification/strength.rs` (the three studies
//! agree at fixed inputs; coverage of a generator's true population breakage).

use super::draws::{MAX_LINEAR, MAX_SCALE, Params};
use super::effects::{Effect, Term};
use super::fit::{Column, StrengthFit};
use super::population::Population;
use crate::contact::{AveragingDomain, Elastic, Impact, Sphere, TensileZone};
use crate::error::{Error, Result};
use crate::lifetime::damage::{DamageModel, Law};
use crate::lifetime::{ImpactLoad, MAX_VELOCITY};
use crate::model::{OutputSpec, Simulator, check_outputs};
use crate::params::{Param, ParamSpace};

/// One output of a breakage evaluation: a damage model after N impacts, with the Tavares–King
/// ln x* of that horizon (0 for the other models).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Horizon {
    /// The damage model.
    pub model: DamageModel,
    /// Impacts N.
    pub impacts: f64,
    /// ln x*(N, γ) (Tavares–King only).
    pub ln_x_star: f64,
}

impl Horizon {
    /// N impacts under independent trials.
    pub fn independent(impacts: f64) -> Horizon {
        Horizon { model: DamageModel::Independent, impacts, ln_x_star: 0.0 }
    }

    /// Its law for Weibull modulus m.
    #[inline]
    pub fn law(&self, m: f64) -> Law {
        Law::new(self.model, m, self.impacts, self.ln_x_star)
    }
}

/// The lifetime model of one particle type.
#[derive(Debug, Clone)]
pub struct LifetimeModel {
    /// Material key (`bl1630`).
    pub key: String,
    /// Material label (`BL 16/30`).
    pub label: String,
    /// Reference particle of the impact outputs (F_max, contact time, force history); its
    /// diameter does not change σ̄ or the breakage.
    pub sphere: Sphere,
    /// The wall (tube) hit in impacts.
    pub wall: Elastic,
    /// Averaging domain of σ̄ (crush and impact alike).
    pub domain: AveragingDomain,
    /// The fitted strength law.
    pub fit: StrengthFit,
    /// The particles predicted for.
    pub population: Population,
    /// The regression columns (β) and scale columns (γ).
    columns: (Vec<Column>, Vec<Column>),
    /// κ_j z_ij per row (row-major, stride `columns.0.len()`; one row of zeros without
    /// regression columns).
    kz: Vec<f64>,
    /// Rows of `kz`.
    rows: usize,
    /// Rows grouped by their scale columns' values (a modulus per level): (v, rows); empty
    /// without scale columns.
    groups: Vec<(Vec<f64>, Vec<usize>)>,
    /// Each row's weight in the point estimate (None: equal).
    point: Option<Vec<f64>>,
    /// ln σ̄ of the reference sphere's impact at η = 1, V = 1 m/s when σ̄ ∝ p0.
    ln_sigma_unit: Option<f64>,
}

impl LifetimeModel {
    /// The model of a material: its fitted strength law, the particle that hits `wall`, the
    /// averaging domain and the population predicted for. A population particle without a
    /// covariate or recorded factor the model needs is an error naming the material and the
    /// source.
    pub fn new(key: &str, label: &str, sphere: Sphere, wall: Elastic, domain: AveragingDomain, fit: StrengthFit, population: Population) -> Result<Self> {
        if let Some(e) = fit.effects().iter().find(|e| matches!(e, Effect::Populations(_))) {
            return Err(Error::Param {
                name: "strength".into(),
                rule: format!("material `{key}`: the lifetime chain needs one Weibull law per particle; `{}` (two flaw populations) is a candidate of strength files only", e.name()),
            });
        }
        let (beta_columns, scale_columns) = (fit.beta_columns(), fit.scale_columns());
        if beta_columns.len() > MAX_LINEAR || scale_columns.len() > MAX_SCALE {
            return Err(Error::numerical("lifetime model", format!("material `{key}`: at most {MAX_LINEAR} regression and {MAX_SCALE} scale columns (each level of a factor but one is a column)")));
        }
        let zone = TensileZone::new(sphere.elastic.poisson_ratio);
        let proportional = domain.ratio_to_peak_pressure(&zone).is_some();
        if let Some(e) = fit.effects().iter().find(|e| e.is_contact_geometry())
            && !proportional
        {
            return Err(Error::Param {
                name: "contact.averaging".into(),
                rule: format!("material `{key}`: the `{}` effect changes the contact curvature, which needs σ̄ ∝ p0 (a domain ending at a multiple of the contact radius), not {}", e.name(), domain.describe()),
            });
        }
        if population.is_empty() {
            return Err(Error::numerical("lifetime model", format!("material `{key}`: the population has no particle")));
        }
        // Temperature softening predicts at a temperature the study must name: the tests' own
        // (a mixture of 20 and 800 °C, say) is no plant's.
        if fit.effects().contains(&Effect::Temperature) && !population.temperature_named() {
            return Err(Error::Param {
                name: "predict".into(),
                rule: format!("material `{key}`: the strength model carries temperature softening; say which temperature the lifetime is for (the operating temperature): predict = {{ temperature_c = 800 }} or a distribution, in °C"),
            });
        }
        let (kz, rows, groups) = if beta_columns.is_empty() && scale_columns.is_empty() {
            (vec![], 1, vec![])
        } else {
            let mut kz = Vec::with_capacity(population.len() * beta_columns.len());
            let mut groups: Vec<(Vec<f64>, Vec<usize>)> = Vec::new();
            for i in 0..population.len() {
                let (z, v) = row_columns(&fit, &population, i, key)?;
                kz.extend(z);
                if !scale_columns.is_empty() {
                    match groups.iter_mut().find(|(g, _)| *g == v) {
                        Some((_, r)) => r.push(i),
                        None => groups.push((v, vec![i])),
                    }
                }
            }
            (kz, population.len(), groups)
        };
        // Without effects every row is alike: the point estimate is one row.
        let point = if kz.is_empty() && groups.is_empty() { None } else { population.point_weights() };
        let ln_sigma_unit = if proportional { Some(ImpactLoad::on_wall(&sphere, &wall, 1.0, domain).at_velocity(1.0)?.mean_tensile.ln()) } else { None };
        Ok(LifetimeModel { key: key.into(), label: label.into(), sphere, wall, domain, fit, population, columns: (beta_columns, scale_columns), kz, rows, groups, point, ln_sigma_unit })
    }

    /// The regression columns (order of β) and scale columns (order of γ).
    pub fn columns(&self) -> (&[Column], &[Column]) {
        (&self.columns.0, &self.columns.1)
    }


    /// Whether every particle has the same breakage (no regression or scale column).
    #[inline]
    pub fn uniform(&self) -> bool {
        self.columns.0.is_empty() && self.columns.1.is_empty()
    }

    /// The impact of the reference sphere on the wall with energy fraction η.
    pub fn impact(&self, eta: f64) -> Impact {
        Impact::sphere_on_wall(&self.sphere, &self.wall, self.sphere.radius(), eta)
    }

    /// ln σ̄ (Pa) of a spherical particle's impact at energy fraction η and velocity V (m/s);
    /// −∞ at V ≤ 0 (no contact).
    #[inline]
    pub fn ln_impact_stress(&self, eta: f64, v: f64) -> Result<f64> {
        if v <= 0.0 {
            return Ok(f64::NEG_INFINITY);
        }
        match self.ln_sigma_unit {
            Some(c) => Ok(c + 0.2 * eta.ln() + 0.4 * v.ln()),
            None => Ok(ImpactLoad::on_wall(&self.sphere, &self.wall, eta, self.domain).at_velocity(v)?.mean_tensile.ln()),
        }
    }

    /// ln σ̄ (Pa) of a spherical particle's impact at (η, V) when the particle's Young's modulus is
    /// `factor` times the model's (Poisson's ratio kept): σ̄ ∝ E*^(4/5) when σ̄ ∝ p0 (the Hertz
    /// impact's p0 at fixed mass, radius and velocity), else the impact recomputed with the
    /// scaled particle. `factor = 1` is [`LifetimeModel::ln_impact_stress`].
    pub fn ln_impact_stress_with_modulus(&self, eta: f64, v: f64, factor: f64) -> Result<f64> {
        if factor == 1.0 || v <= 0.0 {
            return self.ln_impact_stress(eta, v);
        }
        if !(factor.is_finite() && factor > 0.0) {
            return Err(Error::numerical("lifetime model", format!("material `{}`: Young's modulus factor {factor} is not positive", self.key)));
        }
        let mut sphere = self.sphere;
        sphere.elastic.youngs_modulus_pa *= factor;
        match self.ln_sigma_unit {
            Some(c) => {
                let star = |s: &Sphere| crate::contact::effective_modulus(&s.elastic, &self.wall).ln();
                Ok(c + 0.8 * (star(&sphere) - star(&self.sphere)) + 0.2 * eta.ln() + 0.4 * v.ln())
            }
            None => Ok(ImpactLoad::on_wall(&sphere, &self.wall, eta, self.domain).at_velocity(v)?.mean_tensile.ln()),
        }
    }

    /// The population's breaking probability for each of `horizons`, added into `out` (which
    /// the caller zeroes), at the reference sphere's impact stress ln σ̄ = `ln_sigma`. `weights`
    /// (one per row, summing to 1) default to the population's point weights.
    #[inline]
    pub fn breakage_into(&self, p: &Params, weights: Option<&[f64]>, ln_sigma: f64, horizons: &[Horizon], out: &mut [f64]) {
        debug_assert_eq!(horizons.len(), out.len());
        if self.uniform() {
            // One hazard for every particle: each law is used once, no table of laws.
            let base = p.shape * (ln_sigma - p.mu);
            let h = base.exp();
            for (o, hz) in out.iter_mut().zip(horizons) {
                *o += hz.law(p.shape).p(h, base);
            }
            return;
        }
        for (h, o) in horizons.chunks(LAWS).zip(out.chunks_mut(LAWS)) {
            self.breakage_chunk(p, weights, ln_sigma, h, o);
        }
    }

    /// [`LifetimeModel::breakage_into`] for at most [`LAWS`] horizons, rows with effects.
    fn breakage_chunk(&self, p: &Params, weights: Option<&[f64]>, ln_sigma: f64, horizons: &[Horizon], out: &mut [f64]) {
        let mut laws = [Law::Scaled { c: 0.0 }; LAWS];
        let laws = &mut laws[..horizons.len()];
        let build = |laws: &mut [Law], m: f64| {
            for (l, h) in laws.iter_mut().zip(horizons) {
                *l = h.law(m);
            }
        };
        let weights = weights.or(self.point.as_deref());
        let w0 = 1.0 / self.rows as f64;
        let k = self.columns.0.len();
        let row = |i: usize, m: f64, laws: &[Law], out: &mut [f64]| {
            let z = &self.kz[i * k..(i + 1) * k];
            let mut s = 0.0;
            for j in 0..k {
                s += p.beta[j] * z[j];
            }
            let ln_h = m * (ln_sigma - p.mu) - m * s;
            let h = ln_h.exp();
            let w = weights.map_or(w0, |w| w[i]);
            for (o, law) in out.iter_mut().zip(laws) {
                *o += w * law.p(h, ln_h);
            }
        };
        if self.groups.is_empty() {
            build(laws, p.shape);
            for i in 0..self.rows {
                row(i, p.shape, laws, out);
            }
            return;
        }
        for (v, rows) in &self.groups {
            let m = group_modulus(p, v);
            build(laws, m);
            for &i in rows {
                row(i, m, laws, out);
            }
        }
    }

    /// The population's breaking probability after each of `counts` impacts at (η, V) under
    /// independent trials.
    pub fn breakage(&self, p: &Params, weights: Option<&[f64]>, eta: f64, v: f64, counts: &[f64]) -> Result<Vec<f64>> {
        let horizons: Vec<Horizon> = counts.iter().map(|&n| Horizon::independent(n)).collect();
        let mut out = vec![0.0; counts.len()];
        self.breakage_into(p, weights, self.ln_impact_stress(eta, v)?, &horizons, &mut out);
        Ok(out)
    }

    /// Each row's single-impact ln H at ln σ̄ (for tables and tests).
    pub fn ln_hazards(&self, p: &Params, ln_sigma: f64) -> Vec<f64> {
        if self.uniform() {
            return vec![p.shape * (ln_sigma - p.mu); self.population.len()];
        }
        let k = self.columns.0.len();
        let mut m = vec![p.shape; self.rows];
        for (v, rows) in &self.groups {
            let mg = group_modulus(p, v);
            for &i in rows {
                m[i] = mg;
            }
        }
        (0..self.rows).map(|i| m[i] * (ln_sigma - p.mu) - m[i] * (0..k).map(|j| p.beta[j] * self.kz[i * k + j]).sum::<f64>()).collect()
    }

    /// The population's P_N after each of `counts` impacts at (η, V) under independent trials:
    /// (estimate at `estimate`, lower, upper) where the two-sided `level` band comes from `k`
    /// joint draws ([`LifetimeModel::draws`]).
    #[allow(clippy::too_many_arguments)]
    pub fn bands(&self, estimate: &Params, eta: f64, v: f64, counts: &[f64], how: super::options::Uncertainty, k: usize, seed: u64, level: f64) -> Result<Vec<(f64, f64, f64)>> {
        use rayon::prelude::*;
        let point = self.breakage(estimate, None, eta, v, counts)?;
        let (draws, weights) = self.draws(how, k, seed)?;
        let ln_sigma = self.ln_impact_stress(eta, v)?;
        let per: Vec<Vec<f64>> = draws
            .par_iter()
            .enumerate()
            .map(|(r, p)| {
                let horizons: Vec<Horizon> = counts.iter().map(|&n| Horizon::independent(n)).collect();
                let mut out = vec![0.0; counts.len()];
                self.breakage_into(p, weights.as_ref().map(|w| &w[r][..]), ln_sigma, &horizons, &mut out);
                out
            })
            .collect();
        let a = 0.5 * (1.0 - level);
        Ok((0..counts.len())
            .map(|c| {
                let q = crate::stats::interpolated_quantiles(per.iter().map(|d| d[c]).collect(), &[a, 1.0 - a]);
                (point[c], q[0], q[1])
            })
            .collect())
    }

    /// Joint draws of the parameters and, for a sampled population, of its weights (the same
    /// draw index pairs them).
    pub fn draws(&self, how: super::options::Uncertainty, k: usize, seed: u64) -> Result<(Vec<Params>, Option<Vec<Vec<f64>>>)> {
        let params = self.fit.draws(how, k, seed)?;
        let weights = if self.uniform() { None } else { self.population.weight_draws(k, seed ^ 0x9E0_1A7E) };
        Ok((params, weights))
    }
}

/// The Weibull modulus of a row with scale-column values `v`: m e^(−Σ γ_j v_j).
#[inline]
fn group_modulus(p: &Params, v: &[f64]) -> f64 {
    p.shape * (-v.iter().zip(&p.gamma).map(|(a, g)| a * g).sum::<f64>()).exp()
}

/// Most horizons one pass of [`LifetimeModel::breakage_into`] evaluates (more are done in chunks).
pub const LAWS: usize = 32;

/// Row `i` of the population in the model's columns: κ_j z_ij for each regression column and
/// v_ij for each scale column (a recorded factor from the population's factor columns, a
/// particle covariate from the particle). A missing value is an error naming material `key`.
fn row_columns(fit: &StrengthFit, population: &Population, i: usize, key: &str) -> Result<(Vec<f64>, Vec<f64>)> {
    use crate::intake::factors::FactorValues;
    let p = &population.particles[i];
    let (mut z, mut v) = (Vec::new(), Vec::new());
    let mut j = 0;
    let missing = |e: &Effect, what: &str| -> Error {
        if population.source == "declared" {
            Error::Param {
                name: "predict".into(),
                rule: format!("material `{key}`: the strength model's `{}` effect needs the value of `{}` for the particles predicted for (a declared population): set {what} in its [[material]]", e.name(), e.covariate()),
            }
        } else {
            Error::Data {
                file: population.source.trim_start_matches("data: ").to_string(),
                location: format!("row {} (line {}), column {}", i + 1, i + 2, e.covariate()),
                rule: format!("material `{key}`: the strength model's `{}` effect needs this covariate for every particle of the population", e.name()),
            }
        }
    };
    let level_of = |e: &Effect| -> Result<&str> {
        match population.factors.iter().find(|(n, _)| *n == e.covariate()) {
            Some((_, FactorValues::Levels(l))) => Ok(l[i].as_str()),
            _ => Err(missing(e, &format!("`predict = {{ {} = \"<level>\" }}` or levels in proportion", e.covariate()))),
        }
    };
    for (e, t) in &fit.terms {
        match t {
            Term::Linear(_) => {
                let value = match e {
                    Effect::Factor(_) => match population.factors.iter().find(|(n, _)| *n == e.covariate()) {
                        Some((_, FactorValues::Numeric(x))) => Some(x[i]),
                        _ => None,
                    },
                    _ => e.value_of(p),
                };
                let value = value.filter(|x| x.is_finite()).ok_or_else(|| missing(e, &format!("`predict = {{ {} = <value or distribution> }}`", e.covariate())))?;
                z.push(e.impact_exponent() * e.z(value, fit.references[j]));
                j += 1;
            }
            Term::Levels { levels, reference, .. } => {
                let l = level_of(e)?;
                z.extend(levels.iter().filter(|x| *x != reference).map(|x| f64::from(u8::from(x == l))));
                j += levels.len() - 1;
            }
            Term::Pooled { levels, .. } => {
                let l = level_of(e)?;
                z.extend(levels.iter().map(|x| f64::from(u8::from(x == l))));
                j += levels.len();
            }
            Term::Moduli { levels, reference, .. } => {
                let l = level_of(e)?;
                v.extend(levels.iter().filter(|x| *x != reference).map(|x| f64::from(u8::from(x == l))));
            }
            Term::Damage { .. } | Term::Populations(_) => {}
        }
    }
    Ok((z, v))
}

/// The lifetime model as a [`Simulator`].
#[derive(Debug, Clone)]
pub struct LifetimeChain {
    model: LifetimeModel,
    counts: Vec<f64>,
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
}

/// Indices of θ in [`LifetimeChain`] (the β of the regression columns follow the scale, then the
/// γ of the scale columns, then η and V).
pub mod theta {
    /// Weibull shape m (-).
    pub const SHAPE: usize = 0;
    /// Weibull scale σ_θ = e^μ (Pa).
    pub const SCALE: usize = 1;
    /// First β.
    pub const BETA: usize = 2;
}

impl LifetimeChain {
    /// The chain of `model`, with P_N outputs for each of `counts`; `nominal` = (parameters,
    /// η, V in m/s).
    pub fn new(model: LifetimeModel, counts: &[f64], nominal: (Params, f64, f64)) -> Result<Self> {
        if counts.iter().any(|n| !(n.is_finite() && *n >= 1.0)) {
            return Err(Error::Param { name: "impact_counts".into(), rule: format!("every count must be ≥ 1 (got {counts:?})") });
        }
        let (p, eta, v) = nominal;
        // Wide physical bounds; a nominal outside them is an error, never clamped.
        let mut params = vec![Param::uniform("weibull_shape", "-", 0.1, 500.0, p.shape), Param::uniform("weibull_scale_pa", "Pa", 1e3, 1e12, p.mu.exp())];
        let named = |prefix: &str, c: &Column| match &c.level {
            Some(l) => format!("{prefix}_{}_{l}", c.effect.name()),
            None => format!("{prefix}_{}", c.effect.name()),
        };
        let (betas, gammas) = model.columns();
        for (j, c) in betas.iter().enumerate() {
            params.push(Param::uniform(&named("beta", c), "-", -50.0, 50.0, p.beta[j]));
        }
        for (j, c) in gammas.iter().enumerate() {
            params.push(Param::uniform(&named("gamma", c), "-", -20.0, 20.0, p.gamma[j]));
        }
        params.push(Param::uniform("energy_fraction", "-", 1e-9, 1.0, eta));
        params.push(Param::uniform("velocity_m_s", "m/s", 0.0, MAX_VELOCITY, v));
        let space = ParamSpace::new(params)?;
        let mut outputs = vec![OutputSpec::new("f_max_n", "N"), OutputSpec::new("sigma_bar_pa", "Pa")];
        outputs.extend(counts.iter().map(|n| OutputSpec::new(format!("p_break_{n}"), "-")));
        Ok(LifetimeChain { model, counts: counts.to_vec(), space, outputs })
    }

    /// The model.
    pub fn model(&self) -> &LifetimeModel {
        &self.model
    }

    /// The impact counts N of the outputs.
    pub fn counts(&self) -> &[f64] {
        &self.counts
    }

    /// θ of (parameters, η, V).
    pub fn theta(&self, p: &Params, eta: f64, v: f64) -> Vec<f64> {
        let (k, ns) = (self.model.columns.0.len(), self.model.columns.1.len());
        let mut t = vec![p.shape, p.mu.exp()];
        t.extend_from_slice(&p.beta[..k]);
        t.extend_from_slice(&p.gamma[..ns]);
        t.extend([eta, v]);
        t
    }

    /// (parameters, η, V) of θ.
    pub fn unpack(&self, theta: &[f64]) -> Result<(Params, f64, f64)> {
        self.space.check(theta)?;
        if !self.space.contains(theta) {
            return Err(Error::Param { name: "θ".into(), rule: format!("{theta:?} lies outside the bounds") });
        }
        let (k, ns) = (self.model.columns.0.len(), self.model.columns.1.len());
        let mut p = Params::base(theta[theta::SHAPE], theta[theta::SCALE].ln());
        p.beta[..k].copy_from_slice(&theta[theta::BETA..theta::BETA + k]);
        p.gamma[..ns].copy_from_slice(&theta[theta::BETA + k..theta::BETA + k + ns]);
        Ok((p, theta[theta::BETA + k + ns], theta[theta::BETA + k + ns + 1]))
    }
}

impl Simulator for LifetimeChain {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        let (p, eta, v) = self.unpack(theta)?;
        let (force, sigma) = if v > 0.0 {
            let state = ImpactLoad::on_wall(&self.model.sphere, &self.model.wall, eta, self.model.domain).at_velocity(v)?;
            (state.force, self.model.ln_impact_stress(eta, v)?.exp())
        } else {
            (0.0, 0.0)
        };
        let mut y = vec![force, sigma];
        y.extend(self.model.breakage(&p, None, eta, v, &self.counts)?);
        check_outputs("lifetime chain", &self.outputs, theta, &y)?;
        Ok(y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{ContactStress, Hertz, OuterLimit};

    fn e() -> Elastic {
        Elastic::new(112e9, 0.25).unwrap()
    }
    fn steel() -> Elastic {
        Elastic::new(210e9, 0.3).unwrap()
    }

    #[test]
    fn contact_curvature_power_laws_match_direct_hertz() {
        // Crush: σ̄ at a force with R_c against R (line average to 2a): exponent −2/3.
        let (r, c, f) = (0.45e-3, 0.7f64, 120.0);
        let s = |rc: f64| ContactStress::new(Hertz::sphere_on_flat(&e(), &steel(), rc), AveragingDomain::default(), rc).at_force(f).unwrap().mean_tensile;
        assert!((s(c * r) / s(r) - c.powf(-2.0 / 3.0)).abs() < 1e-12);
        // Impact of the same mass with R_c against R: exponent −3/5 (κ = 0.9 of the crush's).
        let sphere = Sphere { diameter: 2.0 * r, density: 3060.0, elastic: e() };
        let imp = |rc: f64| {
            let i = Impact::sphere_on_wall(&sphere, &steel(), rc, 0.1);
            ContactStress::new(i.hertz, AveragingDomain::default(), r).at_force(i.max_force(5.0)).unwrap().mean_tensile
        };
        assert!((imp(c * r) / imp(r) - c.powf(-0.6)).abs() < 1e-12);
    }

    #[test]
    fn sphere_impact_stress_does_not_depend_on_diameter() {
        for outer in [OuterLimit::ContactMultiple, OuterLimit::ParticleRadius] {
            let domain = AveragingDomain { outer, ..AveragingDomain::default() };
            let sig = |d: f64| ImpactLoad::on_wall(&Sphere { diameter: d, density: 3600.0, elastic: e() }, &steel(), 0.1, domain).at_velocity(5.0).unwrap().mean_tensile;
            assert!((sig(0.6e-3) / sig(1.2e-3) - 1.0).abs() < 1e-12, "{outer:?}");
        }
    }

    /// The reference sphere of the one-particle model.
    fn sphere() -> Sphere {
        Sphere { diameter: 0.9e-3, density: 3060.0, elastic: e() }
    }

    /// A model without effects fitted to 20 strengths, predicting for one particle.
    fn one_particle_model(domain: AveragingDomain) -> LifetimeModel {
        let fit = crate::strength::fit::StrengthFit::new(
            &crate::strength::fit::Sample { source: "x".into(), strength: (1..=20).map(|i| 7e8 + 1e7 * i as f64).collect(), particles: true, ..Default::default() },
            &[],
            5.0,
            "x",
        )
        .unwrap();
        let pop = Population { source: "declared".into(), particles: vec![crate::strength::population::Particle { diameter_m: 0.9e-3, roundness: None, sphericity: None, temperature_c: None }], sampled: false, ..Population::default() };
        LifetimeModel::new("x", "X", sphere(), steel(), domain, fit, pop).unwrap()
    }

    #[test]
    fn a_scaled_modulus_moves_the_impact_stress_as_the_direct_hertz_impact() {
        let sphere = sphere();
        for outer in [OuterLimit::ContactMultiple, OuterLimit::ParticleRadius] {
            let domain = AveragingDomain { outer, ..AveragingDomain::default() };
            let m = one_particle_model(domain);
            for f in [0.4, 0.75, 1.3] {
                let soft = Sphere { elastic: Elastic::new(112e9 * f, 0.25).unwrap(), ..sphere };
                let direct = ImpactLoad::on_wall(&soft, &steel(), 0.1, domain).at_velocity(5.0).unwrap().mean_tensile.ln();
                let got = m.ln_impact_stress_with_modulus(0.1, 5.0, f).unwrap();
                assert!((got - direct).abs() < 1e-12, "{outer:?} f = {f}: {got} vs {direct}");
            }
            // A softer particle meets a lower stress.
            assert!(m.ln_impact_stress_with_modulus(0.1, 5.0, 0.5).unwrap() < m.ln_impact_stress(0.1, 5.0).unwrap());
        }
    }

    #[test]
    fn fast_path_is_the_contact_chain() {
        let sphere = sphere();
        let m = one_particle_model(AveragingDomain::default());
        for (eta, v) in [(0.1, 5.0), (0.37, 0.3), (1.0, 45.0)] {
            let direct = ImpactLoad::on_wall(&sphere, &steel(), eta, AveragingDomain::default()).at_velocity(v).unwrap().mean_tensile.ln();
            assert!((m.ln_impact_stress(eta, v).unwrap() - direct).abs() < 1e-12);
        }
    }
}
