//! The effects a strength model can carry (the discrepancy workflow's candidate library).
//!
//! The deliverable's lifetime model reduces every crush test to the average Hertzian tensile
//! stress at break σ̄ with the contact radius of curvature R = d/2 and one Weibull law for all
//! particles. Each effect is a physical extension of that model with one extra parameter,
//! acting on the Weibull scale of particle i in the σ̄ reduced with R = d/2 as
//! `ln σ_i = μ + β z_i` (+ the other effects); the modulus is shared. Their equations and
//! covariate signatures:
//!
//! | effect | covariate | equation | parameter reported |
//! |---|---|---|---|
//! | `roundness` (contact curvature) | `roundness` r | R_c = r^q R. Crush: F ∝ R_c² p0³, so the σ̄ reduced with R is σ̄_true (R_c/R)^(2/3): z = ln r, β = 2q/3 | q = 3β/2 (Wadell: q = 1) |
//! | `size` (weakest link) | `diameter_m` d | σ_θ(d) = σ_θ (d/d̃)^(−α), d̃ the median diameter of the fitted data: z = ln(d/d̃), β = −α | α; volume flaws α = 3/m, surface flaws α = 2/m |
//! | `temperature` (softening) | `temperature_c` T | ln σ_θ(T) = ln σ_θ + β (T − T̄)/1000 °C, T̄ the mean of the fitted data; strength and stiffness both shift the σ̄ reduced at break (σ̄ ∝ (F E*²/R²)^(1/3)), above ≈ 900 °C through the amorphous phase (deliverable §2) | strength ratio per 100 °C, e^(β/10) |
//! | `sphericity` (effective radius) | `sphericity` s | R_c = s^p R, as roundness: z = ln s, β = 2p/3 | p = 3β/2 |
//! | `damage` (Tavares–King) | `impacts` n (prior impacts) | each prior impact at the energy ratio x = E_k/E_m damages the particle, E_m,n = E_m,0 Π(1 − D_j) ([`crate::lifetime::damage::tk_damage`], γ fixed); since the Hertz fracture energy scales as σ̄⁵, ln σ_i gets the offset (1/5) ln(x/x_n) | x, fitted by profile likelihood |
//!
//! Contact-geometry effects (roundness, sphericity) also change the impact: with R_c the peak
//! pressure of a Hertz impact scales as R_c^(−3/5) at a fixed particle mass, so the impact
//! stress of particle i is multiplied by (R_c/R)^(−3/5) = e^(−0.9 β z_i); strength effects
//! (size, temperature) change the scale only ([`Effect::impact_exponent`]). Damage describes
//! impacts a crushed particle received before its test; the particles of a prediction are
//! fresh, so it changes only the fit.
//!
//! Beyond the five particle effects, a strength dataset's recorded factors (numeric or
//! categorical columns, a size measure) give generic candidates, [`Effect::Factor`]: their
//! equations, parameters and the weakest-link test are in [`super::factors`].
//!
//! A candidate whose covariate is missing (no column, empty cells, constant over the sample) is
//! skipped with the reason by the naming loop ([`Effect::term`]); a strength model that lists
//! it explicitly refuses the data.

use serde::{Deserialize, Serialize};

use super::factors::{Factor, Form, MIN_PER_LEVEL, MIN_PER_LEVEL_MODULUS, level_columns, pooled_columns};
use super::population::Particle;
use crate::lifetime::damage::tk_ratio_path;

/// An effect of the strength model. In a study it is written by its name: the five particle
/// effects (`roundness`, `size`, `temperature`, `sphericity`, `damage`) or a recorded factor's
/// effect, `linear(x)`, `power(x)`, `levels(g)`, `moduli(g)` (the column declared in the
/// material's `factors`).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Effect {
    /// Roundness sets the contact radius of curvature.
    Roundness,
    /// Weakest-link size effect on strength.
    Size,
    /// Temperature softening of strength and stiffness.
    Temperature,
    /// Sphericity sets an effective contact radius.
    Sphericity,
    /// Tavares–King damage from prior impacts.
    Damage,
    /// A recorded factor of a dataset ([`super::factors`]): a column its study declares.
    Factor(Factor),
    /// Two flaw populations in place of the one Weibull law ([`super::flaws`]); a candidate
    /// against the base law only, offered by a strength file's study (`populations`).
    Populations(super::flaws::Populations),
}

