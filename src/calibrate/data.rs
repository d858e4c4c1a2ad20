//! Calibration data: measured crush curves and named observations, reduced to a vector of
//! observations d_i with standard deviations σ_i, each tied to one model output.
//!
//! ## Crush curves (`particle, diameter_m, displacement_m, force_n`)
//! One force–displacement curve per particle. Particles differ in diameter; an elastic–plastic
//! continuum without a length scale (JH-2 with a negligible rate term, quasi-static loading)
//! crushes geometrically similar particles with `F(δ; D) = D² f(δ/D)`, so every curve is
//! **normalised to a reference diameter D₀** (`δ·D₀/D`, `F·(D₀/D)²`) and one FE run at D₀
//! serves all particles. The normalised curves are reduced to, per particle:
//! * the force at K grid displacements `δ_k = k/K · fraction · min_p δ_f,p` (below every
//!   particle's fracture, so a grid point is never on a post-fracture branch);
//! * the peak force and the fracture displacement (first sustained drop,
//!   [`crate::fracture::FractureDetector`]); a particle whose curve never drops is censored:
//!   it contributes its grid forces only.
//!
//! σ of each output is the **scatter between particles** (sample sd over particles) with a floor
//! of `sigma_floor` times the mean: particle-to-particle differences in roundness, diameter and
//! flaws are what a single-particle model cannot represent, and they dominate the machine's
//! noise. The calibrated θ is then that of the typical particle, and the posterior predictive of
//! a new particle adds σ.
//!
//! **Test temperature.** Every curve states the temperature it was measured at: a temperature
//! column (`temperature_c`, `temp`, `T [°C]` …; a furnace's log along the curve is one
//! temperature, its mean, where its readings lie within
//! [`crate::intake::observed::TEMPERATURE_TOLERANCE_C`]), else the study's `temperature_c` (a
//! calibration's `[data]`, a curve study's `[[data]]`); a curve with neither is refused, as a
//! crush or strength file is. A calibration fits the curves of one temperature (their mean, the
//! curves within the tolerance): curves at several are refused ([`reduce_curves`]), and the
//! reduction keeps the temperature, which the calibration's report states (`grid.csv`,
//! `summary.md`) and the studies that read it check against their own, to the tolerance.
//!
//! ## Observations (`output, unit, value, sd`)
//! One row per measured model output, by the output's name (for example the DEM's
//! `vz_at_100mm`, `mass_flow`): the unit must equal the model output's unit; sd > 0.

use std::path::Path;

use crate::error::{Error, Result};
use crate::fracture::{FractureDetector, FractureParams};
use crate::intake::{Field, Kind, MapOrigin, Provenance, Quantity, RawTable, Source, read_raw, resolve};
use crate::model::OutputSpec;

/// One measured curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    /// Particle label as in the file.
    pub particle: String,
    /// Diameter (m).
    pub diameter: f64,
    /// Total displacement (m), non-decreasing.
    pub displacement: Vec<f64>,
    /// Force (N).
    pub force: Vec<f64>,
    /// Test temperature (°C).
    pub temperature_c: f64,
}

impl Curve {
    /// The curve normalised to diameter `d0`.
    pub fn normalised(&self, d0: f64) -> Curve {
        let s = d0 / self.diameter;
        Curve {
            particle: self.particle.clone(),
            diameter: d0,
            displacement: self.displacement.iter().map(|x| x * s).collect(),
            force: self.force.iter().map(|f| f * s * s).collect(),
            temperature_c: self.temperature_c,
        }
    }

    /// Linear interpolation ([`crate::stats::locate`]) of the force at `x` (None outside the curve).
    pub fn force_at(&self, x: f64) -> Option<f64> {
        let (&first, &last) = (self.displacement.first()?, self.displacement.last()?);
        if !(x >= first && x <= last) {
            return None;
        }
        if self.displacement.len() == 1 {
            return Some(self.force[0]);
        }
        Some(crate::stats::lerp(&self.force, crate::stats::locate(&self.displacement, x)))
    }

