//! One strength model's comparison of the two particle types, ready to sample: every uncertain
//! input as a marginal, and the evaluation of one sample through each material's
//! [`LifetimeModel`] (no second copy of the chain).
//!
//! # Inputs
//!
//! In order: `strength_<a>` (one of K joint draws of material a's strength model: m, μ, the
//! effects' β and the population weights), one input per effect parameter of material a
//! (`size_alpha_<a>`, `roundness_q_<a>`, …), the same for material b, then `energy_fraction`,
//! `velocity`, `impacts_per_year` and `tk_gamma` (a = candidate, b = reference); with operating
//! temperatures (`[operating]`), then `temperature_law` (one of the joint draws of the temperature
//! laws, [`crate::thermal::ParameterLaws`]) and `operating_temperature_<a>`, `…_<b>` (°C).
//!
//! # Operating temperature
//!
//! The crush data fix the strength law at their temperature T₀ (every row's test temperature,
//! from its `temperature_c` cell or the study's `data.temperature_c`). At an operating temperature T the sample's draw j of the laws
//! multiplies the Weibull scale by s_j(T)/s_j(T₀) and the particle's Young's modulus by
//! E_j(T)/E_j(T₀) ([`crate::thermal::Factors`]); the impact stress follows the modulus
//! ([`LifetimeModel::ln_impact_stress_with_modulus`]).
//!
//! # Joint and split sampling
//!
//! The propagation ([`Mode::Joint`]) takes every parameter of a material from one joint draw:
//! the headline carries the exact joint uncertainty and the effect inputs are not sampled.
//! Sobol' indices need independent inputs; [`Mode::Split`] takes the modulus, the scale at the
//! sample's mean covariates μ_c = μ + Σ β_k z̄_k and the population weights from the joint draw
//! and each effect parameter from its own marginal. With centred covariates the Fisher
//! information of the Weibull regression is block-diagonal between (μ_c, b) and β, so their
//! estimates are asymptotically independent; `strength_models.csv` reports the largest sample
//! correlation of the draws so the approximation can be judged.
//!
//! # Known failure origins
//!
//! A material whose crush file names each particle's failure origin (`origin = "…"` of its
//! `[[material]]`) carries, in every strength model without effects on it (the deliverable's,
//! and `"diagnosed"` where the loop names nothing), each origin's two-parameter Weibull law
//! fitted to its own breaks with the other origins' censored (ASTM C1239;
//! [`crate::strength::origins`]). The origins are independent flaw populations and the weakest
//! breaks first, so a particle survives N impacts only if it survives every origin's flaws:
//! P_N = 1 − Π_k (1 − P_N,k), each P_N,k through the same [`LifetimeModel`] at the same impact
//! stress. Exact under independent trials; under Vogel–Peukert and Tavares–King each origin's
//! flaws are taken to accumulate damage on their own. The sample's joint draw j of the material
//! is draw j of every origin (independent draws: the censored likelihoods factorise); an
//! operating temperature scales every origin's strength alike. A model with effects on the
//! material fits one law to the breaks of every origin, and the summary says so.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::study::UqStudy;
use crate::contact::{AveragingDomain, ContactOptions};
use crate::dist::Marginal;
use crate::error::{Error, Result};
use crate::lifetime::damage::{CriticalRatioTable, DamageModel};
use crate::strength::model::{Horizon, LAWS};
use crate::strength::origins::{OriginFit, from_ln_survival, ln_survival};
use crate::strength::{LifetimeModel, NamingSettings, Params, Sample, StrengthFit, StrengthSpec, sample_of};
use crate::thermal::ParameterLaws;

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

/// How a sample's unit point maps to the inputs (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Every strength parameter from one joint draw (the propagation).
    Joint,
    /// Effect parameters from their own marginals (the Sobol' indices).
    Split,
}