/// What a study may write for an effect.
pub const EFFECT_NAMES: &str = "roundness, size, temperature, sphericity, damage, or a recorded factor's linear(x), power(x), levels(g), moduli(g)";

impl Effect {
    /// The effect a study names: a particle effect, or `form(column)` of a recorded factor.
    pub fn parse(name: &str) -> std::result::Result<Effect, String> {
        let name = name.trim();
        if let Some(e) = ALL.iter().find(|e| e.name() == name) {
            return Ok(e.clone());
        }
        let bad = || format!("unknown effect `{name}`: expected {EFFECT_NAMES}");
        let (form, rest) = name.split_once('(').ok_or_else(bad)?;
        let column = rest.strip_suffix(')').map(str::trim).filter(|c| !c.is_empty()).ok_or_else(bad)?;
        let form = match form.trim() {
            "linear" => Form::Linear,
            "power" => Form::Power,
            "levels" => Form::Levels,
            "moduli" => Form::Moduli,
            "size" => return Err(format!("`{name}`: a size measure's effect is declared with its measure in a strength file's `size = {{ column, measure }}`; a crush file's particle size effect is `size`")),
            _ => return Err(bad()),
        };
        Ok(Effect::Factor(Factor { column: column.to_string(), form }))
    }
}

impl Serialize for Effect {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl<'de> Deserialize<'de> for Effect {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Effect::parse(&name).map_err(serde::de::Error::custom)
    }
}

/// Every effect, in the library's order.
pub const ALL: [Effect; 5] = [Effect::Roundness, Effect::Size, Effect::Temperature, Effect::Sphericity, Effect::Damage];

/// Covariate columns of a crush sample, by name; `None` for an empty cell.
pub type Covariates = [(String, Vec<Option<f64>>)];

/// Categorical factor columns of a strength sample, by name: each specimen's level.
pub type Levels = [(String, Vec<String>)];

/// How an effect enters the regression.
#[derive(Debug, Clone, PartialEq)]
pub enum Term {
    /// A linear column z.
    Linear(Vec<f64>),
    /// Treatment-coded columns of a categorical factor (one per level but the reference).
    Levels {
        /// 0/1 columns, one per non-reference level, in the order of `levels` without the reference.
        columns: Vec<Vec<f64>>,
        /// The levels, in order of appearance.
        levels: Vec<String>,
        /// The reference level (scale μ).
        reference: String,
    },
    /// Treatment-coded scale columns of a categorical factor: one Weibull modulus per level.
    Moduli {
        /// 0/1 columns, one per non-reference level, in the order of `levels` without the reference.
        columns: Vec<Vec<f64>>,
        /// The levels, in order of appearance.
        levels: Vec<String>,
        /// The reference level (modulus m).
        reference: String,
    },
    /// Indicator columns of every level of a categorical factor with a level too small for a
    /// scale of its own: the levels' ln-scale offsets partially pooled (δ ~ N(0, τ²), τ fitted).
    Pooled {
        /// 0/1 columns, one per level, in the order of `levels`.
        columns: Vec<Vec<f64>>,
        /// The levels, in order of appearance.
        levels: Vec<String>,
    },
    /// A two-population law in place of the Weibull law (no other term beside it).
    Populations(super::flaws::Populations),
    /// The Tavares–King offset: prior impact counts and γ.
    Damage {
        /// Prior impacts per particle.
        impacts: Vec<u64>,
        /// Tavares–King γ.
        gamma: f64,
    },
}

