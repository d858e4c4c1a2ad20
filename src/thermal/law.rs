//! The temperature law of a positive material parameter θ (a JH-2 constant, the Weibull scale):
//! a thermal term and a mixture between crystalline and glassy behaviour whose argument is the
//! amorphous fraction f_a(T) of the phase table ([`crate::phases`]),
//!
//! ```text
//! θ(T) = θ_c · exp(a · (T − T_ref)) · [(1 − f_a(T)) + r · f_a(T)]
//! ```
//!
//! θ_c is the crystalline value at the reference temperature T_ref, a the thermal coefficient
//! (1/°C; small, linear in ln θ) and r = θ_glass/θ_crystalline the glassy ratio (r < 1: the
//! amorphous phase softens). The mixture is the Voigt (arithmetic) rule in the amorphous
//! **volume** fraction: an upper bound for a modulus and the simplest law that gives θ_c at
//! f_a = 0 and r·θ_c (times the thermal term) for a fully glassy particle. A rule of mixtures
//! is a rule in volume fractions, so a table of mole or mass fractions is converted first
//! ([`crate::phases::PhaseTable::to_volume`]) and [`TemperatureLaw::fit`] refuses any other
//! basis.
//!
//! # Fitting to two calibrated states
//!
//! Given joint draws of θ at two calibrated temperatures T₁ < T₂ (the calibration posteriors
//! at room temperature and 800 °C) and a draw of r from its prior, each draw's θ_c and a solve
//!
//! ```text
//! ln θ_k = ln θ_c + a · (T_k − T_ref) + ln m_k,   m_k = (1 − f_a(T_k)) + r · f_a(T_k),   k = 1, 2
//! ```
//!
//! exactly: a = [ln(θ₂/m₂) − ln(θ₁/m₁)]/(T₂ − T₁). The law therefore passes through every
//! calibrated draw at its temperature — its distribution there is the calibration's posterior —
//! and carries both posteriors' uncertainty (draw i of the first with draw i of the second;
//! the calibrations are independent, so pairing by index is a joint draw). The data say nothing
//! about r where f_a is 0 at both calibrated temperatures (the deliverable's phases: amorphous
//! only from about 900 °C): there r comes from its prior alone and the bands widen as f_a rises
//! — extrapolation shows as width. With a constant amorphous fraction m₁ = m₂ and the law
//! reduces to its thermal term, whatever r.

use crate::error::{Error, Result};
use crate::phases::{Basis, PhaseTable};

/// One draw of the law's coefficients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawDraw {
    /// ln θ_c (θ_c in the parameter's unit).
    pub ln_crystalline: f64,
    /// Thermal coefficient a (1/°C).
    pub thermal: f64,
    /// Glassy ratio r.
    pub glassy_ratio: f64,
}

/// The temperature law of one parameter: its reference temperature and coefficient draws.
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureLaw {
    /// Reference temperature T_ref (°C).
    pub t_ref_c: f64,
    /// Coefficient draws.
    pub draws: Vec<LawDraw>,
}

/// The mixture factor m = (1 − f_a) + r f_a.
fn mixture(f_a: f64, r: f64) -> f64 {
    (1.0 - f_a) + r * f_a
}

impl LawDraw {
    /// θ at temperature `t_c` with amorphous fraction `f_a`.
    pub fn value(&self, t_c: f64, f_a: f64, t_ref_c: f64) -> f64 {
        (self.ln_crystalline + self.thermal * (t_c - t_ref_c)).exp() * mixture(f_a, self.glassy_ratio)
    }
}

