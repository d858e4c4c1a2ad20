//! Study files: TOML schema (unknown keys rejected), validation and dispatch.
//!
//! A study file `studies/<name>.toml` maps one-to-one to `reports/<name>/`. It starts with two
//! comment lines (purpose; what a good result looks like) and names its kind:
//!
//! ```toml
//! kind = "lifetime"
//! seed = 20261121
//! [contact]            # platen and averaging domain of the tensile stress
//! [impact]             # wall, η, velocities, impact counts, impacts per year
//! [weibull]            # confidence level, pivotal samples, shape estimate
//! [figures]            # width
//! [[material]]         # one per particle type: data file, elastic constants, density
//! ```
//!
//! Every option has a documented default (the `Default` impls below); the manifest records the
//! study with defaults filled in. Relative paths are resolved against the study file's
//! directory. Validation failures name the file, the dotted key and the rule.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

pub use crate::contact::ContactOptions;
use crate::contact::Elastic;
use crate::error::{Error, Result};

/// Parses TOML into `T`; a syntax error, a wrong type or an unknown key becomes one
/// [`Error::Config`] naming the file, the line and the key.
pub fn parse_toml<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T> {
    toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
        let snippet = e
            .span()
            .and_then(|s| text.get(s.clone()))
            .map(|s| s.lines().next().unwrap_or("").trim().to_string())
            .filter(|s| !s.is_empty());
        let key = match (line, snippet) {
            (Some(l), Some(s)) => format!("line {l} (`{s}`)"),
            (Some(l), None) => format!("line {l}"),
            _ => "document".into(),
        };
        Error::config(path.display().to_string(), key, e.message().trim().to_string())
    })
}

fn steel() -> Elastic {
    Elastic { youngs_modulus_pa: 210e9, poisson_ratio: 0.3 }
}

/// Impact options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImpactOptions {
    /// Wall (tube) material hit by the particles (default: steel).
    pub target: Elastic,
    /// Elastic energy fraction η ∈ (0, 1] (default 0.1, the deliverable's "trial and error").
    pub energy_fraction: f64,
    /// Largest velocity of the curves (m/s, default 20).
    pub velocity_max_m_s: f64,
    /// Number of velocities on the curves (default 201).
    pub velocity_points: usize,
    /// Impact counts N of the breakage curves (default 1, 100, 2100, 7300).
    pub impact_counts: Vec<f64>,
    /// High-velocity impacts per particle and year (default 730).
    pub impacts_per_year: f64,
    /// Operating horizons (years) of the summary table (default 1 and 10).
    pub years: Vec<f64>,
    /// Velocity of the force–time figure and the summary table (m/s, default 5, "maximum
    /// velocities on the order of 5 m/s" after the receiver).
    pub reference_velocity_m_s: f64,
}

impl Default for ImpactOptions {
    fn default() -> Self {
        ImpactOptions {
            target: steel(),
            energy_fraction: 0.1,
            velocity_max_m_s: 20.0,
            velocity_points: 201,
            impact_counts: vec![1.0, 100.0, 2100.0, 7300.0],
            impacts_per_year: crate::lifetime::IMPACTS_PER_YEAR,
            years: vec![1.0, 10.0],
            reference_velocity_m_s: 5.0,
        }
    }
}

/// Which modulus estimate drives predictions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeEstimate {
    /// The maximum-likelihood m̂ (biased high for small N).
    Mle,
    /// C1239's unbiased UF(N)·m̂ (default: conservative in the lower tail).
    Unbiased,
}

/// Weibull options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WeibullOptions {
    /// Two-sided confidence level of bounds and bands (default 0.90, as C1239).
    pub confidence: f64,
    /// Monte Carlo replicates of the pivotal simulation (default 10 000).
    pub pivotal_samples: usize,
    /// Modulus used for predictions (default `unbiased`).
    pub shape_estimate: ShapeEstimate,
}

impl Default for WeibullOptions {
    fn default() -> Self {
        WeibullOptions { confidence: 0.90, pivotal_samples: 10_000, shape_estimate: ShapeEstimate::Unbiased }
    }
}

/// Figure options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FigureOptions {
    /// Figure width (cm): 8.5 single column (default), 17 double column.
    pub width_cm: f64,
}

impl Default for FigureOptions {
    fn default() -> Self {
        FigureOptions { width_cm: 8.5 }
    }
}

