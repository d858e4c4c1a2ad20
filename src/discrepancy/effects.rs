//! The library of candidate effects (issue 7, step 2 "Name").
//!
//! The deliverable's lifetime model reduces every crush test to the average Hertzian tensile
//! stress at break σ̄ with the contact radius of curvature R = d/2 and one Weibull law for all
//! particles. Each candidate is a physical extension of that model with one extra parameter,
//! acting on the Weibull scale of particle i as `ln σ_i = μ + β z_i` (+ the other effects
//! already named); the modulus is shared. Their equations and covariate signatures:
//!
//! | candidate | covariate | equation | parameter reported |
//! |---|---|---|---|
//! | `roundness` (contact curvature) | `roundness` r | R_c = r^q R. Crush: F ∝ R_c² p0³, so the σ̄ reduced with R is σ̄_true (R_c/R)^(2/3): z = ln r, β = 2q/3 | q = 3β/2 (Wadell: q = 1) |
//! | `size` (weakest link) | `diameter_m` d | σ_θ(d) = σ_θ (d/d̃)^(−α), d̃ the median diameter: z = ln(d/d̃), β = −α | α; volume flaws α = 3/m, surface flaws α = 2/m |
//! | `temperature` (softening) | `temperature_c` T | ln σ_θ(T) = ln σ_θ + β (T − T̄)/1000 °C; strength and stiffness both shift the σ̄ reduced at break (σ̄ ∝ (F E*²/R²)^(1/3)), above ≈ 900 °C through the amorphous phase (deliverable §2) | strength ratio per 100 °C, e^(β/10) |
//! | `sphericity` (effective radius) | `sphericity` s | R_c = s^p R, as roundness: z = ln s, β = 2p/3 | p = 3β/2 |
//! | `damage` (Tavares–King) | `impacts` n (prior impacts) | each prior impact at the energy ratio x = E_k/E_m damages the particle, E_m,n = E_m,0 Π(1 − D_j) ([`crate::uq::damage::tk_damage`], γ fixed); since the Hertz fracture energy scales as σ̄⁵, ln σ_i gets the offset (1/5) ln(x/x_n) | x, fitted by profile likelihood |
//!
//! Contact-geometry effects (roundness, sphericity) also change the impact: with R_c the peak
//! pressure of a Hertz impact scales as R_c^(−3/5) at a fixed particle mass, so the lifetime
//! chain's impact stress of particle i is multiplied by (R_c/R)^(−3/5) = e^(−0.9 β z_i);
//! strength effects (size, temperature, damage) change the scale only ([`Candidate::impact_exponent`]).
//!
//! A candidate whose covariate is missing (no column, empty cells, constant over the sample) is
//! skipped with the reason ([`Candidate::term`]), not an error.

use serde::{Deserialize, Serialize};

use super::regress::{Design, RegFit, fit};
use crate::error::{Error, Result};
use crate::uq::damage::tk_ratio_path;

/// A candidate effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Candidate {
    /// Roundness sets the contact radius of curvature.
    Roundness,
    /// Weakest-link size effect on strength.
    Size,
    /// Temperature softening of strength and stiffness.
    Temperature,
    /// Sphericity sets an effective contact radius.
    Sphericity,
    /// Tavares–King damage from prior impacts.
    Damage,
}

/// Every candidate, in the library's order.
pub const ALL: [Candidate; 5] = [Candidate::Roundness, Candidate::Size, Candidate::Temperature, Candidate::Sphericity, Candidate::Damage];

/// Covariate columns of a crush sample, by name; `None` for an empty cell.
pub type Covariates = [(String, Vec<Option<f64>>)];

/// How a candidate enters the regression.
#[derive(Debug, Clone, PartialEq)]
pub enum Term {
    /// A linear column z.
    Linear(Vec<f64>),
    /// The Tavares–King offset: prior impact counts and γ.
    Damage {
        /// Prior impacts per particle.
        impacts: Vec<u64>,
        /// Tavares–King γ.
        gamma: f64,
    },
}

