//! The particle population a prediction is for.
//!
//! A breaking probability is a property of a population of particles, not of one median
//! particle: once the strength model carries effects, particles of different diameter,
//! roundness, sphericity or temperature have different strengths, and (contact-geometry
//! effects) different impact stresses. The model predicts P_N = Σ_i w_i P_N,i over the
//! population ([`super::LifetimeModel`]).
//!
//! Two sources:
//! * **data** (the default): the particles of the material's crush file with their measured
//!   covariates, fresh (no prior impacts). The point estimate weighs them 1/n; the uncertainty
//!   draws Dirichlet(1, …, 1) weights (the Bayesian bootstrap, Rubin 1981), so that the finite
//!   sample of particles is part of the band ([`Population::weight_draws`]).
//! * **declared** (`population = { particles = 512, diameter_m = {…}, roundness = {…}, … }` in
//!   the study's `[[material]]`): a stratified sample — randomly shifted Sobol' points through
//!   each declared distribution's quantile function, covariates independent — with equal
//!   weights and no sampling uncertainty (the distributions are declared, not estimated).
//!
//! Without effects every particle is alike and the population is one particle of the median
//! diameter (a Hertz impact of a sphere on a wall has a peak pressure independent of its
//! diameter at a given velocity and η, see [`super::model`]).
//!
//! **Recorded factors** (a crush file's `factors`, such as a powder batch or a sintering
//! temperature) are predicted for as the study's `predict` says ([`Prediction`]):
//!
//! ```toml
//! predict = { batch = "B2" }                       # every particle of level B2
//! predict = { batch = { B1 = 0.6, B2 = 0.4 } }     # levels in proportion (weights normalised)
//! predict = { sinter_c = 1450 }                    # a numeric factor at a value
//! predict = { sinter_c = { distribution = "normal", mean = 1450, sd = 10, min = 1420, max = 1480 } }
//! ```
//!
//! Levels in proportion expand each particle into one row per level, weighted by the level's
//! share (exact, no sampling); a distribution assigns each row a stratified quantile (the n
//! strata of the CDF shifted by one common seeded offset, dealt to the rows in a seeded random
//! order: one value per stratum). Without `predict`, a data
//! population keeps each particle's own recorded value — the levels in the proportions the
//! crush campaign had; a declared population has no recorded values and needs `predict` for
//! every factor its strength model carries. A level must be one of the data's (a new batch's
//! scale is not known), and a value outside the data's range is flagged as extrapolated.
//!
//! **Temperature**: `predict = { temperature_c = 800 }` (or a distribution) sets the temperature
//! every particle is predicted at — the operating temperature the lifetime is for. A strength
//! model that carries temperature softening predicts nothing without it (or a declared
//! population's `temperature_c`): the tests' temperatures are not the plant's
//! ([`Population::temperature_named`]).


use crate::data::CrushData;
use crate::dist::{Dist, Marginal, PopulationSpec};
use crate::error::{Error, Result};
use crate::intake::factors::{FactorColumns, FactorValues};

/// One particle of a population: its covariates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Particle {
    /// Diameter (m).
    pub diameter_m: f64,
    /// Wadell roundness (-), if measured or declared.
    pub roundness: Option<f64>,
    /// Sphericity (-), if measured or declared.
    pub sphericity: Option<f64>,
    /// Temperature (°C), if measured or declared.
    pub temperature_c: Option<f64>,
}

/// The particles a prediction averages over: one row per particle, or per particle and level
/// when a factor is predicted for levels in proportion.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Population {
    /// `data: <file>` or `declared`.
    pub source: String,
    /// The particles (one per row).
    pub particles: Vec<Particle>,
    /// Whether the particles are a sample of an unknown population (data): the uncertainty then
    /// redraws their weights.
    pub sampled: bool,
    /// Recorded factor values per row (named as the study's `factors`).
    pub factors: FactorColumns,
    /// Weight of each row within its particle (a level's share; empty: every row 1).
    pub within: Vec<f64>,
    /// The particle of the sample each row belongs to (empty: row i is particle i).
    pub parent: Vec<usize>,
    /// What each predicted factor is set to, in words (`batch = B2`).
    pub predicted: Vec<String>,
}

