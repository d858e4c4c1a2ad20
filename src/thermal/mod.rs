//! Material parameters at any temperature: the temperature law ([`law`]) of every calibrated
//! parameter, fitted to calibration posteriors at two temperatures, and what the lifetime chain
//! needs from it — the factors by which the Weibull scale and the particle's Young's modulus
//! change between the temperature of the crush data and the operating temperature.
//!
//! # Inputs
//!
//! A temperature study file ([`crate::temperature`]) declares them; every study that runs at an
//! operating temperature reads the same tables from it ([`load_from_study`]):
//!
//! ```toml
//! [phases]
//! file = "../datasets/phases_granulated_illustrative.csv"   # crate::phases
//! composition = "granulated (illustrative)"
//! # A table of mole (or mass) fractions is converted to volume fractions with each phase's
//! # molar volume (or density_kg_m3) and their source; volume fractions are used as they are.
//! # molar_volume_m3_mol = { CORUNDUM = 5.1e-6, … }
//! # source = "…"
//!
//! [law]
//! calibrations = [   # posterior draws at two temperatures: the chains.csv of a calibration
//!                     # study's report (run first when missing or stale), or a file (`chains`)
//!   { temperature_c = 20,  study = "calibrate_gen3_rt.toml" },
//!   { temperature_c = 800, study = "calibrate_gen3_800c.toml" },
//! ]
//! draws = 2000        # joint draws of the laws (drawn without replacement from each posterior)
//! strength = "t"      # the parameter whose law scales the Weibull scale σ_θ of the strength model
//! shear = "g"         # shear and bulk modulus: the particle's Young's modulus in impacts
//! bulk = "k1"
//! [law.glassy_ratio]  # prior of r = θ_glass/θ_crystalline, one per parameter given a law
//! g = { distribution = "uniform", min = 0.01, max = 0.2 }
//! ```
//!
//! # From the laws to the lifetime chain
//!
//! The strength model's Weibull law is of σ̄ at break measured at the crush data's temperature
//! T₀ (with the particle's Young's modulus E(T₀) of the study). At an operating temperature T,
//! joint draw j of the laws gives
//!
//! ```text
//! σ_θ(T) = σ_θ(T₀) · s_j(T)/s_j(T₀)                 s the law of the strength parameter (JH-2 T)
//! E(T)   = E(T₀)   · E_j(T)/E_j(T₀),   E = 9KG/(3K + G)   from the laws of G and K
//! ```
//!
//! The JH-2 hydrostatic tensile strength T is the constant that sets where the crush FE breaks,
//! so its law carries the strength's change with temperature; the Weibull modulus m is kept
//! (nothing at hand measures its change). Poisson's ratio is kept at the study's value. The
//! impact stress follows from E(T) through the Hertz impact (σ̄ ∝ E*^(4/5) for a domain ending at
//! a multiple of the contact radius): a softer particle meets a lower contact stress, so softening
//! of strength and of stiffness act in opposite directions on the breakage.

pub mod law;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

pub use law::{LawDraw, TemperatureLaw};

use crate::contact::Elastic;
use crate::dist::Dist;
use crate::error::{Error, Result};
use crate::phases::{Basis, PhaseTable, VolumeConversion, read_phases};

/// `[phases]` of a temperature study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhasesOptions {
    /// The phase-fraction table ([`crate::phases`]), relative to the study file.
    pub file: PathBuf,
    /// What the table is of, in words (for the report).
    pub composition: String,
    /// Amorphous fraction above which the amorphous phase counts as risen.
    #[serde(default = "onset_level")]
    pub onset_level: f64,
    /// Per phase, its molar volume (m³ per mole as the table counts moles): converts a table
    /// of mole fractions to volume fractions ([`crate::phases`], "Volume fractions").
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub molar_volume_m3_mol: BTreeMap<String, f64>,
    /// Per phase, its density (kg/m³): converts a table of mass fractions.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub density_kg_m3: BTreeMap<String, f64>,
    /// Where the molar volumes or densities come from (required with them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