impl Candidate {
    /// Key used in studies, tables and verdict.json.
    pub fn name(self) -> &'static str {
        match self {
            Candidate::Roundness => "roundness",
            Candidate::Size => "size",
            Candidate::Temperature => "temperature",
            Candidate::Sphericity => "sphericity",
            Candidate::Damage => "damage",
        }
    }

    /// Human label.
    pub fn label(self) -> &'static str {
        match self {
            Candidate::Roundness => "roundness / contact curvature",
            Candidate::Size => "size effect (weakest link)",
            Candidate::Temperature => "temperature softening",
            Candidate::Sphericity => "sphericity / effective radius",
            Candidate::Damage => "damage from prior impacts (Tavares–King)",
        }
    }

    /// The dataset column the candidate needs.
    pub fn covariate(self) -> &'static str {
        match self {
            Candidate::Roundness => "roundness",
            Candidate::Size => "diameter_m",
            Candidate::Temperature => "temperature_c",
            Candidate::Sphericity => "sphericity",
            Candidate::Damage => "impacts",
        }
    }

    /// Its equation, as written in verdict.json.
    pub fn equation(self) -> &'static str {
        match self {
            Candidate::Roundness => "R_c = roundness^q R; ln σ_θ,i = μ + (2q/3) ln roundness_i",
            Candidate::Size => "σ_θ(d) = σ_θ (d/d_median)^(−α); ln σ_θ,i = μ − α ln(d_i/d_median)",
            Candidate::Temperature => "ln σ_θ(T) = μ + β (T − T_mean)/1000 °C",
            Candidate::Sphericity => "R_c = sphericity^p R; ln σ_θ,i = μ + (2p/3) ln sphericity_i",
            Candidate::Damage => "E_m,n = E_m,0 Π(1 − D_j), D_j Tavares–King at ratio x; ln σ_θ,i = μ + (1/5) ln(x/x_n,i)",
        }
    }

    /// Exponent κ with which the effect also scales the impact stress: the lifetime hazard of
    /// particle i is (σ̄_impact · e^(−κ β z_i) / σ_θ)^m. κ = 0.9 for contact-geometry effects
    /// (impact p0 ∝ R_c^(−3/5) against the crush reduction's R_c^(−2/3)), κ = 1 for strength
    /// effects.
    pub fn impact_exponent(self) -> f64 {
        match self {
            Candidate::Roundness | Candidate::Sphericity => 0.9,
            _ => 1.0,
        }
    }

    /// The candidate's term for this sample, or the reason it cannot be fitted.
    pub fn term(self, covariates: &Covariates, gamma: f64) -> std::result::Result<Term, String> {
        let name = self.covariate();
        let Some((_, col)) = covariates.iter().find(|(n, _)| n == name).filter(|(_, c)| c.iter().any(|v| v.is_some())) else {
            return Err(format!("the dataset has no `{name}` values (no such column, or every cell empty)"));
        };
        let missing = col.iter().filter(|v| v.is_none()).count();
        if missing > 0 {
            return Err(format!("`{name}` is empty on {missing} of {} rows", col.len()));
        }
        let v: Vec<f64> = col.iter().map(|x| x.unwrap_or(f64::NAN)).collect();
        if v.iter().all(|x| *x == v[0]) {
            return Err(format!("`{name}` is the same on every row ({}): no contrast to fit", v[0]));
        }
        let positive = |what: &str| -> std::result::Result<(), String> {
            match v.iter().find(|x| x.is_nan() || **x <= 0.0) {
                Some(x) => Err(format!("`{name}` must be > 0 for {what} (got {x})")),
                None => Ok(()),
            }
        };
        match self {
            Candidate::Roundness | Candidate::Sphericity => {
                positive("a power law")?;
                Ok(Term::Linear(v.iter().map(|x| x.ln()).collect()))
            }
            Candidate::Size => {
                positive("a power law")?;
                let med = crate::stats::median(&v);
                Ok(Term::Linear(v.iter().map(|x| (x / med).ln()).collect()))
            }
            Candidate::Temperature => {
                let mean = v.iter().sum::<f64>() / v.len() as f64;
                Ok(Term::Linear(v.iter().map(|t| (t - mean) / 1000.0).collect()))
            }
            Candidate::Damage => {
                if let Some(x) = v.iter().find(|x| !(**x >= 0.0 && x.fract() == 0.0 && **x <= 1e6)) {
                    return Err(format!("`{name}` must be whole numbers in [0, 10⁶] (got {x})"));
                }
                Ok(Term::Damage { impacts: v.iter().map(|x| *x as u64).collect(), gamma })
            }
        }
    }

    /// The reported parameter: (symbol, value from β (or x for damage), meaning).
    pub fn parameter(self, beta: f64, shape: f64) -> (&'static str, f64, String) {
        match self {
            Candidate::Roundness => ("q", 1.5 * beta, format!("contact radius R_c = roundness^{:.2} R (Wadell: 1)", 1.5 * beta)),
            Candidate::Sphericity => ("p", 1.5 * beta, format!("contact radius R_c = sphericity^{:.2} R", 1.5 * beta)),
            Candidate::Size => {
                let a = -beta;
                let (vol, surf) = (3.0 / shape, 2.0 / shape);
                let kind = if a <= 0.0 {
                    "strength rises with size: not a weakest-link effect".to_string()
                } else if (a - vol).abs() <= (a - surf).abs() && a < 1.5 * vol {
                    format!("close to volume flaws (3/m = {vol:.3})")
                } else if a < 1.5 * vol {
                    format!("close to surface flaws (2/m = {surf:.3})")
                } else {
                    format!("stronger than weakest-link scaling (volume 3/m = {vol:.3}, surface 2/m = {surf:.3})")
                };
                ("alpha", a, format!("σ_θ ∝ d^(−α), α = {a:.3}: {kind}"))
            }
            Candidate::Temperature => {
                let r = (beta / 10.0).exp();
                ("strength_ratio_per_100c", r, format!("strength × {r:.3} per 100 °C"))
            }
            Candidate::Damage => ("x", beta, format!("prior impacts at {:.3} of the fracture energy", beta)),
        }
    }
}