/// What a prediction is for, for one recorded factor (`predict.<factor>` of a `[[material]]`).
#[derive(Debug, Clone, PartialEq)]
pub enum Prediction {
    /// One level of a categorical factor.
    Level(String),
    /// Levels of a categorical factor in proportion (weights normalised to 1).
    Levels(Vec<(String, f64)>),
    /// A value of a numeric factor.
    Value(f64),
    /// A distribution of a numeric factor.
    Distribution(Marginal),
}

impl Prediction {
    /// The prediction a study writes for factor `name` whose data values are `data`; `file` and
    /// `key` (`material[0].predict.batch`) name it in errors.
    pub fn parse(value: &toml::Value, data: &FactorValues, file: &str, key: &str, resolve: &dyn Fn(&str) -> std::path::PathBuf) -> Result<Prediction> {
        let bad = |rule: String| Error::config(file, key, rule);
        match data {
            FactorValues::Levels(v) => {
                let mut known: Vec<&String> = v.iter().collect();
                known.sort();
                known.dedup();
                let list = known.iter().map(|l| format!("\"{l}\"")).collect::<Vec<_>>().join(", ");
                let level = |l: &str| -> Result<String> {
                    if known.iter().any(|k| *k == l) {
                        Ok(l.to_string())
                    } else {
                        Err(bad(format!("\"{l}\" is not a level of the data (its levels: {list}); a level the data never saw has no fitted scale")))
                    }
                };
                match value {
                    toml::Value::String(l) => Ok(Prediction::Level(level(l.trim())?)),
                    toml::Value::Integer(i) => Ok(Prediction::Level(level(&i.to_string())?)),
                    toml::Value::Table(t) => {
                        let mut out = Vec::new();
                        for (l, w) in t {
                            let w = w.as_float().or_else(|| w.as_integer().map(|i| i as f64)).ok_or_else(|| bad(format!("the weight of \"{l}\" must be a number")))?;
                            if !(w.is_finite() && w >= 0.0) {
                                return Err(bad(format!("the weight of \"{l}\" must be ≥ 0 (got {w})")));
                            }
                            out.push((level(l.trim())?, w));
                        }
                        let total: f64 = out.iter().map(|(_, w)| w).sum();
                        if !(total > 0.0) {
                            return Err(bad("needs at least one level with a weight > 0".into()));
                        }
                        out.retain(|(_, w)| *w > 0.0);
                        Ok(Prediction::Levels(out.into_iter().map(|(l, w)| (l, w / total)).collect()))
                    }
                    _ => Err(bad(format!("a categorical factor is predicted for a level (\"B2\") or levels in proportion ({{ B1 = 0.6, B2 = 0.4 }}); its levels: {list}"))),
                }
            }
            FactorValues::Numeric(_) => match value {
                toml::Value::Float(x) if x.is_finite() => Ok(Prediction::Value(*x)),
                toml::Value::Integer(i) => Ok(Prediction::Value(*i as f64)),
                toml::Value::Table(_) => {
                    let d: Dist = value.clone().try_into().map_err(|e| bad(format!("not a distribution: {e}")))?;
                    if matches!(d, Dist::Spectrum { .. }) {
                        return Err(bad("a spectrum is a velocity distribution only".into()));
                    }
                    Ok(Prediction::Distribution(d.marginal(file, key, "as in the file", resolve)?))
                }
                _ => Err(bad("a numeric factor is predicted for a value (1450) or a distribution ({ distribution = \"uniform\", min = …, max = … })".into())),
            },
        }
    }
}

/// One value per row from `m`'s n strata: the strata of the CDF shifted by one common seeded
/// offset, dealt to the rows in a seeded random order.
fn stratified(m: &Marginal, n: usize, seed: u64) -> Vec<f64> {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rng);
    let u: f64 = rand::Rng::random(&mut rng);
    order.iter().map(|&k| m.quantile((k as f64 + u) / n as f64)).collect()
}

