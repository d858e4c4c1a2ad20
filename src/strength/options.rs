//! Study-file options of the strength model: which effects it carries, how its uncertainty is
//! drawn, and the settings of the naming loop behind `effects = "diagnosed"`.
//!
//! ```toml
//! [strength]
//! effects = []                        # the deliverable's model (default)
//! # effects = ["size", "roundness"]   # an explicit list
//! # effects = "diagnosed"             # the discrepancy naming loop on each material's data
//! uncertainty = "bootstrap"           # or "bayesian"
//! draws = 4000
//! [strength.naming]                   # the loop's settings (only read for "diagnosed")
//! bootstrap = 499                     # replicates per round at most
//! sequential = true                   # stop a round at 99, 199, … once its decisions are settled
//! guard = "min-p"                     # family-wise p: Westfall–Young min-P, or "max-t"
//! ```

use std::fmt;

use serde::de::{self, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::effects::{ALL, Effect};
use crate::contact::AveragingDomain;
use crate::error::{Error, Result};

/// Which effects a strength model carries.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum StrengthSpec {
    /// An explicit list; empty is the deliverable's model (one Weibull law, R_c = d/2).
    Effects(Vec<Effect>),
    /// The effects the discrepancy naming loop names on each material's own data, with its
    /// false-discovery guard (so two materials may carry different effects).
    Diagnosed,
}

impl Default for StrengthSpec {
    fn default() -> Self {
        StrengthSpec::Effects(Vec::new())
    }
}

impl StrengthSpec {
    /// Name in tables and headlines: `deliverable`, `size+roundness`, `diagnosed`.
    pub fn name(&self) -> String {
        match self {
            StrengthSpec::Effects(v) if v.is_empty() => "deliverable".into(),
            StrengthSpec::Effects(v) => v.iter().map(|e| e.name()).collect::<Vec<_>>().join("+"),
            StrengthSpec::Diagnosed => "diagnosed".into(),
        }
    }

    /// Checks the list (no effect twice; contact-geometry effects need σ̄ ∝ p0), naming `file`
    /// and `key`.
    pub fn validate(&self, file: &str, key: &str, domain: &AveragingDomain) -> Result<()> {
        let StrengthSpec::Effects(v) = self else { return Ok(()) };
        for (i, e) in v.iter().enumerate() {
            if v[..i].contains(e) {
                return Err(Error::config(file, key, format!("lists the effect `{}` twice", e.name())));
            }
        }
        check_geometry(v, domain, file, key)
    }
}

/// Contact-geometry effects (roundness, sphericity) change the Hertz contact radius of
/// curvature; their power laws in the crush and the impact hold only when σ̄ is proportional to
/// the peak pressure (an averaging domain ending at a multiple of the contact radius).
pub fn check_geometry(effects: &[Effect], domain: &AveragingDomain, file: &str, key: &str) -> Result<()> {
    let zone = crate::contact::TensileZone::new(0.25);
    if let Some(e) = effects.iter().find(|e| e.is_contact_geometry())
        && domain.ratio_to_peak_pressure(&zone).is_none()
    {
        return Err(Error::config(
            file,
            key,
            format!(
                "the `{}` effect changes the contact curvature, which needs an averaging domain ending at a multiple of the contact radius (σ̄ ∝ p0); the study's domain is {}",
                e.name(),
                domain.describe()
            ),
        ));
    }
    Ok(())
}

impl Serialize for StrengthSpec {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            StrengthSpec::Effects(v) => v.serialize(s),
            StrengthSpec::Diagnosed => s.serialize_str("diagnosed"),
        }
    }
}

impl<'de> Deserialize<'de> for StrengthSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = StrengthSpec;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "a list of effects ({}) or \"diagnosed\"", super::effects::EFFECT_NAMES)
            }
            fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<StrengthSpec, E> {
                if v == "diagnosed" { Ok(StrengthSpec::Diagnosed) } else { Err(E::invalid_value(de::Unexpected::Str(v), &self)) }
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<StrengthSpec, A::Error> {
                let mut out = Vec::new();
                while let Some(e) = seq.next_element::<Effect>()? {
                    out.push(e);
                }
                Ok(StrengthSpec::Effects(out))
            }
        }
        d.deserialize_any(V)
    }
}

/// How the joint uncertainty of a fitted strength model is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Uncertainty {
    /// Parametric bootstrap in pivotal form (ASTM C1239's pivotal simulation, generalised to
    /// the Weibull regression; a plain parametric bootstrap when the model profiles a damage
    /// ratio).
    #[default]
    Bootstrap,
    /// Posterior with the prior flat in (μ, β, ln b), i.e. ∝ 1/(m σ_θ) without effects.
    Bayesian,
}

/// How the naming loop's guard makes one family-wise p-value of a round's candidates
/// ([`crate::discrepancy::guard`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FamilyGuard {
    /// Westfall–Young single-step min-P: each candidate's Λ is first turned into its own
    /// p-value (from its likelihood ratio's null law, fitted to its bootstrap replicates), and
    /// the family-wise p counts the replicates whose smallest such p lies at or below it. A
    /// candidate whose likelihood ratio has a heavy null tail (a two-population law) then no
    /// longer raises every other candidate's critical value.
    #[default]
    MinP,
    /// max-T: the family-wise p counts the replicates whose largest Λ*, on the one-parameter
    /// (Wilks χ²₁) scale, reaches the candidate's Λ on that scale.
    MaxT,
}

impl FamilyGuard {
    /// The name a study file and the reports use.
    pub fn name(self) -> &'static str {
        match self {
            FamilyGuard::MinP => "min-P",
            FamilyGuard::MaxT => "max-T",
        }
    }
}

