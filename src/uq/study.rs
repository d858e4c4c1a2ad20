//! The `kind = "uq"` study file: the main study comparing two particle types.
//!
//! ```toml
//! kind = "uq"
//! seed = 1
//! compare = { candidate = "gen4", reference = "bl1630" }
//! [contact]        # crush contact (platen, averaging domain), as in a lifetime study
//! [impact]         # target, years, impacts_per_year, energy_fraction, velocity (distributions)
//! [strength]       # effects = [] | [...] | "diagnosed", uncertainty, draws, [strength.naming]
//! [damage]         # models, primary, gamma (Tavares–King coefficient distribution)
//! [propagation]    # method = "plain" | "lhs" | "sobol", samples, replicates
//! [sensitivity]    # n (Saltelli base size), bootstrap, level
//! [model_form]     # strength = [...] (strength models compared and averaged), averaging = [...]
//! [operating]      # optional: law = "temperature.toml", temperature_c = {…}, material = { key = {…} }
//! [[material]]     # key, label, data, elastic, density_kg_m3, impact_diameter_m, population
//! ```
//!
//! Without `[operating]` the chain runs at the crush data's temperature (room temperature for the
//! shipped data). With it, each material runs at its operating temperature (a declared
//! distribution, in °C): the Weibull scale and the particle's Young's modulus move by the
//! temperature laws of the named temperature study ([`crate::thermal`]), one joint draw of the
//! laws per sample (input `temperature_law`).

use serde::{Deserialize, Serialize};

use crate::contact::{AveragingDomain, ContactOptions, Elastic};
use crate::dist::Dist;
use crate::error::{Error, Result};
use crate::lifetime::damage::DamageModel;
use crate::strength::{StrengthOptions, StrengthSpec};
use crate::schema::{FigureOptions, MaterialSpec};

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
    /// Samples in all (per strength model).
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

/// Model-form alternatives (the damage models are compared in every run).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ModelForm {
    /// Strength models compared side by side and averaged with stacking weights; the
    /// `[strength] effects` model (the primary) must be one of them. Empty: the primary alone.
    pub strength: Vec<StrengthSpec>,
    /// Other averaging domains of σ̄: each reruns the chain with the deliverable's strength
    /// model (its own Weibull refit of the crush data) with a quarter of the samples;
    /// `averaging.csv` compares them.
    pub averaging: Vec<AveragingDomain>,
    /// The study states the deliverable's hypothesis — accounting for the particles' shape
    /// (roundness, non-sphericity) makes the lifetime model favour the candidate — and the
    /// summary tests it against the strength models with shape effects fitted to both
    /// materials' data. Not stated (the default), or no such model (no shape columns), and the
    /// summary says nothing of it.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub shape_hypothesis: bool,
}

/// `[operating]`: the operating temperature of each material and the temperature study whose
/// laws carry the strength model there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Operating {
    /// A `kind = "temperature"` study with `[phases]` and `[law]`, relative to this study.
    pub law: std::path::PathBuf,
    /// Operating temperature (°C) of every material not listed in `material`.
    pub temperature_c: Option<Dist>,
    /// Operating temperature (°C) per material key.
    #[serde(default)]
    pub material: std::collections::BTreeMap<String, Dist>,
}

impl Operating {
    /// The operating temperature of material `key` and the study key it is declared at.
    pub fn of(&self, key: &str) -> Option<(&Dist, String)> {
        match self.material.get(key) {
            Some(d) => Some((d, format!("operating.material.{key}"))),
            None => self.temperature_c.as_ref().map(|d| (d, "operating.temperature_c".to_string())),
        }
    }
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
    /// The strength model (the primary of the model-form comparison).
    #[serde(default)]
    pub strength: StrengthOptions,
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
    /// Operating temperatures (absent: the crush data's temperature).
    #[serde(default)]
    pub operating: Option<Operating>,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
    /// Exactly two particle types.
    pub material: Vec<MaterialSpec>,
}

impl UqStudy {
    /// The strength models compared: the primary first, then the others in the file's order.
    pub fn specs(&self) -> Vec<StrengthSpec> {
        let mut out = vec![self.strength.effects.clone()];
        out.extend(self.model_form.strength.iter().filter(|s| **s != self.strength.effects).cloned());
        out
    }

    /// The candidate's and the reference's index in `material`.
    pub fn order(&self) -> [usize; 2] {
        let pos = |k: &str| self.material.iter().position(|m| m.key == k).unwrap_or(0);
        [pos(&self.compare.candidate), pos(&self.compare.reference)]
    }

    /// The studies whose reports it reads (study file at `path`): those of the temperature
    /// study its `[operating] law` names (that study is read, not run).
    pub fn prerequisites(&self, path: &std::path::Path) -> Result<Vec<crate::schema::Prerequisite>> {
        match &self.operating {
            Some(op) => {
                let law = crate::schema::resolve_relative(path, &op.law);
                if !law.is_file() {
                    return Ok(Vec::new());
                }
                crate::thermal::law_prerequisites_of_study(&law)
            }
            None => Ok(Vec::new()),
        }
    }