impl Effect {
    /// Key used in studies, tables and verdict.json.
    pub fn name(&self) -> String {
        match self {
            Effect::Roundness => "roundness".into(),
            Effect::Size => "size".into(),
            Effect::Temperature => "temperature".into(),
            Effect::Sphericity => "sphericity".into(),
            Effect::Damage => "damage".into(),
            Effect::Factor(f) => f.name(),
            Effect::Populations(p) => p.name().into(),
        }
    }

    /// Human label.
    pub fn label(&self) -> String {
        match self {
            Effect::Roundness => "roundness / contact curvature".into(),
            Effect::Size => "size effect (weakest link)".into(),
            Effect::Temperature => "temperature softening".into(),
            Effect::Sphericity => "sphericity / effective radius".into(),
            Effect::Damage => "damage from prior impacts (Tavares–King)".into(),
            Effect::Factor(f) => f.label(),
            Effect::Populations(p) => p.label().into(),
        }
    }

    /// The dataset column the effect needs.
    pub fn covariate(&self) -> String {
        match self {
            Effect::Roundness => "roundness".into(),
            Effect::Size => "diameter_m".into(),
            Effect::Temperature => "temperature_c".into(),
            Effect::Sphericity => "sphericity".into(),
            Effect::Damage => "impacts".into(),
            Effect::Factor(f) => f.column.clone(),
            Effect::Populations(_) => String::new(),
        }
    }

    /// Its equation, as written in verdict.json.
    pub fn equation(&self) -> String {
        match self {
            Effect::Roundness => "R_c = roundness^q R; ln σ_θ,i = μ + (2q/3) ln roundness_i".into(),
            Effect::Size => "σ_θ(d) = σ_θ (d/d_median)^(−α); ln σ_θ,i = μ − α ln(d_i/d_median)".into(),
            Effect::Temperature => "ln σ_θ(T) = μ + β (T − T_mean)/1000 °C".into(),
            Effect::Sphericity => "R_c = sphericity^p R; ln σ_θ,i = μ + (2p/3) ln sphericity_i".into(),
            Effect::Damage => "E_m,n = E_m,0 Π(1 − D_j), D_j Tavares–King at ratio x; ln σ_θ,i = μ + (1/5) ln(x/x_n,i)".into(),
            Effect::Factor(f) => f.equation(),
            Effect::Populations(p) => p.equation().into(),
        }
    }

    /// Extra parameters the effect adds to the base model in `term` (one; L − 1 for the
    /// levels of a categorical factor).
    pub fn extra_parameters(term: &Term) -> usize {
        match term {
            Term::Levels { columns, .. } | Term::Moduli { columns, .. } => columns.len(),
            // Nominally L − 1 (the pooled fit uses fewer effective degrees of freedom: ΔBIC is
            // conservative, the bootstrap guard calibrates the statistic itself).
            Term::Pooled { columns, .. } => columns.len() - 1,
            // Four or five parameters in place of the base law's two.
            Term::Populations(p) => p.parameters() - 2,
            _ => 1,
        }
    }

    /// Whether the effect changes the contact radius of curvature (and so the impact stress).
    pub fn is_contact_geometry(&self) -> bool {
        matches!(self, Effect::Roundness | Effect::Sphericity)
    }

    /// Exponent κ with which the effect also scales the impact stress: the single-impact
    /// hazard of particle i is (σ̄_impact · e^(−κ β z_i) / e^μ)^m. κ = 0.9 for contact-geometry
    /// effects (impact p0 ∝ R_c^(−3/5) against the crush reduction's R_c^(−2/3)), κ = 1 for
    /// strength effects.
    pub fn impact_exponent(&self) -> f64 {
        if self.is_contact_geometry() { 0.9 } else { 1.0 }
    }