/// One particle type.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Short key used in tables (`bl1630`): lowercase letters, digits, underscore.
    pub key: String,
    /// Label for figures (`BL 16/30`).
    pub label: String,
    /// Crush dataset (CSV), relative to the study file.
    pub data: PathBuf,
    /// Particle elastic constants.
    pub elastic: Elastic,
    /// Particle (apparent) density (kg/m³).
    pub density_kg_m3: f64,
    /// Diameter of the reference particle of the impact outputs (F_max, force history; m);
    /// default: median diameter of the crush data. The breakage does not depend on it.
    #[serde(default)]
    pub impact_diameter_m: Option<f64>,
    /// The particles predicted for (default: the crush data's particles, fresh).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub population: Option<crate::strength::PopulationSpec>,
}

impl MaterialSpec {
    /// The population of material `index` of the study `file` (declared, or the particles of
    /// `data`); declared samples are seeded by `seed` and the index.
    pub fn population(&self, index: usize, data: &crate::data::CrushData, file: &Path, seed: u64) -> Result<crate::strength::Population> {
        match &self.population {
            None => Ok(crate::strength::Population::of_data(data)),
            Some(p) => {
                let resolve = |q: &str| resolve_relative(file, Path::new(q));
                crate::strength::Population::declared(p, &file.display().to_string(), &format!("material[{index}].population"), &resolve, seed ^ (0x909 + index as u64))
            }
        }
    }

    /// The reference particle of the impact outputs: `impact_diameter_m` or the median
    /// diameter of `data`.
    pub fn sphere(&self, data: &crate::data::CrushData) -> crate::contact::Sphere {
        let diameter = self.impact_diameter_m.unwrap_or_else(|| crate::stats::median(&data.diameters()));
        crate::contact::Sphere { diameter, density: self.density_kg_m3, elastic: self.elastic }
    }
}

/// The kinds of study this version can run.
pub const KINDS: [&str; 7] = ["lifetime", "dem", "crush", "calibrate", "uq", "discrepancy", "discrepancy_curves"];

/// A lifetime study (kind = "lifetime"): the deliverable's §6 chain for several materials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LifetimeStudy {
    /// Study kind, `lifetime`.
    pub kind: String,
    /// Seed of every random draw of the run.
    pub seed: u64,
    /// Crush contact.
    #[serde(default)]
    pub contact: ContactOptions,
    /// Impacts.
    #[serde(default)]
    pub impact: ImpactOptions,
    /// Weibull statistics (ASTM C1239 analysis of σ̄ at break).
    #[serde(default)]
    pub weibull: WeibullOptions,
    /// The strength model of the predictions (default: the deliverable's, no effects).
    #[serde(default)]
    pub strength: crate::strength::StrengthOptions,
    /// Figures.
    #[serde(default)]
    pub figures: FigureOptions,
    /// Particle types, at least one.
    pub material: Vec<MaterialSpec>,
}

/// A parsed, validated study.
#[derive(Debug, Clone, PartialEq)]
#[allow(clippy::large_enum_variant)] // one per run: the size difference does not matter
pub enum Study {
    /// kind = "lifetime".
    Lifetime(LifetimeStudy),
    /// kind = "dem": particle flow through the tube bank.
    Dem(Box<crate::dem::run::DemStudy>),
    /// kind = "crush": single-particle crush tests with the FE.
    Crush(Box<crate::fem::run::CrushStudy>),
    /// kind = "calibrate": fit a simulator's parameters to data.
    Calibrate(Box<crate::calibrate::run::CalibrateStudy>),
    /// kind = "uq": Monte Carlo propagation and Sobol' indices of the lifetime chain.
    Uq(Box<crate::uq::study::UqStudy>),
    /// kind = "discrepancy": find, name and add what the strength model misses.
    Discrepancy(Box<crate::discrepancy::run::DiscrepancyStudy>),
    /// kind = "discrepancy_curves": the same at the force–displacement level, against a crush
    /// calibration.
    DiscrepancyCurves(Box<crate::discrepancy::curves::CurveStudy>),
}

/// A study file loaded from disk.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedStudy {
    /// Name = file stem; the report goes to `reports/<name>/`.
    pub name: String,
    /// The file.
    pub path: PathBuf,
    /// Its text, verbatim.
    pub text: String,
    /// The validated content.
    pub study: Study,
}

impl LoadedStudy {
    /// Resolves a path of the study relative to the study file's directory (lexically:
    /// `studies/../datasets/x.csv` becomes `datasets/x.csv`).
    pub fn resolve(&self, p: &Path) -> PathBuf {
        resolve_relative(&self.path, p)
    }
}

