//! The `kind = "uq"` study: Monte Carlo propagation of every uncertain input of the lifetime
//! chain to the breaking probabilities of two particle types, the probability that one breaks
//! more than the other, Sobol' indices, and the three damage models side by side.
//!
//! ```toml
//! kind = "uq"
//! seed = 1
//! compare = { candidate = "gen4", reference = "bl1630" }
//! [contact]        # crush contact (platen, averaging domain), as in a lifetime study
//! [impact]         # target, years, impacts_per_year, energy_fraction, velocity (distributions)
//! [weibull]        # uncertainty = "bootstrap" | "bayesian", draws
//! [damage]         # models, primary, gamma (Tavares–King coefficient distribution)
//! [propagation]    # method = "plain" | "lhs" | "sobol", samples, replicates
//! [sensitivity]    # n (Saltelli base size), bootstrap, level
//! [[material]]     # key, label, data, elastic, density_kg_m3, roundness, sphericity
//! ```
//!
//! # One sample
//!
//! Per material j: (m, σ_θ) from the Weibull uncertainty of its crush data (σ̄ at break reduced
//! as in the lifetime study: Hertz, sphere of the particle's radius, the study's averaging
//! domain); the contact curvature factor c = roundness × sphericity (Wadell roundness: corner
//! radius over inscribed radius; sphericity: inscribed over equivalent radius), so the impact
//! contact has radius of curvature c·R; shared by both materials: η, V, impacts per year, γ.
//! The impact (Hertz, sphere of mass m on the steel tube with curvature c·R, energy fraction η)
//! gives the peak pressure; σ̄ = r·p0 (r = σ̄/p0 of the averaging domain, which must be a
//! multiple of the contact radius); the single-impact hazard H = (σ̄/σ_θ)^m; P_N of each damage
//! model ([`super::damage`]) for N = years × impacts per year. Since σ̄ ∝ V^(2/5), the hazard at
//! any other velocity is H(V) = H(1 m/s)·V^(2m/5): the breakage-vs-velocity bands reuse the
//! samples.
//!
//! # Estimates and their Monte Carlo error
//!
//! The samples come in `replicates` independent blocks (plain: own streams; LHS: own
//! hypercubes; Sobol': own random shifts). Every headline is the mean of the block estimates,
//! its standard error the sd of the block estimates over √blocks — valid for all three methods.
//! The convergence table repeats this on the first k points of every block.

use std::collections::BTreeMap;
use std::path::PathBuf;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::damage::{CriticalRatioTable, DamageModel, VogelPeukert, breakage};
use super::inputs::{Dist, Marginal, WeibullUncertainty, bayesian_weibull_draws};
use super::sobol::{SobolIndices, sobol_indices};
use crate::contact::{AveragingDomain, ContactStress, Elastic, Hertz, Impact, Sphere, TensileZone};
use crate::data::read_crush;
use crate::error::{Error, Result};
use crate::io::{InputFile, ReportDir, fcol, scol, table, ucol};
use crate::runner::{RunClock, RunOptions, RunRecord, RunSummary, commit_with_manifest, progress_bar, record_figures};
use crate::study::{ContactOptions, FigureOptions, LoadedStudy, MaterialSpec};
use crate::weibull::{Weibull, fit_mle, simulate_pivotal};

/// Impacts and the shared uncertain inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UqImpact {
    /// Tube material (default steel).
    #[serde(default = "steel")]
    pub target: Elastic,
    /// Horizons (years), each > 0.
    pub years: Vec<f64>,
    /// High-velocity impacts per particle and year.
    pub impacts_per_year: Dist,
    /// Elastic energy fraction η ∈ (0, 1].
    pub energy_fraction: Dist,
    /// Impact velocity (m/s): a distribution or a DEM spectrum.
    pub velocity: Dist,
    /// Velocity range of the breakage-vs-velocity figure (m/s).
    #[serde(default = "velocity_range")]
    pub velocity_range: [f64; 2],
}

fn steel() -> Elastic {
    Elastic { youngs_modulus_pa: 210e9, poisson_ratio: 0.3 }
}

fn velocity_range() -> [f64; 2] {
    [0.5, 20.0]
}

/// Weibull parameter uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct UqWeibull {
    /// Bootstrap of the MLE or Bayesian posterior.
    pub uncertainty: WeibullUncertainty,
    /// Joint draws per material.
    pub draws: usize,
}

impl Default for UqWeibull {
    fn default() -> Self {
        UqWeibull { uncertainty: WeibullUncertainty::Bootstrap, draws: 4000 }
    }
}

/// Damage models.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct UqDamage {
    /// Models compared (all three by default).
    pub models: Vec<DamageModel>,
    /// The model of the headline and the Sobol' indices.
    pub primary: DamageModel,
    /// Tavares–King damage coefficient γ.
    pub gamma: Dist,
}

impl Default for UqDamage {
    fn default() -> Self {
        UqDamage { models: DamageModel::ALL.to_vec(), primary: DamageModel::Independent, gamma: Dist::Uniform { min: 2.0, max: 7.0 } }
    }
}

/// Sampling method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Independent uniform draws.
    Plain,
    /// Latin hypercube.
    Lhs,
    /// Randomly shifted Sobol' points.
    #[default]
    Sobol,
}

/// Propagation settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Propagation {
    /// Sampling method.
    pub method: Method,
    /// Samples in all.
    pub samples: usize,
    /// Independent blocks (for the standard errors).
    pub replicates: usize,
}

impl Default for Propagation {
    fn default() -> Self {
        Propagation { method: Method::Sobol, samples: 1 << 17, replicates: 8 }
    }
}

/// Sobol' index settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sensitivity {
    /// Saltelli base sample size (a power of two is best).
    pub n: usize,
    /// Bootstrap resamples of the intervals.
    pub bootstrap: usize,
    /// Interval level.
    pub level: f64,
}

impl Default for Sensitivity {
    fn default() -> Self {
        Sensitivity { n: 1 << 13, bootstrap: 500, level: 0.95 }
    }
}