/// One particle type of the comparison.
#[derive(Debug, Clone)]
pub struct Material {
    /// Its lifetime model (fitted strength law, population, impact).
    pub model: LifetimeModel,
    /// Joint draws of its strength parameters.
    pub draws: Vec<Params>,
    /// Population weights paired with the draws (a sampled population), or equal weights.
    pub weights: Option<Vec<Vec<f64>>>,
    /// Its crush sample (σ̄ at break and covariates).
    pub sample: Sample,
    /// The crush data file.
    pub path: PathBuf,
    /// How it was read (for the manifest).
    pub read: crate::intake::Provenance,
    /// Index of `strength_<key>` in the inputs.
    strength_input: usize,
    /// Indices of its effect parameters in the inputs (order of the linear effects).
    effect_inputs: Vec<usize>,
    /// The single-column effects of those inputs, with their β index (same order).
    effect_columns: Vec<(crate::strength::Effect, usize)>,
    /// Each failure origin's law, where the crush file names the origins and this strength
    /// model has no effect on the material (module docs): together they replace `model` and
    /// `draws` in every evaluation. Empty otherwise.
    pub origins: Vec<OriginLaw>,
    /// The column naming each crush test's failure origin (`origin = "…"`), if the study names one.
    pub origin_column: Option<String>,
    /// Each crush test's failure origin (rows of `sample`; empty without `origin_column`).
    pub failure_origins: Vec<String>,
}

/// One failure origin's law in a material's lifetime (module docs).
#[derive(Debug, Clone)]
pub struct OriginLaw {
    /// Its fit: breaks, modulus, scale, 90 % bands and the draws the samples take.
    pub fit: OriginFit,
    /// Its lifetime model (the origin's two-parameter law, the material's impact and population).
    pub model: LifetimeModel,
}

/// Seed of the failure origins' draws (xor the study's seed, + the material's slot).
const ORIGINS_SEED: u64 = 0x0519_A5A5;

/// The crush data's temperature of a sample without a `temperature_c` covariate (°C): only a
/// sample built by hand, since the intake gives every crush row a test temperature.
pub const ROOM_TEMPERATURE_C: f64 = 20.0;

/// γ points of a Tavares–King table of critical ratios (linear in γ between them).
const TK_GAMMA_POINTS: usize = 41;

impl Material {
    /// Each crushed particle's test temperature (°C; the intake gives every row one).
    pub fn temperatures_c(&self) -> Vec<f64> {
        self.sample.covariates.iter().find(|(n, _)| n == "temperature_c").map_or(Vec::new(), |(_, v)| v.iter().flatten().copied().collect())
    }

    /// This material's tests for [`crate::lifetime::tested`] (`temperatures`: [`Self::temperatures_c`]).
    pub fn tested<'a>(&'a self, temperatures: &'a [f64]) -> crate::lifetime::tested::Tested<'a> {
        crate::lifetime::tested::Tested { label: &self.model.label, temperatures_c: temperatures, temperature_term: self.model.fit.effects().contains(&crate::strength::Effect::Temperature) }
    }

    /// The temperature of its crush data T₀ (°C): every row's `temperature_c` (the intake gives
    /// each row one; [`ROOM_TEMPERATURE_C`] for a hand-built sample without); data at several temperatures are refused (the
    /// temperature laws scale a strength measured at one temperature).
    pub fn data_temperature_c(&self) -> Result<f64> {
        let t: &[Option<f64>] = self.sample.covariates.iter().find(|(n, _)| n == "temperature_c").map_or(&[], |(_, v)| v);
        let Some(t0) = t.iter().flatten().next().copied() else {
            return Ok(ROOM_TEMPERATURE_C);
        };
        if let Some(i) = t.iter().position(|v| *v != Some(t0)) {
            return Err(Error::Data {
                file: self.path.display().to_string(),
                location: format!("row {} (line {}), column temperature_c", i + 1, i + 2),
                rule: format!("material `{}`: an operating temperature needs crush data at one temperature (the first given is {t0} °C); the temperature laws scale a strength measured at one temperature", self.model.key),
            });
        }
        Ok(t0)
    }
}

/// The operating temperatures of a study: the laws and each material's temperature marginal.
#[derive(Debug, Clone)]
pub struct SharedThermal {
    /// The temperature laws.
    pub laws: Arc<ParameterLaws>,
    /// Operating temperature (°C) per material of the study file (its `material` order).
    pub temperatures: Vec<Marginal>,
}

