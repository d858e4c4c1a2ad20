//! Distributions declared in study files (`{ distribution = "…", … }`) and the DEM
//! impact-velocity spectrum, as marginals sampled by their inverse CDF.
//!
//! Every marginal is sampled from a uniform u ∈ [0, 1], so plain Monte Carlo, Latin hypercube
//! and Sobol' points, the Saltelli designs of the sensitivity analysis and the stratified
//! particle populations of the strength model all use the same code.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::params::{Param, Prior};

/// A distribution declared in a study file (`{ distribution = "…", … }`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "distribution", rename_all = "snake_case", deny_unknown_fields)]
pub enum Dist {
    /// A known value.
    Fixed {
        /// The value.
        value: f64,
    },
    /// Uniform on [min, max].
    Uniform {
        /// Lower end.
        min: f64,
        /// Upper end.
        max: f64,
    },
    /// Normal truncated to [min, max].
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation, > 0.
        sd: f64,
        /// Lower truncation.
        min: f64,
        /// Upper truncation.
        max: f64,
    },
    /// Log-normal (ln x normal) truncated to [min, max].
    LogNormal {
        /// Median exp(μ), > 0.
        median: f64,
        /// sd of ln x, > 0.
        sd_log: f64,
        /// Lower truncation, > 0.
        min: f64,
        /// Upper truncation.
        max: f64,
    },
    /// (velocity only) the normal impact velocities of a DEM impact spectrum
    /// (`partlife run` of a `kind = "dem"` study writes `impact_spectrum.csv`): its quantile
    /// function, linear between the tabulated quantiles, from 0 at p = 0 and held at the
    /// highest quantile above it, times `scale`.
    Spectrum {
        /// The spectrum file, relative to the study.
        file: String,
        /// `tube` or `particle`.
        #[serde(default = "tube")]
        target: String,
        /// Row of the bank (0 = all rows).
        #[serde(default)]
        row: u32,
        /// Factor on every velocity (a different drop height than the rig's, say).
        #[serde(default = "one")]
        scale: f64,
    },
}

fn tube() -> String {
    "tube".into()
}

fn one() -> f64 {
    1.0
}

/// A marginal ready to sample.
#[derive(Debug, Clone, PartialEq)]
pub enum Marginal {
    /// A constant.
    Fixed(f64),
    /// A truncated prior.
    Param(Param),
    /// A piecewise-linear quantile function: values `v` at probabilities `p` (ascending from 0,
    /// v ascending).
    Quantiles {
        /// Probabilities.
        p: Vec<f64>,
        /// Values.
        v: Vec<f64>,
    },
    /// One of K joint draws (of a strength model's parameters): the value is the draw's index.
    Index(usize),
}

impl Marginal {
    /// Whether u matters.
    pub fn varies(&self) -> bool {
        !matches!(self, Marginal::Fixed(_))
    }

    /// The value at u ∈ [0, 1] (for joint draws: the draw's index ⌊u·K⌋).
    pub fn quantile(&self, u: f64) -> f64 {
        match self {
            Marginal::Fixed(v) => *v,
            Marginal::Param(p) => p.quantile(u),
            Marginal::Quantiles { p, v } => {
                if u >= p[p.len() - 1] {
                    return v[v.len() - 1];
                }
                crate::stats::lerp(v, crate::stats::locate(p, u))
            }
            Marginal::Index(k) => ((u * *k as f64) as usize).min(k - 1) as f64,
        }
    }
}