/// One particle type: a lifetime study's material plus its shape distributions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UqMaterial {
    /// Key, label, crush data, elastic constants, density, impact diameter.
    #[serde(flatten)]
    pub spec: MaterialSpec,
    /// Wadell roundness distribution (0, 1].
    pub roundness: Dist,
    /// Sphericity distribution (0, 1].
    pub sphericity: Dist,
    /// Keys nobody took (serde cannot deny unknown fields through `flatten`): rejected at load.
    #[serde(flatten, skip_serializing)]
    pub unknown: BTreeMap<String, toml::Value>,
}

/// Model-form alternatives (the damage models are compared in every run).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModelForm {
    /// Other averaging domains of σ̄: each reruns the whole chain (Weibull refit of the crush
    /// data included) with a quarter of the samples; `averaging.csv` compares them.
    pub averaging: Vec<AveragingDomain>,
}

/// Which material is compared with which.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Compare {
    /// The candidate ("is it worse?").
    pub candidate: String,
    /// The reference.
    pub reference: String,
}

/// A `kind = "uq"` study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UqStudy {
    /// `uq`.
    pub kind: String,
    /// Seed of every random draw.
    pub seed: u64,
    /// Candidate and reference.
    pub compare: Compare,
    /// Crush contact.
    #[serde(default)]
    pub contact: ContactOptions,
    /// Impacts and shared inputs.
    pub impact: UqImpact,
    /// Weibull uncertainty.
    #[serde(default)]
    pub weibull: UqWeibull,
    /// Damage models.
    #[serde(default)]
    pub damage: UqDamage,
    /// Propagation.
    #[serde(default)]
    pub propagation: Propagation,
    /// Sobol' indices.
    #[serde(default)]
    pub sensitivity: Sensitivity,
    /// Model-form alternatives run besides the main chain.
    #[serde(default)]
    pub model_form: ModelForm,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
    /// Exactly two particle types.
    pub material: Vec<UqMaterial>,
}

/// One uncertain input.
#[derive(Debug, Clone)]
pub struct Input {
    /// Name in tables.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Its marginal.
    pub marginal: Marginal,
}

/// Per material, what the samples need.
#[derive(Debug, Clone)]
pub struct PreparedMaterial {
    /// Key.
    pub key: String,
    /// Label.
    pub label: String,
    /// The impacting sphere.
    pub sphere: Sphere,
    /// Crush particles and the MLE of σ̄ at break (n, m̂, σ̂_θ).
    pub fit: (usize, f64, f64),
    /// Crush data file.
    pub path: PathBuf,
}

/// Everything a run needs, checked at load.
#[derive(Debug, Clone)]
pub struct Chain {
    /// Inputs in order: `weibull_<a>`, `weibull_<b>`, `roundness_<a>`, `sphericity_<a>`,
    /// `roundness_<b>`, `sphericity_<b>`, `energy_fraction`, `velocity`, `impacts_per_year`,
    /// `tk_gamma` (a = candidate, b = reference).
    pub inputs: Vec<Input>,
    /// The two materials: candidate first, reference second.
    pub materials: [PreparedMaterial; 2],
    /// The averaging domain of σ̄ (crush and impact alike).
    pub domain: AveragingDomain,
    /// σ̄/p0 of the domain when constant (outer limit a multiple of a): the fast path.
    pub ratio: Option<f64>,
    /// Tensile zones of the two materials (their ν).
    pub zones: [TensileZone; 2],
    /// Tube.
    pub wall: Elastic,
    /// Horizons (years).
    pub years: Vec<f64>,
    /// Damage models (primary first).
    pub models: Vec<DamageModel>,
    /// Tavares–King x* tables per horizon (fixed impacts per year only).
    pub tk: Vec<Option<CriticalRatioTable>>,
}

/// Input indices.
mod idx {
    pub const WEIBULL: usize = 0; // + material
    pub const ROUNDNESS: usize = 2; // + 2 × material
    pub const SPHERICITY: usize = 3; // + 2 × material
    pub const ETA: usize = 6;
    pub const VELOCITY: usize = 7;
    pub const PER_YEAR: usize = 8;
    pub const GAMMA: usize = 9;
}

/// What the single-impact hazard of one sample needs: H(V) = (σ̄(p0, a)/σ_θ)^m with
/// p0 = c_p V^(2/5) and a = c_a V^(2/5) (Hertz impact).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hazard {
    /// Weibull modulus m.
    pub m: f64,
    /// ln σ_θ.
    pub ln_scale: f64,
    /// Peak pressure at 1 m/s (Pa).
    pub c_p: f64,
    /// Contact radius at 1 m/s (m).
    pub c_a: f64,
    /// Particle radius (m).
    pub radius: f64,
}

/// One evaluated sample: per material its hazard parameters and P per material, horizon and
/// model (index [`Chain::slot`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluated {
    /// Hazard parameters per material.
    pub hazard: [Hazard; 2],
    /// ln V.
    pub ln_v: f64,
    /// Impacts per year.
    pub per_year: f64,
    /// γ.
    pub gamma: f64,
    /// P_N per material, horizon, model (flattened: (j·Y + h)·D + d).
    pub p: Vec<f64>,
}

impl Chain {
    /// Index into [`Evaluated::p`] of material j (0 candidate, 1 reference), horizon h, model k.
    pub fn slot(&self, j: usize, h: usize, k: usize) -> usize {
        (j * self.years.len() + h) * self.models.len() + k
    }

    /// The varying inputs' indices (the dimensions of the unit points).
    pub fn varying(&self) -> Vec<usize> {
        (0..self.inputs.len()).filter(|&i| self.inputs[i].marginal.varies()).collect()
    }

    /// Full input vector from a unit point over the varying inputs.
    /// (The hot path of the propagation: one inverse CDF per varying input, no allocation but
    /// the result.)
    pub fn values(&self, u: &[f64]) -> Vec<f64> {
        let mut k = 0;
        self.inputs
            .iter()
            .map(|i| match &i.marginal {
                Marginal::Fixed(v) => *v,
                m => {
                    k += 1;
                    m.quantile(u[k - 1])
                }
            })
            .collect()
    }

