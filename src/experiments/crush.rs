//! Crush tests as candidate experiments: n more particles of one material, optionally from a
//! sieve fraction (a diameter range) and at a temperature, each crushed to break with or
//! without its diameter, roundness and sphericity measured.
//!
//! The new particles are drawn from the material's crush sample (its covariate rows, resampled
//! with replacement; only the rows inside the diameter range when one is given). Under sample k
//! the strength σ̄ of a particle with covariate row r is Weibull with modulus m_k and scale
//! ln σ_θ,r(k) = μ_k + Σ_l β_kl z_lr — the strength model of the sample's strength model M_k
//! with its joint draw (the linear columns z of the model's effects, as fitted). The likelihood
//! of the strengths s_i at rows r_i is
//! ln p(s | k) = Σ_i [ln m_k + m_k (ln s_i − ln σ_θ,r_i(k)) − exp(m_k (ln s_i − ln σ_θ,r_i(k)))]
//! (the density of ln s; the Jacobian is the same for every k).
//!
//! # Without the shape measurement
//!
//! A laboratory may crush particles without measuring each one's roundness and sphericity (only
//! the sieve fraction is then known). The strength of such a particle is a mixture over the
//! population it is drawn from — the eligible rows r = 1…R —
//! ln p(s | k) = ln[(1/R) Σ_r f(ln s; m_k, ln σ_θ,r(k))], with f the density of ln s above. Under a
//! strength model without covariate effects every row has the same scale and the two tests carry
//! the same information; under a model with shape effects the measured test carries more, and the
//! difference is what the measurement is worth. For speed the mixture's log density is tabulated
//! per sample, with its slope, on [`GRID`] points over [min_r ln σ_θ,r − 14/m,
//! max_r ln σ_θ,r + 3/m] (the 10⁻⁶ and 1 − e^(−e³) ≈ 1 − 2·10⁻⁹ quantiles of the extreme rows)
//! and interpolated by cubic Hermite ([`crate::stats::hermite`]); outside that range the sum is
//! evaluated exactly. The error per particle is below 10⁻⁵ for moduli 4–12 and a spread of
//! scales of ±0.4 (unit test).
//!
//! # At a temperature
//!
//! A test at temperature T gives every new particle the temperature covariate T: under a
//! strength model with the temperature effect, z = (T − T̄)/1000 °C (T̄ the mean temperature
//! of the fitted data); a model without it says strength does not depend on T. The main study's
//! models can only carry strength between the temperatures its crush data cover, so a T outside
//! them is refused: extrapolating in temperature needs a temperature model of the parameters
//! (phases, softening), not a crush-test likelihood.
//!
//! # At a force limit
//!
//! A rig may stop at a force limit F_lim (`force_limit_n`): a particle that has not broken by
//! then is recorded as not broken by F_lim, and its strength as above σ̄_lim,r — the σ̄ of a
//! particle of row r's diameter at F_lim ([`crate::strength::crush_contact`], the same reduction
//! as the crush data's). Each simulated particle is drawn as above; one whose σ̄ exceeds its row's
//! σ̄_lim,r is recorded at σ̄_lim,r, not broken (type I censoring at the rig's limit). Its term
//! of the likelihood is the survival function, ln S = −exp(m_k (ln σ̄_lim,r − ln σ_θ,r(k)));
//! without the shape measurement, the mixture's over the rows' scales at the particle's own
//! σ̄_lim (known as a broken particle's σ̄ is), ln[(1/R) Σ_r' S(σ̄_lim; σ_θ,r'(k))]. A limit well
//! above every break changes nothing; a limit near the median force leaves about half the
//! particles as lower bounds, and the test carries less. The naming loop's verdict pools them as right-censored rows, censored at the
//! limit in its bootstrap redraws as the test censors them.
//!
//! # The naming loop's verdict
//!
//! Optionally (`naming_draws`), each of the first outer draws also runs the discrepancy
//! workflow's naming loop ([`crate::discrepancy::workflow::names`], with the main study's
//! naming settings) on the pooled data — the material's crush sample and the simulated
//! particles, each with its row's diameter, roundness and sphericity — and scores 1 when it
//! names exactly the effects of the truth's strength model (no effect for the deliverable's
//! model, roundness and sphericity for the shape model, the diagnosed effects for the diagnosed
//! one), else 0 (also when the loop fails on the data). This is the question "after these tests,
//! would the workflow that chose the main study's model find the true one?", asked of the same
//! simulated data as the Bayesian reweighting, so the two decision rules can be compared draw by
//! draw. It needs the shape measured (the loop diagnoses roundness and sphericity per particle).
//!
//! Where reweighting collapses, resample-move ([`super::smc`]) moves the samples among the main
//! study's joint strength draws with this likelihood at any sample ([`super::smc::Movable`]);
//! it does not refit the strength model on the pooled data.