/// ln(x0/x_n)/5 for a particle after n impacts at the initial ratio x0 (Tavares–King, γ): the
/// ln-strength change, since the Hertz fracture energy scales as the strength⁵. None if it
/// would have broken.
pub(crate) fn damage_offset(x0: f64, gamma: f64, n: u64) -> Option<f64> {
    let path = tk_ratio_path(x0, gamma, n)?;
    Some((path[0] - path[n as usize]) / 5.0)
}

/// A fitted model: the base Weibull plus zero or more effects.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelFit {
    /// The effects, in the order they were added.
    pub effects: Vec<Candidate>,
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
}

impl ModelFit {
    /// The regression design of the fitted model.
    pub fn design(&self) -> Design<'_> {
        Design { columns: &self.columns, offset: self.offset.as_deref() }
    }

    /// Number of parameters: μ, b, one per effect.
    pub fn parameters(&self) -> usize {
        2 + self.effects.len()
    }

    /// Weibull modulus.
    pub fn shape(&self) -> f64 {
        self.reg.shape()
    }

    /// Maximised log-likelihood.
    pub fn loglik(&self) -> f64 {
        self.reg.loglik
    }

    /// β of a linear effect (or the ratio x for damage), with its standard error (NaN for damage).
    pub fn coefficient(&self, c: Candidate) -> Option<(f64, f64)> {
        if c == Candidate::Damage {
            return self.damage_ratio.map(|x| (x, f64::NAN));
        }
        let j = self.effects.iter().filter(|e| **e != Candidate::Damage).position(|e| *e == c)?;
        Some((self.reg.beta[j], self.reg.beta_se[j]))
    }

    /// Parametric-bootstrap replicate `r` (its own ChaCha8 stream of `seed`): strengths drawn
    /// from this model at the sample's covariates, refitted with `terms` (the model's own terms
    /// or more). None if the refit fails.
    pub fn bootstrap_refit(&self, terms: &[(Candidate, Term)], seed: u64, r: usize) -> Option<(Vec<f64>, ModelFit)> {
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let xs = self.reg.sample(&self.design(), self.n, &mut rng);
        let refit = fit_model_near(&xs, terms, self.damage_ratio).ok()?;
        Some((xs, refit))
    }

    /// Σ_k κ_k β_k z_ik + damage offset: the part of particle i's ln-scale that also scales the
    /// impact stress in the lifetime hazard ([`Candidate::impact_exponent`]).
    pub fn impact_shift(&self, i: usize) -> f64 {
        let linear = self.effects.iter().filter(|e| **e != Candidate::Damage);
        linear.enumerate().map(|(j, c)| c.impact_exponent() * self.reg.beta[j] * self.columns[j][i]).sum::<f64>()
            + self.offset.as_ref().map_or(0.0, |o| o[i])
    }
}