    /// Single-impact hazard parameters of material j at inputs x.
    pub fn hazard(&self, j: usize, x: &[f64]) -> Hazard {
        let mat = &self.materials[j];
        let w: Weibull = match &self.inputs[idx::WEIBULL + j].marginal {
            Marginal::Weibull(d) => d[x[idx::WEIBULL + j] as usize],
            _ => unreachable!("input 0/1 are Weibull draws"),
        };
        let c = x[idx::ROUNDNESS + 2 * j] * x[idx::SPHERICITY + 2 * j];
        let impact = Impact::sphere_on_wall(&mat.sphere, &self.wall, c * mat.sphere.radius(), x[idx::ETA]);
        let f1 = impact.max_force(1.0);
        Hazard { m: w.shape, ln_scale: w.scale.ln(), c_p: impact.hertz.peak_pressure(f1), c_a: impact.hertz.contact_radius(f1), radius: mat.sphere.radius() }
    }

    /// ln H at ln V for material j: σ̄ = r·p0 on the fast path, else the domain's formula at
    /// (p0, a, R); a contact larger than the domain (a > R, far beyond 100 m/s) counts as a
    /// certain break.
    pub fn ln_hazard(&self, j: usize, hz: &Hazard, ln_v: f64) -> f64 {
        if ln_v == f64::NEG_INFINITY {
            return f64::NEG_INFINITY; // V = 0: no contact, no hazard
        }
        let ln_sigma = match self.ratio {
            Some(r) => (r * hz.c_p).ln() + 0.4 * ln_v,
            None => {
                let t = (0.4 * ln_v).exp();
                self.domain.mean_tensile_stress(&self.zones[j], hz.c_p * t, hz.c_a * t, hz.radius).map(f64::ln).unwrap_or(f64::INFINITY)
            }
        };
        hz.m * (ln_sigma - hz.ln_scale)
    }

    /// P_N of model `d` for modulus m and ln H, N impacts and γ (horizon h).
    pub fn p(&self, model: DamageModel, m: f64, ln_h: f64, n: f64, gamma: f64, h: usize) -> f64 {
        let hz = ln_h.exp();
        let vp = if model == DamageModel::VogelPeukert { VogelPeukert::matched(m / 5.0) } else { VogelPeukert { rate: 0.0, threshold: 0.0 } };
        let x_star = match (model, &self.tk[h]) {
            (DamageModel::TavaresKing, Some(t)) => t.ratio(gamma),
            _ => 1.0,
        };
        breakage(model, hz, m, n, &vp, x_star)
    }

    /// Evaluates one unit point.
    pub fn evaluate(&self, u: &[f64]) -> Evaluated {
        let x = self.values(u);
        let hazard = [self.hazard(0, &x), self.hazard(1, &x)];
        let v = x[idx::VELOCITY];
        let ln_v = if v > 0.0 { v.ln() } else { f64::NEG_INFINITY };
        let ln_h = [self.ln_hazard(0, &hazard[0], ln_v), self.ln_hazard(1, &hazard[1], ln_v)];
        let (y, d) = (self.years.len(), self.models.len());
        let mut p = vec![0.0; 2 * y * d];
        for j in 0..2 {
            for h in 0..y {
                let n = self.years[h] * x[idx::PER_YEAR];
                for (k, &model) in self.models.iter().enumerate() {
                    p[self.slot(j, h, k)] = self.p(model, hazard[j].m, ln_h[j], n, x[idx::GAMMA], h);
                }
            }
        }
        Evaluated { hazard, ln_v, per_year: x[idx::PER_YEAR], gamma: x[idx::GAMMA], p }
    }
}