    /// (peak force, fracture displacement) by the first sustained drop; None if it never drops.
    pub fn fracture(&self, p: FractureParams) -> Option<(f64, f64)> {
        let mut det = FractureDetector::new(p);
        for (&x, &f) in self.displacement.iter().zip(&self.force) {
            if let Some(at) = det.push(x, f) {
                return Some((det.result().0, at));
            }
        }
        None
    }
}

/// The fields of a curve file (read through [`crate::intake`]: any delimiter, decimal mark,
/// encoding or sheet; units from the headers, `displacement [mm]`, `F [kN]`).
pub const CURVE_FIELDS: [Field; 5] = [
    Field { key: "particle", column: "particle", kind: Kind::Text, synonyms: &["id", "particle_id", "probe", "sample", "specimen"], required: true, plausible: None },
    Field { key: "diameter", column: "diameter_m", kind: Kind::Number(Quantity::Length), synonyms: &["d", "dp"], required: true, plausible: Some(crate::data::DIAMETER) },
    Field { key: "displacement", column: "displacement_m", kind: Kind::Number(Quantity::Length), synonyms: &["s", "delta", "travel", "deformation"], required: true, plausible: None },
    Field { key: "force", column: "force_n", kind: Kind::Number(Quantity::Force), synonyms: &["f", "load"], required: true, plausible: Some(crate::data::CURVE_FORCE) },
    // Not `t`: a curve's time goes by it.
    Field { key: "temperature", column: "temperature_c", kind: Kind::Number(Quantity::Temperature), synonyms: &["temp", "test_temperature", "temperature", "temperatur", "prüftemperatur", "prueftemperatur"], required: false, plausible: Some(crate::intake::observed::TEMPERATURE) },
];

/// Reads a curve file (`temperature_c`: the test temperature of curves whose file states none,
/// module docs); every rule broken names the file, row and column.
pub fn load_curves(path: &Path, temperature_c: Option<f64>) -> Result<Vec<Curve>> {
    load_curves_mapped(path, &Default::default(), &Default::default(), &MapOrigin::default(), temperature_c)
}

/// [`load_curves`] with the study's map of the file: `columns` (field → the file's header, for
/// headers that do not name their field, e.g. `displacement = "Weg [µm]"`) and `units` (field →
/// unit, for headers that state none), as every crush data table takes them; `origin` names the
/// study table that holds the map; `temperature_c` the study's test temperature (module docs).
pub fn load_curves_mapped(path: &Path, columns: &std::collections::BTreeMap<String, String>, units: &std::collections::BTreeMap<String, String>, origin: &MapOrigin, temperature_c: Option<f64>) -> Result<Vec<Curve>> {
    Ok(read_curves(&Source { columns: columns.clone(), units: units.clone(), temperature_c, ..Source::file(path) }, origin)?.0)
}

/// The curves of `src` as a study describes the file (its sheet and header row, the column and
/// unit maps, the test temperature where the file gives none), with the record of how it was
/// read (columns, units, the test temperature and where it came from), for a report's manifest
/// and summary.
pub fn read_curves(src: &Source, origin: &MapOrigin) -> Result<(Vec<Curve>, Provenance)> {
    // One sheet: curves of several sheets would merge where their particle numbers repeat.
    if let Some(crate::intake::SheetRef::Several(_)) = &src.sheet {
        let key = if origin.key.is_empty() { "sheet".to_string() } else { format!("{}.sheet", origin.key) };
        return Err(crate::error::Error::config(&origin.file, key, "a curve file is read from one sheet (a name or a position): curves of several sheets would merge where their particle numbers repeat; give each sheet its own file entry"));
    }
    curves_of(&read_raw(src)?, &src.file, &src.columns, &src.units, origin, src.temperature_c)
}