/// The operating temperatures as inputs of one comparison.
#[derive(Debug, Clone)]
pub struct Thermal {
    /// The temperature laws.
    pub laws: Arc<ParameterLaws>,
    /// Index of `temperature_law` in the inputs.
    pub law_input: usize,
    /// Indices of the operating temperatures (candidate, reference).
    pub temperature_inputs: [usize; 2],
    /// Temperatures of the crush data (candidate, reference), °C.
    pub data_c: [f64; 2],
}

/// The inputs shared by every strength model.
#[derive(Debug, Clone)]
pub struct Shared {
    /// η, V, impacts per year, γ.
    pub inputs: [Input; 4],
    /// Tavares–King x* tables per horizon (fixed impacts per year only).
    pub tk: Vec<Option<CriticalRatioTable>>,
    /// Damage models (primary first).
    pub models: Vec<DamageModel>,
    /// Operating temperatures (`[operating]`), if any.
    pub thermal: Option<SharedThermal>,
}

impl Shared {
    /// Builds the shared inputs of a study (`path` its file; the reports of the studies its
    /// operating-temperature law reads are under `reports_root`).
    pub fn new(s: &UqStudy, path: &Path, reports_root: &Path) -> Result<Shared> {
        let file = path.display().to_string();
        let resolve = |p: &str| crate::schema::resolve_relative(path, Path::new(p));
        let m = |d: &crate::dist::Dist, key: &str, unit: &str, lo: f64, hi: f64| -> Result<Marginal> {
            let mg = d.marginal(&file, key, unit, &resolve)?;
            let (a, b) = (mg.quantile(0.0), mg.quantile(1.0));
            if a >= lo && b <= hi && a.is_finite() && b.is_finite() { Ok(mg) } else { Err(Error::config(&file, key, format!("values must lie in [{lo}, {hi}], the distribution spans [{a}, {b}]"))) }
        };
        let eta = m(&s.impact.energy_fraction, "impact.energy_fraction", "-", 1e-6, 1.0)?;
        let v = m(&s.impact.velocity, "impact.velocity", "m/s", 0.0, crate::lifetime::MAX_VELOCITY)?;
        let per_year = m(&s.impact.impacts_per_year, "impact.impacts_per_year", "1/yr", 1e-9, 1e9)?;
        let gamma = m(&s.damage.gamma, "damage.gamma", "-", 0.1, 100.0)?;
        let mut models = vec![s.damage.primary];
        models.extend(s.damage.models.iter().copied().filter(|m| *m != s.damage.primary));
        models.dedup();
        let tk = if models.contains(&DamageModel::TavaresKing) {
            let Marginal::Fixed(n_year) = per_year else {
                return Err(Error::config(&file, "impact.impacts_per_year", "the Tavares–King model needs a fixed number of impacts per year (its damage table is per N)"));
            };
            let (glo, ghi) = (gamma.quantile(0.0), gamma.quantile(1.0));
            let ns: Vec<u64> = s.impact.years.iter().map(|y| (y * n_year).round().max(1.0) as u64).collect();
            CriticalRatioTable::for_impacts(&ns, glo, ghi.max(glo + 1e-9), TK_GAMMA_POINTS).into_iter().map(Some).collect()
        } else {
            vec![None; s.impact.years.len()]
        };
        let thermal = match &s.operating {
            None => None,
            Some(op) => {
                let law_path = crate::schema::resolve_relative(path, &op.law);
                if !law_path.is_file() {
                    return Err(Error::config(&file, "operating.law", format!("{} does not exist (a `kind = \"temperature\"` study with [phases] and [law])", law_path.display())));
                }
                let laws = Arc::new(crate::thermal::load_from_study(&law_path, reports_root)?);
                let temperatures = s
                    .material
                    .iter()
                    .map(|m| {
                        let (d, key) = op.of(&m.key).ok_or_else(|| Error::config(&file, "operating.temperature_c", format!("material `{}` has no operating temperature", m.key)))?;
                        let mg = d.marginal(&file, &key, "°C", &resolve)?;
                        laws.check_range(&file, &key, mg.quantile(0.0), mg.quantile(1.0))?;
                        Ok(mg)
                    })
                    .collect::<Result<Vec<_>>>()?;
                Some(SharedThermal { laws, temperatures })
            }
        };
        let input = |name: &str, unit: &str, marginal: Marginal| Input { name: name.into(), unit: unit.into(), marginal };
        Ok(Shared {
            inputs: [input("energy_fraction", "-", eta), input("velocity", "m/s", v), input("impacts_per_year", "1/yr", per_year), input("tk_gamma", "-", gamma)],
            tk,
            models,
            thermal,
        })
    }
}