impl Population {
    /// The crushed particles of a dataset, fresh.
    pub fn of_data(data: &CrushData) -> Population {
        let particles = data
            .records
            .iter()
            .map(|r| Particle { diameter_m: r.diameter_m, roundness: r.roundness, sphericity: r.sphericity, temperature_c: r.temperature_c })
            .collect();
        Population { source: format!("data: {}", data.path.display()), particles, sampled: true, factors: data.factors.clone(), ..Population::default() }
    }

    /// A declared population: `spec.particles` randomly shifted Sobol' points (seeded) through
    /// the declared quantile functions. `file` and `key` name the study key in errors.
    pub fn declared(spec: &PopulationSpec, file: &str, key: &str, resolve: &dyn Fn(&str) -> std::path::PathBuf, seed: u64) -> Result<Population> {
        let bad = |k: &str, rule: String| Error::config(file, format!("{key}.{k}"), rule);
        if !(16..=100_000).contains(&spec.particles) {
            return Err(bad("particles", format!("must lie in [16, 100000] (got {})", spec.particles)));
        }
        let mut marginals: Vec<(&str, Marginal)> = Vec::new();
        use crate::data::{DIAMETER, ROUNDNESS, SPHERICITY, TEMPERATURE};
        // The plausibility ranges of the crush data's columns.
        let ranges = [("diameter_m", Some(&spec.diameter_m), DIAMETER, "m"), ("roundness", spec.roundness.as_ref(), ROUNDNESS, "-"), ("sphericity", spec.sphericity.as_ref(), SPHERICITY, "-"), ("temperature_c", spec.temperature_c.as_ref(), TEMPERATURE, "°C")];
        for (name, dist, range, unit) in ranges {
            let Some(d) = dist else { continue };
            if matches!(d, Dist::Spectrum { .. }) {
                return Err(bad(name, "a spectrum is a velocity distribution only".into()));
            }
            let m = d.marginal(file, &format!("{key}.{name}"), unit, resolve)?;
            let (a, b) = (m.quantile(0.0), m.quantile(1.0));
            if !(range.contains(a) && range.contains(b)) {
                return Err(bad(name, format!("values must lie in {} ({}); the distribution spans [{a}, {b}]", range.shown, range.why)));
            }
            marginals.push((name, m));
        }
        let points = crate::design::shifted_sobol(marginals.len(), spec.particles, seed, 0)?;
        let particles = points
            .iter()
            .map(|u| {
                let get = |name: &str| marginals.iter().position(|(n, _)| *n == name).map(|k| marginals[k].1.quantile(u[k]));
                Particle { diameter_m: get("diameter_m").unwrap_or(f64::NAN), roundness: get("roundness"), sphericity: get("sphericity"), temperature_c: get("temperature_c") }
            })
            .collect();
        Ok(Population { source: "declared".into(), particles, sampled: false, ..Population::default() })
    }

    /// The population of material `index` of the study `file`: declared (`population = { … }`,
    /// seeded by `seed` and the index) or the particles of `data`, with the recorded factors set
    /// as its `predict` says (module docs).
    pub fn of_material(m: &crate::schema::MaterialSpec, index: usize, data: &CrushData, file: &std::path::Path, seed: u64) -> Result<Population> {
        let resolve = |q: &str| crate::schema::resolve_relative(file, std::path::Path::new(q));
        let name = file.display().to_string();
        let mut pop = match &m.population {
            None => Population::of_data(data),
            Some(p) => Population::declared(p, &name, &format!("material[{index}].population"), &resolve, seed ^ (0x909 + index as u64))?,
        };
        for (k, (factor, value)) in m.predict.iter().enumerate() {
            let key = format!("material[{index}].predict.{factor}");
            if factor == "temperature_c" && !data.factors.iter().any(|(n, _)| n == factor) {
                // The operating temperature: a value or a distribution over the tests' range.
                let tested: Vec<f64> = data.records.iter().filter_map(|r| r.temperature_c).collect();
                let prediction = Prediction::parse(value, &FactorValues::Numeric(tested.clone()), &name, &key, &resolve)?;
                pop.predict_temperature(&tested, &prediction, seed ^ (0x7E3 + 97 * index as u64));
                continue;
            }
            let Some((_, values)) = data.factors.iter().find(|(n, _)| n == factor) else {
                let known = data.factors.iter().map(|(n, _)| format!("`{n}`")).collect::<Vec<_>>().join(", ");
                return Err(Error::config(&name, key, format!("`{factor}` is not a recorded factor of this material (declared in its `factors`: {})", if known.is_empty() { "none".into() } else { known })));
            };
            let prediction = Prediction::parse(value, values, &name, &key, &resolve)?;
            pop.predict(factor, values, &prediction, seed ^ (0xFAC7 + 97 * index as u64 + k as u64));
        }
        Ok(pop)
    }