/// The curves of a table already read from `path` (what [`load_curves_mapped`] does after
/// reading it), with how its columns were read.
pub fn curves_of(t: &RawTable, path: &Path, columns: &std::collections::BTreeMap<String, String>, units: &std::collections::BTreeMap<String, String>, origin: &MapOrigin, temperature_c: Option<f64>) -> Result<(Vec<Curve>, Provenance)> {
    // `T [°C]` is the test temperature (a bare `t` would be a time).
    let mut columns = columns.clone();
    let named_t = crate::intake::observed::temperature_named_t(&t.headers, &columns);
    if let Some(h) = &named_t {
        columns.insert("temperature".into(), h.clone());
    }
    let r = resolve(t, &CURVE_FIELDS, &columns, units, origin)?;
    for w in &r.provenance.warnings {
        crate::intake::warn(w);
    }
    let mut curves: Vec<Curve> = Vec::new();
    // Per curve: its first row and its temperature readings (none: no column, or empty cells).
    let mut cells: Vec<(usize, Vec<f64>)> = Vec::new();
    for i in 0..t.rows.len() {
        let particle = r.need_text("particle", i)?;
        let diam = r.need_number("diameter", i)?;
        let disp = r.need_number("displacement", i)?;
        let force = r.need_number("force", i)?;
        let temperature = r.number("temperature", i)?;
        if !(disp >= 0.0 && disp <= diam) {
            return Err(r.error(i, "displacement", format!("displacement must lie in [0, d = {diam} m] (a platen cannot travel more than the particle's diameter); got {disp} m")));
        }
        match curves.last_mut() {
            Some(c) if c.particle == particle => {
                if diam != c.diameter {
                    return Err(r.error(i, "diameter", format!("{diam} m differs from {} m earlier in particle {}'s curve", c.diameter, c.particle)));
                }
                let readings = &mut cells.last_mut().expect("readings per curve").1;
                if let Some(b) = temperature {
                    readings.push(b);
                    let (lo, hi) = crate::stats::min_max(readings);
                    if hi - lo > crate::intake::observed::TEMPERATURE_TOLERANCE_C {
                        return Err(r.error(i, "temperature", format!("{b} °C: particle {}'s curve spans {lo}–{hi} °C, more than the {} °C a furnace's readings of one test temperature scatter by: one curve is measured at one temperature", c.particle, crate::intake::observed::TEMPERATURE_TOLERANCE_C)));
                    }
                }
                if disp < *c.displacement.last().unwrap_or(&0.0) {
                    return Err(r.error(i, "displacement", format!("falls back (from {:e} to {:e} m): a curve's displacement must not decrease", c.displacement.last().unwrap_or(&0.0), disp)));
                }
                c.displacement.push(disp);
                c.force.push(force);
            }
            _ => {
                if curves.iter().any(|c| c.particle == particle) {
                    return Err(r.error(i, "particle", format!("particle {particle} appears again after another particle's rows")));
                }
                curves.push(Curve { particle, diameter: diam, displacement: vec![disp], force: vec![force], temperature_c: f64::NAN });
                cells.push((i, temperature.into_iter().collect()));
            }
        }
    }
    if curves.len() < 3 {
        return Err(Error::data_file(path, "file", format!("{} curves: at least 3 particles are needed to estimate their scatter", curves.len())));
    }
    if let Some(c) = curves.iter().find(|c| c.displacement.len() < 10) {
        return Err(Error::data_file(path, format!("particle {}", c.particle), format!("{} samples: a curve needs at least 10", c.displacement.len())));
    }
    // Every curve's test temperature: its column's, else the study's.
    let mut provenance = r.provenance.clone();
    if named_t.is_some() {
        crate::intake::observed::found_by_name(&mut provenance);
    }
    let column = r.column("temperature");
    let src = Source { temperature_c, ..Source::file(path) };
    // A curve's temperature: the mean of its readings, to 0.1 °C (a thermocouple's resolution).
    let means: Vec<Option<f64>> = cells.iter().map(|c| (!c.1.is_empty()).then(|| (10.0 * c.1.iter().sum::<f64>() / c.1.len() as f64).round() / 10.0)).collect();
    let temperatures = crate::intake::observed::test_temperatures(&means, &|k| t.place(cells[k].0, column), column.map(|c| format!("`{}`", t.headers[c])).as_deref(), &src, origin, &mut provenance)?;
    for (c, temperature) in curves.iter_mut().zip(temperatures) {
        c.temperature_c = temperature;
    }
    Ok((curves, provenance))
}

/// Observations d_i with σ_i, each of model output `output[i]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Observations {
    /// Values.
    pub values: Vec<f64>,
    /// Standard deviations (> 0).
    pub sigma: Vec<f64>,
    /// Model output index of each value.
    pub output: Vec<usize>,
    /// Group of each value (particle index for curves, 0 otherwise).
    pub group: Vec<usize>,
}