/// The comparison under one strength model.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The strength model (as specified; `diagnosed` resolves per material).
    pub spec: StrengthSpec,
    /// Inputs in order (module docs).
    pub inputs: Vec<Input>,
    /// Candidate first, reference second.
    pub materials: [Material; 2],
    /// Horizons (years).
    pub years: Vec<f64>,
    /// Damage models (primary first).
    pub models: Vec<DamageModel>,
    /// Averaging domain of σ̄.
    pub domain: AveragingDomain,
    /// Operating temperatures, if any.
    pub thermal: Option<Thermal>,
    tk: Vec<Option<CriticalRatioTable>>,
    shared_at: usize,
}

impl Setup {
    /// Fits strength model `spec` to both materials of study `s` (file `path`) with averaging
    /// domain `domain`, and draws its uncertainty.
    pub fn new(s: &UqStudy, path: &Path, spec: &StrengthSpec, domain: &AveragingDomain, shared: &Shared) -> Result<Setup> {
        let file = path.display().to_string();
        let contact = ContactOptions { platen: s.contact.platen, averaging: *domain };
        let mut inputs = Vec::new();
        let mut materials = Vec::new();
        for (slot, &i) in s.order().iter().enumerate() {
            let m = &s.material[i];
            let data = m.read_data(path, i)?;
            let dpath = data.path.clone();
            let sample = sample_of(&data, &m.elastic, &contact)?;
            let naming = NamingSettings { seed: s.seed.wrapping_add(7919 * i as u64), ..s.strength.naming.clone() };
            let effects = crate::discrepancy::specs::resolve(spec, &sample, &naming)?;
            let fit = StrengthFit::new(&sample, &effects, naming.gamma, &m.key)?;
            let population = crate::strength::Population::of_material(m, i, &data, path, s.seed)?;
            let model = LifetimeModel::new(&m.key, &m.label, m.sphere(&data), s.impact.target, *domain, fit, population).map_err(|e| e.in_study(&file, &format!("material[{i}]")))?;
            let (draws, weights) = model.draws(s.strength.uncertainty, s.strength.draws, s.seed ^ (0xA5A5 + slot as u64))?;
            let origins = match &m.origin {
                Some(column) if effects.is_empty() => origin_laws(s, &model, &sample, &data, column, i, s.seed ^ (ORIGINS_SEED + slot as u64))?,
                _ => Vec::new(),
            };
            let strength_input = inputs.len();
            inputs.push(Input { name: format!("strength_{}", m.key), unit: "joint draw".into(), marginal: Marginal::Index(draws.len()) });
            let mut effect_inputs = Vec::new();
            let effect_columns = model.fit.scalar_effects();
            for (e, l) in &effect_columns {
                let mut v: Vec<f64> = draws.iter().map(|d| e.natural(d.beta[*l])).collect();
                v.sort_by(f64::total_cmp);
                let k = v.len();
                let p: Vec<f64> = (0..k).map(|r| r as f64 / (k - 1) as f64).collect();
                let (sym, _, _) = e.parameter(0.0, 1.0);
                effect_inputs.push(inputs.len());
                inputs.push(Input { name: format!("{}_{sym}_{}", e.name(), m.key), unit: "-".into(), marginal: Marginal::Quantiles { p, v } });
            }
            materials.push(Material { model, draws, weights, sample, path: dpath, read: data.provenance.clone(), strength_input, effect_inputs, effect_columns, origins, origin_column: m.origin.clone(), failure_origins: data.origins.clone() });
        }
        let samples: Vec<&Sample> = materials.iter().map(|m: &Material| &m.sample).collect();
        if let Some(e) = crate::discrepancy::specs::unclaimed(spec, &samples) {
            return Err(Error::config(&file, "strength.effects", format!("`{}`: neither material declares the factor `{}` in its `factors`", e.name(), e.covariate())));
        }
        let shared_at = inputs.len();
        inputs.extend(shared.inputs.iter().cloned());
        let [a, b]: [Material; 2] = materials.try_into().map_err(|_| Error::config(&file, "material", "two materials"))?;
        let mut setup = Setup { spec: spec.clone(), inputs, materials: [a, b], years: s.impact.years.clone(), models: shared.models.clone(), domain: *domain, thermal: None, tk: shared.tk.clone(), shared_at };
        if let Some(th) = &shared.thermal {
            let [ia, ib] = s.order();
            setup.attach_thermal(th.laws.clone(), [th.temperatures[ia].clone(), th.temperatures[ib].clone()])?;
        }
        Ok(setup)
    }

