//! The set-up of a crush test: particle, mesh, material, platens, solver and fracture
//! definition ([`CrushSetup`]), with its validation.

use serde::{Deserialize, Serialize};
use crate::error::{Error, Result};
use super::material::MaterialParams;
use super::mesh::{Mesh, MeshParams, Shape};

/// Platen loading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlatenParams {
    /// Speed of each platen after the ramp (m/s, default 1): time scaling of a test run at
    /// mm/min (docs/reference.md, mechanics §2.3).
    pub speed: f64,
    /// Coulomb friction coefficient (default 0, frictionless).
    pub friction: f64,
    /// Largest total crush displacement δ_tot (m, default 60 µm).
    pub max_displacement: f64,
    /// Ramp duration in dilatational wave transits 2R/c (default 20).
    pub ramp_transits: f64,
}

impl Default for PlatenParams {
    fn default() -> Self {
        PlatenParams { speed: 1.0, friction: 0.0, max_displacement: 60e-6, ramp_transits: 20.0 }
    }
}

/// Solver controls.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverParams {
    /// Fraction of the critical time step (default 0.8).
    pub safety: f64,
    /// Density multiplier of the nodal masses (default 1, none).
    pub mass_scaling: f64,
    /// Hourglass stiffness coefficient (default 0.05).
    pub hourglass: f64,
    /// Linear bulk viscosity Q₁ (default 0.06, LS-DYNA's).
    pub bulk_viscosity_linear: f64,
    /// Quadratic bulk viscosity Q₂ (default 1.5, LS-DYNA's).
    pub bulk_viscosity_quadratic: f64,
    /// Steps between time-step updates (default 10).
    pub step_interval: u32,
    /// Force–displacement samples over `max_displacement` (default 300).
    pub samples: u32,
    /// Geometrically linear kinematics (default false): for comparisons with small-strain
    /// theory only; crush runs use the finite-deformation rate form.
    pub small_strain: bool,
}

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            safety: 0.8,
            mass_scaling: 1.0,
            hourglass: 0.05,
            bulk_viscosity_linear: 0.06,
            bulk_viscosity_quadratic: 1.5,
            step_interval: 10,
            samples: 300,
            small_strain: false,
        }
    }
}

pub use crate::fracture::FractureParams;

/// Kinematics of the section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kinematics {
    /// The (r, z) quarter of a body of revolution (forces in N).
    #[default]
    Axisymmetric,
    /// The whole (x, z) section of a prism, two platens (forces per unit thickness, N/m).
    PlaneStrain,
}

/// One crush test.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrushSetup {
    /// Particle height along the load = diameter of the sphere (m).
    pub diameter: f64,
    /// Outline.
    #[serde(default = "sphere")]
    pub shape: Shape,
    /// Particle material.
    pub material: MaterialParams,
    /// Mesh density.
    #[serde(default)]
    pub mesh: MeshParams,
    /// Loading.
    #[serde(default)]
    pub platen: PlatenParams,
    /// Solver controls.
    #[serde(default)]
    pub solver: SolverParams,
    /// Fracture definition.
    #[serde(default)]
    pub fracture: FractureParams,
    /// Total displacements δ_tot (m) at which element fields are kept.
    #[serde(default)]
    pub fields_at: Vec<f64>,
    /// Axisymmetric (default) or plane strain.
    #[serde(default)]
    pub kinematics: Kinematics,
    /// An irregular outline (plane strain only); replaces `shape`.
    #[serde(default)]
    pub outline: Option<super::outline::Outline>,
}

fn sphere() -> Shape {
    Shape::Sphere
}

impl CrushSetup {
    /// The mesh of this set-up: the axisymmetric quarter, or the plane-strain section of the
    /// shape or the outline.
    pub fn mesh(&self, file: &str) -> Result<Mesh> {
        let radius = 0.5 * self.diameter;
        let mesh = match (&self.kinematics, &self.outline) {
            (Kinematics::Axisymmetric, _) => Mesh::quarter(&self.shape, self.diameter, &self.mesh),
            (Kinematics::PlaneStrain, None) => {
                let shape = self.shape;
                Mesh::section(&|t: f64| radius * shape.radius_factor(t.abs().min(std::f64::consts::PI - t.abs())), 0.0, std::f64::consts::PI, &self.mesh)
            }
            (Kinematics::PlaneStrain, Some(o)) => {
                let poly = o.polygon(self.diameter, file, "crush.outline")?;
                let (top, bottom) = poly.poles();
                Mesh::section(&|t: f64| poly.radius(t), top, bottom, &self.mesh)
            }
        };
        mesh.map_err(|e| match e {
            Error::Config { key, rule, .. } => Error::config(file, format!("crush.{key}"), rule),
            other => other,
        })
    }