impl Observations {
    /// Number of observations.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    /// True without observations.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// Crush curves reduced for calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct CrushReduction {
    /// Reference diameter D₀ (m).
    pub reference_diameter: f64,
    /// Grid displacements at D₀ (m): the model's `force_at_…` outputs.
    pub grid: Vec<f64>,
    /// The curves normalised to D₀.
    pub curves: Vec<Curve>,
    /// Per particle: normalised (peak force, fracture displacement), None when censored.
    pub fractures: Vec<Option<(f64, f64)>>,
    /// The observations; outputs 0..K are the grid forces, K the peak force, K+1 the fracture
    /// displacement.
    pub observations: Observations,
    /// The curves' test temperature (°C).
    pub temperature_c: f64,
}

/// Reduces curves (see the module documentation); curves at several test temperatures are
/// refused.
pub fn reduce_curves(path: &Path, curves: &[Curve], d0: f64, points: usize, fraction: f64, sigma_floor: f64, fracture: FractureParams) -> Result<CrushReduction> {
    let all: Vec<f64> = curves.iter().map(|c| c.temperature_c).collect();
    let (lo, hi) = crate::stats::min_max(&all);
    if hi - lo > crate::intake::observed::TEMPERATURE_TOLERANCE_C {
        // Which particles are at which temperature.
        let mut at: Vec<(f64, Vec<&str>)> = Vec::new();
        for c in curves {
            match at.iter_mut().find(|(t, _)| *t == c.temperature_c) {
                Some(a) => a.1.push(&c.particle),
                None => at.push((c.temperature_c, vec![&c.particle])),
            }
        }
        at.sort_by(|a, b| a.0.total_cmp(&b.0));
        let which: Vec<String> = at.iter().map(|(t, p)| format!("{} °C: particle{} {}", crate::intake::columns::shown(*t), if p.len() == 1 { "" } else { "s" }, p.join(", "))).collect();
        return Err(Error::data_file(path, "file", format!("the curves were measured at {} ({}): a calibration fits the constants of one temperature; give each temperature its own file and calibration (a temperature study carries the constants between them)", crate::intake::observed::describe_temperatures(&all), which.join("; "))));
    }
    // One temperature: the mean of the curves'.
    let temperature_c = all.iter().sum::<f64>() / all.len().max(1) as f64;
    let curves: Vec<Curve> = curves.iter().map(|c| c.normalised(d0)).collect();
    let fractures: Vec<Option<(f64, f64)>> = curves.iter().map(|c| c.fracture(fracture)).collect();
    let fracture_min = fractures.iter().flatten().map(|f| f.1).fold(f64::INFINITY, f64::min);
    let broken = fractures.iter().flatten().count();
    if broken < 3 {
        return Err(Error::data_file(path, "file", format!("only {broken} curves show a sustained force drop (fracture): at least 3 are needed")));
    }
    let grid: Vec<f64> = (1..=points).map(|k| k as f64 / points as f64 * fraction * fracture_min).collect();
    let k = grid.len();
    // values[o][p]: output o of particle p.
    let mut per_output: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k + 2];
    for (p, c) in curves.iter().enumerate() {
        for (o, &x) in grid.iter().enumerate() {
            let f = c.force_at(x).ok_or_else(|| Error::data_file(path, format!("particle {}", c.particle), format!("the curve ends before the grid displacement {:.2} µm", x * 1e6)))?;
            per_output[o].push((p, f));
        }
        if let Some((f, x)) = fractures[p] {
            per_output[k].push((p, f));
            per_output[k + 1].push((p, x));
        }
    }
    let mut obs = Observations { values: vec![], sigma: vec![], output: vec![], group: vec![] };
    for (o, vals) in per_output.iter().enumerate() {
        let n = vals.len() as f64;
        let mean = vals.iter().map(|v| v.1).sum::<f64>() / n;
        let sd = (vals.iter().map(|v| (v.1 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let sigma = sd.max(sigma_floor * mean.abs());
        if !(sigma > 0.0) {
            return Err(Error::data_file(path, "file", format!("output {o} has zero scatter between particles: set a sigma floor > 0")));
        }
        for &(p, v) in vals {
            obs.values.push(v);
            obs.sigma.push(sigma);
            obs.output.push(o);
            obs.group.push(p);
        }
    }
    Ok(CrushReduction { reference_diameter: d0, grid, curves, fractures, observations: obs, temperature_c })
}

/// One row of an observation file.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservationRow {
    /// The model output's name.
    pub output: String,
    /// Its unit as written.
    pub unit: String,
    /// The value.
    pub value: f64,
    /// Its standard deviation (> 0).
    pub sd: f64,
}

/// Reads the rows of an observation file (`output, unit, value, sd`, through
/// [`crate::intake`]), checking each number; `place` gives each row's location for messages.
pub fn read_observation_rows(path: &Path) -> Result<(Vec<ObservationRow>, crate::intake::RawTable)> {
    let t = read_raw(&Source::file(path))?;
    let c = t.require(&["output", "unit", "value", "sd"])?;
    let mut rows = Vec::with_capacity(t.rows.len());
    for i in 0..t.rows.len() {
        let output = t.need_text(i, c[0])?;
        let unit = t.text(i, c[1]).unwrap_or_default();
        let value = t.need_number(i, c[2])?;
        let sd = t.need_number(i, c[3])?;
        if !(sd > 0.0) {
            return Err(t.error(i, Some(c[3]), format!("{sd} must be a finite number > 0")));
        }
        rows.push(ObservationRow { output, unit, value, sd });
    }
    if rows.is_empty() {
        return Err(Error::data_file(path, "file", "no observations"));
    }
    Ok((rows, t))
}

/// Reads an observation file (`output, unit, value, sd`) against the model outputs.
pub fn load_observations(path: &Path, outputs: &[OutputSpec]) -> Result<Observations> {
    let (rows, t) = read_observation_rows(path)?;
    let (c_output, c_unit) = (t.column("output"), t.column("unit"));
    let mut obs = Observations { values: vec![], sigma: vec![], output: vec![], group: vec![] };
    for (i, row) in rows.iter().enumerate() {
        let Some(o) = outputs.iter().position(|s| s.name == row.output) else {
            let known: Vec<&str> = outputs.iter().map(|s| s.name.as_str()).collect();
            return Err(t.error(i, c_output, format!("`{}` is not an output of the model ({})", row.output, known.join(", "))));
        };
        if row.unit != outputs[o].unit {
            return Err(t.error(i, c_unit, format!("`{}` does not match the model output's unit `{}`", row.unit, outputs[o].unit)));
        }
        obs.values.push(row.value);
        obs.sigma.push(row.sd);
        obs.output.push(o);
        obs.group.push(0);
    }
    Ok(obs)
}

/// The observations of each output combined into their precision-weighted mean: for Gaussian
/// noise this carries the whole likelihood of θ (the scatter about the mean does not depend on
/// θ), and an error common to all replicates of an output (emulator, model error) enters once,
/// not once per replicate.
#[derive(Debug, Clone, PartialEq)]
pub struct Aggregated {
    /// Model output index.
    pub output: Vec<usize>,
    /// Weighted mean d̄_o.
    pub mean: Vec<f64>,
    /// Its sd: `√(1/Σ σ_i⁻² + (model_error·d̄_o)²)`.
    pub sd: Vec<f64>,
    /// Observations combined.
    pub count: Vec<usize>,
}

impl Aggregated {
    /// Combines `obs` per output.
    pub fn new(obs: &Observations, model_error: f64) -> Aggregated {
        let mut outs: Vec<usize> = obs.output.clone();
        outs.sort_unstable();
        outs.dedup();
        let mut a = Aggregated { output: vec![], mean: vec![], sd: vec![], count: vec![] };
        for o in outs {
            let (mut w, mut wd, mut n) = (0.0, 0.0, 0);
            for i in (0..obs.len()).filter(|&i| obs.output[i] == o) {
                let wi = 1.0 / (obs.sigma[i] * obs.sigma[i]);
                w += wi;
                wd += wi * obs.values[i];
                n += 1;
            }
            let mean = wd / w;
            a.output.push(o);
            a.mean.push(mean);
            a.sd.push((1.0 / w + (model_error * mean).powi(2)).sqrt());
            a.count.push(n);
        }
        a
    }
}