use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::preposterior::{Experiment, Score};
use super::smc::Movable;
use super::state::{State, StateSample};
use crate::contact::{ContactOptions, Elastic};
use crate::error::{Error, Result};
use crate::strength::regress::{draw_particles, ln_density_of_log};
use crate::strength::{Effect, NamingSettings, Sample, Term};
use crate::uq::setup::Mode;

/// A crush test with every sample's Weibull parameters at every eligible row.
#[derive(Debug, Clone, PartialEq)]
pub struct CrushTest {
    /// Material (0 candidate, 1 reference).
    pub material: usize,
    /// Particles crushed.
    pub particles: usize,
    /// Diameter range (m) of the sieve fraction, or every diameter.
    pub diameter: Option<(f64, f64)>,
    /// Rows of the crush sample the new particles are drawn from.
    rows: Vec<usize>,
    /// Test temperature (°C), or the temperatures of the crush data.
    temperature_c: Option<f64>,
    /// The rig's force limit (N) and, per eligible row, ln σ̄ at it (module docs); None: every
    /// particle is crushed to break.
    limit: Option<(f64, Vec<f64>)>,
    /// Per sample: m.
    shape: Vec<f64>,
    /// Per sample and eligible row: ln σ_θ (K × rows).
    ln_scale: Vec<f64>,
    /// Without the shape measurement: per sample, the mixture's log-density table (None when
    /// every row has the same scale). None: the shape is measured.
    mixture: Option<Vec<Option<MixtureTable>>>,
    /// The naming loop's verdict on the pooled data (module docs), when asked for.
    naming: Option<NamingCheck>,
}

/// What the naming loop's verdict needs: its settings, the material's crush sample, the effects
/// of every strength model and each prior sample's strength model.
#[derive(Debug, Clone, PartialEq)]
struct NamingCheck {
    settings: NamingSettings,
    sample: Sample,
    /// The test temperature that replaces the rows' temperatures, if any.
    temperature_c: Option<f64>,
    /// Per strength model, its effects for the material.
    effects: Vec<Vec<Effect>>,
    /// Per prior sample, its strength model.
    forms: Vec<usize>,
}

/// How a crush test is run.
#[derive(Debug, Clone, PartialEq)]
pub struct CrushOptions {
    /// Diameter range (m) of the sieve fraction, or every diameter.
    pub diameter: Option<(f64, f64)>,
    /// Each particle's roundness and sphericity measured (and its diameter).
    pub shape_measured: bool,
    /// Test temperature (°C), or the temperatures of the crush data.
    pub temperature_c: Option<f64>,
    /// Run the discrepancy naming loop on the pooled data with these settings (the main
    /// study's), for the naming loop's verdict; None: not.
    pub naming: Option<NamingSettings>,
    /// The rig's force limit, if any (module docs).
    pub force_limit: Option<ForceLimit>,
}

impl Default for CrushOptions {
    fn default() -> Self {
        CrushOptions { diameter: None, shape_measured: true, temperature_c: None, naming: None, force_limit: None }
    }
}

/// A rig's force limit and what turns it into each particle's σ̄: the material's elastic
/// constants and the contact options (platen, averaging domain) of the main study.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceLimit {
    /// The force (N) at which the rig stops.
    pub force_n: f64,
    /// The particle's elastic constants.
    pub elastic: Elastic,
    /// The platen and the averaging domain of σ̄.
    pub contact: ContactOptions,
}

/// One particle of a simulated crush test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crushed {
    /// Its eligible row (an index into the test's rows).
    pub row: usize,
    /// ln σ̄ (ln Pa): at break, or at the rig's limit when it did not break.
    pub ln_sigma: f64,
    /// Whether it broke (false: not broken by the rig's limit, right-censored).
    pub broke: bool,
}

/// Points of a mixture's log-density table.
pub const GRID: usize = 257;

/// ln f(y; m, ℓ) of y = ln s for Weibull strength s with modulus m and scale e^ℓ
/// ([`ln_density_of_log`]).
fn ln_gumbel_min(y: f64, m: f64, l: f64) -> f64 {
    ln_density_of_log(y, l, 1.0 / m)
}

