//! Parameter spaces: names, units, bounds and priors of a model's inputs θ.
//!
//! A [`ParamSpace`] is the contract between a physical model (a [`crate::model::Simulator`])
//! and the methods that drive it (Monte Carlo, least squares, MCMC, experiment design). It is
//! an ordered list of [`Param`]s; a model resolves names to indices once, at construction, so
//! the hot path is index based.
//!
//! Two maps to the unit cube are offered:
//! * [`ParamSpace::from_unit`] / [`ParamSpace::to_unit`]: linear in the bounds, for optimisers
//!   and space-filling designs;
//! * [`ParamSpace::from_unit_prior`]: the inverse CDF of each (truncated) prior, for Monte Carlo
//!   propagation, so uniform points become prior draws.
//!
//! Every prior is truncated to `[lower, upper]`; [`ParamSpace::log_prior`] is the normalised log
//! density of the truncated prior and `−∞` outside the bounds (never NaN).
//!
//! Verified by the unit tests at the foot of this file (round trips, normalisation of the
//! truncated densities by quadrature, inverse-CDF against the CDF).

use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, Normal};

use crate::error::{Error, Result};

/// Prior distribution of one parameter, always truncated to the parameter's bounds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Prior {
    /// Uniform on `[lower, upper]`.
    Uniform,
    /// Normal with mean and standard deviation (same unit as the parameter).
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation, > 0.
        sd: f64,
    },
    /// Log-normal: `ln x ~ N(mu, sigma²)`; `median = exp(mu)`.
    LogNormal {
        /// Mean of `ln x` (x in the parameter's unit).
        mu: f64,
        /// Standard deviation of `ln x`, > 0.
        sigma: f64,
    },
}

/// One model input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Param {
    /// Name, unique within a space (`weibull_shape`).
    pub name: String,
    /// Unit in words or SI symbols (`Pa`, `m/s`, `-`).
    pub unit: String,
    /// Lower bound (inclusive), finite.
    pub lower: f64,
    /// Upper bound (inclusive), finite, > lower.
    pub upper: f64,
    /// Prior, truncated to the bounds.
    pub prior: Prior,
    /// Nominal (default) value, within the bounds.
    pub nominal: f64,
}

impl Param {
    /// A parameter with a uniform prior.
    pub fn uniform(name: &str, unit: &str, lower: f64, upper: f64, nominal: f64) -> Self {
        Param {
            name: name.into(),
            unit: unit.into(),
            lower,
            upper,
            prior: Prior::Uniform,
            nominal,
        }
    }

    /// A robust prior width: half the distance between the 15.9 % and 84.1 % quantiles of the
    /// truncated prior (the sd of a normal prior far from its bounds).
    pub fn prior_sd(&self) -> f64 {
        0.5 * (self.quantile(0.841_344_746) - self.quantile(0.158_655_254))
    }

    /// Checks bounds, nominal and prior (finite, lower < upper, positive spreads).
    pub fn check(&self) -> Result<()> {
        let bad = |rule: String| Err(Error::Param { name: self.name.clone(), rule });
        if self.name.is_empty() {
            return bad("name is empty".into());
        }
        if !(self.lower.is_finite() && self.upper.is_finite() && self.lower < self.upper) {
            return bad(format!(
                "bounds must be finite with lower < upper (got [{}, {}])",
                self.lower, self.upper
            ));
        }
        if !(self.nominal >= self.lower && self.nominal <= self.upper) {
            return bad(format!(
                "nominal {} lies outside [{}, {}]",
                self.nominal, self.lower, self.upper
            ));
        }
        match self.prior {
            Prior::Uniform => {}
            Prior::Normal { mean, sd } => {
                if !(mean.is_finite() && sd.is_finite() && sd > 0.0) {
                    return bad(format!("normal prior needs finite mean and sd > 0 (got {mean}, {sd})"));
                }
            }
            Prior::LogNormal { mu, sigma } => {
                if !(mu.is_finite() && sigma.is_finite() && sigma > 0.0) {
                    return bad(format!(
                        "log-normal prior needs finite mu and sigma > 0 (got {mu}, {sigma})"
                    ));
                }
                if self.lower <= 0.0 {
                    return bad(format!("log-normal prior needs lower > 0 (got {})", self.lower));
                }
            }
        }
        Ok(())
    }

