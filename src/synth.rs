//! Generator of the synthetic crush datasets (`partlife datasets synth`).
//!
//! The measured crush data of the deliverable's project are not public. This generator makes
//! stand-ins from committed settings (`datasets/synth_crush.toml`) and a fixed seed. Its
//! "nature" is deliberately richer than the deliverable's lifetime model, so that later
//! workflows have hidden effects to discover:
//!
//! 1. **Roundness sets the contact curvature.** A particle of diameter d touches the platen
//!    with a radius of curvature R_c = ρ·d/2, ρ = roundness^q (q = `curvature_exponent`; q = 1
//!    follows Wadell's definition of roundness as the mean corner radius over the inscribed
//!    radius). The deliverable's model assumes R_c = d/2.
//! 2. **Strength has a size effect.** The strength of each particle is a Weibull draw with
//!    modulus m (`strength_shape`) and scale σ_0 (d/d_ref)^(−α) (`size_exponent` α).
//! 3. **Break criterion.** The particle breaks when the maximum surface tension of the Hertz
//!    contact with its true curvature, σ_r(a) = (1 − 2ν) p0/3, reaches its strength:
//!    F = π³ R_c² p0³ / (6 E*²) with p0 = 3σ/(1 − 2ν).
//! 4. **Measurement.** Diameter, roundness and sphericity are measured with Gaussian errors and
//!    rounded to the instrument resolution; the force has a relative Gaussian error.
//!
//! 5. **Optional temperature softening** (`[material.nature] softening`): particles tested
//!    above `reference_c` have strength and Young's modulus reduced linearly with temperature;
//!    `temperature_c` may be a list the particles cycle through (temperatures mixed in a file).
//!
//! 6. **Optional prior impacts** (`[material.nature] prior_impacts`): Tavares–King damage from
//!    a random number of earlier impacts lowers the strength ([`PriorImpacts`]); the counts go
//!    to an `impacts` column.
//!
//! Sphericity is recorded but has no effect in this nature (a null covariate). The hidden
//! effects are switched off by a zero exponent (and no softening).
//!
//! The settings are the generator's truth. They are documented in `datasets/README.md` and
//! never read by fitting code: the lifetime chain reads only the CSV files.
//!
//! Randomness: one ChaCha8 stream per material (stream = material index), draws in a fixed
//! order per particle, so the files are byte-identical for the same settings
//! (`tests/datasets.rs` regenerates and compares).

use std::path::{Path, PathBuf};

use polars::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Beta, Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::contact::{Elastic, effective_modulus};
use crate::data::{CRUSH_COLUMNS, CrushRecord};
use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::stats::{median, pearson};
use crate::weibull::Weibull;

/// Generator settings (the file `datasets/synth_crush.toml`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SynthSettings {
    /// Seed of all random draws.
    pub seed: u64,
    /// Platen material of the crush test.
    pub platen: Elastic,
    /// One entry per output file.
    pub material: Vec<SynthMaterial>,
}

/// Settings of one synthetic material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SynthMaterial {
    /// Output file name, relative to the output directory.
    pub file: String,
    /// Material label written to every row.
    pub label: String,
    /// Particle id prefix (`BL` → `BL-001`).
    pub id_prefix: String,
    /// Number of particles.
    pub count: usize,
    /// Test temperature (°C): one value for every row, or a list the particles cycle through
    /// (particle i is tested at list[i mod len]: temperatures mixed in one file).
    pub temperature_c: Temperatures,
    /// Particle elastic constants.
    pub elastic: Elastic,
    /// Diameter distribution: normal truncated to [min, max] (m).
    pub diameter: TruncatedNormal,
    /// True roundness distribution (beta with this mean and sd).
    pub roundness: MeanSd,
    /// True sphericity distribution (beta with this mean and sd).
    pub sphericity: MeanSd,
    /// The hidden physics.
    pub nature: Nature,
    /// Measurement errors and resolutions.
    pub measurement: Measurement,
}

/// One test temperature or a cycle of them (°C).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Temperatures {
    /// Every particle at this temperature.
    One(f64),
    /// Particle i at list[i mod len].
    Cycle(Vec<f64>),
}

impl Temperatures {
    /// Temperature of particle i.
    pub fn of(&self, i: usize) -> f64 {
        match self {
            Temperatures::One(t) => *t,
            Temperatures::Cycle(v) => v[i % v.len()],
        }
    }

    fn all(&self) -> Vec<f64> {
        match self {
            Temperatures::One(t) => vec![*t],
            Temperatures::Cycle(v) => v.clone(),
        }
    }
}

