//! The phases of a microstructure: elastic constants and tensile strength, from a documented
//! table of the four phases the deliverable names, or given in the study.
//!
//! # The built-in table
//!
//! | name | phase | E (GPa) | ν | σ_t (MPa) | source |
//! |---|---|---|---|---|---|
//! | `alumina` | α-Al₂O₃ (corundum), dense sintered | 416 | 0.231 | 267 | Munro (1997): evaluated properties of 99.5 % sintered α-alumina at 20 °C (E, ν, tensile strength) |
//! | `fused_silica` | amorphous SiO₂ | 72.7 | 0.16 | 48 | Corning HPFS 7980 data sheet (E, ν; design tensile strength 7000 psi) |
//! | `quartz` | α-SiO₂, isotropic polycrystal | 95.6 | 0.079 | 100 | Bass (1995): Voigt–Reuss–Hill K = 37.8, G = 44.3 GPa; σ_t an order-of-magnitude estimate |
//! | `hematite` | α-Fe₂O₃, isotropic polycrystal | 238 | 0.31 | 100 | Liebermann & Schreiber (1968): K = 206.6, G = 91.0 GPa; σ_t an order-of-magnitude estimate |
//!
//! E and ν of quartz and hematite follow from K and G by E = 9KG/(3K + G),
//! ν = (3K − 2G)/(2(3K + G)). No tensile strength of quartz or hematite grains inside a particle has
//! been measured; 100 MPa is a placeholder of the right order for dense oxide grains and should be
//! replaced (`[[phase]] tensile_strength_pa`) when a value is known. The strengths enter only the
//! hot-spot measures and the first-failure stress, never the moduli.
//!
//! Note the deliverable's "harder quartz in a softer Fe₂O₃ matrix" (§5, §6.1): by these constants
//! hematite is the *stiffer* phase (E 238 vs 96 GPa); hardness and stiffness rank the two phases
//! differently, and only stiffness enters an elastic calculation.
//!
//! * R. G. Munro, *Evaluated material properties for a sintered α-alumina*, J. Am. Ceram. Soc. 80
//!   (1997) 1919–1928.
//! * J. D. Bass, *Elasticity of minerals, glasses, and melts*, in: Mineral Physics and
//!   Crystallography, AGU Reference Shelf 2 (1995) 45–63.
//! * R. C. Liebermann, E. Schreiber, *Elastic constants of polycrystalline hematite as a function of
//!   pressure to 3 kilobars*, J. Geophys. Res. 73 (1968) 6585–6590.
//! * Corning Inc., *HPFS Fused Silica Standard Grade* product information (7980).
//!
//! # Ranges
//!
//! A phase given in a study is refused (exit 2, naming the study file and key) unless
//! 1 GPa ≤ E ≤ 1500 GPa, −0.5 < ν < 0.5 and 1 MPa ≤ σ_t ≤ 20 GPa: outside them a value is a unit
//! slip (MPa for Pa) rather than a material.

use serde::{Deserialize, Serialize};

use crate::contact::Elastic;
use crate::error::{Error, Result};

/// A phase: its name, elastic constants and tensile strength.
#[derive(Debug, Clone, PartialEq)]
pub struct Phase {
    /// Name (`alumina`, …), as the study refers to it.
    pub name: String,
    /// Elastic constants.
    pub elastic: Elastic,
    /// Tensile strength σ_t (Pa): the maximum principal stress at which the phase cracks.
    pub tensile_strength_pa: f64,
    /// Where the constants come from.
    pub source: String,
}

/// The built-in table's names.
pub const BUILT_IN: [&str; 4] = ["alumina", "fused_silica", "quartz", "hematite"];

/// A phase of the built-in table (see the module documentation).
pub fn built_in(name: &str) -> Option<Phase> {
    let phase = |elastic: Elastic, tensile_strength_pa: f64, source: &str| Phase { name: name.to_string(), elastic, tensile_strength_pa, source: source.to_string() };
    let e_nu = |youngs_modulus_pa: f64, poisson_ratio: f64| Elastic { youngs_modulus_pa, poisson_ratio };
    Some(match name {
        "alumina" => phase(e_nu(416e9, 0.231), 267e6, "Munro (1997), J. Am. Ceram. Soc. 80, 1919"),
        "fused_silica" => phase(e_nu(72.7e9, 0.16), 48e6, "Corning HPFS 7980 data sheet"),
        "quartz" => phase(Elastic::from_shear_and_bulk(44.3e9, 37.8e9), 100e6, "Bass (1995) VRH K, G; σ_t order of magnitude"),
        "hematite" => phase(Elastic::from_shear_and_bulk(91.0e9, 206.6e9), 100e6, "Liebermann & Schreiber (1968) K, G; σ_t order of magnitude"),
        _ => return None,
    })
}