    /// Dilatational wave speed at rest (m/s).
    pub fn wave_speed(&self) -> f64 {
        let m = self.material.build();
        (m.wave_modulus(0.0) / m.density()).sqrt()
    }

    /// Checks every input before any step runs; `file` names the study in errors.
    pub fn validate(&self, file: &str) -> Result<()> {
        let bad = |k: &str, rule: String| Err(Error::config(file, k, rule));
        if !(self.diameter.is_finite() && self.diameter > 0.0) {
            return bad("crush.diameter", format!("must be positive, got {}", self.diameter));
        }
        self.shape.validate(file, "crush.shape")?;
        if self.outline.is_some() && self.kinematics != Kinematics::PlaneStrain {
            return bad("crush.outline", "an irregular outline needs kinematics = \"plane_strain\"".into());
        }
        self.material.validate(file, "crush.material")?;
        self.mesh.validate(file, "crush.mesh")?;
        let p = &self.platen;
        if !(p.speed.is_finite() && p.speed > 0.0) {
            return bad("crush.platen.speed", format!("must be positive, got {}", p.speed));
        }
        let c = self.wave_speed();
        if p.speed > 0.01 * c {
            return bad(
                "crush.platen.speed",
                format!(
                    "{} m/s is more than 1 % of the dilatational wave speed {c:.0} m/s: the run would be an impact, not a quasi-static crush (use ≤ {:.1} m/s)",
                    p.speed,
                    0.01 * c
                ),
            );
        }
        if !(p.friction.is_finite() && p.friction >= 0.0) {
            return bad("crush.platen.friction", format!("must be ≥ 0, got {}", p.friction));
        }
        if !(p.max_displacement > 0.0 && p.max_displacement < 0.5 * self.diameter) {
            return bad("crush.platen.max_displacement", format!("must lie in (0, d/2), got {}", p.max_displacement));
        }
        if !(p.ramp_transits >= 0.0 && p.ramp_transits.is_finite()) {
            return bad("crush.platen.ramp_transits", format!("must be ≥ 0, got {}", p.ramp_transits));
        }
        let s = &self.solver;
        if !(s.safety > 0.0 && s.safety <= 1.0) {
            return bad("crush.solver.safety", format!("must lie in (0, 1], got {}", s.safety));
        }
        if !(s.mass_scaling >= 1.0 && s.mass_scaling <= 1e4) {
            return bad("crush.solver.mass_scaling", format!("must lie in [1, 1e4], got {}", s.mass_scaling));
        }
        for (k, v) in [("hourglass", s.hourglass), ("bulk_viscosity_linear", s.bulk_viscosity_linear), ("bulk_viscosity_quadratic", s.bulk_viscosity_quadratic)] {
            if !(v.is_finite() && (0.0..=5.0).contains(&v)) {
                return bad(&format!("crush.solver.{k}"), format!("must lie in [0, 5], got {v}"));
            }
        }
        if s.step_interval == 0 || s.samples < 10 {
            return bad("crush.solver.samples", "step_interval ≥ 1 and samples ≥ 10 required".into());
        }
        let f = &self.fracture;
        let ok = f.drop > 0.0 && f.drop < 1.0 && f.sustain >= 0.0 && f.run_on >= 0.0;
        if !ok {
            return bad("crush.fracture", format!("drop must lie in (0, 1), sustain and run_on ≥ 0; got {f:?}"));
        }
        for (i, &d) in self.fields_at.iter().enumerate() {
            if !(d > 0.0 && d <= p.max_displacement) {
                return bad(&format!("crush.fields_at[{i}]"), format!("must lie in (0, max_displacement], got {d}"));
            }
        }
        Ok(())
    }
}