impl UqStudy {
    /// Checks the study and builds the chain (reads and fits the crush data).
    pub fn prepare(&self, path: &std::path::Path) -> Result<Chain> {
        let file = path.display().to_string();
        let resolve = |p: &str| crate::study::resolve_relative(path, std::path::Path::new(p));
        let bad = |k: &str, rule: String| Err(Error::config(&file, k, rule));
        if self.material.len() != 2 {
            return bad("material", format!("a UQ study compares exactly two [[material]]s, got {}", self.material.len()));
        }
        let pos = |k: &str, key: &str| -> Result<usize> {
            self.material.iter().position(|m| m.spec.key == k).ok_or_else(|| Error::config(&file, key, format!("`{k}` is not a material key ({}, {})", self.material[0].spec.key, self.material[1].spec.key)))
        };
        let (ic, ir) = (pos(&self.compare.candidate, "compare.candidate")?, pos(&self.compare.reference, "compare.reference")?);
        if ic == ir {
            return bad("compare", "candidate and reference must differ".into());
        }
        if self.impact.years.is_empty() || self.impact.years.iter().any(|y| !(y.is_finite() && *y > 0.0)) {
            return bad("impact.years", format!("every horizon must be a finite number of years > 0, got {:?}", self.impact.years));
        }
        let [vlo, vhi] = self.impact.velocity_range;
        if !(vlo > 0.0 && vlo < vhi && vhi <= crate::lifetime::MAX_VELOCITY) {
            return bad("impact.velocity_range", format!("needs 0 < low < high ≤ {} m/s, got [{vlo}, {vhi}]", crate::lifetime::MAX_VELOCITY));
        }
        crate::study::elastic_checked(&file, "impact.target", &self.impact.target)?;
        crate::study::elastic_checked(&file, "contact.platen", &self.contact.platen)?;
        self.contact.averaging.validate(&file, "contact.averaging")?;
        let zone_ratio = |nu: f64| self.contact.averaging.ratio_to_peak_pressure(&TensileZone::new(nu));
        if !(2..=1_000_000).contains(&self.weibull.draws) {
            return bad("weibull.draws", format!("must lie in [2, 10⁶], got {}", self.weibull.draws));
        }
        let p = &self.propagation;
        if p.replicates < 2 || p.samples < 64 * p.replicates || p.samples > 50_000_000 {
            return bad("propagation", format!("needs replicates ≥ 2 and 64·replicates ≤ samples ≤ 5·10⁷, got {} samples in {} replicates", p.samples, p.replicates));
        }
        let s = &self.sensitivity;
        if s.n < 64 || s.n > 1 << 20 || !(s.level > 0.0 && s.level < 1.0) || s.bootstrap > 100_000 {
            return bad("sensitivity", format!("needs 64 ≤ n ≤ 2²⁰ and level in (0, 1), got n = {}, level {}", s.n, s.level));
        }
        if self.damage.models.is_empty() || !self.damage.models.contains(&self.damage.primary) {
            return bad("damage.primary", format!("{:?} must be one of damage.models {:?}", self.damage.primary, self.damage.models));
        }
        let mut models = vec![self.damage.primary];
        models.extend(self.damage.models.iter().copied().filter(|m| *m != self.damage.primary));
        models.dedup();

        // Inputs.
        let m = |d: &Dist, key: &str, unit: &str| d.marginal(&file, key, unit, &resolve);
        let in_range = |mg: &Marginal, key: &str, lo: f64, hi: f64| -> Result<()> {
            let (a, b) = (mg.quantile(0.0), mg.quantile(1.0));
            if a >= lo && b <= hi && a.is_finite() && b.is_finite() { Ok(()) } else { Err(Error::config(&file, key, format!("values must lie in [{lo}, {hi}], the distribution spans [{a}, {b}]"))) }
        };
        let mut mats = Vec::new();
        let mut inputs = Vec::new();
        let order = [ic, ir];
        let mut shape_inputs = Vec::new();
        for (slot, &i) in order.iter().enumerate() {
            let (mm, shape) = (&self.material[i].spec, &self.material[i]);
            let key = |k: &str| format!("material[{i}].{k}");
            if let Some(k) = shape.unknown.keys().next() {
                return bad(&key(k), "unknown key (known: key, label, data, elastic, density_kg_m3, impact_diameter_m, roundness, sphericity)".into());
            }
            crate::study::elastic_checked(&file, &key("elastic"), &mm.elastic)?;
            if !(mm.density_kg_m3 > 0.0 && mm.density_kg_m3.is_finite()) {
                return bad(&key("density_kg_m3"), format!("must be > 0, got {}", mm.density_kg_m3));
            }
            let dpath = resolve(&mm.data.display().to_string());
            if !dpath.is_file() {
                return bad(&key("data"), format!("{} does not exist", dpath.display()));
            }
            let data = read_crush(&dpath)?;
            let zone = TensileZone::new(mm.elastic.poisson_ratio);
            let sigma: Vec<f64> = data
                .records
                .iter()
                .map(|r| {
                    let radius = 0.5 * r.diameter_m;
                    let hertz = Hertz::sphere_on_flat(&mm.elastic, &self.contact.platen, radius);
                    ContactStress { hertz, zone, domain: self.contact.averaging, particle_radius: radius }.at_force(r.crush_force_n).map(|c| c.mean_tensile)
                })
                .collect::<Result<_>>()?;
            let fit = fit_mle(&sigma).map_err(|e| Error::data_file(&dpath, "all rows", format!("Weibull fit of the average tensile stress failed: {e}")))?;
            let seed = self.seed ^ (0xA5A5 + slot as u64);
            let draws = match self.weibull.uncertainty {
                WeibullUncertainty::Bootstrap => simulate_pivotal(fit.n, self.weibull.draws, seed)?.draws(&fit),
                WeibullUncertainty::Bayesian => bayesian_weibull_draws(&sigma, &fit, self.weibull.draws, seed)?,
            };
            let diameter = match mm.impact_diameter_m {
                Some(d) if d > 0.0 && d.is_finite() => d,
                Some(d) => return bad(&key("impact_diameter_m"), format!("must be > 0, got {d}")),
                None => crate::stats::quantiles(&mut data.diameters(), &[0.5])[0],
            };
            inputs.push(Input { name: format!("weibull_{}", mm.key), unit: "m (-)".into(), marginal: Marginal::Weibull(draws) });
            let r = m(&shape.roundness, &key("roundness"), "-")?;
            in_range(&r, &key("roundness"), 1e-3, 1.0)?;
            let sp = m(&shape.sphericity, &key("sphericity"), "-")?;
            in_range(&sp, &key("sphericity"), 1e-3, 1.0)?;
            shape_inputs.push(Input { name: format!("roundness_{}", mm.key), unit: "-".into(), marginal: r });
            shape_inputs.push(Input { name: format!("sphericity_{}", mm.key), unit: "-".into(), marginal: sp });
            mats.push(PreparedMaterial { key: mm.key.clone(), label: mm.label.clone(), sphere: Sphere { diameter, density: mm.density_kg_m3, elastic: mm.elastic }, fit: (fit.n, fit.mle.shape, fit.mle.scale), path: dpath });
        }
        // One ratio: both materials' ν enter the tensile zone; they must agree for one r.
        let nus = [self.material[ic].spec.elastic.poisson_ratio, self.material[ir].spec.elastic.poisson_ratio];
        let zones = nus.map(TensileZone::new);
        // The fast path needs one constant σ̄/p0 for both materials.
        let ratio = match (zone_ratio(nus[0]), zone_ratio(nus[1])) {
            (Some(a), Some(b)) if (a / b - 1.0).abs() < 1e-12 => Some(a),
            _ => None,
        };
        for (i, d) in self.model_form.averaging.iter().enumerate() {
            d.validate(&file, &format!("model_form.averaging[{i}]"))?;
        }
        inputs.extend(shape_inputs);
        let eta = m(&self.impact.energy_fraction, "impact.energy_fraction", "-")?;
        in_range(&eta, "impact.energy_fraction", 1e-6, 1.0)?;
        let v = m(&self.impact.velocity, "impact.velocity", "m/s")?;
        in_range(&v, "impact.velocity", 0.0, crate::lifetime::MAX_VELOCITY)?;
        let per_year = m(&self.impact.impacts_per_year, "impact.impacts_per_year", "1/yr")?;
        in_range(&per_year, "impact.impacts_per_year", 1e-9, 1e9)?;
        let gamma = m(&self.damage.gamma, "damage.gamma", "-")?;
        in_range(&gamma, "damage.gamma", 0.1, 100.0)?;
        for (d, key) in [(&self.impact.energy_fraction, "impact.energy_fraction"), (&self.impact.impacts_per_year, "impact.impacts_per_year"), (&self.damage.gamma, "damage.gamma")] {
            if matches!(d, Dist::Spectrum { .. }) {
                return bad(key, "a spectrum is a velocity distribution only".into());
            }
        }
        for mm in &self.material {
            if matches!(mm.roundness, Dist::Spectrum { .. }) || matches!(mm.sphericity, Dist::Spectrum { .. }) {
                return bad("material", "a spectrum is a velocity distribution only".into());
            }
        }
        let tk = if models.contains(&DamageModel::TavaresKing) {
            let Marginal::Fixed(n_year) = per_year else {
                return bad("impact.impacts_per_year", "the Tavares–King model needs a fixed number of impacts per year (its damage table is per N)".into());
            };
            let (glo, ghi) = (gamma.quantile(0.0), gamma.quantile(1.0));
            self.impact.years.iter().map(|y| Some(CriticalRatioTable::new((y * n_year).round().max(1.0) as u64, glo, ghi.max(glo + 1e-9), 41))).collect()
        } else {
            vec![None; self.impact.years.len()]
        };
        inputs.push(Input { name: "energy_fraction".into(), unit: "-".into(), marginal: eta });
        inputs.push(Input { name: "velocity".into(), unit: "m/s".into(), marginal: v });
        inputs.push(Input { name: "impacts_per_year".into(), unit: "1/yr".into(), marginal: per_year });
        inputs.push(Input { name: "tk_gamma".into(), unit: "-".into(), marginal: gamma });
        if !(4.0..=40.0).contains(&self.figures.width_cm) {
            return bad("figures.width_cm", format!("must lie in [4, 40], got {}", self.figures.width_cm));
        }
        let [a, b]: [PreparedMaterial; 2] = mats.try_into().map_err(|_| Error::config(&file, "material", "two materials"))?;
        Ok(Chain { inputs, materials: [a, b], domain: self.contact.averaging, ratio, zones, wall: self.impact.target, years: self.impact.years.clone(), models, tk })
    }
}