    /// Whether the study named the temperature the population is predicted at: `predict`'s
    /// `temperature_c`, or a declared population with a `temperature_c` for every particle.
    pub fn temperature_named(&self) -> bool {
        self.predicted.iter().any(|p| p.starts_with("temperature_c ")) || (self.source == "declared" && self.particles.iter().all(|p| p.temperature_c.is_some()))
    }

    /// The temperature the study predicts at, in words (`800 °C`, `700–800 °C (declared
    /// distribution)`), or None where it named none.
    pub fn predicted_temperature(&self) -> Option<String> {
        let p = self.predicted.iter().find(|p| p.starts_with("temperature_c "))?;
        Some(p.trim_start_matches("temperature_c ").trim_start_matches("= ").trim_start_matches("over ").to_string())
    }

    /// Sets every particle's temperature as `prediction` (a value or a distribution) says;
    /// `tested`: the tests' temperatures, for the range.
    pub fn predict_temperature(&mut self, tested: &[f64], prediction: &Prediction, seed: u64) {
        let (lo, hi) = tested.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        let outside = |a: f64, b: f64| if a < lo || b > hi { format!(" (outside the tests' {lo}–{hi} °C: extrapolated)") } else { String::new() };
        let values = match prediction {
            Prediction::Value(x) => {
                self.predicted.push(format!("temperature_c = {x} °C{}", outside(*x, *x)));
                vec![*x; self.particles.len()]
            }
            Prediction::Distribution(m) => {
                let (a, b) = (m.quantile(0.0), m.quantile(1.0));
                self.predicted.push(format!("temperature_c over {a}–{b} °C (declared distribution){}", outside(a, b)));
                stratified(m, self.particles.len(), seed)
            }
            // A numeric factor's prediction is a value or a distribution (Prediction::parse).
            Prediction::Level(_) | Prediction::Levels(_) => return,
        };
        for (p, t) in self.particles.iter_mut().zip(values) {
            p.temperature_c = Some(t);
        }
    }

    /// Sets factor `name` of every row as `prediction` says (`data`: its values in the fitted
    /// data, for the range; `seed`: the order of a distribution's strata).
    pub fn predict(&mut self, name: &str, data: &FactorValues, prediction: &Prediction, seed: u64) {
        let n = self.particles.len();
        if self.parent.is_empty() {
            self.parent = (0..n).collect();
        }
        if self.within.is_empty() {
            self.within = vec![1.0; n];
        }
        let set = |pop: &mut Population, values: FactorValues| match pop.factors.iter_mut().find(|(c, _)| c == name) {
            Some((_, v)) => *v = values,
            None => pop.factors.push((name.to_string(), values)),
        };
        let range = match data {
            FactorValues::Numeric(v) => (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(f64::NEG_INFINITY, f64::max)),
            FactorValues::Levels(_) => (f64::NAN, f64::NAN),
        };
        let outside = |lo: f64, hi: f64| if lo < range.0 || hi > range.1 { format!(" (outside the data's {}–{}: extrapolated)", range.0, range.1) } else { String::new() };
        match prediction {
            Prediction::Level(l) => {
                set(self, FactorValues::Levels(vec![l.clone(); n]));
                self.predicted.push(format!("{name} = {l}"));
            }
            Prediction::Value(x) => {
                set(self, FactorValues::Numeric(vec![*x; n]));
                self.predicted.push(format!("{name} = {x}{}", outside(*x, *x)));
            }
            Prediction::Levels(weights) => {
                let rows: Vec<(usize, usize)> = (0..n).flat_map(|r| (0..weights.len()).map(move |k| (r, k))).collect();
                self.particles = rows.iter().map(|&(r, _)| self.particles[r]).collect();
                self.parent = rows.iter().map(|&(r, _)| self.parent[r]).collect();
                self.within = rows.iter().map(|&(r, k)| self.within[r] * weights[k].1).collect();
                for (_, v) in self.factors.iter_mut() {
                    let mut keep = v.clone();
                    keep.keep(&rows.iter().map(|&(r, _)| r).collect::<Vec<_>>());
                    *v = keep;
                }
                set(self, FactorValues::Levels(rows.iter().map(|&(_, k)| weights[k].0.clone()).collect()));
                let shares = weights.iter().map(|(l, w)| format!("{l} {:.0} %", 100.0 * w)).collect::<Vec<_>>().join(", ");
                self.predicted.push(format!("{name}: {shares}"));
            }
            Prediction::Distribution(m) => {
                let values = stratified(m, n, seed);
                let (lo, hi) = (m.quantile(0.0), m.quantile(1.0));
                set(self, FactorValues::Numeric(values));
                self.predicted.push(format!("{name} over {lo}–{hi} (declared distribution){}", outside(lo, hi)));
            }
        }
    }