/// ln[(1/R) Σ_r f(y; m, ℓ_r)] and its derivative in y, evaluated exactly (log-sum-exp; the
/// derivative is Σ_r w_r m (1 − e^(z_r)) with w_r each row's share of the density).
fn ln_mixture(y: f64, m: f64, ls: &[f64]) -> (f64, f64) {
    let terms: Vec<f64> = ls.iter().map(|&l| ln_gumbel_min(y, m, l)).collect();
    let top = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !top.is_finite() {
        return (top, 0.0);
    }
    let (mut sum, mut slope) = (0.0, 0.0);
    for (t, &l) in terms.iter().zip(ls) {
        let w = (t - top).exp();
        sum += w;
        slope += w * m * (1.0 - (m * (y - l)).exp());
    }
    (top + (sum / ls.len() as f64).ln(), slope / sum)
}

/// Whether every row has the same scale (to round-off): the mixture is then one density.
fn one_scale(ls: &[f64]) -> bool {
    let lmin = ls.iter().copied().fold(f64::INFINITY, f64::min);
    let lmax = ls.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    lmax - lmin <= 1e-12 * lmax.abs().max(1.0)
}

/// A mixture's log density tabulated on [`GRID`] points with its slopes (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct MixtureTable {
    lo: f64,
    step: f64,
    ln_density: Vec<f64>,
    slope: Vec<f64>,
}

impl MixtureTable {
    /// The table of modulus `m` and row scales `ls`; None when every row has the same scale
    /// (the mixture is then one density).
    pub fn new(m: f64, ls: &[f64]) -> Option<MixtureTable> {
        if one_scale(ls) {
            return None;
        }
        let lmin = ls.iter().copied().fold(f64::INFINITY, f64::min);
        let lmax = ls.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = (lmin - 14.0 / m, lmax + 3.0 / m);
        let step = (hi - lo) / (GRID - 1) as f64;
        let (ln_density, slope) = (0..GRID).map(|g| ln_mixture(lo + g as f64 * step, m, ls)).unzip();
        Some(MixtureTable { lo, step, ln_density, slope })
    }

    /// ln of the mixture's density at y: cubic Hermite inside the table, exact outside.
    pub fn ln_density(&self, y: f64, m: f64, ls: &[f64]) -> f64 {
        let t = (y - self.lo) / self.step;
        if t >= 0.0 && t <= (GRID - 1) as f64 {
            let j = (t.floor() as usize).min(GRID - 2);
            crate::stats::hermite(&self.ln_density, &self.slope, self.step, (j + 1, t - j as f64))
        } else {
            ln_mixture(y, m, ls).0
        }
    }
}