    /// Runs the comparison at operating temperatures: appends the inputs `temperature_law` and
    /// `operating_temperature_<key>` (marginals `temperatures`, candidate then reference).
    pub fn attach_thermal(&mut self, laws: Arc<ParameterLaws>, temperatures: [Marginal; 2]) -> Result<()> {
        let data_c = [self.materials[0].data_temperature_c()?, self.materials[1].data_temperature_c()?];
        for (m, t0) in self.materials.iter().zip(data_c) {
            laws.check_range(&m.path.display().to_string(), "temperature_c", t0, t0)?;
        }
        let law_input = self.inputs.len();
        self.inputs.push(Input { name: "temperature_law".into(), unit: "joint draw".into(), marginal: Marginal::Index(laws.len()) });
        let mut temperature_inputs = [0; 2];
        for (j, t) in temperatures.into_iter().enumerate() {
            temperature_inputs[j] = self.inputs.len();
            self.inputs.push(Input { name: format!("operating_temperature_{}", self.materials[j].model.key), unit: "°C".into(), marginal: t });
        }
        self.thermal = Some(Thermal { laws, law_input, temperature_inputs, data_c });
        Ok(())
    }

    /// Index into a sample's P of material j (0 candidate, 1 reference), horizon h, model k.
    pub fn slot(&self, j: usize, h: usize, k: usize) -> usize {
        (j * self.years.len() + h) * self.models.len() + k
    }

    /// Number of P values per sample.
    pub fn outputs(&self) -> usize {
        2 * self.years.len() * self.models.len()
    }

    /// Index of input `eta`, `velocity`, `per_year` or `gamma` (0–3).
    pub fn shared(&self, k: usize) -> usize {
        self.shared_at + k
    }

    /// Index of material j's input `strength_<key>` (the index of its joint draw).
    pub fn strength_input(&self, j: usize) -> usize {
        self.materials[j].strength_input
    }

    /// Index of the velocity input.
    pub fn velocity_input(&self) -> usize {
        self.shared(1)
    }

    /// Whether input i is an effect parameter (sampled in split mode only).
    fn is_effect(&self, i: usize) -> bool {
        self.materials.iter().any(|m| m.effect_inputs.contains(&i))
    }

    /// The inputs a unit point covers in `mode`.
    pub fn varying(&self, mode: Mode) -> Vec<usize> {
        (0..self.inputs.len()).filter(|&i| self.inputs[i].marginal.varies() && (mode == Mode::Split || !self.is_effect(i))).collect()
    }

    /// Full input vector from a unit point over the varying inputs of `mode` (in joint mode the
    /// effect inputs hold the joint draw's values).
    pub fn values(&self, u: &[f64], mode: Mode) -> Vec<f64> {
        let mut x = vec![0.0; self.inputs.len()];
        self.values_into(u, mode, &mut x);
        x
    }