    /// [`UqStudy::prerequisites`] of the main study file at `path` (none when it is not a main
    /// study: its reader says so).
    pub fn prerequisites_of_file(path: &std::path::Path) -> Result<Vec<crate::schema::Prerequisite>> {
        if !path.is_file() {
            return Ok(Vec::new());
        }
        let f = crate::schema::StudyFile::read(path)?;
        match f.parse::<UqStudy>() {
            Ok(u) => u.prerequisites(path),
            Err(_) => Ok(Vec::new()),
        }
    }

    /// Checks every option that needs no data (file named in messages).
    pub fn validate(&self, file: &str) -> Result<()> {
        let bad = |k: &str, rule: String| Err(Error::config(file, k, rule));
        if self.material.len() != 2 {
            return bad("material", format!("a UQ study compares exactly two [[material]]s, got {}", self.material.len()));
        }
        let pos = |k: &str, key: &str| -> Result<usize> {
            self.material.iter().position(|m| m.key == k).ok_or_else(|| Error::config(file, key, format!("`{k}` is not a material key ({}, {})", self.material[0].key, self.material[1].key)))
        };
        if pos(&self.compare.candidate, "compare.candidate")? == pos(&self.compare.reference, "compare.reference")? {
            return bad("compare", "candidate and reference must differ".into());
        }
        if self.impact.years.is_empty() || self.impact.years.iter().any(|y| !(y.is_finite() && *y > 0.0)) {
            return bad("impact.years", format!("every horizon must be a finite number of years > 0, got {:?}", self.impact.years));
        }
        let [vlo, vhi] = self.impact.velocity_range;
        if !(vlo > 0.0 && vlo < vhi && vhi <= crate::lifetime::MAX_VELOCITY) {
            return bad("impact.velocity_range", format!("needs 0 < low < high ≤ {} m/s, got [{vlo}, {vhi}]", crate::lifetime::MAX_VELOCITY));
        }
        crate::schema::elastic_checked(file, "impact.target", &self.impact.target)?;
        crate::schema::elastic_checked(file, "contact.platen", &self.contact.platen)?;
        self.contact.averaging.validate(file, "contact.averaging")?;
        self.strength.validate(file, &self.contact.averaging)?;
        for (i, spec) in self.model_form.strength.iter().enumerate() {
            let key = format!("model_form.strength[{i}]");
            spec.validate(file, &key, &self.contact.averaging)?;
            if self.model_form.strength[..i].contains(spec) {
                return bad(&key, format!("the strength model `{}` is listed twice", spec.name()));
            }
        }
        if !self.model_form.strength.is_empty() && !self.model_form.strength.contains(&self.strength.effects) {
            return bad("strength.effects", format!("the primary strength model `{}` must be one of model_form.strength ({})", self.strength.effects.name(), self.model_form.strength.iter().map(|s| s.name()).collect::<Vec<_>>().join(", ")));
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
        if self.impact.years.len() * self.damage.models.len() > 32 {
            return bad("impact.years", "at most 32 horizon × damage-model pairs".into());
        }
        for (i, d) in self.model_form.averaging.iter().enumerate() {
            d.validate(file, &format!("model_form.averaging[{i}]"))?;
        }
        for (d, key) in [(&self.impact.energy_fraction, "impact.energy_fraction"), (&self.impact.impacts_per_year, "impact.impacts_per_year"), (&self.damage.gamma, "damage.gamma")] {
            if matches!(d, Dist::Spectrum { .. }) {
                return bad(key, "a spectrum is a velocity distribution only".into());
            }
        }
        for (i, m) in self.material.iter().enumerate() {
            let key = |k: &str| format!("material[{i}].{k}");
            if !(!m.key.is_empty() && m.key.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')) {
                return bad(&key("key"), format!("must be lowercase letters, digits or _ (got \"{}\")", m.key));
            }
            crate::schema::elastic_checked(file, &key("elastic"), &m.elastic)?;
            if !(m.density_kg_m3 > 0.0 && m.density_kg_m3.is_finite()) {
                return bad(&key("density_kg_m3"), format!("must be > 0, got {}", m.density_kg_m3));
            }
            if let Some(d) = m.impact_diameter_m
                && !crate::data::DIAMETER.contains(d)
            {
                return bad(&key("impact_diameter_m"), format!("must lie in {}, got {d}", crate::data::DIAMETER.shown));
            }
        }
        if let Some(op) = &self.operating {
            for k in op.material.keys() {
                if !self.material.iter().any(|m| &m.key == k) {
                    return bad(&format!("operating.material.{k}"), format!("`{k}` is not a material key ({}, {})", self.material[0].key, self.material[1].key));
                }
            }
            for m in &self.material {
                match op.of(&m.key) {
                    None => return bad("operating.temperature_c", format!("material `{}` has no operating temperature: give operating.temperature_c or operating.material.{}", m.key, m.key)),
                    Some((Dist::Spectrum { .. }, key)) => return bad(&key, "a spectrum is a velocity distribution only".into()),
                    Some(_) => {}
                }
            }
        }
        self.figures.validate(file)
    }
}