impl CrushTest {
    /// The test on `state`'s samples.
    pub fn new(state: &State, material: usize, particles: usize, options: &CrushOptions) -> Result<CrushTest> {
        let bad = |rule: String| Err(Error::numerical("crush test", rule));
        if material > 1 || particles == 0 {
            return bad(format!("material {material}, {particles} particles: needs at least one particle"));
        }
        if options.naming.is_some() && !options.shape_measured {
            return bad("the naming loop's verdict needs each particle's roundness and sphericity: set shape_measured = true or drop naming_draws".into());
        }
        let diameter = options.diameter;
        let sample = &state.forms[0].setup.materials[material].sample;
        let n_rows = sample.strength.len();
        let column = |effect: Effect| -> Vec<f64> { sample.covariates.iter().find(|(n, _)| *n == effect.covariate()).map(|(_, c)| c.iter().map(|v| v.unwrap_or(f64::NAN)).collect()).unwrap_or_else(|| vec![f64::NAN; n_rows]) };
        let diameters = column(Effect::Size);
        let rows: Vec<usize> = (0..n_rows).filter(|&r| diameter.is_none_or(|(lo, hi)| diameters[r] >= lo && diameters[r] <= hi)).collect();
        if rows.is_empty() {
            return bad(format!("no crushed particle of the material lies in the diameter range {diameter:?} m"));
        }
        if let Some(t) = options.temperature_c {
            let temps: Vec<f64> = column(Effect::Temperature).into_iter().filter(|v| v.is_finite()).collect();
            let (lo, hi) = (temps.iter().copied().fold(f64::INFINITY, f64::min), temps.iter().copied().fold(f64::NEG_INFINITY, f64::max));
            if temps.is_empty() {
                return bad(format!("temperature_c = {t} °C: the material's crush data record no temperature_c"));
            }
            if !(t >= lo - 1e-9 && t <= hi + 1e-9) {
                return bad(format!("temperature_c = {t} °C lies outside the temperatures of the material's crush data ({lo}–{hi} °C): the main study's strength models cannot carry strength there (that needs crush data at that temperature, or a temperature model of the parameters)"));
            }
        }
        let mut shape = Vec::with_capacity(state.samples.len());
        let mut ln_scale = Vec::with_capacity(state.samples.len() * rows.len());
        for s in &state.samples {
            let (m, ls) = scales_at(state, material, &rows, options.temperature_c, s)?;
            shape.push(m);
            ln_scale.extend(ls);
        }
        let r = rows.len();
        let naming = options.naming.as_ref().map(|settings| NamingCheck {
            settings: settings.clone(),
            sample: sample.clone(),
            temperature_c: options.temperature_c,
            effects: state.forms.iter().map(|f| f.setup.materials[material].model.fit.model.effects.clone()).collect(),
            forms: state.samples.iter().map(|s| s.form).collect(),
        });
        let mixture = (!options.shape_measured).then(|| (0..shape.len()).into_par_iter().map(|k| MixtureTable::new(shape[k], &ln_scale[k * r..(k + 1) * r])).collect());
        let limit = match &options.force_limit {
            None => None,
            Some(f) => {
                if !(f.force_n.is_finite() && f.force_n > 0.0) {
                    return bad(format!("force limit {} N: needs a finite force > 0", f.force_n));
                }
                let ln_limit = rows
                    .iter()
                    .map(|&i| {
                        let s = crate::strength::crush_contact(&f.elastic, &f.contact, diameters[i]).at_force(f.force_n)?.mean_tensile;
                        if s.is_finite() && s > 0.0 { Ok(s.ln()) } else { Err(Error::numerical("crush test", format!("σ̄ at the force limit {} N is {s} Pa for a particle of diameter {} m", f.force_n, diameters[i]))) }
                    })
                    .collect::<Result<Vec<f64>>>()?;
                Some((f.force_n, ln_limit))
            }
        };
        Ok(CrushTest { material, particles, diameter, rows, temperature_c: options.temperature_c, limit, shape, ln_scale, mixture, naming })
    }

    /// Number of rows new particles are drawn from.
    pub fn eligible(&self) -> usize {
        self.rows.len()
    }

    /// The rig's force limit (N), if any.
    pub fn force_limit_n(&self) -> Option<f64> {
        self.limit.as_ref().map(|l| l.0)
    }

    /// The expected share of particles not broken by the rig's limit under the samples weighted
    /// by `weights` (one per sample): Σ_k w_k (1/R) Σ_r S_k,r(σ̄_lim,r) / Σ_k w_k. None without a
    /// limit.
    pub fn expected_unbroken(&self, weights: &[f64]) -> Option<f64> {
        let (_, ln_limit) = self.limit.as_ref()?;
        let r = self.rows.len();
        let (mut sum, mut total) = (0.0, 0.0);
        for (k, &w) in weights.iter().enumerate().take(self.shape.len()) {
            let row = &self.ln_scale[k * r..(k + 1) * r];
            sum += w * ln_limit.iter().zip(row).map(|(&l, &s)| ln_survival(l, self.shape[k], s).exp()).sum::<f64>() / r as f64;
            total += w;
        }
        Some(sum / total)
    }
}

/// ln S(y; m, ℓ) = −e^(m (y − ℓ)) of y = ln s for Weibull strength s with modulus m and scale e^ℓ.
fn ln_survival(y: f64, m: f64, l: f64) -> f64 {
    -(m * (y - l)).exp()
}

/// ln[(1/R) Σ_r S(y; m, ℓ_r)]: the survival at y of a particle drawn from the rows
/// (log-sum-exp).
fn ln_mixture_survival(y: f64, m: f64, ls: &[f64]) -> f64 {
    let terms: Vec<f64> = ls.iter().map(|&l| ln_survival(y, m, l)).collect();
    let top = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !top.is_finite() {
        return top;
    }
    top + (terms.iter().map(|t| (t - top).exp()).sum::<f64>() / ls.len() as f64).ln()
}