impl PhasesOptions {
    /// The table of `path` (declared by study `file`) in volume fractions: read, then converted
    /// with the declared molar volumes or densities when it holds mole or mass fractions.
    pub fn read(&self, file: &str, path: &Path) -> Result<PhaseTable> {
        if !path.is_file() {
            return Err(Error::config(file, "phases.file", format!("{} does not exist", path.display())));
        }
        let table = read_phases(path)?;
        let declared = [("phases.molar_volume_m3_mol", &self.molar_volume_m3_mol, Basis::Mole), ("phases.density_kg_m3", &self.density_kg_m3, Basis::Mass)];
        let mut conversion = None;
        for (key, values, basis) in declared {
            if values.is_empty() {
                continue;
            }
            if table.basis != basis {
                return Err(Error::config(file, key, format!("converts {}, but {} holds {}", basis.words(), path.display(), table.basis.words())));
            }
            if self.source.as_deref().is_none_or(|s| s.trim().is_empty()) {
                return Err(Error::config(file, "phases.source", format!("{key} needs its source (a handbook, a database, a paper): where each value comes from")));
            }
            conversion = Some(VolumeConversion { per_phase: values.clone(), key: key.into() });
        }
        table.to_volume(file, conversion.as_ref())
    }
}

fn onset_level() -> f64 {
    0.01
}

/// One calibrated state: a calibration's posterior draws at its temperature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibratedState {
    /// The temperature of the calibration's data (°C).
    pub temperature_c: f64,
    /// The calibration study (relative to the study file) whose report's `chains.csv` holds the
    /// posterior draws; its report is found under the run's reports root, and the study is run
    /// first when its report is missing or stale.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub study: Option<PathBuf>,
    /// Or a file of posterior draws given directly (relative to the study file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chains: Option<PathBuf>,
}

impl CalibratedState {
    /// The file of posterior draws: `<reports_root>/<study stem>/chains.csv`, or `chains`.
    pub fn chains_file(&self, file: &str, key: &str, resolve: &dyn Fn(&Path) -> PathBuf, reports_root: &Path) -> Result<PathBuf> {
        crate::schema::one_of(file, key, &self.study, &self.chains, "study", "chains")?;
        Ok(match (&self.study, &self.chains) {
            (Some(s), _) => crate::schema::report_file(reports_root, &resolve(s), "chains.csv"),
            (_, Some(c)) => resolve(c),
            _ => unreachable!("one_of checked"),
        })
    }
}

/// The studies whose reports the `[law]` of a temperature study reads (its calibrations).
pub fn law_prerequisites(o: &LawOptions, resolve: &dyn Fn(&Path) -> PathBuf) -> Vec<crate::schema::Prerequisite> {
    o.calibrations
        .iter()
        .enumerate()
        .filter_map(|(i, c)| c.study.as_ref().map(|s| crate::schema::Prerequisite { key: format!("law.calibrations[{i}].study"), study: resolve(s), files: vec!["chains.csv", "parameters.csv", "grid.csv"] }))
        .collect()
}

/// The prerequisites of the `[law]` of the temperature study at `path` (none without a law).
pub fn law_prerequisites_of_study(path: &Path) -> Result<Vec<crate::schema::Prerequisite>> {
    let loaded = crate::schema::StudyFile::read(path)?;
    let src: LawSource = loaded.parse()?;
    Ok(src.law.as_ref().map(|l| law_prerequisites(l, &|p| loaded.resolve(p))).unwrap_or_default())
}

/// `[law]` of a temperature study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawOptions {
    /// The two calibrated states, in increasing temperature.
    pub calibrations: Vec<CalibratedState>,
    /// Joint draws of the laws.
    #[serde(default = "law_draws")]
    pub draws: usize,
    /// Prior of the glassy ratio of each parameter given a law (the chains' column names).
    pub glassy_ratio: BTreeMap<String, Dist>,
    /// The parameter whose law scales the Weibull scale.
    #[serde(default = "strength_name")]
    pub strength: String,
    /// The shear modulus parameter.
    #[serde(default = "shear_name")]
    pub shear: String,
    /// The bulk modulus parameter.
    #[serde(default = "bulk_name")]
    pub bulk: String,
}