/// `[[phase]]` of a study: a built-in phase by name, any of its constants overridden, or a new
/// phase with all three constants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseSpec {
    /// Name; a built-in name takes its constants from the table.
    pub name: String,
    /// Young's modulus (Pa).
    pub youngs_modulus_pa: Option<f64>,
    /// Poisson's ratio.
    pub poisson_ratio: Option<f64>,
    /// Tensile strength (Pa).
    pub tensile_strength_pa: Option<f64>,
    /// Where the given constants come from (required when any is given).
    pub source: Option<String>,
}

impl PhaseSpec {
    /// The phase, checked against the ranges; `key` is the study key (`phase[1]`).
    pub fn resolve(&self, file: &str, key: &str) -> Result<Phase> {
        if self.name.trim().is_empty() || self.name.chars().any(|c| !(c.is_ascii_alphanumeric() || c == '_' || c == '-')) {
            return Err(Error::config(file, format!("{key}.name"), format!("must be a non-empty name of letters, digits, _ or -, got \"{}\"", self.name)));
        }
        let given = self.youngs_modulus_pa.is_some() || self.poisson_ratio.is_some() || self.tensile_strength_pa.is_some();
        let mut phase = match built_in(&self.name) {
            Some(p) => p,
            None => {
                let (Some(e), Some(nu), Some(st)) = (self.youngs_modulus_pa, self.poisson_ratio, self.tensile_strength_pa) else {
                    return Err(Error::config(file, key, format!("\"{}\" is not a built-in phase ({}): give youngs_modulus_pa, poisson_ratio and tensile_strength_pa", self.name, BUILT_IN.join(", "))));
                };
                Phase { name: self.name.clone(), elastic: Elastic { youngs_modulus_pa: e, poisson_ratio: nu }, tensile_strength_pa: st, source: String::new() }
            }
        };
        if given {
            let Some(source) = self.source.as_ref().filter(|s| !s.trim().is_empty()) else {
                return Err(Error::config(file, format!("{key}.source"), "say where the given constants come from"));
            };
            phase.source = source.clone();
        }
        if let Some(e) = self.youngs_modulus_pa {
            phase.elastic.youngs_modulus_pa = e;
        }
        if let Some(nu) = self.poisson_ratio {
            phase.elastic.poisson_ratio = nu;
        }
        if let Some(st) = self.tensile_strength_pa {
            phase.tensile_strength_pa = st;
        }
        let (e, nu, st) = (phase.elastic.youngs_modulus_pa, phase.elastic.poisson_ratio, phase.tensile_strength_pa);
        if !(e.is_finite() && (1e9..=1.5e12).contains(&e)) {
            return Err(Error::config(file, format!("{key}.youngs_modulus_pa"), format!("must lie in 1e9…1.5e12 Pa (1–1500 GPa), got {e}")));
        }
        if !(nu > -0.5 && nu < 0.5) {
            return Err(Error::config(file, format!("{key}.poisson_ratio"), format!("must lie in (−0.5, 0.5), got {nu}")));
        }
        if !(st.is_finite() && (1e6..=2e10).contains(&st)) {
            return Err(Error::config(file, format!("{key}.tensile_strength_pa"), format!("must lie in 1e6…2e10 Pa (1 MPa–20 GPa), got {st}")));
        }
        Ok(phase)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_table_converts_k_and_g() {
        let q = built_in("quartz").unwrap();
        assert!((q.elastic.youngs_modulus_pa - 95.6e9).abs() < 0.1e9 && (q.elastic.poisson_ratio - 0.079).abs() < 0.001, "{q:?}");
        let h = built_in("hematite").unwrap();
        assert!((h.elastic.youngs_modulus_pa - 238.05e9).abs() < 0.01e9 && (h.elastic.poisson_ratio - 0.308).abs() < 0.001, "{h:?}");
        for n in BUILT_IN {
            let spec = PhaseSpec { name: n.into(), youngs_modulus_pa: None, poisson_ratio: None, tensile_strength_pa: None, source: None };
            assert_eq!(spec.resolve("s.toml", "phase[0]").unwrap(), built_in(n).unwrap());
        }
    }

    #[test]
    fn a_phase_out_of_range_or_without_source_is_refused() {
        let spec = |e: Option<f64>, src: Option<&str>| PhaseSpec { name: "alumina".into(), youngs_modulus_pa: e, poisson_ratio: None, tensile_strength_pa: None, source: src.map(String::from) };
        let msg = spec(Some(416.0), Some("a typo")).resolve("s.toml", "phase[0]").unwrap_err().to_string();
        assert!(msg.contains("s.toml") && msg.contains("phase[0].youngs_modulus_pa") && msg.contains("1e9"), "{msg}");
        let msg = spec(Some(400e9), None).resolve("s.toml", "phase[0]").unwrap_err().to_string();
        assert!(msg.contains("phase[0].source"), "{msg}");
        let new = PhaseSpec { name: "glass".into(), youngs_modulus_pa: Some(70e9), poisson_ratio: None, tensile_strength_pa: None, source: Some("x".into()) };
        assert!(new.resolve("s.toml", "phase[2]").unwrap_err().to_string().contains("not a built-in phase"));
    }
}