impl Dist {
    /// Builds the marginal; `file` and `key` name the study key in errors; `resolve` maps a
    /// study-relative path.
    pub fn marginal(&self, file: &str, key: &str, unit: &str, resolve: &dyn Fn(&str) -> std::path::PathBuf) -> Result<Marginal> {
        let bad = |rule: String| Err(Error::config(file, key, rule));
        let param = |prior: Prior, lower: f64, upper: f64| -> Result<Marginal> {
            let p = Param { name: key.into(), unit: unit.into(), lower, upper, prior, nominal: 0.5 * (lower + upper) };
            p.check().map_err(|e| Error::config(file, key, e.to_string()))?;
            Ok(Marginal::Param(p))
        };
        match self {
            Dist::Fixed { value } => {
                if !value.is_finite() {
                    return bad(format!("the value must be finite, got {value}"));
                }
                Ok(Marginal::Fixed(*value))
            }
            Dist::Uniform { min, max } => {
                if !(min.is_finite() && max.is_finite() && min < max) {
                    return bad(format!("needs finite min < max, got [{min}, {max}]"));
                }
                param(Prior::Uniform, *min, *max)
            }
            Dist::Normal { mean, sd, min, max } => {
                if !(sd.is_finite() && *sd > 0.0) {
                    return bad(format!("sd must be a finite number > 0, got {sd}"));
                }
                if !(min.is_finite() && max.is_finite() && min < max && mean.is_finite()) {
                    return bad(format!("needs a finite mean and finite min < max, got mean {mean}, [{min}, {max}]"));
                }
                param(Prior::Normal { mean: *mean, sd: *sd }, *min, *max)
            }
            Dist::LogNormal { median, sd_log, min, max } => {
                if !(median.is_finite() && *median > 0.0) {
                    return bad(format!("the median must be a finite number > 0, got {median}"));
                }
                if !(sd_log.is_finite() && *sd_log > 0.0) {
                    return bad(format!("sd_log must be a finite number > 0, got {sd_log}"));
                }
                if !(*min > 0.0 && max.is_finite() && min < max) {
                    return bad(format!("needs 0 < min < max, finite, got [{min}, {max}]"));
                }
                param(Prior::LogNormal { mu: median.ln(), sigma: *sd_log }, *min, *max)
            }
            Dist::Spectrum { file: spec, target, row, scale } => {
                if !(scale.is_finite() && *scale > 0.0) {
                    return bad(format!("scale must be a finite number > 0, got {scale}"));
                }
                let path = resolve(spec);
                if !path.is_file() {
                    return bad(format!("the spectrum file {} does not exist", path.display()));
                }
                let q = read_spectrum(&path, target, *row)?;
                Ok(Marginal::Quantiles { p: q.iter().map(|x| x.0).collect(), v: q.iter().map(|x| x.1 * scale).collect() })
            }
        }
    }
}

/// Reads the quantile function of one target and row of a DEM impact spectrum: the columns
/// `q<k>_v_normal_m_s` give the k % quantiles. Rejects negative or non-finite speeds, quantiles
/// out of order, and a missing or empty row, naming file, row and rule.
pub fn read_spectrum(path: &Path, target: &str, row: u32) -> Result<Vec<(f64, f64)>> {
    let t = crate::intake::read_raw(&crate::intake::Source::file(path))?;
    let c = t.require(&["target", "row", "impacts"])?;
    let mut cols: Vec<(f64, usize)> = t
        .headers
        .iter()
        .enumerate()
        .filter_map(|(k, s)| {
            let p = s.strip_prefix('q')?.strip_suffix("_v_normal_m_s")?.parse::<f64>().ok()?;
            Some((p / 100.0, k))
        })
        .collect();
    cols.sort_by(|a, b| a.0.total_cmp(&b.0));
    if cols.is_empty() {
        return Err(Error::data_file(path, "columns", "no quantile columns `q<k>_v_normal_m_s`: not an impact spectrum"));
    }
    let mut found = None;
    for i in 0..t.rows.len() {
        if t.text(i, c[0]).as_deref() == Some(target) && t.need_number(i, c[1])? == row as f64 {
            found = Some(i);
            break;
        }
    }
    let Some(i) = found else {
        return Err(Error::data_file(path, "target/row", format!("no row with target `{target}` and row {row}")));
    };
    let impacts = t.need_number(i, c[2])?;
    if !(impacts >= 1.0) {
        return Err(t.error(i, Some(c[2]), format!("the spectrum of target `{target}`, row {row} is empty ({impacts} impacts)")));
    }
    let mut q = vec![(0.0, 0.0)];
    for &(p, k) in &cols {
        let v = t.need_number(i, k)?;
        if let Some(rule) = crate::data::VELOCITY.broken(v) {
            return Err(t.error(i, Some(k), rule));
        }
        if v < q[q.len() - 1].1 {
            return Err(t.error(i, Some(k), format!("quantiles must not decrease ({v} after {})", q[q.len() - 1].1)));
        }
        q.push((p, v));
    }
    Ok(q)
}

fn default_particles() -> usize {
    512
}

/// A declared population (`population = { … }` of a `[[material]]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PopulationSpec {
    /// Particles of the stratified sample (default 512).
    #[serde(default = "default_particles")]
    pub particles: usize,
    /// Diameter distribution (m).
    pub diameter_m: Dist,
    /// Roundness distribution, in (0, 1].
    #[serde(default)]
    pub roundness: Option<Dist>,
    /// Sphericity distribution, in (0, 1].
    #[serde(default)]
    pub sphericity: Option<Dist>,
    /// Temperature distribution (°C).
    #[serde(default)]
    pub temperature_c: Option<Dist>,
}

