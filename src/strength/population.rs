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


use crate::data::CrushData;
use crate::dist::{Dist, Marginal, PopulationSpec};
use crate::error::{Error, Result};

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

/// The particles a prediction averages over.
#[derive(Debug, Clone, PartialEq)]
pub struct Population {
    /// `data: <file>` or `declared`.
    pub source: String,
    /// The particles.
    pub particles: Vec<Particle>,
    /// Whether the particles are a sample of an unknown population (data): the uncertainty then
    /// redraws their weights.
    pub sampled: bool,
}

impl Population {
    /// The crushed particles of a dataset, fresh.
    pub fn of_data(data: &CrushData) -> Population {
        let particles = data
            .records
            .iter()
            .map(|r| Particle { diameter_m: r.diameter_m, roundness: r.roundness, sphericity: r.sphericity, temperature_c: r.temperature_c })
            .collect();
        Population { source: format!("data: {}", data.path.display()), particles, sampled: true }
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
        Ok(Population { source: "declared".into(), particles, sampled: false })
    }

    /// The population of material `index` of the study `file`: declared (`population = { … }`,
    /// seeded by `seed` and the index) or the particles of `data`.
    pub fn of_material(m: &crate::schema::MaterialSpec, index: usize, data: &CrushData, file: &std::path::Path, seed: u64) -> Result<Population> {
        match &m.population {
            None => Ok(Population::of_data(data)),
            Some(p) => {
                let resolve = |q: &str| crate::schema::resolve_relative(file, std::path::Path::new(q));
                Population::declared(p, &file.display().to_string(), &format!("material[{index}].population"), &resolve, seed ^ (0x909 + index as u64))
            }
        }
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.particles.len()
    }

    /// Whether it has no particle.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty()
    }

    /// `k` draws of the particles' weights: Dirichlet(1, …, 1) for a sampled population (the
    /// Bayesian bootstrap; draw r from its own ChaCha8 stream of `seed`), None for a declared one
    /// (equal weights).
    pub fn weight_draws(&self, k: usize, seed: u64) -> Option<Vec<Vec<f64>>> {
        use rand::SeedableRng;
        use rand_distr::Distribution;
        if !self.sampled || self.particles.len() < 2 {
            return None;
        }
        Some(
            (0..k)
                .map(|r| {
                    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
                    rng.set_stream(r as u64 + 1);
                    let g: Vec<f64> = (0..self.particles.len()).map(|_| rand_distr::Exp1.sample(&mut rng)).collect();
                    let total: f64 = g.iter().sum();
                    g.into_iter().map(|x| x / total).collect()
                })
                .collect(),
        )
    }
}