    /// The reference value of the covariate over the fitted sample: the median diameter (size),
    /// the mean temperature (temperature); for factors the mean (linear) or the median (power,
    /// size); 0 for the others (unused).
    pub fn reference(&self, values: &[f64]) -> f64 {
        let mean = || values.iter().sum::<f64>() / values.len() as f64;
        match self {
            Effect::Size => crate::stats::median(values),
            Effect::Temperature => mean(),
            Effect::Factor(f) => match f.form {
                Form::Linear => mean(),
                Form::Power | Form::Size(_) => crate::stats::median(values),
                Form::Levels | Form::Moduli => 0.0,
            },
            _ => 0.0,
        }
    }

    /// What [`Self::reference`] is, in words for a report ("the data's median"); empty where
    /// the reference is a fixed value (0, or 1 for the contact geometry).
    pub fn reference_said(&self) -> &'static str {
        match self {
            Effect::Size => "the data's median",
            Effect::Temperature => "the data's mean",
            Effect::Factor(f) => match f.form {
                Form::Linear => "the data's mean",
                Form::Power | Form::Size(_) => "the data's median",
                Form::Levels | Form::Moduli => "",
            },
            _ => "",
        }
    }

    /// The regression column z of a covariate value, given the reference.
    pub fn z(&self, value: f64, reference: f64) -> f64 {
        match self {
            Effect::Roundness | Effect::Sphericity => value.ln(),
            Effect::Size => (value / reference).ln(),
            Effect::Temperature => (value - reference) / 1000.0,
            Effect::Damage | Effect::Populations(_) => 0.0,
            Effect::Factor(f) => match f.form {
                Form::Linear => value - reference,
                Form::Power | Form::Size(_) => (value / reference).ln(),
                Form::Levels | Form::Moduli => 0.0,
            },
        }
    }

    /// The covariate of a particle of a population (None if it was not measured or declared;
    /// always None for a recorded factor, which a particle population does not carry).
    pub fn value_of(&self, p: &Particle) -> Option<f64> {
        match self {
            Effect::Roundness => p.roundness,
            Effect::Size => Some(p.diameter_m),
            Effect::Temperature => p.temperature_c,
            Effect::Sphericity => p.sphericity,
            Effect::Damage => Some(0.0),
            Effect::Factor(_) | Effect::Populations(_) => None,
        }
    }

    /// The effect's term for a sample's numeric `covariates` and categorical `levels`, or the
    /// reason it cannot be fitted.
    pub fn term(&self, covariates: &Covariates, levels: &Levels, gamma: f64) -> std::result::Result<Term, String> {
        let name = self.covariate();
        if let Effect::Populations(p) = self {
            return Ok(Term::Populations(*p));
        }
        if let Effect::Factor(f) = self
            && matches!(f.form, Form::Levels | Form::Moduli)
        {
            let Some((_, col)) = levels.iter().find(|(n, _)| *n == name) else {
                return Err(format!("the dataset has no categorical column `{name}`"));
            };
            let min = if f.form == Form::Moduli { MIN_PER_LEVEL_MODULUS } else { MIN_PER_LEVEL };
            let fixed = level_columns(col, min);
            // A level too small for its own scale: the scales are partially pooled instead.
            let mut counts = std::collections::BTreeMap::<&str, usize>::new();
            for v in col {
                *counts.entry(v.as_str()).or_default() += 1;
            }
            if f.form == Form::Levels
                && counts.len() >= 2
                && counts.values().any(|&k| k < MIN_PER_LEVEL)
                && let Err(why) = &fixed
            {
                let (levels, columns) = pooled_columns(col).map_err(|pooled| format!("`{name}`: {why}; partial pooling: {pooled}"))?;
                return Ok(Term::Pooled { columns, levels });
            }
            let (levels, reference, columns) = fixed.map_err(|why| format!("`{name}`: {why}"))?;
            return Ok(if f.form == Form::Moduli { Term::Moduli { columns, levels, reference } } else { Term::Levels { columns, levels, reference } });
        }
        let Some((_, col)) = covariates.iter().find(|(n, _)| *n == name).filter(|(_, c)| c.iter().any(|v| v.is_some())) else {
            return Err(format!("the dataset has no `{name}` values (no such column, or every cell empty)"));
        };
        let missing = col.iter().filter(|v| v.is_none()).count();
        if missing > 0 {
            return Err(format!("`{name}` is empty on {missing} of {} rows", col.len()));
        }
        let v: Vec<f64> = col.iter().map(|x| x.unwrap_or(f64::NAN)).collect();
        if v.iter().all(|x| *x == v[0]) {
            return Err(format!("`{name}` is the same on every row ({}): no contrast to fit", v[0]));
        }
        let positive = |what: &str| -> std::result::Result<(), String> {
            match v.iter().find(|x| x.is_nan() || **x <= 0.0) {
                Some(x) => Err(format!("`{name}` must be > 0 for {what} (got {x})")),
                None => Ok(()),
            }
        };
        match self {
            Effect::Damage => {
                if let Some(x) = v.iter().find(|x| !(**x >= 0.0 && x.fract() == 0.0 && **x <= 1e6)) {
                    return Err(format!("`{name}` must be whole numbers in [0, 10⁶] (got {x})"));
                }
                Ok(Term::Damage { impacts: v.iter().map(|x| *x as u64).collect(), gamma })
            }
            Effect::Factor(f) if f.form == Form::Linear => {
                let r = self.reference(&v);
                Ok(Term::Linear(v.iter().map(|&x| self.z(x, r)).collect()))
            }
            _ => {
                if *self != Effect::Temperature {
                    positive("a power law")?;
                }
                let r = self.reference(&v);
                Ok(Term::Linear(v.iter().map(|&x| self.z(x, r)).collect()))
            }
        }
    }

    /// The reported parameter: (symbol, value from β (or x for damage), meaning).
    pub fn parameter(&self, beta: f64, shape: f64) -> (&'static str, f64, String) {
        let value = self.natural(beta);
        match self {
            Effect::Roundness => ("q", value, format!("contact radius R_c = roundness^{value:.2} R (Wadell: 1)")),
            Effect::Sphericity => ("p", value, format!("contact radius R_c = sphericity^{value:.2} R")),
            Effect::Size => {
                let a = value;
                let (vol, surf) = (3.0 / shape, 2.0 / shape);
                let kind = if a <= 0.0 {
                    "strength rises with size: not a weakest-link effect".to_string()
                } else if (a - vol).abs() <= (a - surf).abs() && a < 1.5 * vol {
                    format!("close to volume flaws (3/m = {vol:.3})")
                } else if a < 1.5 * vol {
                    format!("close to surface flaws (2/m = {surf:.3})")
                } else {
                    format!("stronger than weakest-link scaling (volume 3/m = {vol:.3}, surface 2/m = {surf:.3})")
                };
                ("alpha", a, format!("σ_θ ∝ d^(−α), α = {a:.3}: {kind}"))
            }
            Effect::Temperature => ("strength_ratio_per_100c", value, format!("strength × {value:.3} per 100 °C")),
            Effect::Damage => ("x", value, format!("prior impacts at {value:.3} of the fracture energy")),
            Effect::Populations(p) => (p.name(), value, String::new()),
            Effect::Factor(f) => {
                let c = &f.column;
                match f.form {
                    Form::Linear => ("beta", value, format!("σ_θ × {:.4} per unit of `{c}`", value.exp())),
                    Form::Power => ("exponent", value, format!("σ_θ ∝ {c}^{value:.3}")),
                    Form::Levels => ("scale_ratio", value, format!("scales of the levels of `{c}`")),
                    Form::Moduli => ("modulus_ratio", value, format!("moduli of the levels of `{c}`")),
                    Form::Size(s) => {
                        let k = s.k();
                        ("alpha", value, format!("σ_θ ∝ {c}^(−α), α = {value:.3}; weakest link at this modulus: {k}/m = {:.3}", k / shape))
                    }
                }
            }
        }
    }

    /// The reported parameter's value for a regression coefficient β (α = −β, q = p = 3β/2,
    /// strength ratio per 100 °C e^(β/10), a level's scale ratio to the reference e^β; damage:
    /// β is already the ratio x).
    pub fn natural(&self, beta: f64) -> f64 {
        match self {
            Effect::Roundness | Effect::Sphericity => 1.5 * beta,
            Effect::Size => -beta,
            Effect::Temperature => (beta / 10.0).exp(),
            Effect::Damage | Effect::Populations(_) => beta,
            Effect::Factor(f) => match f.form {
                Form::Size(_) => -beta,
                Form::Levels => beta.exp(),
                _ => beta,
            },
        }
    }

    /// The inverse of [`Effect::natural`].
    pub fn beta_of(&self, natural: f64) -> f64 {
        match self {
            Effect::Roundness | Effect::Sphericity => natural / 1.5,
            Effect::Size => -natural,
            Effect::Temperature => 10.0 * natural.ln(),
            Effect::Damage | Effect::Populations(_) => natural,
            Effect::Factor(f) => match f.form {
                Form::Size(_) => -natural,
                Form::Levels => natural.ln(),
                _ => natural,
            },
        }
    }
}