    /// [`Setup::values`] into `x` (length: the number of inputs).
    pub fn values_into(&self, u: &[f64], mode: Mode, x: &mut [f64]) {
        let mut k = 0;
        for (i, xi) in x.iter_mut().enumerate() {
            let m = &self.inputs[i].marginal;
            *xi = if !m.varies() {
                m.quantile(0.5)
            } else if mode == Mode::Joint && self.is_effect(i) {
                f64::NAN
            } else {
                k += 1;
                m.quantile(u[k - 1])
            };
        }
        if mode == Mode::Joint {
            for mat in &self.materials {
                let d = &mat.draws[x[mat.strength_input] as usize];
                for (&i, (e, l)) in mat.effect_inputs.iter().zip(&mat.effect_columns) {
                    x[i] = e.natural(d.beta[*l]);
                }
            }
        }
    }

    /// Material j's strength parameters and population weights at inputs x.
    pub fn params(&self, j: usize, x: &[f64], mode: Mode) -> (Params, Option<&[f64]>) {
        let mat = &self.materials[j];
        let k = x[mat.strength_input] as usize;
        let d = mat.draws[k];
        let w = mat.weights.as_ref().map(|w| &w[k][..]);
        if mode == Mode::Joint {
            return (d, w);
        }
        // Split: keep the draw's μ_c = μ + Σ β z̄ and replace each single-column effect's β
        // by its input (a categorical factor's level columns stay the joint draw's).
        let mut p = d;
        for (&i, (e, l)) in mat.effect_inputs.iter().zip(&mat.effect_columns) {
            let l = *l;
            p.beta[l] = e.beta_of(x[i]);
            p.mu += (d.beta[l] - p.beta[l]) * mat.model.fit.centre[l];
        }
        (p, w)
    }

    /// P per material, horizon and damage model of the sample with inputs x, into `out`
    /// (length [`Setup::outputs`]).
    pub fn evaluate_into(&self, x: &[f64], mode: Mode, out: &mut [f64]) -> Result<()> {
        let temperatures = self.sample_temperatures(x);
        self.evaluate_at_temperatures(x, mode, temperatures, out)
    }

    /// [`Setup::evaluate_into`] with the operating temperatures (candidate, reference; °C) given
    /// instead of read from x (`None`: at the crush data's temperature). Needs
    /// [`Setup::attach_thermal`] for `Some`.
    pub fn evaluate_at_temperatures(&self, x: &[f64], mode: Mode, temperatures: Option<[f64; 2]>, out: &mut [f64]) -> Result<()> {
        let (strength, moduli, shared) = self.chain_inputs(x, mode, temperatures)?;
        self.evaluate_at(strength, moduli, shared, out)
    }

    /// Material j's P per horizon of `laws`, added into `out` (which the caller zeroes), at the
    /// impact stress `ln_sigma`: its one law at the sample's strength `s`, or with known failure
    /// origins every origin's law at the sample's draw, its scale shifted as `s`'s was, combined
    /// (module docs).
    fn material_into(&self, j: usize, s: &Strength, ln_sigma: f64, laws: &[Horizon], out: &mut [f64]) {
        let mat = &self.materials[j];
        if mat.origins.is_empty() {
            mat.model.breakage_into(&s.params, s.weights, ln_sigma, laws, out);
            return;
        }
        for (h, o) in laws.chunks(LAWS).zip(out.chunks_mut(LAWS)) {
            let mut survival = [0.0; LAWS];
            for origin in &mat.origins {
                let mut p = s.draw.map_or_else(|| origin.model.fit.estimate(), |d| origin.fit.draws[d]);
                p.mu += s.shift;
                let mut each = [0.0; LAWS];
                origin.model.breakage_into(&p, None, ln_sigma, h, &mut each[..h.len()]);
                for (sv, e) in survival.iter_mut().zip(&each[..h.len()]) {
                    *sv += ln_survival(*e);
                }
            }
            for (o, sv) in o.iter_mut().zip(&survival) {
                *o += from_ln_survival(*sv);
            }
        }
    }

    /// The operating temperatures of sample x (candidate, reference; °C), where the study has them.
    fn sample_temperatures(&self, x: &[f64]) -> Option<[f64; 2]> {
        self.thermal.as_ref().map(|th| [x[th.temperature_inputs[0]], x[th.temperature_inputs[1]]])
    }

