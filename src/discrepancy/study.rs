//! The `kind = "discrepancy"` study file and what its run computes per material (the types the
//! run fills and the report writes).

use serde::{Deserialize, Serialize};

use super::workflow::{MIN_PARTICLES, Outcome};
use crate::error::Result;
use crate::strength::specimens::{Factors, SizeSpec};
use crate::strength::{NamingSettings, Sample};
use crate::schema::{ContactOptions, FigureOptions, ImpactOptions, MaterialSpec, check, elastic_checked};

/// Options of the lifetime bands.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LifetimeOptions {
    /// Parametric-bootstrap replicates of the 90 % bands (default 200): the lifetime's, and each
    /// failure origin's modulus and scale (`origins.csv`).
    pub bootstrap: usize,
}

impl Default for LifetimeOptions {
    fn default() -> Self {
        LifetimeOptions { bootstrap: 200 }
    }
}

/// Options of the detection-power study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PowerOptions {
    /// Sample sizes (default 20, 40, 80, 160).
    pub particles: Vec<usize>,
    /// Synthetic datasets per size and scenario (default 40; 0 switches the study off).
    pub replicates: usize,
    /// Bootstrap replicates per round inside each (default 199).
    pub bootstrap: usize,
}

impl Default for PowerOptions {
    fn default() -> Self {
        PowerOptions { particles: vec![20, 40, 80, 160], replicates: 40, bootstrap: 199 }
    }
}

/// A discrepancy study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscrepancyStudy {
    /// `discrepancy`.
    pub kind: String,
    /// Seed of every random draw.
    pub seed: u64,
    /// Crush contact (the strength reduction).
    #[serde(default)]
    pub contact: ContactOptions,
    /// Impacts (the lifetime change).
    #[serde(default)]
    pub impact: ImpactOptions,
    /// The naming loop.
    #[serde(default)]
    pub discrepancy: NamingSettings,
    /// The lifetime bands.
    #[serde(default)]
    pub lifetime: LifetimeOptions,
    /// The detection-power study.
    #[serde(default)]
    pub power: PowerOptions,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
    /// Crush datasets, one per material.
    #[serde(default)]
    pub material: Vec<MaterialSpec>,
    /// Strength files (specimens with their strengths, a size measure and recorded factors).
    #[serde(default)]
    pub strength: Vec<SpecimenSet>,
}

/// A strength file of a discrepancy study (`[[strength]]`;
/// [`crate::strength::specimens`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpecimenSet {
    /// Short key used in tables: lowercase letters, digits, underscore.
    pub key: String,
    /// Label for figures.
    pub label: String,
    /// The file, or how to read it (`{ file = "…", units = { strength = "MPa" }, … }`).
    pub data: crate::intake::DataRef,
    /// The size measure, if the specimens differ in size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<SizeSpec>,
    /// The recorded factors: `["lab", "rate"]` or `{ lab = "categorical", rate = "numeric" }`.
    #[serde(default)]
    pub factors: Factors,
    /// Laws offered as candidates in place of the one Weibull law: two flaw populations and a
    /// threshold strength, `["mixture", "competing_risks", "threshold"]` or a part of it; `[]`
    /// for none. Default ([`SpecimenSet::offered`]): all three, and without the latent
    /// competing-risks law (two populations, causes unknown) where `origin` makes the causes
    /// known. Each bootstrap replicate refits them from six or seven starts (the Jahanmir
    /// study's 480 bars with 499 replicates: 7 s on two cores).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub populations: Option<Vec<crate::strength::flaws::Populations>>,
    /// The column naming each specimen's failure origin (fractography: volume, surface, edge,
    /// pore …): each origin's law with the other origins' breaks censored (ASTM C1239) and the
    /// test of one shared modulus ([`crate::strength::origins`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<String>,
}

impl SpecimenSet {
    /// The laws the naming loop offers ([`SpecimenSet::populations`]): the study's list, else
    /// the mixture, the threshold law and — where no `origin` column names the causes — the
    /// latent competing-risks law.
    pub fn offered(&self) -> Vec<crate::strength::flaws::Populations> {
        use crate::strength::flaws::Populations;
        match &self.populations {
            Some(list) => list.clone(),
            None if self.origin.is_some() => vec![Populations::Mixture, Populations::Threshold],
            None => vec![Populations::Mixture, Populations::Competing, Populations::Threshold],
        }
    }

    /// Whether the default left out the latent competing-risks law because the origins are
    /// known (for the summary to say).
    pub fn competing_left_out(&self) -> bool {
        self.populations.is_none() && self.origin.is_some()
    }
}

/// Column names of `residuals.csv` a factor may not take.
pub const RESERVED_COLUMNS: [&str; 7] = ["material", "id", "stage", "strength_pa", "adjusted_pa", "residual", "failure_origin"];