/// Temperature softening of the hidden physics: above `reference_c` strength and Young's
/// modulus fall linearly, by the given fractions per 100 °C.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Softening {
    /// Temperature below which nothing changes (°C).
    pub reference_c: f64,
    /// Fractional strength loss per 100 °C above the reference.
    pub strength_per_100c: f64,
    /// Fractional Young's-modulus loss per 100 °C above the reference.
    pub stiffness_per_100c: f64,
}

impl Softening {
    /// (strength factor, stiffness factor) at temperature t.
    pub fn factors(&self, t: f64) -> (f64, f64) {
        let k = (t - self.reference_c).max(0.0) / 100.0;
        (1.0 - self.strength_per_100c * k, 1.0 - self.stiffness_per_100c * k)
    }
}

/// A normal distribution truncated to [min, max].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TruncatedNormal {
    /// Mean of the untruncated normal.
    pub mean: f64,
    /// Standard deviation of the untruncated normal.
    pub sd: f64,
    /// Lower truncation.
    pub min: f64,
    /// Upper truncation.
    pub max: f64,
}

/// Mean and standard deviation of a beta distribution on (0, 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeanSd {
    /// Mean, in (0, 1).
    pub mean: f64,
    /// Standard deviation, with sd² < mean (1 − mean).
    pub sd: f64,
}

/// The generator's hidden physics (its "truth").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Nature {
    /// Weibull modulus m of the true strength.
    pub strength_shape: f64,
    /// Weibull scale σ_0 (Pa) of the true strength (maximum surface tension at break) at d_ref.
    pub strength_scale_pa: f64,
    /// Reference diameter d_ref (m) of the size effect.
    pub reference_diameter_m: f64,
    /// Size-effect exponent α in σ_0 (d/d_ref)^(−α).
    pub size_exponent: f64,
    /// Exponent q in ρ = roundness^q, R_c = ρ d/2.
    pub curvature_exponent: f64,
    /// Temperature softening (none: strength and stiffness do not depend on temperature).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub softening: Option<Softening>,
    /// Damage from impacts before the crush test (none: no particle was impacted).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior_impacts: Option<PriorImpacts>,
}

/// Tavares–King damage before the crush test: particle i received k_i impacts, k_i uniform on
/// {0, …, `max`}, each at the energy ratio x = E_k/E_m (`ratio`, relative to its current fracture
/// energy at the first impact) with damage exponent γ; its fracture energy fell to
/// E_m,0 Π(1 − D_j) and, since the Hertz fracture energy scales as the strength⁵, its strength
/// by the fifth root of that. The counts are written to the `impacts` column.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorImpacts {
    /// Most prior impacts of a particle.
    pub max: u32,
    /// Energy ratio x = E_k/E_m,0 of each impact.
    pub ratio: f64,
    /// Tavares–King γ.
    pub gamma: f64,
}

impl PriorImpacts {
    /// Strength factor (E_m,k/E_m,0)^(1/5) after k impacts; None if the particle breaks.
    pub fn strength_factor(&self, k: u32) -> Option<f64> {
        let path = crate::lifetime::damage::tk_ratio_path(self.ratio, self.gamma, u64::from(k))?;
        Some(((path[0] - path[k as usize]) / 5.0).exp())
    }
}

/// Measurement model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Measurement {
    /// Relative standard deviation of the force reading.
    pub force_rel_sd: f64,
    /// Force resolution (N).
    pub force_resolution_n: f64,
    /// Standard deviation of the diameter reading (m).
    pub diameter_sd_m: f64,
    /// Diameter resolution (m).
    pub diameter_resolution_m: f64,
    /// Standard deviation of the roundness and sphericity readings.
    pub shape_sd: f64,
    /// Roundness and sphericity resolution.
    pub shape_resolution: f64,
}

/// One generated particle: the measured record and the hidden truth behind it.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParticle {
    /// What is written to the CSV.
    pub record: CrushRecord,
    /// True diameter (m).
    pub diameter_true: f64,
    /// True roundness.
    pub roundness_true: f64,
    /// True strength (Pa).
    pub strength_pa: f64,
    /// True force at break (N).
    pub force_true: f64,
}

fn bad(file: &str, key: String, rule: String) -> Error {
    Error::config(file, key, rule)
}