/// The unit points of block r (n points in d dimensions).
pub fn block_points(method: Method, d: usize, n: usize, seed: u64, r: usize) -> Result<Vec<Vec<f64>>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(r as u64 + 1);
    Ok(match method {
        Method::Plain => (0..n).map(|_| (0..d).map(|_| rng.random::<f64>()).collect()).collect(),
        Method::Lhs => crate::design::latin_hypercube(n, d, seed.wrapping_add(1 + r as u64)),
        Method::Sobol => {
            let shift: Vec<f64> = (0..d).map(|_| rng.random::<f64>()).collect();
            crate::design::Sobol::points(d, n, 1)?
                .into_iter()
                .map(|p| p.iter().zip(&shift).map(|(x, s)| (x + s).fract()).collect())
                .collect()
        }
    })
}

/// Mean and standard error over blocks.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, (var / n).sqrt())
}

/// The propagation result.
pub struct Propagated {
    /// Blocks of evaluated samples.
    pub blocks: Vec<Vec<Evaluated>>,
}

/// Runs the propagation (rayon-parallel; the result does not depend on the thread count).
pub fn propagate(chain: &Chain, p: &Propagation, seed: u64, tick: &(dyn Fn() + Sync)) -> Result<Propagated> {
    let d = chain.varying().len().max(1);
    let n = p.samples / p.replicates;
    let mut blocks = Vec::with_capacity(p.replicates);
    for r in 0..p.replicates {
        let pts = block_points(p.method, d, n, seed, r)?;
        blocks.push(pts.par_iter().map(|u| chain.evaluate(u)).collect());
        tick();
    }
    Ok(Propagated { blocks })
}

/// log10 of a probability, floored at 1e-300.
fn lg(p: f64) -> f64 {
    p.max(1e-300).log10()
}

/// Runs the study.
pub fn run_uq(loaded: &LoadedStudy, s: &UqStudy, opts: &RunOptions) -> Result<RunSummary> {
    let clock = RunClock::start();
    let chain = s.prepare(&loaded.path)?;
    let mut inputs = vec![InputFile::hash(&loaded.path)?];
    for m in &chain.materials {
        inputs.push(InputFile::hash(&m.path)?);
    }
    if let Dist::Spectrum { file, .. } = &s.impact.velocity {
        inputs.push(InputFile::hash(&loaded.resolve(std::path::Path::new(file)))?);
    }
    let sens_sizes: Vec<usize> = (0..5).rev().map(|k| (s.sensitivity.n >> k).max(64)).collect();
    let pb = progress_bar((s.propagation.replicates + sens_sizes.len() + 2) as u64, opts.progress, crate::runner::PROGRESS_COUNT);
    pb.set_message("Monte Carlo propagation");
    let prop = propagate(&chain, &s.propagation, s.seed, &|| pb.inc(1))?;

    let mut dir = ReportDir::create(&opts.reports_root, &loaded.name)?;
    let headline = write_headline(&mut dir, &chain, &prop)?;
    write_convergence(&mut dir, &chain, &prop)?;
    write_distributions(&mut dir, &chain, &prop)?;
    write_breakage_vs_velocity(&mut dir, &chain, &prop, s.impact.velocity_range)?;
    pb.inc(1);
    pb.set_message("Sobol' indices");
    let (final_indices, outputs) = write_sobol(&mut dir, &chain, s, &sens_sizes, &|| pb.inc(1))?;
    write_inputs(&mut dir, &chain)?;
    pb.set_message("averaging-domain alternatives");
    let averaging = write_averaging(&mut dir, s, &loaded.path, &chain, &prop)?;
    let varying = chain.varying();
    let mut md = summary(s, &chain, &prop, &final_indices, &varying, &outputs, &headline);
    if averaging.len() > chain.years.len() {
        md.push_str("\n## Averaging domain of σ̄ (independent trials)\n\n| domain | horizon | P(candidate worse) | median P candidate | median P reference |\n|---|---|---|---|---|\n");
        for (d, years, worse, se, a, b) in &averaging {
            md.push_str(&format!("| {d} | {years} yr | {worse:.4} ± {se:.4} | {a:.2e} | {b:.2e} |\n"));
        }
        md.push_str("\nEvery domain whose outer limit is a multiple of the contact radius gives σ̄ = r·p0 in the crush test and in the impact alike, so r cancels between the Weibull scale and the impact stress: those domains give identical answers. Only a domain reaching the particle radius (σ̄ depends on a/R, which differs between the crush at break and a 5 m/s impact) changes them.\n");
    }
    dir.write_bytes("summary.md", md.as_bytes())?;
    pb.set_message("figures");
    let mut failures = Vec::new();
    let rendered = crate::report::uq::render(dir.path(), s.figures.width_cm)?;
    record_figures(&mut dir, rendered, &mut failures);
    pb.inc(1);
    let mut evaluations = BTreeMap::new();
    evaluations.insert("propagation_samples".to_string(), prop.count() as u64);
    evaluations.insert("sobol_model_runs".to_string(), sens_sizes.iter().map(|n| (n * (varying.len() + 2)) as u64).sum());
    let study_resolved = serde_json::to_value(s).map_err(|e| Error::numerical("manifest", e.to_string()))?;
    let report_dir = commit_with_manifest(dir, loaded, study_resolved, RunRecord { inputs, seed: s.seed, clock, evaluations, failures })?;
    pb.finish_and_clear();
    Ok(RunSummary { report_dir, wall_time_s: clock.seconds(), headlines: headline.lines })
}