    /// Underlying (untruncated) standard-normal coordinate of `x`, for normal-family priors.
    fn z(&self, x: f64) -> f64 {
        match self.prior {
            Prior::Uniform => f64::NAN,
            Prior::Normal { mean, sd } => (x - mean) / sd,
            Prior::LogNormal { mu, sigma } => (x.ln() - mu) / sigma,
        }
    }

    /// Probability mass of the untruncated prior inside the bounds, as (Φ(z_lo), Φ(z_hi)).
    fn mass(&self) -> (f64, f64) {
        let n = std_normal();
        (n.cdf(self.z(self.lower)), n.cdf(self.z(self.upper)))
    }

    /// Normalised log density of the truncated prior; `−∞` outside the bounds.
    pub fn log_prior(&self, x: f64) -> f64 {
        if !(x >= self.lower && x <= self.upper) {
            return f64::NEG_INFINITY;
        }
        const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_8;
        match self.prior {
            Prior::Uniform => -(self.upper - self.lower).ln(),
            Prior::Normal { sd, .. } => {
                let (lo, hi) = self.mass();
                let z = self.z(x);
                -0.5 * z * z - LN_SQRT_2PI - sd.ln() - (hi - lo).ln()
            }
            Prior::LogNormal { sigma, .. } => {
                let (lo, hi) = self.mass();
                let z = self.z(x);
                -0.5 * z * z - LN_SQRT_2PI - sigma.ln() - x.ln() - (hi - lo).ln()
            }
        }
    }

    /// Inverse CDF of the truncated prior at `u ∈ [0, 1]`.
    pub fn quantile(&self, u: f64) -> f64 {
        let u = u.clamp(0.0, 1.0);
        let x = match self.prior {
            Prior::Uniform => self.lower + u * (self.upper - self.lower),
            Prior::Normal { mean, sd } => {
                let (lo, hi) = self.mass();
                mean + sd * std_normal().inverse_cdf(lo + u * (hi - lo))
            }
            Prior::LogNormal { mu, sigma } => {
                let (lo, hi) = self.mass();
                (mu + sigma * std_normal().inverse_cdf(lo + u * (hi - lo))).exp()
            }
        };
        // Round-off at the extreme tails must not leave the box.
        x.clamp(self.lower, self.upper)
    }
}

fn std_normal() -> Normal {
    // Parameters are constants: cannot fail.
    Normal::new(0.0, 1.0).unwrap_or_else(|_| unreachable!("N(0,1) is valid"))
}

/// Ordered set of model inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamSpace {
    params: Vec<Param>,
}

impl ParamSpace {
    /// Builds a space; names must be unique and every parameter valid.
    pub fn new(params: Vec<Param>) -> Result<Self> {
        for (i, p) in params.iter().enumerate() {
            p.check()?;
            if params[..i].iter().any(|q| q.name == p.name) {
                return Err(Error::Param { name: p.name.clone(), rule: "duplicate name".into() });
            }
        }
        Ok(ParamSpace { params })
    }

    /// Number of parameters (dimension of θ).
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// True for a space without parameters.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The parameters, in order.
    pub fn params(&self) -> &[Param] {
        &self.params
    }

    /// Index of a named parameter; an unknown name is an error listing the known names.
    pub fn index_of(&self, name: &str) -> Result<usize> {
        self.params.iter().position(|p| p.name == name).ok_or_else(|| Error::Param {
            name: name.into(),
            rule: format!(
                "unknown parameter; known: {}",
                self.params.iter().map(|p| p.name.as_str()).collect::<Vec<_>>().join(", ")
            ),
        })
    }