impl TemperatureLaw {
    /// Fits the law to draws `theta1` at `t1_c` and `theta2` at `t2_c` (paired by index) with
    /// glassy ratios `ratio` (one per pair), the amorphous fractions from `phases`; T_ref = t1.
    pub fn fit(phases: &PhaseTable, (t1_c, theta1): (f64, &[f64]), (t2_c, theta2): (f64, &[f64]), ratio: &[f64]) -> Result<TemperatureLaw> {
        let bad = |rule: String| Err(Error::numerical("temperature law", rule));
        if !(t2_c > t1_c) {
            return bad(format!("needs two calibrated temperatures in increasing order, got {t1_c} and {t2_c} °C"));
        }
        if theta1.len() != theta2.len() || theta1.len() != ratio.len() || theta1.is_empty() {
            return bad(format!("needs as many draws at each temperature as glassy ratios, got {}, {} and {}", theta1.len(), theta2.len(), ratio.len()));
        }
        if let Some(v) = theta1.iter().chain(theta2).find(|v| !(v.is_finite() && **v > 0.0)) {
            return bad(format!("a parameter draw {v} is not positive: the law is of positive parameters"));
        }
        if let Some(r) = ratio.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
            return bad(format!("a glassy ratio {r} is not positive"));
        }
        if phases.basis != Basis::Volume {
            return bad(format!("the rule of mixtures takes volume fractions; {} holds {} (convert them first: PhaseTable::to_volume)", phases.path.display(), phases.basis.words()));
        }
        let (f1, f2) = (phases.amorphous_at(t1_c)?, phases.amorphous_at(t2_c)?);
        let draws = theta1
            .iter()
            .zip(theta2)
            .zip(ratio)
            .map(|((&a1, &a2), &r)| {
                let (l1, l2) = ((a1 / mixture(f1, r)).ln(), (a2 / mixture(f2, r)).ln());
                LawDraw { ln_crystalline: l1, thermal: (l2 - l1) / (t2_c - t1_c), glassy_ratio: r }
            })
            .collect();
        Ok(TemperatureLaw { t_ref_c: t1_c, draws })
    }

    /// Every draw's θ at `t_c` (the amorphous fraction from `phases`; refused outside its table).
    pub fn values_at(&self, phases: &PhaseTable, t_c: f64) -> Result<Vec<f64>> {
        let f_a = phases.amorphous_at(t_c)?;
        Ok(self.draws.iter().map(|d| d.value(t_c, f_a, self.t_ref_c)).collect())
    }

    /// Median and central band of θ at `t_c` at probability `level` (0.9: the 5 % and 95 %
    /// quantiles).
    pub fn band_at(&self, phases: &PhaseTable, t_c: f64, level: f64) -> Result<(f64, f64, f64)> {
        Ok(crate::stats::median_and_band(self.values_at(phases, t_c)?, level))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phases::illustrative;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_table_not_in_volume_fractions_is_refused() {
        let mole = PhaseTable { basis: Basis::Mole, file_basis: Basis::Mole, ..table(&|_| 0.1) };
        let e = TemperatureLaw::fit(&mole, (20.0, &[1.0]), (800.0, &[0.9]), &[0.5]).unwrap_err().to_string();
        assert!(e.contains("volume fractions") && e.contains("mole fractions"), "{e}");
        assert!(TemperatureLaw::fit(&table(&|_| 0.1), (20.0, &[1.0]), (800.0, &[0.9]), &[0.5]).is_ok());
    }

    /// A two-phase table with amorphous fraction `f(T)` on 20–1000 °C.
    fn table(f: &dyn Fn(f64) -> f64) -> PhaseTable {
        let temperatures_c: Vec<f64> = (0..=49).map(|k| 20.0 + 20.0 * k as f64).collect();
        let fractions = temperatures_c.iter().map(|&t| vec![1.0 - f(t), f(t)]).collect();
        PhaseTable { path: Default::default(), basis: Basis::Volume, file_basis: Basis::Volume, temperatures_c, phases: vec!["C".into(), "GLASS".into()], amorphous: vec![false, true], fractions }
    }

    /// Lognormal draws around `median` with sd of ln `sd`.
    fn draws(median: f64, sd: f64, n: usize, seed: u64) -> Vec<f64> {
        use rand_distr::Distribution;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let z = rand_distr::Normal::new(0.0, sd).unwrap();
        (0..n).map(|_| median * z.sample(&mut rng).exp()).collect()
    }

    #[test]
    fn a_constant_amorphous_fraction_leaves_only_the_thermal_term() {
        let phases = table(&|_| 0.2);
        let (a, b) = (draws(40e9, 0.05, 500, 1), draws(30e9, 0.08, 500, 2));
        for r in [0.1, 0.5, 2.0] {
            let law = TemperatureLaw::fit(&phases, (20.0, &a), (800.0, &b), &vec![r; a.len()]).unwrap();
            for (i, d) in law.draws.iter().enumerate() {
                // ln θ linear in T through both calibrated draws, whatever r.
                let expected = (b[i] / a[i]).ln() / 780.0;
                assert!((d.thermal - expected).abs() < 1e-15, "r = {r}: a = {} vs {expected}", d.thermal);
                for t in [300.0, 600.0, 950.0] {
                    let lin = a[i].ln() + expected * (t - 20.0);
                    assert!((d.value(t, 0.2, 20.0).ln() - lin).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn the_law_reproduces_the_calibrated_states_and_widens_where_it_extrapolates() {
        let phases = illustrative();
        let n = 4000;
        let (a, b) = (draws(40e9, 0.05, n, 3), draws(30e9, 0.08, n, 4));
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let ratio: Vec<f64> = (0..n).map(|_| 0.05 + 0.45 * rng.random::<f64>()).collect();
        let law = TemperatureLaw::fit(&phases, (20.0, &a), (800.0, &b), &ratio).unwrap();
        // At each calibrated temperature, every draw is the calibration's draw.
        for (t, cal) in [(20.0, &a), (800.0, &b)] {
            let v = law.values_at(&phases, t).unwrap();
            assert!(v.iter().zip(cal.iter()).all(|(x, y)| ((x - y) / y).abs() < 1e-12), "{t} °C");
        }
        // Relative band width: grows beyond the calibrated temperatures, and beyond 900 °C the
        // prior on r adds to it (the same law with r fixed at its prior median is narrower
        // there, and identical where there is no glass).
        let fixed = TemperatureLaw::fit(&phases, (20.0, &a), (800.0, &b), &vec![0.275; n]).unwrap();
        let width = |law: &TemperatureLaw, t: f64| {
            let (m, lo, hi) = law.band_at(&phases, t, 0.9).unwrap();
            (hi - lo) / m
        };
        assert!(width(&law, 1000.0) > width(&law, 800.0) && width(&law, 1200.0) > width(&law, 1000.0), "{} {} {}", width(&law, 800.0), width(&law, 1000.0), width(&law, 1200.0));
        assert_eq!(width(&law, 600.0), width(&fixed, 600.0));
        assert!(width(&law, 1200.0) > 1.02 * width(&fixed, 1200.0), "{} vs {}", width(&law, 1200.0), width(&fixed, 1200.0));
        // Monotone softening where the amorphous fraction rises (r < 1): every draw's glassy
        // factor falls from 900 to 1200 °C.
        for d in &law.draws {
            let mut prev = f64::INFINITY;
            for t in (900..=1200).step_by(50) {
                let m = mixture(phases.amorphous_at(t as f64).unwrap(), d.glassy_ratio);
                assert!(m <= prev + 1e-15);
                prev = m;
            }
        }
        // Refused outside the phase table.
        assert!(law.values_at(&phases, 1500.0).is_err());
    }

    #[test]
    fn a_hidden_temperature_law_is_predicted_at_a_third_temperature_within_its_band() {
        // Truth: θ_c = 50 GPa, a = −2·10⁻⁴ /°C, r = 0.3, with f_a rising from 500 °C (so both
        // calibrated temperatures carry glass). Calibrations at 20 and 700 °C with 5 % noise;
        // prediction at 900 °C with r from a prior that contains the truth.
        let phases = table(&|t| (0.4 * ((t - 500.0) / 500.0)).clamp(0.0, 0.4));
        let truth = LawDraw { ln_crystalline: 50e9f64.ln(), thermal: -2e-4, glassy_ratio: 0.3 };
        let at = |t: f64| truth.value(t, phases.amorphous_at(t).unwrap(), 20.0);
        let n = 4000;
        let (a, b) = (draws(at(20.0), 0.05, n, 6), draws(at(700.0), 0.05, n, 7));
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let ratio: Vec<f64> = (0..n).map(|_| 0.1 + 0.5 * rng.random::<f64>()).collect();
        let law = TemperatureLaw::fit(&phases, (20.0, &a), (700.0, &b), &ratio).unwrap();
        let (m, lo, hi) = law.band_at(&phases, 900.0, 0.9).unwrap();
        assert!(lo <= at(900.0) && at(900.0) <= hi, "truth {} outside [{lo}, {hi}] (median {m})", at(900.0));
        assert!((m / at(900.0) - 1.0).abs() < 0.1, "median {m} vs truth {}", at(900.0));
    }

    #[test]
    fn bad_draws_are_refused() {
        let phases = table(&|_| 0.0);
        assert!(TemperatureLaw::fit(&phases, (800.0, &[1.0]), (20.0, &[1.0]), &[0.5]).is_err());
        assert!(TemperatureLaw::fit(&phases, (20.0, &[1.0, 2.0]), (800.0, &[1.0]), &[0.5]).is_err());
        assert!(TemperatureLaw::fit(&phases, (20.0, &[-1.0]), (800.0, &[1.0]), &[0.5]).is_err());
        assert!(TemperatureLaw::fit(&phases, (20.0, &[1.0]), (800.0, &[1.0]), &[0.0]).is_err());
        assert!(TemperatureLaw::fit(&phases, (20.0, &[1.0]), (1800.0, &[1.0]), &[0.5]).is_err());
    }
}