/// The study's domain and every `[model_form] averaging` alternative (each a rerun of the
/// chain with its own Weibull fit, a quarter of the samples): P(candidate worse) and the
/// medians, primary model, per horizon.
#[allow(clippy::type_complexity)]
fn write_averaging(dir: &mut ReportDir, s: &UqStudy, path: &std::path::Path, chain: &Chain, prop: &Propagated) -> Result<Vec<(String, f64, f64, f64, f64, f64)>> {
    let mut rows = Vec::new();
    let mut add = |c: &Chain, p: &Propagated, d: &AveragingDomain| {
        for (h, &years) in c.years.iter().enumerate() {
            let (a, b) = (c.slot(0, h, 0), c.slot(1, h, 0));
            let (worse, se) = mean_se(&p.fraction_worse(a, b, p.blocks[0].len()));
            rows.push((d.describe(), years, worse, se, crate::stats::interpolated_quantiles(p.values(a), &[0.5])[0], crate::stats::interpolated_quantiles(p.values(b), &[0.5])[0]));
        }
    };
    add(chain, prop, &chain.domain);
    for d in &s.model_form.averaging {
        let mut alt = s.clone();
        alt.contact.averaging = *d;
        let c = alt.prepare(path)?;
        let opts = Propagation { samples: (s.propagation.samples / 4).max(64 * s.propagation.replicates), ..s.propagation.clone() };
        let p = propagate(&c, &opts, s.seed, &|| {})?;
        add(&c, &p, d);
    }
    dir.write_table(
        "averaging",
        &mut table(vec![
            scol("domain", rows.iter().map(|r| r.0.clone()).collect()),
            fcol("years", rows.iter().map(|r| r.1).collect()),
            fcol("p_candidate_worse", rows.iter().map(|r| r.2).collect()),
            fcol("mc_se", rows.iter().map(|r| r.3).collect()),
            fcol("median_p_candidate", rows.iter().map(|r| r.4).collect()),
            fcol("median_p_reference", rows.iter().map(|r| r.5).collect()),
        ])?,
    )?;
    Ok(rows)
}

impl Propagated {
    /// Every sample.
    pub fn all(&self) -> impl Iterator<Item = &Evaluated> {
        self.blocks.iter().flatten()
    }

    /// Number of samples.
    pub fn count(&self) -> usize {
        self.blocks.iter().map(|b| b.len()).sum()
    }

    /// P at `slot` over every sample.
    pub fn values(&self, slot: usize) -> Vec<f64> {
        self.all().map(|e| e.p[slot]).collect()
    }

    /// Per block, the fraction of its first `first` samples in which the candidate's P (slot
    /// `a`) exceeds the reference's (slot `b`).
    pub fn fraction_worse(&self, a: usize, b: usize, first: usize) -> Vec<f64> {
        self.blocks.iter().map(|bl| bl[..first.min(bl.len())].iter().filter(|e| e.p[a] > e.p[b]).count() as f64 / first.min(bl.len()) as f64).collect()
    }
}

/// The headline lines and, per model and horizon, (model, years, P(candidate worse), its se,
/// fraction of ties, median P of candidate and reference).
pub struct Headline {
    /// Printed lines (primary model).
    pub lines: Vec<String>,
    /// Per model and horizon.
    pub rows: Vec<(DamageModel, f64, f64, f64, f64, f64, f64)>,
}