/// Resolves `p` relative to the directory of the file `study` (lexically:
/// `studies/../datasets/x.csv` becomes `datasets/x.csv`); absolute paths stay.
pub fn resolve_relative(study: &Path, p: &Path) -> PathBuf {
    if p.is_absolute() {
        return p.to_path_buf();
    }
    let joined = study.parent().unwrap_or(Path::new(".")).join(p);
    let mut out = PathBuf::new();
    for c in joined.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir if matches!(out.components().next_back(), Some(std::path::Component::Normal(_))) => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// Reads, parses and validates a study file.
pub fn load(path: &Path) -> Result<LoadedStudy> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
    let file = path.display().to_string();
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty() && !s.starts_with('.'))
        .ok_or_else(|| Error::config(&file, "file name", "a study file needs a name (its stem names the report)"))?;
    let head: toml::Table = parse_toml(path, &text)?;
    let kind = head
        .get("kind")
        .and_then(|k| k.as_str())
        .ok_or_else(|| Error::config(&file, "kind", format!("required: one of {}", KINDS.join(", "))))?;
    let study = match kind {
        "lifetime" => {
            let s: LifetimeStudy = parse_toml(path, &text)?;
            validate_lifetime(&s, &file)?;
            Study::Lifetime(s)
        }
        "dem" => {
            let s: crate::dem::run::DemStudy = parse_toml(path, &text)?;
            s.setup(&file)?;
            Study::Dem(Box::new(s))
        }
        "crush" => {
            let s: crate::fem::run::CrushStudy = parse_toml(path, &text)?;
            s.setups(&file)?;
            Study::Crush(Box::new(s))
        }
        "calibrate" => {
            let s: crate::calibrate::run::CalibrateStudy = parse_toml(path, &text)?;
            s.prepare(path, &|p: &str| resolve_relative(path, Path::new(p)))?;
            Study::Calibrate(Box::new(s))
        }
        "uq" => {
            let s: crate::uq::study::UqStudy = parse_toml(path, &text)?;
            s.validate(&file)?;
            Study::Uq(Box::new(s))
        }
        "discrepancy" => {
            let s: crate::discrepancy::run::DiscrepancyStudy = parse_toml(path, &text)?;
            s.validate(&file)?;
            Study::Discrepancy(Box::new(s))
        }
        "discrepancy_curves" => {
            let s: crate::discrepancy::curves::CurveStudy = parse_toml(path, &text)?;
            s.validate(&file)?;
            Study::DiscrepancyCurves(Box::new(s))
        }
        other => {
            return Err(Error::config(&file, "kind", format!("unknown kind \"{other}\"; known: {}", KINDS.join(", "))));
        }
    };
    Ok(LoadedStudy { name, path: path.to_path_buf(), text, study })
}

/// `Ok` if `ok`, else a configuration error naming `file`, `key` and `rule`.
pub(crate) fn check(file: &str, key: &str, ok: bool, rule: String) -> Result<()> {
    if ok { Ok(()) } else { Err(Error::config(file, key, rule)) }
}

/// Checks elastic constants, naming the study file and key.
pub fn elastic_checked(file: &str, key: &str, e: &Elastic) -> Result<()> {
    elastic(file, key, e)
}

fn elastic(file: &str, key: &str, e: &Elastic) -> Result<()> {
    e.validate(key).map_err(|err| match err {
        Error::Config { key, rule, .. } => Error::config(file, key, rule),
        other => other,
    })
}

