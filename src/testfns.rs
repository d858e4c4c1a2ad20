//! Analytic test functions implementing [`Simulator`], for tests, docs and smoke studies.
//!
//! * [`Ishigami`]: f = sin x₁ + a sin² x₂ + b x₃⁴ sin x₁, xᵢ ~ U(−π, π); with a = 7, b = 0.1 the
//!   variance is 13.844588 and the Sobol indices are known in closed form
//!   (docs/reference.md, verification §1.1). Verified by `tests::ishigami_variance`.

use crate::error::Result;
use crate::model::{OutputSpec, Simulator};
use crate::params::{Param, ParamSpace};

/// The Ishigami function.
#[derive(Debug, Clone)]
pub struct Ishigami {
    /// Coefficient a (7 in the standard form).
    pub a: f64,
    /// Coefficient b (0.1 in the standard form).
    pub b: f64,
    space: ParamSpace,
    outputs: Vec<OutputSpec>,
}

impl Ishigami {
    /// The standard form, a = 7, b = 0.1, on (−π, π)³.
    pub fn standard() -> Self {
        Self::new(7.0, 0.1)
    }

    /// Ishigami with coefficients a and b.
    pub fn new(a: f64, b: f64) -> Self {
        use std::f64::consts::PI;
        let p = |n: &str| Param::uniform(n, "-", -PI, PI, 0.0);
        let space = ParamSpace::new(vec![p("x1"), p("x2"), p("x3")])
            .unwrap_or_else(|_| unreachable!("constant valid space"));
        Ishigami { a, b, space, outputs: vec![OutputSpec::new("f", "-")] }
    }

    /// Total variance V = a²/8 + bπ⁴/5 + b²π⁸/18 + 1/2.
    pub fn variance(&self) -> f64 {
        use std::f64::consts::PI;
        self.a * self.a / 8.0 + self.b * PI.powi(4) / 5.0 + self.b * self.b * PI.powi(8) / 18.0 + 0.5
    }
}

impl Simulator for Ishigami {
    fn space(&self) -> &ParamSpace {
        &self.space
    }
    fn outputs(&self) -> &[OutputSpec] {
        &self.outputs
    }
    fn simulate(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.space.check(x)?;
        let s1 = x[0].sin();
        Ok(vec![s1 + self.a * x[1].sin().powi(2) + self.b * x[2].powi(4) * s1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn ishigami_variance() {
        let f = Ishigami::standard();
        assert!((f.variance() - 13.844588).abs() < 1e-6);
        // Monte Carlo mean and variance through the batch interface (order preserved).
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let thetas: Vec<Vec<f64>> = (0..200_000)
            .map(|_| f.space().from_unit(&[rng.random(), rng.random(), rng.random()]))
            .collect();
        let ys: Vec<f64> = f.simulate_batch(&thetas).into_iter().map(|r| r.unwrap()[0]).collect();
        assert_eq!(ys[17], f.simulate(&thetas[17]).unwrap()[0]);
        let n = ys.len() as f64;
        let mean = ys.iter().sum::<f64>() / n;
        let var = ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1.0);
        // Standard errors: sd/sqrt(n) ≈ 0.008 for the mean; ≈ 0.06 for the variance.
        assert!((mean - 3.5).abs() < 0.04, "mean {mean}");
        assert!((var - f.variance()).abs() < 0.3, "variance {var}");
    }
}