/// Sample `s`'s Weibull modulus and ln σ_θ at each of `rows` of `material`'s crush sample (the
/// temperature column at `temperature_c` when given).
fn scales_at(state: &State, material: usize, rows: &[usize], temperature_c: Option<f64>, s: &StateSample) -> Result<(f64, Vec<f64>)> {
    let st = &state.forms[s.form].setup;
    let (p, _) = st.params(material, &s.x, Mode::Joint);
    let fit = &st.materials[material].model.fit;
    if fit.terms.iter().any(|(_, t)| matches!(t, Term::Damage { .. })) {
        return Err(Error::numerical("crush test", "a strength model with the damage effect has no crush-test likelihood here yet"));
    }
    if !fit.model.scale_columns.is_empty() {
        return Err(Error::numerical("crush test", "a strength model with a modulus per level has no crush-test likelihood here yet"));
    }
    // Every regression column in the order of β; the temperature column at the test's T.
    let columns: Vec<(Effect, &Vec<f64>)> = fit.beta_columns().into_iter().map(|c| c.effect).zip(&fit.model.columns).collect();
    let scales = rows
        .iter()
        .map(|&r| {
            let z = |l: usize, (e, col): &(Effect, &Vec<f64>)| match (e, temperature_c) {
                (Effect::Temperature, Some(t)) => e.z(t, fit.references[l]),
                _ => col[r],
            };
            p.mu + columns.iter().enumerate().map(|(l, c)| p.beta[l] * z(l, c)).sum::<f64>()
        })
        .collect();
    Ok((p.shape, scales))
}

/// ln p(data | m, ℓ) of the crushed particles `data` with modulus `m` and eligible rows' scales
/// `row` (module docs): a broken particle's density, a particle not broken by the rig's limit
/// its survival at the limit; `mixture`: the shape is not measured, with the mixture's table
/// when tabulated.
fn loglik_of(data: &[Crushed], m: f64, row: &[f64], mixture: Option<Option<&MixtureTable>>) -> f64 {
    let broke = data.iter().filter(|c| c.broke);
    let unbroken = data.iter().filter(|c| !c.broke);
    let censored: f64 = match mixture {
        None => unbroken.map(|c| ln_survival(c.ln_sigma, m, row[c.row])).sum(),
        Some(_) => unbroken.map(|c| ln_mixture_survival(c.ln_sigma, m, row)).sum(),
    };
    censored
        + match mixture {
            None => broke.map(|c| ln_gumbel_min(c.ln_sigma, m, row[c.row])).sum::<f64>(),
            // Shape not measured, every row at the same scale: one density.
            Some(None) if one_scale(row) => broke.map(|c| ln_gumbel_min(c.ln_sigma, m, row[0])).sum(),
            Some(None) => broke.map(|c| ln_mixture(c.ln_sigma, m, row).0).sum(),
            Some(Some(table)) => broke.map(|c| table.ln_density(c.ln_sigma, m, row)).sum(),
        }
}

impl Movable<State> for CrushTest {
    fn loglik_at(&self, state: &State, data: &Self::Data, s: &StateSample) -> f64 {
        match scales_at(state, self.material, &self.rows, self.temperature_c, s) {
            Ok((m, row)) => loglik_of(data, m, &row, self.mixture.as_ref().map(|_| None)),
            Err(_) => f64::NEG_INFINITY,
        }
    }
}

impl Experiment for CrushTest {
    /// The crushed particles: each one's row, ln σ̄ and whether it broke.
    type Data = Vec<Crushed>;

    /// The particles drawn as without a limit (the same random numbers), then censored at the
    /// rig's limit.
    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> Self::Data {
        let r = self.rows.len();
        let drawn = draw_particles(&self.ln_scale[truth * r..(truth + 1) * r], self.shape[truth], self.particles, rng);
        drawn
            .into_iter()
            .map(|(row, y)| match &self.limit {
                Some((_, l)) if y > l[row] => Crushed { row, ln_sigma: l[row], broke: false },
                _ => Crushed { row, ln_sigma: y, broke: true },
            })
            .collect()
    }

    fn loglik(&self, data: &Self::Data, k: usize) -> f64 {
        let r = self.rows.len();
        loglik_of(data, self.shape[k], &self.ln_scale[k * r..(k + 1) * r], self.mixture.as_ref().map(|t| t[k].as_ref()))
    }