impl SynthSettings {
    /// Reads and validates the settings file (unknown keys rejected).
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        let s: SynthSettings = crate::schema::parse_toml(path, &text)?;
        s.validate(&path.display().to_string())?;
        Ok(s)
    }

    /// Checks every setting; `file` names the settings file in messages.
    pub fn validate(&self, file: &str) -> Result<()> {
        self.platen.validate("platen").map_err(|e| relabel(e, file))?;
        if self.material.is_empty() {
            return Err(bad(file, "material".into(), "at least one [[material]] is required".into()));
        }
        for (i, m) in self.material.iter().enumerate() {
            let k = |s: &str| format!("material[{i}].{s}");
            m.elastic.validate(&k("elastic")).map_err(|e| relabel(e, file))?;
            if m.count < 2 {
                return Err(bad(file, k("count"), format!("must be ≥ 2 (got {})", m.count)));
            }
            let d = m.diameter;
            if !(d.min > 0.0 && d.min < d.max && d.sd > 0.0 && d.mean.is_finite()) {
                return Err(bad(file, k("diameter"), format!("needs 0 < min < max and sd > 0 (got {d:?})")));
            }
            if !(d.min < d.mean + 4.0 * d.sd && d.max > d.mean - 4.0 * d.sd) {
                return Err(bad(file, k("diameter"), format!("[min, max] lies in the far tail of the normal (got {d:?})")));
            }
            for (name, ms) in [("roundness", m.roundness), ("sphericity", m.sphericity)] {
                if !(ms.mean > 0.0 && ms.mean < 1.0 && ms.sd > 0.0 && ms.sd * ms.sd < ms.mean * (1.0 - ms.mean)) {
                    return Err(bad(file, k(name), format!("needs 0 < mean < 1 and 0 < sd² < mean(1 − mean) (got {ms:?})")));
                }
            }
            let n = m.nature;
            if !(n.strength_shape > 0.0 && n.strength_scale_pa > 0.0 && n.reference_diameter_m > 0.0) {
                return Err(bad(file, k("nature"), format!("strength shape, scale and reference diameter must be > 0 (got {n:?})")));
            }
            if let Temperatures::Cycle(v) = &m.temperature_c
                && v.is_empty()
            {
                return Err(bad(file, k("temperature_c"), "a list of temperatures must not be empty".into()));
            }
            if let Some(t) = m.temperature_c.all().iter().find(|t| !(t.is_finite() && **t >= -273.15)) {
                return Err(bad(file, k("temperature_c"), format!("temperatures must be finite and ≥ −273.15 °C (got {t})")));
            }
            if let Some(sf) = n.softening {
                for t in m.temperature_c.all() {
                    let (a, b) = sf.factors(t);
                    if !(a > 0.0 && b > 0.0 && a <= 1.0 && b <= 1.0) {
                        return Err(bad(file, k("nature.softening"), format!("strength and stiffness factors must stay in (0, 1] (at {t} °C: {a}, {b})")));
                    }
                }
            }
            if let Some(pi) = n.prior_impacts
                && !(pi.ratio > 0.0 && pi.gamma > 0.0 && pi.strength_factor(pi.max).is_some())
            {
                return Err(bad(file, k("nature.prior_impacts"), format!("needs ratio > 0, γ > 0 and no particle broken within {} impacts (got {pi:?})", pi.max)));
            }
            let ms = m.measurement;
            if [ms.force_rel_sd, ms.force_resolution_n, ms.diameter_sd_m, ms.diameter_resolution_m, ms.shape_sd, ms.shape_resolution]
                .iter()
                .any(|v| !(v.is_finite() && *v >= 0.0))
            {
                return Err(bad(file, k("measurement"), format!("errors and resolutions must be ≥ 0 (got {ms:?})")));
            }
        }
        Ok(())
    }
}

fn relabel(e: Error, file: &str) -> Error {
    match e {
        Error::Config { key, rule, .. } => Error::Config { file: file.into(), key, rule },
        other => other,
    }
}

fn beta(ms: MeanSd) -> Result<Beta<f64>> {
    let nu = ms.mean * (1.0 - ms.mean) / (ms.sd * ms.sd) - 1.0;
    Beta::new(ms.mean * nu, (1.0 - ms.mean) * nu)
        .map_err(|e| Error::numerical("beta distribution", format!("{ms:?}: {e}")))
}

fn round_to(x: f64, step: f64) -> f64 {
    if step > 0.0 { (x / step).round() * step } else { x }
}

/// Decimal places needed to print a resolution exactly (1e-6 → 6, 0.01 → 2).
fn decimals(step: f64) -> usize {
    if step <= 0.0 {
        return 9;
    }
    (0..12).find(|&k| ((step * 10f64.powi(k as i32)).round() - step * 10f64.powi(k as i32)).abs() < 1e-9).unwrap_or(12)
}