impl DiscrepancyStudy {
    /// Validates every option (file named in messages).
    pub fn validate(&self, file: &str) -> Result<()> {
        elastic_checked(file, "contact.platen", &self.contact.platen)?;
        self.contact.averaging.validate(file, "contact.averaging")?;
        elastic_checked(file, "impact.target", &self.impact.target)?;
        let i = &self.impact;
        check(file, "impact.energy_fraction", i.energy_fraction > 0.0 && i.energy_fraction <= 1.0, format!("must lie in (0, 1] (got {})", i.energy_fraction))?;
        check(file, "impact.reference_velocity_m_s", i.reference_velocity_m_s > 0.0 && i.reference_velocity_m_s <= crate::lifetime::MAX_VELOCITY, format!("must lie in (0, {}] m/s (got {})", crate::lifetime::MAX_VELOCITY, i.reference_velocity_m_s))?;
        check(file, "impact.impacts_per_year", i.impacts_per_year > 0.0 && i.impacts_per_year.is_finite(), format!("must be > 0 (got {})", i.impacts_per_year))?;
        check(file, "impact.years", !i.years.is_empty() && i.years.iter().all(|y| *y > 0.0 && y.is_finite()), format!("needs at least one horizon, each > 0 (got {:?})", i.years))?;
        self.discrepancy.validate(file, "discrepancy")?;
        check(file, "lifetime.bootstrap", self.lifetime.bootstrap >= 20, format!("must be ≥ 20 (got {})", self.lifetime.bootstrap))?;
        let p = &self.power;
        if p.replicates > 0 {
            check(file, "power.particles", !p.particles.is_empty() && p.particles.iter().all(|n| *n >= MIN_PARTICLES && *n <= 100_000), format!("sizes must lie in [{MIN_PARTICLES}, 100000] (got {:?})", p.particles))?;
            check(file, "power.bootstrap", p.bootstrap >= 99, format!("must be ≥ 99 (got {})", p.bootstrap))?;
        }
        self.figures.validate(file)?;
        check(file, "material", !self.material.is_empty() || !self.strength.is_empty(), "at least one [[material]] (crush data) or [[strength]] (strength file) is required".into())?;
        let mut keys = Vec::new();
        for (k, m) in self.strength.iter().enumerate() {
            let key = |s: &str| format!("strength[{k}].{s}");
            check(file, &key("key"), !m.key.is_empty() && m.key.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'), format!("must be lowercase letters, digits or _ (got \"{}\")", m.key))?;
            check(file, &key("key"), !keys.contains(&m.key), format!("\"{}\" is used twice", m.key))?;
            keys.push(m.key.clone());
            m.data.validate(file, &key("data"))?;
            let names: Vec<String> = m.size.iter().map(|s| s.column.clone()).chain(m.factors.declared().into_iter().map(|d| d.0)).collect();
            for n in &names {
                check(file, &key("factors"), !n.trim().is_empty(), "a factor or size column's name is empty".into())?;
                check(file, &key("factors"), !RESERVED_COLUMNS.contains(&n.as_str()) && !crate::data::COVARIATE_COLUMNS.contains(&n.as_str()), format!("`{n}` is a name the report's tables use ({}, {}): rename the column in the file", RESERVED_COLUMNS.join(", "), crate::data::COVARIATE_COLUMNS.join(", ")))?;
                check(file, &key("factors"), names.iter().filter(|x| *x == n).count() == 1, format!("`{n}` is declared twice (a size measure is not also a factor)"))?;
            }
        }
        for (k, m) in self.material.iter().enumerate() {
            let key = |s: &str| format!("material[{k}].{s}");
            check(file, &key("key"), !m.key.is_empty() && m.key.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'), format!("must be lowercase letters, digits or _ (got \"{}\")", m.key))?;
            check(file, &key("key"), !keys.contains(&m.key), format!("\"{}\" is used twice", m.key))?;
            keys.push(m.key.clone());
            elastic_checked(file, &key("elastic"), &m.elastic)?;
            check(file, &key("density_kg_m3"), m.density_kg_m3 > 0.0 && m.density_kg_m3.is_finite(), format!("must be > 0 (got {})", m.density_kg_m3))?;
        }
        Ok(())
    }

    pub(super) fn settings(&self) -> NamingSettings {
        NamingSettings { seed: self.seed, ..self.discrepancy.clone() }
    }
}

/// Lifetime prediction of one model: per horizon (median-free point estimate, 5 %, 95 %).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LifetimeBand {
    /// Horizon (years).
    pub years: f64,
    /// Point estimate from the fitted model.
    pub estimate: f64,
    /// 5 % bootstrap quantile.
    pub q05: f64,
    /// 95 % bootstrap quantile.
    pub q95: f64,
}

/// Detection power at one sample size.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PowerRow {
    /// `effects` (data drawn from the fitted final model) or `none` (from the base model).
    pub scenario: String,
    /// Sample size.
    pub particles: usize,
    /// Datasets run.
    pub replicates: usize,
    /// Datasets in which the first effect named in the data was named first (`effects`), or
    /// any effect was named (`none`).
    pub first: usize,
    /// Datasets in which every effect named in the data was named (`effects`); = `first` for `none`.
    pub all: usize,
}

/// Everything computed for one material (crush data) or strength file.
pub struct MaterialResult {
    /// Key in tables.
    pub key: String,
    /// Label.
    pub label: String,
    /// The data file.
    pub path: std::path::PathBuf,
    /// Specimen (particle) ids, in the sample's order.
    pub ids: Vec<String>,
    /// The crush material as declared (None for a strength file: no lifetime).
    pub crush: Option<MaterialSpec>,
    /// σ̄ at break (or specimen strength) and covariates.
    pub sample: Sample,
    /// The naming loop.
    pub outcome: Outcome,
    /// Lifetime bands of the base and the final model.
    pub lifetime: Vec<(String, Vec<LifetimeBand>)>,
    /// Detection power (empty when off).
    pub power: Vec<PowerRow>,
    /// Each specimen's test temperature (°C).
    pub temperatures_c: Vec<f64>,
    /// Each failure origin's law and the shared-modulus test (a strength file with `origin`).
    pub origins: Option<crate::strength::origins::Origins>,
    /// Each specimen's failure origin, where the study names the column (empty otherwise).
    pub failure_origins: Vec<String>,
    /// What the file's reading says the summary must repeat
    /// ([`crate::intake::Provenance::summary_notes`]): columns not
    /// used or ignored, rows counting several specimens (and those counting none, dropped),
    /// failure-origin labels read as one, origins on specimens that did not break.
    pub read_notes: Vec<String>,
}