fn write_headline(dir: &mut ReportDir, chain: &Chain, prop: &Propagated) -> Result<Headline> {
    let names = [&chain.materials[0].label, &chain.materials[1].label];
    let nb = prop.blocks[0].len();
    let mut out = Headline { lines: Vec::new(), rows: Vec::new() };
    let mut q_rows: (Vec<String>, Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    for (k, model) in chain.models.iter().enumerate() {
        for (h, &years) in chain.years.iter().enumerate() {
            let (a, b) = (chain.slot(0, h, k), chain.slot(1, h, k));
            let (mean, se) = mean_se(&prop.fraction_worse(a, b, nb));
            let ties = prop.all().filter(|e| e.p[a] == e.p[b]).count() as f64 / prop.count() as f64;
            if k == 0 {
                out.lines.push(format!("P({} breaks more than {} in {} yr) = {:.4} ± {:.4} (Monte Carlo se)", names[0], names[1], years, mean, se));
            }
            let mut medians = [0.0; 2];
            for j in 0..2 {
                let slot = chain.slot(j, h, k);
                let all = prop.values(slot);
                let block_medians: Vec<f64> = prop.blocks.iter().map(|bl| crate::stats::interpolated_quantiles(bl.iter().map(|e| e.p[slot]).collect(), &[0.5])[0]).collect();
                let mean_p = all.iter().sum::<f64>() / all.len() as f64;
                let q = crate::stats::interpolated_quantiles(all, &[0.05, 0.5, 0.95]);
                medians[j] = q[1];
                q_rows.0.push(model.name().into());
                q_rows.1.push(chain.materials[j].key.clone());
                q_rows.2.push(years);
                q_rows.3.push(q[0]);
                q_rows.4.push(q[1]);
                q_rows.5.push(mean_se(&block_medians).1);
                q_rows.6.push(q[2]);
                q_rows.7.push(mean_p);
            }
            out.rows.push((*model, years, mean, se, ties, medians[0], medians[1]));
        }
    }
    dir.write_table(
        "materials",
        &mut table(vec![
            scol("role", vec!["candidate".into(), "reference".into()]),
            scol("key", chain.materials.iter().map(|m| m.key.clone()).collect()),
            scol("label", chain.materials.iter().map(|m| m.label.clone()).collect()),
            ucol("crush_particles", chain.materials.iter().map(|m| m.fit.0 as u64).collect()),
            fcol("weibull_m_mle", chain.materials.iter().map(|m| m.fit.1).collect()),
            fcol("weibull_scale_mle_pa", chain.materials.iter().map(|m| m.fit.2).collect()),
            fcol("impact_diameter_m", chain.materials.iter().map(|m| m.sphere.diameter).collect()),
        ])?,
    )?;
    let r = &out.rows;
    dir.write_table(
        "comparison",
        &mut table(vec![
            scol("model", r.iter().map(|x| x.0.name().to_string()).collect()),
            fcol("years", r.iter().map(|x| x.1).collect()),
            fcol("p_candidate_worse", r.iter().map(|x| x.2).collect()),
            fcol("mc_se", r.iter().map(|x| x.3).collect()),
            fcol("ties", r.iter().map(|x| x.4).collect()),
        ])?,
    )?;
    dir.write_table(
        "breakage",
        &mut table(vec![scol("model", q_rows.0), scol("material", q_rows.1), fcol("years", q_rows.2), fcol("q05", q_rows.3), fcol("median", q_rows.4), fcol("median_mc_se", q_rows.5), fcol("q95", q_rows.6), fcol("mean", q_rows.7)])?,
    )?;
    Ok(out)
}

/// Convergence of P(candidate worse), primary model, every horizon, on the first k samples of
/// every block (k doubling from 16).
fn write_convergence(dir: &mut ReportDir, chain: &Chain, prop: &Propagated) -> Result<()> {
    let nb = prop.blocks[0].len();
    let mut conv: (Vec<f64>, Vec<u64>, Vec<f64>, Vec<f64>) = Default::default();
    let mut k = 16usize.min(nb);
    loop {
        for (h, &years) in chain.years.iter().enumerate() {
            let (m, se) = mean_se(&prop.fraction_worse(chain.slot(0, h, 0), chain.slot(1, h, 0), k));
            conv.0.push(years);
            conv.1.push((k * prop.blocks.len()) as u64);
            conv.2.push(m);
            conv.3.push(se);
        }
        if k == nb {
            break;
        }
        k = (k * 2).min(nb);
    }
    dir.write_table("convergence", &mut table(vec![fcol("years", conv.0), ucol("samples", conv.1), fcol("p_candidate_worse", conv.2), fcol("mc_se", conv.3)])?)
}

/// Densities of log₁₀ P per material and horizon (primary model), 60 bins over the pooled range.
fn write_distributions(dir: &mut ReportDir, chain: &Chain, prop: &Propagated) -> Result<()> {
    let mut hist: (Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    for (h, &years) in chain.years.iter().enumerate() {
        let vals: Vec<Vec<f64>> = (0..2).map(|j| prop.values(chain.slot(j, h, 0)).into_iter().map(lg).collect()).collect();
        let lo = vals.iter().flatten().cloned().fold(f64::INFINITY, f64::min).max(-30.0);
        let hi = vals.iter().flatten().cloned().fold(f64::NEG_INFINITY, f64::max).max(lo + 1e-6);
        let bins = 60;
        let width = (hi - lo) / bins as f64;
        for (j, v) in vals.iter().enumerate() {
            let mut c = vec![0usize; bins];
            for &x in v {
                c[((x - lo) / width).floor().clamp(0.0, bins as f64 - 1.0) as usize] += 1;
            }
            for (b, n) in c.iter().enumerate() {
                hist.0.push(chain.materials[j].key.clone());
                hist.1.push(years);
                hist.2.push(lo + (b as f64 + 0.5) * width);
                hist.3.push(*n as f64 / v.len() as f64 / width);
            }
        }
    }
    dir.write_table("distributions", &mut table(vec![scol("material", hist.0), fcol("years", hist.1), fcol("log10_p", hist.2), fcol("density", hist.3)])?)
}

/// P_break vs velocity with its 90 % band (primary model) from up to 4000 samples' hazards:
/// H(V) = H(1 m/s)·V^(2m/5).
fn write_breakage_vs_velocity(dir: &mut ReportDir, chain: &Chain, prop: &Propagated, [vlo, vhi]: [f64; 2]) -> Result<()> {
    let sub: Vec<&Evaluated> = prop.blocks.iter().flat_map(|b| b.iter().take(4000 / prop.blocks.len())).collect();
    let mut vv: (Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    for j in 0..2 {
        for (h, &years) in chain.years.iter().enumerate() {
            for i in 0..48 {
                let v = vlo * (vhi / vlo).powf(i as f64 / 47.0);
                let ps: Vec<f64> = sub.iter().map(|e| chain.p(chain.models[0], e.hazard[j].m, chain.ln_hazard(j, &e.hazard[j], v.ln()), years * e.per_year, e.gamma, h)).collect();
                let q = crate::stats::interpolated_quantiles(ps, &[0.05, 0.5, 0.95]);
                vv.0.push(chain.materials[j].key.clone());
                vv.1.push(years);
                vv.2.push(v);
                vv.3.push(q[0]);
                vv.4.push(q[1]);
                vv.5.push(q[2]);
            }
        }
    }
    dir.write_table("breakage_vs_velocity", &mut table(vec![scol("material", vv.0), fcol("years", vv.1), fcol("velocity_m_s", vv.2), fcol("q05", vv.3), fcol("median", vv.4), fcol("q95", vv.5)])?)
}

/// Sobol' indices of the primary model at the last horizon for every base size in `sizes`
/// (the last is the study's n); returns the final indices and the output names.
fn write_sobol(dir: &mut ReportDir, chain: &Chain, s: &UqStudy, sizes: &[usize], tick: &dyn Fn()) -> Result<(Vec<SobolIndices>, Vec<String>)> {
    let h = chain.years.len() - 1;
    let at = |j: usize, h: usize, k: usize| chain.slot(j, h, k);
    let varying = chain.varying();
    let f = |u: &[f64]| -> Result<Vec<f64>> {
        let e = chain.evaluate(u);
        Ok(vec![lg(e.p[at(0, h, 0)]), lg(e.p[at(1, h, 0)]), e.p[at(0, h, 0)] - e.p[at(1, h, 0)]])
    };
    let outputs = vec![
        format!("log10_p_{}", chain.materials[0].key),
        format!("log10_p_{}", chain.materials[1].key),
        format!("p_{}_minus_p_{}", chain.materials[0].key, chain.materials[1].key),
    ];
    let mut sob: (Vec<String>, Vec<u64>, Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<String>) = Default::default();
    let mut final_indices: Vec<SobolIndices> = Vec::new();
    for &n in sizes {
        let ind = sobol_indices(f, varying.len(), n, s.seed ^ 0x50B0, s.sensitivity.bootstrap, s.sensitivity.level)?;
        for (o, si) in ind.iter().enumerate() {
            for (k, &i) in varying.iter().enumerate() {
                sob.0.push(outputs[o].clone());
                sob.1.push(n as u64);
                sob.2.push(chain.inputs[i].name.clone());
                sob.3.push(si.first[k]);
                sob.4.push(si.first_ci[k].0);
                sob.5.push(si.first_ci[k].1);
                sob.6.push(si.total[k]);
                sob.7.push(si.total_ci[k].0);
                sob.8.push(si.total_ci[k].1);
                sob.9.push(if si.first[k] < 0.0 || si.total[k] < 0.0 { "negative: zero within MC error".into() } else { String::new() });
            }
        }
        if n == s.sensitivity.n {
            final_indices = ind;
        }
        tick();
    }
    dir.write_table(
        "sobol",
        &mut table(vec![
            scol("output", sob.0),
            ucol("n", sob.1),
            scol("input", sob.2),
            fcol("s1", sob.3),
            fcol("s1_lo", sob.4),
            fcol("s1_hi", sob.5),
            fcol("st", sob.6),
            fcol("st_lo", sob.7),
            fcol("st_hi", sob.8),
            scol("flag", sob.9),
        ])?,
    )?;
    Ok((final_indices, outputs))
}

/// The inputs' 5/50/95 % quantiles (Weibull draws: of the modulus m).
fn write_inputs(dir: &mut ReportDir, chain: &Chain) -> Result<()> {
    let mut it: (Vec<String>, Vec<String>, Vec<f64>, Vec<f64>, Vec<f64>) = Default::default();
    for i in &chain.inputs {
        it.0.push(i.name.clone());
        it.1.push(i.unit.clone());
        // Weibull draws: the quantiles of the modulus m over the draws.
        let qs = match &i.marginal {
            Marginal::Weibull(d) => {
                let q = crate::stats::interpolated_quantiles(d.iter().map(|w| w.shape).collect(), &[0.05, 0.5, 0.95]);
                [q[0], q[1], q[2]]
            }
            m => [0.05, 0.5, 0.95].map(|u| m.quantile(u)),
        };
        it.2.push(qs[0]);
        it.3.push(qs[1]);
        it.4.push(qs[2]);
    }
    dir.write_table("inputs", &mut table(vec![scol("input", it.0), scol("unit", it.1), fcol("q05", it.2), fcol("median", it.3), fcol("q95", it.4)])?)
}

/// The plain-language summary.
fn summary(s: &UqStudy, chain: &Chain, prop: &Propagated, ind: &[SobolIndices], varying: &[usize], outputs: &[String], headline: &Headline) -> String {
    let [a, b] = [&chain.materials[0], &chain.materials[1]];
    let mut md = format!("# {} against {}: breakage over {} years, with its uncertainty\n\n", a.label, b.label, chain.years.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" and "));
    md.push_str(&format!(
        "{} Monte Carlo samples ({:?}, {} independent blocks for the standard errors) of every uncertain input; damage model of the headline: {}.\n\n",
        prop.count(),
        s.propagation.method,
        prop.blocks.len(),
        chain.models[0].label()
    ));
    md.push_str("## Headline\n\n");
    for l in &headline.lines {
        md.push_str(&format!("* {l}\n"));
    }
    md.push_str("\n| material | horizon | median P | 90 % band |\n|---|---|---|---|\n");
    for j in 0..2 {
        for (h, years) in chain.years.iter().enumerate() {
            let q = crate::stats::interpolated_quantiles(prop.values(chain.slot(j, h, 0)), &[0.05, 0.5, 0.95]);
            md.push_str(&format!("| {} | {} yr | {:.2e} | {:.1e} – {:.1e} |\n", chain.materials[j].label, years, q[1], q[0], q[2]));
        }
    }
    md.push_str("\n## What drives it (Sobol' total indices, last horizon)\n\n");
    for (o, si) in ind.iter().enumerate() {
        let mut order: Vec<usize> = (0..varying.len()).collect();
        order.sort_by(|&p, &q| si.total[q].total_cmp(&si.total[p]));
        let top: Vec<String> = order.iter().take(3).map(|&k| format!("{} (S_T = {:.2}, S = {:.2})", chain.inputs[varying[k]].name, si.total[k], si.first[k])).collect();
        md.push_str(&format!("* `{}`: {}\n", outputs[o], top.join("; ")));
        let neg: Vec<String> = si.negative().iter().map(|&k| chain.inputs[varying[k]].name.clone()).collect();
        if !neg.is_empty() {
            md.push_str(&format!("  (negative estimates, i.e. zero within Monte Carlo error: {})\n", neg.join(", ")));
        }
    }
    md.push_str("\n## Damage models side by side\n\n| model | horizon | P(candidate worse) | both equal | ");
    md.push_str(&format!("median P {} | median P {} |\n|---|---|---|---|---|---|\n", a.label, b.label));
    for &(model, years, worse, _, ties, med_a, med_b) in &headline.rows {
        md.push_str(&format!("| {} | {} yr | {:.3} | {:.3} | {:.2e} | {:.2e} |\n", model.label(), years, worse, ties, med_a, med_b));
    }
    md.push_str(&format!(
        "\nCrush data: {} N = {} (m̂ = {:.2}, σ̂_θ = {:.0} MPa), {} N = {} (m̂ = {:.2}, σ̂_θ = {:.0} MPa); Weibull uncertainty by {:?}.\n",
        a.label, a.fit.0, a.fit.1, a.fit.2 / 1e6, b.label, b.fit.0, b.fit.1, b.fit.2 / 1e6, s.weibull.uncertainty
    ));
    md.push_str("\nIndependent trials treat every impact as a new chance to break; Tavares–King treats a particle as a fixed flaw population that only breaks earlier when damage accumulates, so it gives far smaller probabilities; Vogel–Peukert has an energy threshold below which nothing breaks. The spread between the models is model-form uncertainty that more crush data cannot remove: it needs repeated-impact tests.\n");
    md
}
