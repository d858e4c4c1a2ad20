//! The crush test as a [`Simulator`]: θ = selected JH-2 (or elastic) constants, y = the platen
//! force at fixed total displacements, the peak force and the fracture displacement.
//!
//! θ names are the JH-2 card names of [`Jh2Params`] (`g`, `a`, `n`, `b`, `m`, `t`, `hel`, `phel`,
//! `beta`, `d1`, `d2`, `k1`, `k2`, `k3`, `sfmax`, `c`) or, for a linear elastic base,
//! `youngs_modulus` and `poisson_ratio`; they are resolved to setters once, at construction (an
//! unknown name is an error). A run that does not fracture reports the largest displacement
//! reached as its fracture displacement (a censored value) so the output stays finite.

use super::material::{Jh2Params, MaterialParams};
use super::{CrushSetup, CrushTest};
use crate::error::{Error, Result};
use crate::model::{OutputSpec, Simulator, check_outputs};
use crate::params::{Param, ParamSpace};

type Setter = fn(&mut MaterialParams, f64);
/// A JH-2 constant: its setter, getter and unit.
type Jh2Field = (Setter, fn(&Jh2Params) -> f64, &'static str);

fn jh2_setter(name: &str) -> Option<Jh2Field> {
    macro_rules! field {
        ($f:ident, $unit:expr) => {
            Some((
                |m: &mut MaterialParams, v: f64| {
                    if let MaterialParams::Jh2(j) = m {
                        j.$f = v;
                    }
                },
                |j: &Jh2Params| j.$f,
                $unit,
            ))
        };
    }
    match name {
        "g" => field!(g, "Pa"),
        "a" => field!(a, "-"),
        "n" => field!(n, "-"),
        "b" => field!(b, "-"),
        "m" => field!(m, "-"),
        "c" => field!(c, "-"),
        "t" => field!(t, "Pa"),
        "sfmax" => field!(sfmax, "-"),
        "hel" => field!(hel, "Pa"),
        "phel" => field!(phel, "Pa"),
        "beta" => field!(beta, "-"),
        "d1" => field!(d1, "-"),
        "d2" => field!(d2, "-"),
        "k1" => field!(k1, "Pa"),
        "k2" => field!(k2, "Pa"),
        "k3" => field!(k3, "Pa"),
        _ => None,
    }
}

/// The crush test as θ ↦ y.
#[derive(Debug, Clone)]
pub struct CrushModel {
    base: CrushSetup,
    setters: Vec<Setter>,
    displacements: Vec<f64>,
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
}

impl CrushModel {
    /// A model varying `params` (names, bounds and priors; nominal values are overwritten by
    /// the base set) and reporting the force at total displacements `displacements` (m).
    pub fn new(base: CrushSetup, params: Vec<Param>, displacements: Vec<f64>) -> Result<Self> {
        base.validate("<CrushModel>")?;
        let mut setters = Vec::new();
        let mut params = params;
        for p in params.iter_mut() {
            let (setter, getter, unit): (Setter, f64, &str) = match (&base.material, p.name.as_str()) {
                (MaterialParams::Jh2(j), name) => {
                    let (s, g, u) = jh2_setter(name)
                        .ok_or_else(|| Error::Param { name: name.into(), rule: "not a JH-2 constant (g a n b m c t sfmax hel phel beta d1 d2 k1 k2 k3)".into() })?;
                    (s, g(j), u)
                }
                (MaterialParams::LinearElastic(e), "youngs_modulus") => (
                    |m: &mut MaterialParams, v: f64| {
                        if let MaterialParams::LinearElastic(e) = m {
                            e.youngs_modulus = v;
                        }
                    },
                    e.youngs_modulus,
                    "Pa",
                ),
                (MaterialParams::LinearElastic(e), "poisson_ratio") => (
                    |m: &mut MaterialParams, v: f64| {
                        if let MaterialParams::LinearElastic(e) = m {
                            e.poisson_ratio = v;
                        }
                    },
                    e.poisson_ratio,
                    "-",
                ),
                (_, name) => return Err(Error::Param { name: name.into(), rule: "not a linear elastic constant (youngs_modulus, poisson_ratio)".into() }),
            };
            p.unit = unit.into();
            p.nominal = getter.clamp(p.lower, p.upper);
            setters.push(setter);
        }
        let space = ParamSpace::new(params)?;
        for (i, &d) in displacements.iter().enumerate() {
            if !(d > 0.0 && d <= base.platen.max_displacement) {
                return Err(Error::config("<CrushModel>", format!("displacements[{i}]"), format!("must lie in (0, max_displacement], got {d}")));
            }
        }
        let mut outputs: Vec<OutputSpec> = displacements.iter().map(|d| OutputSpec::new(format!("force_at_{:.1}um", d * 1e6), "N")).collect();
        outputs.push(OutputSpec::new("peak_force", "N"));
        outputs.push(OutputSpec::new("fracture_displacement", "m"));
        Ok(CrushModel { base, setters, displacements, space, outputs })
    }

    /// The set-up an evaluation runs.
    pub fn setup_at(&self, theta: &[f64]) -> Result<CrushSetup> {
        self.space.check(theta)?;
        let mut s = self.base.clone();
        s.fields_at.clear();
        for (set, &v) in self.setters.iter().zip(theta) {
            set(&mut s.material, v);
        }
        Ok(s)
    }
}

impl CrushModel {
    /// One FE run at θ: the outputs y and the whole result (curve, fields, checks).
    pub fn evaluate(&self, theta: &[f64]) -> Result<(Vec<f64>, super::CrushResult)> {
        let setup = self.setup_at(theta)?;
        let mut t = CrushTest::new(setup, "<CrushModel>")?;
        let r = t.run(None)?;
        let mut y: Vec<f64> = self.displacements.iter().map(|&d| force_at(&r.curve, d)).collect();
        y.push(r.peak_force);
        y.push(r.fracture_displacement.unwrap_or_else(|| r.curve.last().map(|s| s.displacement).unwrap_or(0.0)));
        check_outputs("crush FE", &self.outputs, theta, &y)?;
        Ok((y, r))
    }

    /// The force of the same particle with other contact tips, at θ and diameter `diameter`
    /// (m), on the displacements `grid` (m): one FE run per shape of `shapes`, in parallel, each
    /// calling `progress` when done. The curve-level discrepancy workflow's curvature term is the
    /// ratio of an asperity's forces to the sphere's.
    pub fn forces_with_shapes(&self, theta: &[f64], diameter: f64, shapes: &[super::mesh::Shape], grid: &[f64], progress: &(dyn Fn() + Sync)) -> Result<Vec<Vec<f64>>> {
        use rayon::prelude::*;
        shapes
            .par_iter()
            .map(|shape| {
                let mut s = self.setup_at(theta)?;
                s.diameter = diameter;
                s.shape = *shape;
                let r = CrushTest::new(s, "<CrushModel shapes>")?.run(None)?;
                progress();
                Ok(grid.iter().map(|&x| force_at(&r.curve, x)).collect())
            })
            .collect()
    }
}

/// Linear interpolation ([`crate::stats::locate`]) of the force at total displacement `d` on a
/// curve; 0 outside it (before its first or beyond its last sample).
pub fn force_at(curve: &[super::CurveSample], d: f64) -> f64 {
    let (Some(first), Some(last)) = (curve.first(), curve.last()) else { return 0.0 };
    if curve.len() < 2 || !(d >= first.displacement && d <= last.displacement) {
        return 0.0;
    }
    let x: Vec<f64> = curve.iter().map(|s| s.displacement).collect();
    let f: Vec<f64> = curve.iter().map(|s| s.force).collect();
    crate::stats::lerp(&f, crate::stats::locate(&x, d))
}

impl Simulator for CrushModel {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.evaluate(theta).map(|(y, _)| y)
    }
}