impl SynthMaterial {
    /// The generator's own single-impact hazard of a fresh particle (its truth; for tests that
    /// compare a fitted model with it, never for fitting). A particle of true diameter `d` and
    /// roundness `roundness`, of density `density`, hits `wall` at `v` (m/s) with elastic energy
    /// fraction `eta`; the Hertz impact ([`crate::contact::Impact`]) with its true contact
    /// curvature R_c = roundness^q d/2 gives the peak pressure p0, and the hazard is
    /// ((1 − 2ν) p0/3 / σ_0 (d/d_ref)^(−α))^m — the same law as the crush test's (temperature
    /// below the softening reference).
    pub fn impact_hazard(&self, d: f64, roundness: f64, density: f64, wall: &Elastic, eta: f64, v: f64) -> f64 {
        let n = &self.nature;
        let sphere = crate::contact::Sphere { diameter: d, density, elastic: self.elastic };
        let impact = crate::contact::Impact::sphere_on_wall(&sphere, wall, roundness.powf(n.curvature_exponent) * 0.5 * d, eta);
        let p0 = impact.hertz.peak_pressure(impact.max_force(v));
        let scale = n.strength_scale_pa * (d / n.reference_diameter_m).powf(-n.size_exponent);
        ((1.0 - 2.0 * self.elastic.poisson_ratio) * p0 / 3.0 / scale).powf(n.strength_shape)
    }
}

/// Generates the particles of material `index` of the settings.
pub fn generate(settings: &SynthSettings, index: usize) -> Result<Vec<SynthParticle>> {
    let m = &settings.material[index];
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    rng.set_stream(index as u64);
    let normal = |sd: f64| Normal::new(0.0, sd).map_err(|e| Error::numerical("normal distribution", e.to_string()));
    let std_normal = normal(1.0)?;
    let round_dist = beta(m.roundness)?;
    let spher_dist = beta(m.sphericity)?;
    let e_star = effective_modulus(&m.elastic, &settings.platen);
    let nu = m.elastic.poisson_ratio;
    let meas = m.measurement;
    let mut out = Vec::with_capacity(m.count);
    for i in 0..m.count {
        // Fixed draw order per particle: diameter (rejection), roundness, sphericity, strength,
        // then the four measurement errors.
        let mut d = f64::NAN;
        for _ in 0..100_000 {
            let x = m.diameter.mean + m.diameter.sd * std_normal.sample(&mut rng);
            if x >= m.diameter.min && x <= m.diameter.max {
                d = x;
                break;
            }
        }
        if d.is_nan() {
            return Err(Error::config(
                "<generator settings>",
                format!("material[{index}].diameter"),
                "the truncation interval [min, max] is practically outside the normal distribution".to_string(),
            ));
        }
        let roundness = round_dist.sample(&mut rng);
        let sphericity = spher_dist.sample(&mut rng);
        let n = m.nature;
        let temperature = m.temperature_c.of(i);
        let (soft_strength, soft_stiffness) = n.softening.map_or((1.0, 1.0), |sf| sf.factors(temperature));
        let scale = soft_strength * n.strength_scale_pa * (d / n.reference_diameter_m).powf(-n.size_exponent);
        let strength = Weibull::new(n.strength_shape, scale)?.sample(&mut rng);
        let e_f = std_normal.sample(&mut rng);
        let e_d = std_normal.sample(&mut rng);
        let e_r = std_normal.sample(&mut rng);
        let e_s = std_normal.sample(&mut rng);
        // Prior impacts (drawn last, so files without them are unchanged).
        let impacts = n.prior_impacts.map(|pi| rng.random_range(0..=pi.max));
        let strength = match (n.prior_impacts, impacts) {
            (Some(pi), Some(k)) => strength * pi.strength_factor(k).ok_or_else(|| {
                Error::config("<generator settings>", format!("material[{index}].nature.prior_impacts"), format!("ratio {} breaks a particle within {k} impacts", pi.ratio))
            })?,
            _ => strength,
        };
        let rc = roundness.powf(n.curvature_exponent) * 0.5 * d;
        let p0 = 3.0 * strength / (1.0 - 2.0 * nu);
        let e_star = if soft_stiffness == 1.0 {
            e_star
        } else {
            let soft = Elastic { youngs_modulus_pa: m.elastic.youngs_modulus_pa * soft_stiffness, ..m.elastic };
            effective_modulus(&soft, &settings.platen)
        };
        let force = std::f64::consts::PI.powi(3) * rc * rc * p0.powi(3) / (6.0 * e_star * e_star);
        let shape = |x: f64, e: f64| round_to((x + meas.shape_sd * e).clamp(meas.shape_resolution.max(1e-3), 1.0), meas.shape_resolution);
        out.push(SynthParticle {
            record: CrushRecord {
                id: format!("{}-{:03}", m.id_prefix, i + 1),
                material: m.label.clone(),
                diameter_m: round_to(d + meas.diameter_sd_m * e_d, meas.diameter_resolution_m),
                crush_force_n: round_to(force * (1.0 + meas.force_rel_sd * e_f), meas.force_resolution_n),
                roundness: Some(shape(roundness, e_r)),
                sphericity: Some(shape(sphericity, e_s)),
                temperature_c: Some(temperature),
                impacts: impacts.map(u64::from),
            },
            diameter_true: d,
            roundness_true: roundness,
            strength_pa: strength,
            force_true: force,
        });
    }
    Ok(out)
}