/// ln(x0/x_n)/5 for a particle after n impacts at the initial ratio x0 (Tavares–King, γ): the
/// ln-strength change, since the Hertz fracture energy scales as the strength⁵. None if it
/// would have broken.
pub(crate) fn damage_offset(x0: f64, gamma: f64, n: u64) -> Option<f64> {
    let path = tk_ratio_path(x0, gamma, n)?;
    Some((path[0] - path[n as usize]) / 5.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The words a report gives for a reference say what [`Effect::reference`] computes: on
    /// values whose median (2) and mean (13/3) differ.
    #[test]
    fn a_reference_is_said_as_it_is_computed() {
        let v = [1.0, 2.0, 10.0];
        let linear = Effect::Factor(Factor { column: "rate".into(), form: Form::Linear });
        let power = Effect::Factor(Factor { column: "rate".into(), form: Form::Power });
        for e in [Effect::Size, Effect::Temperature, linear, power] {
            let r = e.reference(&v);
            let said = e.reference_said();
            assert_eq!(said == "the data's median", r == 2.0, "{e:?}: {r}, \"{said}\"");
            assert_eq!(said == "the data's mean", (r - 13.0 / 3.0).abs() < 1e-12, "{e:?}: {r}, \"{said}\"");
        }
        assert_eq!(Effect::Damage.reference_said(), "");
    }

    fn cov(name: &str, v: Vec<f64>) -> (String, Vec<Option<f64>>) {
        (name.to_string(), v.into_iter().map(Some).collect())
    }


    #[test]
    fn missing_or_constant_covariates_are_skipped_with_a_reason() {
        let c = vec![cov("temperature_c", vec![20.0; 12]), ("roundness".into(), vec![Some(0.7), None, Some(0.8)])];
        assert!(Effect::Temperature.term(&c, &[], 5.0).unwrap_err().contains("same on every row"));
        assert!(Effect::Roundness.term(&c, &[], 5.0).unwrap_err().contains("empty on 1 of 3"));
        assert!(Effect::Damage.term(&c, &[], 5.0).unwrap_err().contains("no `impacts` values"));
    }

    #[test]
    fn natural_parameters_invert() {
        for e in ALL {
            for b in [-0.4, 0.1, 0.7] {
                assert!((e.beta_of(e.natural(b)) - b).abs() < 1e-12, "{e:?}");
            }
        }
        // A particle's column uses the sample's reference: the median diameter.
        let c = vec![cov("diameter_m", vec![0.8e-3, 1.0e-3, 0.9e-3])];
        let Term::Linear(z) = Effect::Size.term(&c, &[], 5.0).unwrap() else { panic!() };
        assert!((z[2]).abs() < 1e-15 && (z[1] - (1.0f64 / 0.9).ln()).abs() < 1e-15);
    }
}