    /// What the population is for in the recorded factors `names`, in words: the study's
    /// `predict` where it set them, else the data's own values (`Charge as recorded: K1 15,
    /// K2 15, K3 15`, `rate as recorded: 1.5–4`).
    pub fn describe_factors(&self, names: &[String]) -> String {
        names
            .iter()
            .map(|n| match self.predicted.iter().find(|p| p.starts_with(&format!("{n} ")) || p.starts_with(&format!("{n}:"))) {
                Some(p) => p.clone(),
                None => match self.factors.iter().find(|(c, _)| c == n) {
                    Some((_, FactorValues::Levels(v))) => {
                        let mut counts: Vec<(&str, usize)> = Vec::new();
                        for l in v {
                            match counts.iter_mut().find(|(x, _)| *x == l) {
                                Some(c) => c.1 += 1,
                                None => counts.push((l, 1)),
                            }
                        }
                        format!("{n} as recorded: {}", counts.iter().map(|(l, k)| format!("{l} {k}")).collect::<Vec<_>>().join(", "))
                    }
                    Some((_, FactorValues::Numeric(v))) => {
                        let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
                        format!("{n} as recorded: {lo}–{hi}")
                    }
                    None => format!("{n}: no value"),
                },
            })
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// Number of particles of the sample (rows of one particle at several levels count once).
    pub fn sample_size(&self) -> usize {
        if self.parent.is_empty() { self.particles.len() } else { self.parent.iter().copied().max().map_or(0, |k| k + 1) }
    }

    /// Each row's weight in the point estimate (None: equal).
    pub fn point_weights(&self) -> Option<Vec<f64>> {
        if self.within.is_empty() {
            return None;
        }
        let n = self.sample_size() as f64;
        Some(self.within.iter().map(|w| w / n).collect())
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// Whether it has no particle.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty()
    }

    /// `k` draws of the rows' weights: Dirichlet(1, …, 1) over the particles of a sampled
    /// population (the Bayesian bootstrap; draw r from its own ChaCha8 stream of `seed`), each
    /// row getting its particle's weight times its share within the particle; for a declared
    /// population None (the point weights).
    pub fn weight_draws(&self, k: usize, seed: u64) -> Option<Vec<Vec<f64>>> {
        use rand::SeedableRng;
        use rand_distr::Distribution;
        let n = self.sample_size();
        if !self.sampled || n < 2 {
            return None;
        }
        Some(
            (0..k)
                .map(|r| {
                    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                    rng.set_stream(r as u64 + 1);
                    let g: Vec<f64> = (0..n).map(|_| rand_distr::Exp1.sample(&mut rng)).collect();
                    let total: f64 = g.iter().sum();
                    if self.within.is_empty() {
                        g.into_iter().map(|x| x / total).collect()
                    } else {
                        self.within.iter().zip(&self.parent).map(|(w, &p)| w * g[p] / total).collect()
                    }
                })
                .collect(),
        )
    }
}