    /// The chain's inputs of sample x: strength parameters and population weights, Young's
    /// modulus factors (candidate, reference) and the shared inputs (η, V, impacts per year, γ).
    fn chain_inputs<'a>(&'a self, x: &'a [f64], mode: Mode, temperatures: Option<[f64; 2]>) -> Result<([Strength<'a>; 2], [f64; 2], [f64; 4])> {
        let mut strength = [0, 1].map(|j| {
            let (params, weights) = self.params(j, x, mode);
            Strength { params, weights, draw: Some(x[self.materials[j].strength_input] as usize), shift: 0.0 }
        });
        let mut moduli = [1.0; 2];
        if let Some(t) = temperatures {
            let th = self.thermal.as_ref().ok_or_else(|| Error::numerical("comparison", "operating temperatures without temperature laws"))?;
            let j = x[th.law_input] as usize;
            for k in 0..2 {
                let f = th.laws.factors(j, t[k], th.data_c[k])?;
                strength[k].shift = f.strength.ln();
                strength[k].params.mu += strength[k].shift;
                moduli[k] = f.modulus;
            }
        }
        Ok((strength, moduli, [x[self.shared(0)], x[self.shared(1)], x[self.shared(2)], x[self.shared(3)]]))
    }

    /// The Tavares–King tables of critical ratios x*(N, γ) at horizons `years` (N = years ×
    /// impacts per year, rounded, at least 1), over the study's γ range, as the study's own
    /// horizons have them; None when the study has no Tavares–King model (which guarantees a
    /// fixed number of impacts per year).
    pub fn tk_tables(&self, years: &[f64]) -> Option<Vec<CriticalRatioTable>> {
        if !self.models.contains(&DamageModel::TavaresKing) {
            return None;
        }
        let Marginal::Fixed(per_year) = self.inputs[self.shared(2)].marginal else { return None };
        let gamma = &self.inputs[self.shared(3)].marginal;
        let (lo, hi) = (gamma.quantile(0.0), gamma.quantile(1.0));
        let ns: Vec<u64> = years.iter().map(|y| (y * per_year).round().max(1.0) as u64).collect();
        Some(CriticalRatioTable::for_impacts(&ns, lo, hi.max(lo + 1e-9), TK_GAMMA_POINTS))
    }

    /// P of sample x per material, horizon of `years` and damage model of `models`, at the
    /// sample's operating temperatures where the study has them (as [`Setup::evaluate_into`]),
    /// into `out` (length 2 · years · models, laid out as [`Setup::slot`] lays out the study's
    /// horizons and models). Tavares–King needs `tk`, its tables at `years` ([`Setup::tk_tables`]).
    pub fn evaluate_years(&self, x: &[f64], mode: Mode, years: &[f64], models: &[DamageModel], tk: Option<&[CriticalRatioTable]>, out: &mut [f64]) -> Result<()> {
        if models.contains(&DamageModel::TavaresKing) && tk.is_none_or(|t| t.len() != years.len()) {
            return Err(Error::numerical("comparison", "Tavares–King at horizons without a table of critical ratios"));
        }
        let temperatures = self.sample_temperatures(x);
        let (strength, moduli, [eta, v, per_year, gamma]) = self.chain_inputs(x, mode, temperatures)?;
        out.fill(0.0);
        let per = years.len() * models.len();
        let laws: Vec<Horizon> = years
            .iter()
            .enumerate()
            .flat_map(|(h, y)| {
                let ln_x_star = tk.map_or(0.0, |t| t[h].ln_ratio(gamma));
                models.iter().map(move |&model| Horizon { model, impacts: y * per_year, ln_x_star })
            })
            .collect();
        for (j, st) in strength.iter().enumerate() {
            let ln_sigma = self.materials[j].model.ln_impact_stress_with_modulus(eta, v, moduli[j])?;
            self.material_into(j, st, ln_sigma, &laws, &mut out[j * per..(j + 1) * per]);
        }
        Ok(())
    }

    /// P per material, horizon and damage model at a sample's strengths (candidate, reference),
    /// Young's modulus factors (candidate, reference; 1 at the crush data's temperature) and
    /// shared inputs (η, V, impacts per year, γ), into `out`.
    fn evaluate_at(&self, strength: [Strength; 2], moduli: [f64; 2], [eta, v, per_year, gamma]: [f64; 4], out: &mut [f64]) -> Result<()> {
        out.fill(0.0);
        let per = self.years.len() * self.models.len();
        let mut laws = [Horizon::independent(0.0); LAWS];
        for (j, st) in strength.iter().enumerate() {
            let mut c = 0;
            for (h, years) in self.years.iter().enumerate() {
                let ln_x_star = self.tk[h].as_ref().map_or(0.0, |t| t.ln_ratio(gamma));
                for &model in &self.models {
                    laws[c] = Horizon { model, impacts: years * per_year, ln_x_star };
                    c += 1;
                }
            }
            let ln_sigma = self.materials[j].model.ln_impact_stress_with_modulus(eta, v, moduli[j])?;
            self.material_into(j, st, ln_sigma, &laws[..per], &mut out[j * per..(j + 1) * per]);
        }
        Ok(())
    }

    /// P per material, horizon and damage model at each material's maximum-likelihood estimate
    /// (its one law with the population's point weights, or every failure origin's law), Young's
    /// modulus factors (candidate, reference) and shared inputs (η, V, impacts per year, γ), into
    /// `out`.
    pub fn evaluate_at_estimates(&self, moduli: [f64; 2], shared: [f64; 4], out: &mut [f64]) -> Result<()> {
        let strength = [0, 1].map(|j| Strength { params: self.materials[j].model.fit.estimate(), weights: None, draw: None, shift: 0.0 });
        self.evaluate_at(strength, moduli, shared, out)
    }

    /// [`Setup::evaluate_into`] from a unit point.
    pub fn evaluate(&self, u: &[f64], mode: Mode) -> Result<(Vec<f64>, Vec<f64>)> {
        let x = self.values(u, mode);
        let mut p = vec![0.0; self.outputs()];
        self.evaluate_into(&x, mode, &mut p)?;
        Ok((x, p))
    }
}

