//! Crush tests as candidate experiments: n more particles of one material, optionally from a
//! sieve fraction (a diameter range), each crushed to break with its diameter, roundness and
//! sphericity measured.
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
//! Not yet: tests without the shape measurement (the likelihood would mix over the population's
//! roundness and sphericity), tests at another temperature, and a refit of the strength model on
//! the pooled data as the fallback when reweighting collapses (the reserve of prior samples is
//! the fallback today).

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::preposterior::Experiment;
use super::state::State;
use crate::error::{Error, Result};
use crate::strength::{Effect, Term};
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
    /// Per sample: m.
    shape: Vec<f64>,
    /// Per sample and eligible row: ln σ_θ (K × rows).
    ln_scale: Vec<f64>,
}

impl CrushTest {
    /// The test on `state`'s samples.
    pub fn new(state: &State, material: usize, particles: usize, diameter: Option<(f64, f64)>) -> Result<CrushTest> {
        let bad = |rule: String| Err(Error::numerical("crush test", rule));
        if material > 1 || particles == 0 {
            return bad(format!("material {material}, {particles} particles: needs at least one particle"));
        }
        let sample = &state.forms[0].setup.materials[material].sample;
        let n_rows = sample.strength.len();
        let diameters: Vec<f64> = sample.covariates.iter().find(|(n, _)| n == Effect::Size.covariate()).map(|(_, c)| c.iter().map(|v| v.unwrap_or(f64::NAN)).collect()).unwrap_or_else(|| vec![f64::NAN; n_rows]);
        let rows: Vec<usize> = (0..n_rows).filter(|&r| diameter.is_none_or(|(lo, hi)| diameters[r] >= lo && diameters[r] <= hi)).collect();
        if rows.is_empty() {
            return bad(format!("no crushed particle of the material lies in the diameter range {diameter:?} m"));
        }
        let mut shape = Vec::with_capacity(state.samples.len());
        let mut ln_scale = Vec::with_capacity(state.samples.len() * rows.len());
        for s in &state.samples {
            let st = &state.forms[s.form].setup;
            let (p, _) = st.params(material, &s.x, Mode::Joint);
            let fit = &st.materials[material].model.fit;
            if fit.terms.iter().any(|(_, t)| matches!(t, Term::Damage { .. })) {
                return bad("a strength model with the damage effect has no crush-test likelihood here yet".into());
            }
            let columns: Vec<&Vec<f64>> = fit.terms.iter().filter_map(|(_, t)| if let Term::Linear(z) = t { Some(z) } else { None }).collect();
            shape.push(p.shape);
            for &r in &rows {
                ln_scale.push(p.mu + columns.iter().enumerate().map(|(l, z)| p.beta[l] * z[r]).sum::<f64>());
            }
        }
        Ok(CrushTest { material, particles, diameter, rows, shape, ln_scale })
    }

    /// Number of rows new particles are drawn from.
    pub fn eligible(&self) -> usize {
        self.rows.len()
    }
}

impl Experiment for CrushTest {
    /// (eligible-row index, ln σ̄ at break) per particle.
    type Data = Vec<(usize, f64)>;

    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> Self::Data {
        let r = self.rows.len();
        let m = self.shape[truth];
        (0..self.particles)
            .map(|_| {
                let i = rng.random_range(0..r);
                // Weibull by inversion: ln s = ln σ_θ + ln(−ln U)/m.
                let u: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
                (i, self.ln_scale[truth * r + i] + (-u.ln()).ln() / m)
            })
            .collect()
    }

    fn loglik(&self, data: &Self::Data, k: usize) -> f64 {
        let r = self.rows.len();
        let m = self.shape[k];
        let row = &self.ln_scale[k * r..(k + 1) * r];
        data.iter()
            .map(|&(i, ln_s)| {
                let z = m * (ln_s - row[i]);
                m.ln() + z - z.exp()
            })
            .sum()
    }
}