    /// Nominal θ.
    pub fn nominal(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.nominal).collect()
    }

    /// Checks length and finiteness of θ (not the bounds: samplers treat those as −∞ prior).
    pub fn check(&self, theta: &[f64]) -> Result<()> {
        if theta.len() != self.params.len() {
            return Err(Error::Param {
                name: "θ".into(),
                rule: format!("expected {} values, got {}", self.params.len(), theta.len()),
            });
        }
        for (p, x) in self.params.iter().zip(theta) {
            if !x.is_finite() {
                return Err(Error::Param { name: p.name.clone(), rule: format!("value {x} is not finite") });
            }
        }
        Ok(())
    }

    /// True when every component lies within its bounds.
    pub fn contains(&self, theta: &[f64]) -> bool {
        theta.len() == self.params.len()
            && self.params.iter().zip(theta).all(|(p, &x)| x >= p.lower && x <= p.upper)
    }

    /// Linear map from the unit cube to the bounds.
    pub fn from_unit(&self, u: &[f64]) -> Vec<f64> {
        self.params.iter().zip(u).map(|(p, &u)| p.lower + u * (p.upper - p.lower)).collect()
    }

    /// Linear map from the bounds to the unit cube (inverse of [`Self::from_unit`]).
    pub fn to_unit(&self, theta: &[f64]) -> Vec<f64> {
        self.params.iter().zip(theta).map(|(p, &x)| (x - p.lower) / (p.upper - p.lower)).collect()
    }

    /// Inverse-CDF map of the unit cube through each truncated prior (independent components).
    pub fn from_unit_prior(&self, u: &[f64]) -> Vec<f64> {
        self.params.iter().zip(u).map(|(p, &u)| p.quantile(u)).collect()
    }

    /// Sum of the normalised log prior densities; `−∞` outside the bounds.
    pub fn log_prior(&self, theta: &[f64]) -> f64 {
        if theta.len() != self.params.len() {
            return f64::NEG_INFINITY;
        }
        self.params.iter().zip(theta).map(|(p, &x)| p.log_prior(x)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::uniform("a", "-", -1.0, 3.0, 0.0),
            Param {
                name: "b".into(),
                unit: "Pa".into(),
                lower: 0.0,
                upper: 2.0,
                prior: Prior::Normal { mean: 0.5, sd: 1.0 },
                nominal: 0.5,
            },
            Param {
                name: "c".into(),
                unit: "-".into(),
                lower: 0.01,
                upper: 1.0,
                prior: Prior::LogNormal { mu: (0.1f64).ln(), sigma: 0.5 },
                nominal: 0.1,
            },
        ])
        .unwrap()
    }

    #[test]
    fn unit_maps_round_trip() {
        let s = space();
        let u = [0.25, 0.5, 0.9];
        let x = s.from_unit(&u);
        let back = s.to_unit(&x);
        for (a, b) in u.iter().zip(&back) {
            assert!((a - b).abs() < 1e-14);
        }
        assert_eq!(s.index_of("c").unwrap(), 2);
        assert!(s.index_of("zz").is_err());
    }

    #[test]
    fn truncated_priors_are_normalised() {
        // Trapezoid quadrature of exp(log_prior) over the bounds must give 1.
        for p in space().params() {
            let n = 200_000;
            let h = (p.upper - p.lower) / n as f64;
            let mut sum = 0.0;
            for i in 0..=n {
                let x = p.lower + i as f64 * h;
                let w = if i == 0 || i == n { 0.5 } else { 1.0 };
                sum += w * p.log_prior(x).exp();
            }
            assert!((sum * h - 1.0).abs() < 1e-6, "{}: integral {}", p.name, sum * h);
        }
    }

    #[test]
    fn quantile_inverts_the_truncated_cdf() {
        // The quantile of u must have CDF u: check by integrating the density up to it.
        for p in space().params() {
            for &u in &[0.1, 0.5, 0.93] {
                let q = p.quantile(u);
                let n = 100_000;
                let h = (q - p.lower) / n as f64;
                let mut sum = 0.0;
                for i in 0..=n {
                    let x = p.lower + i as f64 * h;
                    let w = if i == 0 || i == n { 0.5 } else { 1.0 };
                    sum += w * p.log_prior(x).exp();
                }
                assert!((sum * h - u).abs() < 1e-5, "{} u={u}: cdf {}", p.name, sum * h);
            }
        }
    }

    #[test]
    fn outside_bounds_is_minus_infinity_not_nan() {
        let s = space();
        assert_eq!(s.log_prior(&[5.0, 0.5, 0.1]), f64::NEG_INFINITY);
        assert!(s.log_prior(&[0.0, 0.5, 0.1]).is_finite());
        assert!(!s.contains(&[0.0, -0.1, 0.1]));
    }

    #[test]
    fn invalid_spaces_are_rejected() {
        assert!(ParamSpace::new(vec![Param::uniform("a", "-", 1.0, 1.0, 1.0)]).is_err());
        assert!(ParamSpace::new(vec![Param::uniform("a", "-", 0.0, 1.0, 2.0)]).is_err());
        assert!(
            ParamSpace::new(vec![
                Param::uniform("a", "-", 0.0, 1.0, 0.5),
                Param::uniform("a", "-", 0.0, 1.0, 0.5)
            ])
            .is_err()
        );
    }
}