    /// 1 when the naming loop on the pooled data names exactly the truth's effects (module docs).
    fn score(&self, data: &Self::Data, truth: usize, draw: usize) -> Option<Score> {
        let n = self.naming.as_ref()?;
        let mut pooled = n.sample.clone();
        pooled.source = format!("{} + {} simulated particles", n.sample.source, data.len());
        // Each new particle with the σ̄ at the rig's limit its redraws are censored at (∞: none).
        let limit = |c: &Crushed| self.limit.as_ref().map_or(f64::INFINITY, |l| l.1[c.row].exp());
        pooled.strength.append_tested(data.iter().map(|c| (c.ln_sigma.exp(), limit(c), c.broke)));
        for ((name, column), (_, base)) in pooled.covariates.iter_mut().zip(&n.sample.covariates) {
            let at_test = (*name == Effect::Temperature.covariate()).then_some(n.temperature_c).flatten();
            column.extend(data.iter().map(|c| at_test.or(base[self.rows[c.row]])));
        }
        let settings = NamingSettings { seed: n.settings.seed.wrapping_add(draw as u64 + 1), ..n.settings.clone() };
        // A loop that fails on the data scores 0 and is counted as a failure: it names no
        // model, not the model without effects.
        let Ok(named) = crate::discrepancy::workflow::names(&pooled, &settings) else {
            return Some(Score { value: 0.0, failed: true });
        };
        let truth_effects = &n.effects[n.forms[truth]];
        Some(Score { value: if named.len() == truth_effects.len() && truth_effects.iter().all(|e| named.contains(e)) { 1.0 } else { 0.0 }, failed: false })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A crush test of one sample with no effects whose naming loop runs on `sample` plus the
    /// simulated strengths.
    fn naming_test(sample: Sample) -> CrushTest {
        let settings = NamingSettings { bootstrap: 49, permutations: 99, ..NamingSettings::default() };
        let naming = NamingCheck { settings, sample, temperature_c: None, effects: vec![vec![]], forms: vec![0] };
        CrushTest { material: 0, particles: 2, diameter: None, rows: vec![0, 1], temperature_c: None, limit: None, shape: vec![8.0], ln_scale: vec![18.4; 2], mixture: None, naming: Some(naming) }
    }

    #[test]
    fn a_naming_loop_that_fails_scores_zero_and_is_counted_as_a_failure() {
        // Five particles are too few for the loop. The truth's model has no effects, which a
        // failure read as "named nothing" would match (it scored 1 before).
        let few = Sample { source: "few".into(), strength: crate::obs::Observations::exact(vec![1.0e8, 1.2e8, 0.9e8, 1.1e8, 0.95e8]), particles: true, ..Sample::default() };
        let two = vec![Crushed { row: 0, ln_sigma: 18.4, broke: true }, Crushed { row: 1, ln_sigma: 18.5, broke: true }];
        assert_eq!(naming_test(few).score(&two, 0, 0), Some(Score { value: 0.0, failed: true }));
        // Forty Weibull-like strengths without covariates: the loop runs, names nothing, and
        // that is the truth's model.
        let many = Sample { source: "many".into(), strength: (0..40).map(|i| 1e8 * (-(1.0 - (i as f64 + 0.5) / 40.0).ln()).powf(1.0 / 8.0)).collect(), particles: true, ..Sample::default() };
        assert_eq!(naming_test(many).score(&two, 0, 0), Some(Score { value: 1.0, failed: false }));
    }

    #[test]
    fn the_tabulated_mixture_matches_the_exact_sum() {
        // 120 rows spread over ±0.4 in ln σ_θ (wider than the shipped data's shape effects),
        // moduli around the shipped ones.
        for m in [4.0, 8.0, 12.0] {
            let ls: Vec<f64> = (0..120).map(|r| 18.4 + 0.8 * ((r * 37 % 120) as f64 / 119.0 - 0.5)).collect();
            let t = MixtureTable::new(m, &ls).unwrap();
            let mut worst: f64 = 0.0;
            for g in 0..20_000 {
                let y = 18.4 - 3.0 + 4.0 * g as f64 / 20_000.0;
                worst = worst.max((t.ln_density(y, m, &ls) - ln_mixture(y, m, &ls).0).abs());
            }
            assert!(worst < 1e-5, "m = {m}: worst interpolation error {worst}");
            // Exact outside the table.
            for y in [t.lo - 0.1, t.lo + t.step * GRID as f64 + 0.1] {
                assert_eq!(t.ln_density(y, m, &ls), ln_mixture(y, m, &ls).0);
            }
        }
        // One scale: no table, and the mixture is that density.
        assert!(MixtureTable::new(8.0, &[18.0; 5]).is_none());
        assert!((ln_mixture(18.1, 8.0, &[18.0; 5]).0 - ln_gumbel_min(18.1, 8.0, 18.0)).abs() < 1e-12);
    }
}