/// One material's strength in a sample: its one law's parameters and population weights, the
/// index of its joint draw (None: the maximum-likelihood estimates, each origin's where it has
/// them), and the ln factor of the operating temperature on its scale (already in `params`; 0 at
/// the crush data's temperature).
struct Strength<'a> {
    params: Params,
    weights: Option<&'a [f64]>,
    draw: Option<usize>,
    shift: f64,
}

/// Each failure origin's law of material `i` of study `s` (crush data `data` in `sample`, the
/// origins named in `column`) for a strength model without effects on it, with `s`'s draws
/// (module docs), its lifetime model `model`'s impact and population. An origin with fewer than
/// two breaks is refused, naming the file, the column and what to do.
fn origin_laws(s: &UqStudy, model: &LifetimeModel, sample: &Sample, data: &crate::data::CrushData, column: &str, i: usize, seed: u64) -> Result<Vec<OriginLaw>> {
    let x = sample.strength.view();
    let analysed = crate::strength::origins::analyse(x, &data.origins, column, s.strength.uncertainty, s.strength.draws, seed)?;
    if let Some(f) = analysed.fits.iter().find(|f| !f.shape.is_finite()) {
        return Err(Error::Data {
            file: data.path.display().to_string(),
            location: format!("column {column}"),
            rule: format!(
                "material `{}`: failure origin \"{}\" has {} break{}; each origin's Weibull law needs at least two. Merge it with another origin (relabel its particles, where the fractography allows), or fit one law to every origin: list the column in `material[{i}].data.ignore = [\"{column}\"]` instead of `origin`",
                model.key,
                f.origin,
                f.breaks,
                if f.breaks == 1 { "" } else { "s" }
            ),
        });
    }
    analysed
        .fits
        .into_iter()
        .map(|mut fit| {
            let strength = fit.strength.take().ok_or_else(|| Error::numerical("failure origins", format!("origin \"{}\" has a law but no fit", fit.origin)))?;
            let model = LifetimeModel::new(&model.key, &model.label, model.sphere, model.wall, model.domain, strength, model.population.clone())?;
            Ok(OriginLaw { fit, model })
        })
        .collect()
}