/// Writes crush records as CSV (columns of [`CRUSH_COLUMNS`]), numbers printed at the
/// measurement resolution, atomically.
pub fn write_crush_csv(path: &Path, records: &[CrushRecord], meas: &Measurement) -> Result<()> {
    let fmt = |v: Option<f64>, step: f64| v.map(|x| format!("{:.*}", decimals(step), x)).unwrap_or_default();
    let cols: Vec<Vec<String>> = vec![
        records.iter().map(|r| r.id.clone()).collect(),
        records.iter().map(|r| r.material.clone()).collect(),
        records.iter().map(|r| fmt(Some(r.diameter_m), meas.diameter_resolution_m)).collect(),
        records.iter().map(|r| fmt(Some(r.crush_force_n), meas.force_resolution_n)).collect(),
        records.iter().map(|r| fmt(r.roundness, meas.shape_resolution)).collect(),
        records.iter().map(|r| fmt(r.sphericity, meas.shape_resolution)).collect(),
        records.iter().map(|r| fmt(r.temperature_c, 1.0)).collect(),
    ];
    let mut columns: Vec<Column> = CRUSH_COLUMNS
        .iter()
        .zip(cols)
        .map(|(name, values)| Column::new((*name).into(), values))
        .collect();
    if records.iter().any(|r| r.impacts.is_some()) {
        let v: Vec<String> = records.iter().map(|r| r.impacts.map(|k| k.to_string()).unwrap_or_default()).collect();
        columns.push(Column::new("impacts".into(), v));
    }
    let mut df = DataFrame::new_infer_height(columns).map_err(|e| Error::numerical("building crush table", e.to_string()))?;
    let mut buf = Vec::new();
    CsvWriter::new(&mut buf)
        .finish(&mut df)
        .map_err(|e| Error::numerical("formatting crush table", e.to_string()))?;
    write_atomic(path, &buf)
}

/// Summary statistics of one generated file, printed by `partlife datasets synth` and quoted in
/// `datasets/README.md`.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthSummary {
    /// File written.
    pub path: PathBuf,
    /// Number of particles.
    pub count: usize,
    /// Smallest and largest measured diameter (m).
    pub diameter_range: (f64, f64),
    /// Median force of the particles with 0.8 mm ≤ d ≤ 1.0 mm (N).
    pub median_force_08_10mm: f64,
    /// Pearson correlation of force with diameter.
    pub force_diameter_r: f64,
    /// Two-sided p-value of that correlation (Student t, n − 2 dof).
    pub force_diameter_p: f64,
}

/// Generates every material of the settings into `out_dir` and returns the summaries.
pub fn synthesize(settings: &SynthSettings, out_dir: &Path) -> Result<Vec<SynthSummary>> {
    let mut out = Vec::new();
    for (i, m) in settings.material.iter().enumerate() {
        let particles = generate(settings, i)?;
        let records: Vec<CrushRecord> = particles.into_iter().map(|p| p.record).collect();
        let path = out_dir.join(&m.file);
        write_crush_csv(&path, &records, &m.measurement)?;
        let d: Vec<f64> = records.iter().map(|r| r.diameter_m).collect();
        let f: Vec<f64> = records.iter().map(|r| r.crush_force_n).collect();
        let mid: Vec<f64> = records
            .iter()
            .filter(|r| (0.8e-3..=1.0e-3).contains(&r.diameter_m))
            .map(|r| r.crush_force_n)
            .collect();
        let (r, p) = pearson(&d, &f);
        out.push(SynthSummary {
            path,
            count: records.len(),
            diameter_range: (d.iter().cloned().fold(f64::MAX, f64::min), d.iter().cloned().fold(f64::MIN, f64::max)),
            median_force_08_10mm: median(&mid),
            force_diameter_r: r,
            force_diameter_p: p,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_of_resolutions() {
        assert_eq!(decimals(1e-6), 6);
        assert_eq!(decimals(0.01), 2);
        assert_eq!(decimals(0.001), 3);
        assert_eq!(decimals(1.0), 0);
    }

}