/// Settings of the name → add → diagnose loop (the `[discrepancy]` section of a discrepancy
/// study, `[strength.naming]` of a study whose strength model is `"diagnosed"`); the seed is
/// the study's.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NamingSettings {
    /// Candidates to consider (default: all).
    pub candidates: Vec<Effect>,
    /// Bootstrap replicates per round at most: LR calibration and AD/KS p-values (default 499).
    pub bootstrap: usize,
    /// Stop a round's bootstrap at 99, 199, … replicates once every decision of the round is
    /// settled (default true; `crate::discrepancy::guard`'s sequential pretest); false draws
    /// all `bootstrap` replicates in every round.
    pub sequential: bool,
    /// How the family-wise p is made (default `"min-p"`, Westfall–Young; `"max-t"`).
    pub guard: FamilyGuard,
    /// Permutations of each residual-trend test (default 999).
    pub permutations: usize,
    /// Family-wise error rate of the guard (default 0.05).
    pub alpha: f64,
    /// Folds of the cross-validated log score (default 10).
    pub cv_folds: usize,
    /// Most effects to name (default 3).
    pub max_effects: usize,
    /// Tavares–King γ of the damage candidate (default 5).
    #[serde(rename = "tavares_king_gamma")]
    pub gamma: f64,
    /// Seed (set from the study's seed, not read from the section).
    #[serde(skip)]
    pub seed: u64,
}

impl Default for NamingSettings {
    fn default() -> Self {
        NamingSettings { candidates: ALL.to_vec(), bootstrap: 499, sequential: true, guard: FamilyGuard::MinP, permutations: 999, alpha: 0.05, cv_folds: 10, max_effects: 3, gamma: 5.0, seed: 20261122 }
    }
}

impl NamingSettings {
    /// Checks every setting, naming `file` and `key.<setting>`.
    pub fn validate(&self, file: &str, key: &str) -> Result<()> {
        let bad = |k: &str, rule: String| Err(Error::config(file, format!("{key}.{k}"), rule));
        if self.candidates.is_empty() {
            return bad("candidates", "needs at least one candidate".into());
        }
        if (1..self.candidates.len()).any(|i| self.candidates[..i].contains(&self.candidates[i])) {
            return bad("candidates", "lists a candidate twice".into());
        }
        if self.bootstrap < 99 {
            return bad("bootstrap", format!("must be ≥ 99 for a 5 % guard (got {})", self.bootstrap));
        }
        if self.permutations < 99 {
            return bad("permutations", format!("must be ≥ 99 (got {})", self.permutations));
        }
        if !(self.alpha > 0.0 && self.alpha <= 0.5) {
            return bad("alpha", format!("must lie in (0, 0.5] (got {})", self.alpha));
        }
        if self.cv_folds < 2 {
            return bad("cv_folds", format!("must be ≥ 2 (got {})", self.cv_folds));
        }
        if self.max_effects < 1 {
            return bad("max_effects", format!("must be ≥ 1 (got {})", self.max_effects));
        }
        if !(self.gamma > 0.0 && self.gamma.is_finite()) {
            return bad("tavares_king_gamma", format!("must be > 0 (got {})", self.gamma));
        }
        Ok(())
    }
}

/// The `[strength]` section of a lifetime or UQ study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StrengthOptions {
    /// Effects of the model (default: none, the deliverable's).
    pub effects: StrengthSpec,
    /// How its joint uncertainty is drawn (default: parametric bootstrap).
    pub uncertainty: Uncertainty,
    /// Joint draws per material (default 4000).
    pub draws: usize,
    /// Settings of the naming loop (read for `effects = "diagnosed"`).
    pub naming: NamingSettings,
}

impl Default for StrengthOptions {
    fn default() -> Self {
        StrengthOptions { effects: StrengthSpec::default(), uncertainty: Uncertainty::default(), draws: 4000, naming: NamingSettings::default() }
    }
}

impl StrengthOptions {
    /// Checks the section, naming `file` and the `strength.*` keys.
    pub fn validate(&self, file: &str, domain: &AveragingDomain) -> Result<()> {
        self.effects.validate(file, "strength.effects", domain)?;
        if !(100..=1_000_000).contains(&self.draws) {
            return Err(Error::config(file, "strength.draws", format!("must lie in [100, 10⁶] (got {})", self.draws)));
        }
        self.naming.validate(file, "strength.naming")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct S {
        effects: StrengthSpec,
    }

    #[test]
    fn lists_and_diagnosed_parse_and_print_back() {
        let s: S = toml::from_str("effects = [\"size\", \"roundness\"]").unwrap();
        assert_eq!(s.effects, StrengthSpec::Effects(vec![Effect::Size, Effect::Roundness]));
        assert_eq!(s.effects.name(), "size+roundness");
        let s: S = toml::from_str("effects = \"diagnosed\"").unwrap();
        assert_eq!(s.effects, StrengthSpec::Diagnosed);
        let s: S = toml::from_str("effects = []").unwrap();
        assert_eq!(s.effects.name(), "deliverable");
        let e = toml::from_str::<S>("effects = [\"rondness\"]").err().unwrap().to_string();
        assert!(e.contains("rondness") && e.contains("roundness"), "{e}");
        let e = toml::from_str::<S>("effects = \"all\"").err().unwrap().to_string();
        assert!(e.contains("diagnosed"), "{e}");
        let twice = StrengthSpec::Effects(vec![Effect::Size, Effect::Size]);
        let e = twice.validate("s.toml", "strength.effects", &AveragingDomain::default()).unwrap_err().to_string();
        assert!(e.contains("twice"), "{e}");
    }
}