/// Fits the base model plus `terms` to the strengths `x`.
pub fn fit_model(x: &[f64], terms: &[(Candidate, Term)]) -> Result<ModelFit> {
    fit_model_near(x, terms, None)
}

/// [`fit_model`] with a hint for the damage ratio (that of a fit to similar data, as in a
/// bootstrap refit): the profile search then starts near it, which is several times faster.
pub fn fit_model_near(x: &[f64], terms: &[(Candidate, Term)], hint: Option<f64>) -> Result<ModelFit> {
    let mut columns = Vec::new();
    let mut damage = None;
    let mut effects = Vec::new();
    for (c, t) in terms {
        effects.push(*c);
        match t {
            Term::Linear(z) => columns.push(z.clone()),
            Term::Damage { impacts, gamma } => damage = Some((impacts, *gamma)),
        }
    }
    // Linear effects first in `effects`' β order; damage (if any) is profiled.
    let Some((impacts, gamma)) = damage else {
        let reg = fit(x, &Design { columns: &columns, offset: None })?;
        return Ok(ModelFit { effects, reg, columns, offset: None, damage_ratio: None, n: x.len() });
    };
    let n_max = impacts.iter().copied().max().unwrap_or(0);
    // One Tavares–King trajectory per trial ratio serves every particle.
    let offsets = |lx: f64| -> Option<Vec<f64>> {
        let path = tk_ratio_path(lx.exp(), gamma, n_max)?;
        Some(impacts.iter().map(|&n| (lx - path[n as usize]) / 5.0).collect())
    };
    let profile = |lx: f64| -> f64 {
        offsets(lx)
            .and_then(|o| fit(x, &Design { columns: &columns, offset: Some(&o) }).ok())
            .map_or(f64::NEG_INFINITY, |r| r.loglik)
    };
    let (lo, hi) = ((1e-4f64).ln(), (0.99f64).ln());
    let golden = |mut a: f64, mut b: f64, tol: f64| -> f64 {
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        let (mut c, mut d) = (b - phi * (b - a), a + phi * (b - a));
        let (mut fc, mut fd) = (profile(c), profile(d));
        while b - a > tol {
            if fc >= fd {
                (b, d, fd) = (d, c, fc);
                c = b - phi * (b - a);
                fc = profile(c);
            } else {
                (a, c, fc) = (c, d, fd);
                d = a + phi * (b - a);
                fd = profile(d);
            }
        }
        0.5 * (a + b)
    };
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
                return Err(Error::numerical("damage candidate", "every trial damage ratio breaks a particle or fails to fit"));
            }
            golden(grid[best.saturating_sub(1)], grid[(best + 1).min(grid.len() - 1)], 1e-4)
        }
    };
    let off = offsets(lx).ok_or_else(|| Error::numerical("damage candidate", "the fitted ratio breaks a particle"))?;
    let reg = fit(x, &Design { columns: &columns, offset: Some(&off) })?;
    // `effects` keeps damage wherever it was added; β follow the linear effects' order.
    Ok(ModelFit { effects, reg, columns, offset: Some(off), damage_ratio: Some(lx.exp()), n: x.len() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::weibull::Weibull;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn cov(name: &str, v: Vec<f64>) -> (String, Vec<Option<f64>>) {
        (name.to_string(), v.into_iter().map(Some).collect())
    }

    #[test]
    fn missing_or_constant_covariates_are_skipped_with_a_reason() {
        let c = vec![cov("temperature_c", vec![20.0; 12]), ("roundness".into(), vec![Some(0.7), None, Some(0.8)])];
        assert!(Candidate::Temperature.term(&c, 5.0).unwrap_err().contains("same on every row"));
        assert!(Candidate::Roundness.term(&c, 5.0).unwrap_err().contains("empty on 1 of 3"));
        assert!(Candidate::Damage.term(&c, 5.0).unwrap_err().contains("no `impacts` values"));
    }

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
        let c = vec![cov("impacts", impacts.iter().map(|&k| k as f64).collect())];
        let t = Candidate::Damage.term(&c, 5.0).unwrap();
        let m = fit_model(&x, &[(Candidate::Damage, t)]).unwrap();
        let r = m.damage_ratio.unwrap();
        assert!((r / 0.05 - 1.0).abs() < 0.25, "x = {r}");
        assert!((m.shape() - 15.0).abs() < 1.5);
    }
}