/// Validates every option of a lifetime study.
pub fn validate_lifetime(s: &LifetimeStudy, file: &str) -> Result<()> {
    elastic(file, "contact.platen", &s.contact.platen)?;
    s.contact.averaging.validate(file, "contact.averaging")?;
    s.strength.validate(file, &s.contact.averaging)?;
    let i = &s.impact;
    elastic(file, "impact.target", &i.target)?;
    check(
        file,
        "impact.energy_fraction",
        i.energy_fraction > 0.0 && i.energy_fraction <= 1.0,
        format!("the elastic energy fraction η must lie in (0, 1] (got {})", i.energy_fraction),
    )?;
    let vmax = crate::lifetime::MAX_VELOCITY;
    check(
        file,
        "impact.velocity_max_m_s",
        i.velocity_max_m_s > 0.0 && i.velocity_max_m_s <= vmax,
        format!("must lie in (0, {vmax}] m/s (got {})", i.velocity_max_m_s),
    )?;
    check(
        file,
        "impact.velocity_points",
        (2..=100_000).contains(&i.velocity_points),
        format!("must lie in [2, 100000] (got {})", i.velocity_points),
    )?;
    check(
        file,
        "impact.impact_counts",
        !i.impact_counts.is_empty() && i.impact_counts.iter().all(|n| n.is_finite() && *n >= 1.0),
        format!("needs at least one count, each ≥ 1 (got {:?})", i.impact_counts),
    )?;
    check(
        file,
        "impact.impacts_per_year",
        i.impacts_per_year.is_finite() && i.impacts_per_year > 0.0,
        format!("must be > 0 (got {})", i.impacts_per_year),
    )?;
    check(
        file,
        "impact.years",
        !i.years.is_empty() && i.years.iter().all(|y| y.is_finite() && *y > 0.0),
        format!("needs at least one horizon, each > 0 (got {:?})", i.years),
    )?;
    check(
        file,
        "impact.reference_velocity_m_s",
        i.reference_velocity_m_s > 0.0 && i.reference_velocity_m_s <= vmax,
        format!("must lie in (0, {vmax}] m/s (got {})", i.reference_velocity_m_s),
    )?;
    let w = &s.weibull;
    check(
        file,
        "weibull.confidence",
        w.confidence > 0.0 && w.confidence < 1.0,
        format!("must lie in (0, 1) (got {})", w.confidence),
    )?;
    check(
        file,
        "weibull.pivotal_samples",
        (1000..=10_000_000).contains(&w.pivotal_samples),
        format!("must lie in [1000, 10000000] (got {})", w.pivotal_samples),
    )?;
    check(
        file,
        "figures.width_cm",
        s.figures.width_cm >= 5.0 && s.figures.width_cm <= 40.0,
        format!("must lie in [5, 40] cm (got {})", s.figures.width_cm),
    )?;
    check(file, "material", !s.material.is_empty(), "at least one [[material]] is required".into())?;
    for (k, m) in s.material.iter().enumerate() {
        let key = |f: &str| format!("material[{k}].{f}");
        check(
            file,
            &key("key"),
            !m.key.is_empty() && m.key.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_'),
            format!("must be non-empty lowercase letters, digits or _ (got \"{}\")", m.key),
        )?;
        check(
            file,
            &key("key"),
            !s.material[..k].iter().any(|o| o.key == m.key),
            format!("duplicate material key \"{}\"", m.key),
        )?;
        elastic(file, &key("elastic"), &m.elastic)?;
        check(
            file,
            &key("density_kg_m3"),
            m.density_kg_m3.is_finite() && m.density_kg_m3 > 0.0,
            format!("must be > 0 (got {})", m.density_kg_m3),
        )?;
        if let Some(d) = m.impact_diameter_m {
            check(
                file,
                &key("impact_diameter_m"),
                d.is_finite() && d > 0.0 && d <= 0.1,
                format!("must be > 0 and ≤ 0.1 m (got {d})"),
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: &str = r#"
kind = "lifetime"
seed = 1
[[material]]
key = "a"
label = "A"
data = "a.csv"
elastic = { youngs_modulus_pa = 112e9, poisson_ratio = 0.25 }
density_kg_m3 = 3600
"#;

    #[test]
    fn defaults_fill_in() {
        let s: LifetimeStudy = parse_toml(Path::new("s.toml"), MIN).unwrap();
        validate_lifetime(&s, "s.toml").unwrap();
        assert_eq!(s.impact.energy_fraction, 0.1);
        assert_eq!(s.impact.impact_counts, vec![1.0, 100.0, 2100.0, 7300.0]);
        assert_eq!(s.weibull.shape_estimate, ShapeEstimate::Unbiased);
    }

    #[test]
    fn unknown_keys_name_the_line() {
        let text = MIN.replace("seed = 1", "seed = 1\nsede = 2");
        let e = parse_toml::<LifetimeStudy>(Path::new("s.toml"), &text).unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("line 4") && e.contains("sede"), "{e}");
    }

    #[test]
    fn impossible_options_are_rejected() {
        let text = MIN.replace("seed = 1", "seed = 1\n[impact]\nenergy_fraction = 0.0");
        let s: LifetimeStudy = parse_toml(Path::new("s.toml"), &text).unwrap();
        let e = validate_lifetime(&s, "s.toml").unwrap_err().to_string();
        assert!(e.contains("impact.energy_fraction") && e.contains("(0, 1]"), "{e}");
    }
}