fn law_draws() -> usize {
    2000
}
fn strength_name() -> String {
    "t".into()
}
fn shear_name() -> String {
    "g".into()
}
fn bulk_name() -> String {
    "k1".into()
}

impl LawOptions {
    /// Checks every option that needs no file.
    pub fn validate(&self, file: &str) -> Result<()> {
        let c = &self.calibrations;
        if c.len() != 2 {
            return Err(Error::config(file, "law.calibrations", format!("the law is fitted to exactly two calibrated states, got {}", c.len())));
        }
        for (i, s) in c.iter().enumerate() {
            crate::schema::one_of(file, &format!("law.calibrations[{i}]"), &s.study, &s.chains, "study", "chains")?;
            if !(s.temperature_c.is_finite() && s.temperature_c > -273.15) {
                return Err(Error::config(file, format!("law.calibrations[{i}].temperature_c"), format!("must be a temperature above absolute zero (°C), got {}", s.temperature_c)));
            }
        }
        if !(c[1].temperature_c > c[0].temperature_c) {
            return Err(Error::config(file, "law.calibrations", format!("the temperatures must increase, got {} then {} °C", c[0].temperature_c, c[1].temperature_c)));
        }
        if !(100..=100_000).contains(&self.draws) {
            return Err(Error::config(file, "law.draws", format!("must lie in 100…100000, got {}", self.draws)));
        }
        for (key, what) in [(&self.strength, "law.strength"), (&self.shear, "law.shear"), (&self.bulk, "law.bulk")] {
            if !self.glassy_ratio.contains_key(key) {
                return Err(Error::config(file, what, format!("`{key}` has no prior in [law.glassy_ratio] (it needs a law)")));
            }
        }
        if self.shear == self.bulk {
            return Err(Error::config(file, "law.bulk", "the shear and bulk modulus must be different parameters"));
        }
        Ok(())
    }
}

/// The factors by which a draw of the laws changes the strength model between two temperatures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Factors {
    /// σ_θ(T)/σ_θ(T₀).
    pub strength: f64,
    /// E(T)/E(T₀).
    pub modulus: f64,
}

/// Young's modulus of shear modulus `g` and bulk modulus `k` ([`Elastic::from_shear_and_bulk`]).
pub fn youngs_modulus(g: f64, k: f64) -> f64 {
    Elastic::from_shear_and_bulk(g, k).youngs_modulus_pa
}

/// The laws of every parameter with a glassy-ratio prior, as joint draws (draw j of every law
/// comes from the same pair of posterior draws).
#[derive(Debug, Clone)]
pub struct ParameterLaws {
    /// The phase table of the amorphous fraction.
    pub phases: PhaseTable,
    /// Parameter names (the chains' columns), in the order of `laws`.
    pub names: Vec<String>,
    /// One law per parameter.
    pub laws: Vec<TemperatureLaw>,
    /// The calibrated states: temperature and, per parameter, the posterior draws used.
    pub calibrated: Vec<(f64, Vec<Vec<f64>>)>,
    /// The files read (chains).
    pub inputs: Vec<PathBuf>,
    strength: usize,
    shear: usize,
    bulk: usize,
}

/// `[phases]` and `[law]` of a temperature study, read by the studies that use its law.
#[derive(Debug, Clone, Deserialize)]
struct LawSource {
    seed: u64,
    phases: PhasesOptions,
    law: Option<LawOptions>,
}

/// Reads the phase table and fits the laws of temperature study `path` (its `[phases]` and
/// `[law]`, its seed): what a main study's `[operating] law = "…"` points at.
pub fn load_from_study(path: &Path, reports_root: &Path) -> Result<ParameterLaws> {
    let loaded = crate::schema::StudyFile::read(path)?;
    let file = path.display().to_string();
    loaded.kind(&["temperature"])?;
    let src: LawSource = loaded.parse()?;
    let Some(law) = &src.law else {
        return Err(Error::config(&file, "law", "this temperature study declares no [law] (calibrated states and glassy-ratio priors)"));
    };
    let phases = src.phases.read(&file, &loaded.resolve(&src.phases.file))?;
    ParameterLaws::load(&file, &|p| loaded.resolve(p), reports_root, phases, law, src.seed)
}

impl ParameterLaws {
    /// Fits the laws of `o` (study file `file`, paths resolved by `resolve`) with the amorphous
    /// fraction of `phases`; `seed` chooses the posterior draws and the glassy ratios.
    pub fn load(file: &str, resolve: &dyn Fn(&Path) -> PathBuf, reports_root: &Path, phases: PhaseTable, o: &LawOptions, seed: u64) -> Result<ParameterLaws> {
        o.validate(file)?;
        let (lo, hi) = phases.range();
        let names: Vec<String> = o.glassy_ratio.keys().cloned().collect();
        let mut calibrated = Vec::new();
        let mut inputs = Vec::new();
        for (i, c) in o.calibrations.iter().enumerate() {
            let key = format!("law.calibrations[{i}]");
            if c.temperature_c < lo || c.temperature_c > hi {
                return Err(Error::config(file, format!("{key}.temperature_c"), format!("{} °C lies outside the phase table {} ({lo}–{hi} °C)", c.temperature_c, phases.path.display())));
            }
            let path = c.chains_file(file, &key, resolve, reports_root)?;
            if !path.is_file() {
                let sub = if c.study.is_some() { "study" } else { "chains" };
                return Err(Error::config(file, format!("{key}.{sub}"), format!("{} does not exist: it is the chains.csv a calibration study's run writes", path.display())));
            }
            // A calibration study's report states its curves' test temperature: it must be the
            // one this state is declared at.
            if let Some(s) = &c.study {
                let grid = crate::schema::report_file(reports_root, &resolve(s), "grid.csv");
                if !grid.is_file() {
                    return Err(Error::config(file, format!("{key}.study"), format!("{} does not exist: the law is fitted to crush calibrations, whose report's grid.csv states the curves' test temperature", grid.display())));
                }
                let tested = crate::report::Table::load_file(&grid)?.f("test_temperature_c")?;
                if let Some(&t) = tested.iter().find(|&&t| (t - c.temperature_c).abs() > crate::intake::observed::TEMPERATURE_TOLERANCE_C) {
                    return Err(Error::config(file, format!("{key}.temperature_c"), format!("{} °C, but the calibration {} fitted curves measured at {t} °C ({}): a calibrated state is at its data's temperature", c.temperature_c, s.display(), grid.display())));
                }
            }
            let t = crate::report::Table::load_file(&path)?;
            let cols: Vec<Vec<f64>> = names.iter().map(|n| t.f(n)).collect::<Result<_>>()?;
            let rows = cols.first().map_or(0, |c| c.len());
            if rows < o.draws {
                return Err(Error::data_file(&path, "file", format!("{rows} posterior draws, fewer than law.draws = {} of {file}", o.draws)));
            }
            for (n, col) in names.iter().zip(&cols) {
                if let Some(r) = col.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
                    return Err(Error::data_file(&path, format!("row {} (line {}), column {n}", r + 1, r + 2), format!("{} is not positive: the law is of positive parameters", col[r])));
                }
            }
            // Draws without replacement, each posterior with its own stream.
            let mut order: Vec<usize> = (0..rows).collect();
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(1 + i as u64);
            order.shuffle(&mut rng);
            order.truncate(o.draws);
            calibrated.push((c.temperature_c, cols.iter().map(|col| order.iter().map(|&r| col[r]).collect()).collect::<Vec<Vec<f64>>>()));
            inputs.push(path);
        }
        let mut laws = Vec::new();
        for (k, n) in names.iter().enumerate() {
            let key = format!("law.glassy_ratio.{n}");
            let m = o.glassy_ratio[n].marginal(file, &key, "-", &|p| resolve(Path::new(p)))?;
            let (a, b) = (m.quantile(0.0), m.quantile(1.0));
            if !(a > 0.0 && b.is_finite()) {
                return Err(Error::config(file, &key, format!("a glassy ratio must be positive and finite, the distribution spans [{a}, {b}]")));
            }
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(100 + k as u64);
            let ratio: Vec<f64> = (0..o.draws).map(|_| m.quantile(rand::Rng::random::<f64>(&mut rng))).collect();
            let law = TemperatureLaw::fit(&phases, (calibrated[0].0, &calibrated[0].1[k]), (calibrated[1].0, &calibrated[1].1[k]), &ratio)?;
            laws.push(law);
        }
        let at = |n: &str| names.iter().position(|x| x == n).unwrap_or(0);
        let (strength, shear, bulk) = (at(&o.strength), at(&o.shear), at(&o.bulk));
        Ok(ParameterLaws { phases, names, laws, calibrated, inputs, strength, shear, bulk })
    }

    /// Number of joint draws.
    pub fn len(&self) -> usize {
        self.laws.first().map_or(0, |l| l.draws.len())
    }

    /// Whether there is no draw.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The temperature range the laws may be evaluated on (the phase table's).
    pub fn range(&self) -> (f64, f64) {
        self.phases.range()
    }

    /// Refuses temperatures from `lo` to `hi` outside the phase table (study `file`, key `key`).
    pub fn check_range(&self, file: &str, key: &str, lo: f64, hi: f64) -> Result<()> {
        let (a, b) = self.range();
        if lo < a || hi > b || !(lo.is_finite() && hi.is_finite()) {
            return Err(Error::config(file, key, format!("the temperatures {lo}–{hi} °C reach outside the phase table {} ({a}–{b} °C): the laws are not extrapolated beyond it", self.phases.path.display())));
        }
        Ok(())
    }

    /// Draw j of parameter k at `t_c` with amorphous fraction `f_a`.
    fn value(&self, k: usize, j: usize, t_c: f64, f_a: f64) -> f64 {
        self.laws[k].draws[j].value(t_c, f_a, self.laws[k].t_ref_c)
    }

    /// Draw j of every law at `t_c`, in the order of `names`.
    pub fn values_at(&self, j: usize, t_c: f64) -> Result<Vec<f64>> {
        let f = self.phases.amorphous_at(t_c)?;
        Ok((0..self.laws.len()).map(|k| self.value(k, j, t_c, f)).collect())
    }

    /// Draw j's shear and bulk modulus at `t_c`.
    pub fn shear_bulk_at(&self, j: usize, t_c: f64) -> Result<(f64, f64)> {
        let f = self.phases.amorphous_at(t_c)?;
        Ok((self.value(self.shear, j, t_c, f), self.value(self.bulk, j, t_c, f)))
    }

    /// Indices in `names` of the shear and the bulk modulus.
    pub fn shear_bulk(&self) -> (usize, usize) {
        (self.shear, self.bulk)
    }

    /// Draw j's factors between the crush data's temperature `t0_c` and `t_c`.
    pub fn factors(&self, j: usize, t_c: f64, t0_c: f64) -> Result<Factors> {
        let (f, f0) = (self.phases.amorphous_at(t_c)?, self.phases.amorphous_at(t0_c)?);
        let s = self.value(self.strength, j, t_c, f) / self.value(self.strength, j, t0_c, f0);
        let e = |t, f| youngs_modulus(self.value(self.shear, j, t, f), self.value(self.bulk, j, t, f));
        Ok(Factors { strength: s, modulus: e(t_c, f) / e(t0_c, f0) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn youngs_modulus_and_poisson_ratio_of_g_and_k() {
        // Steel: E = 210 GPa, ν = 0.3 ⇒ G = E/(2(1+ν)), K = E/(3(1−2ν)).
        let (e, nu) = (210e9, 0.3);
        let (g, k) = (e / (2.0 * (1.0 + nu)), e / (3.0 * (1.0 - 2.0 * nu)));
        let el = Elastic::from_shear_and_bulk(g, k);
        assert!((youngs_modulus(g, k) / e - 1.0).abs() < 1e-14);
        assert!((el.youngs_modulus_pa / e - 1.0).abs() < 1e-14);
        assert!((el.poisson_ratio - nu).abs() < 1e-14);
    }
}
