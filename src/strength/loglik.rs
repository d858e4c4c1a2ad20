//! One row's log-likelihood under the Weibull law of its strength, in logs: y = ln x is
//! minimum-Gumbel with location η = ln σ and scale b = 1/m, w = (y − η)/b.
//!
//! ```text
//! exact           ℓ = −ln b + w − e^w − y                   (the density of x)
//! right-censored  ℓ = ln S = −e^w                            (did not break by x)
//! left-censored   ℓ = ln F = ln(1 − e^(−e^w))                (broke at or below x)
//! interval        ℓ = ln[S(x) − S(x_u)] = −A + ln(1 − e^(−D)),  A = e^w, D = e^(w_u) − e^w
//! ```
//!
//! ([`crate::obs`] for the row kinds.) Written as ℓ = −c s + φ(w, w_u) with s = ln b and c = 1
//! for an exact row only, the gradient and Hessian in (η, s) that the Weibull regression's
//! Newton iteration ([`super::regress`]) needs follow from φ's first and second derivatives and
//! ∂w/∂η = −1/b, ∂w/∂s = −u, ∂²w/∂η∂s = 1/b, ∂²w/∂s² = u, u = (y − η)/b ([`row_terms`]).
//!
//! Verified by the unit test below: central differences of ℓ for every kind, and ℓ equal to
//! [`Obs::ln_prob`] of the law.

use crate::obs::{Censor, Obs, ln_one_minus_exp};

/// Log density of y = ln x for Weibull strength x with scale e^ln_scale and modulus 1/b: y is
/// minimum-Gumbel with location ln_scale and scale b, ln f = −ln b + w − e^w with
/// w = (y − ln_scale)/b (the crate's one copy; the density of x subtracts y).
pub fn ln_density_of_log(y: f64, ln_scale: f64, b: f64) -> f64 {
    let w = (y - ln_scale) / b;
    -b.ln() + w - w.exp()
}

/// ln P(row i of `x`) for Weibull strength with scale e^ln_scale and modulus 1/b, in the units
/// of x: the density for an exact row, the survival, CDF or class probability for a censored
/// or interval one ([`Obs::ln_prob`]).
pub fn ln_prob(x: Obs, i: usize, ln_scale: f64, b: f64) -> f64 {
    let w = |v: f64| (v.ln() - ln_scale) / b;
    x.ln_prob(i, |v| ln_density_of_log(v.ln(), ln_scale, b) - v.ln(), |v| -w(v).exp())
}

/// One row's log-likelihood and its derivatives in the location η and s = ln b (module docs):
/// `[ℓ, ∂ℓ/∂η, ∂ℓ/∂s, ∂²ℓ/∂η², ∂²ℓ/∂η∂s, ∂²ℓ/∂s²]`, for a row of kind `kind` whose log
/// values (less any offset) are `ya` (the value, or an interval's lower end) and `yb` (an
/// interval's upper end), at b = e^s; `shift` adds to both standardised values (the tied size
/// column, k t_i). ℓ omits the exact row's −y (a constant).
#[inline]
pub fn row_terms(kind: Censor, ya: f64, yb: f64, eta: f64, s: f64, b: f64, shift: f64) -> [f64; 6] {
    // φ's derivatives in its arguments (w_a, w_b), then the chain rule.
    let (l, u, d1, d2): (f64, [f64; 2], [f64; 2], [[f64; 2]; 2]) = match kind {
        Censor::Exact => return exact_terms(ya, eta, s, b, shift),
        Censor::Right => {
            let u = (ya - eta) / b;
            let a = (u + shift).exp();
            (-a, [u, 0.0], [-a, 0.0], [[-a, 0.0], [0.0, 0.0]])
        }
        Censor::Left => {
            let u = (ya - eta) / b;
            let w = u + shift;
            let a = w.exp();
            // φ = ln(1 − e^(−A)); φ' = A q, φ'' = A q (1 − A − A q), q = 1/(e^A − 1).
            let aq = if a < 1e-300 { 1.0 } else if a > 700.0 { 0.0 } else { a / a.exp_m1() };
            (ln_one_minus_exp(-a), [u, 0.0], [aq, 0.0], [[aq * (1.0 - a - aq), 0.0], [0.0, 0.0]])
        }
        Censor::Interval => {
            let (ua, ub) = ((ya - eta) / b, (yb - eta) / b);
            let a = (ua + shift).exp();
            // D = e^(w_b) − e^(w_a) = A (e^(w_b − w_a) − 1), without cancellation.
            let d = a * ((yb - ya) / b).exp_m1();
            let bb = a + d;
            let q = if d > 700.0 { 0.0 } else { 1.0 / d.exp_m1() };
            let (qa, qb) = (a * q, if q == 0.0 { 0.0 } else { bb * q });
            let l = -a + ln_one_minus_exp(-d);
            let d1 = [-a - qa, qb];
            let d2 = [[-(a + qa) * (1.0 + a * q), qa * bb * (1.0 + q)], [qa * bb * (1.0 + q), qb * (1.0 - bb * (1.0 + q))]];
            (l, [ua, ub], d1, d2)
        }
    };
    let (mut g1, mut g2, mut hee, mut hes, mut hss) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for a in 0..2 {
        g1 += d1[a];
        g2 += d1[a] * u[a];
        hes += d1[a];
        hss += d1[a] * u[a];
        for c in 0..2 {
            hee += d2[a][c];
            hes += d2[a][c] * u[c];
            hss += d2[a][c] * u[a] * u[c];
        }
    }
    [l, -g1 / b, -g2, hee / (b * b), hes / b, hss]
}

/// [`row_terms`] of an exact row, the density's: with u = (y − η)/b and w = u + shift,
/// [−s + w − e^w, (e^w − 1)/b, −1 − u + u e^w, −e^w/b², −(u e^w + e^w − 1)/b, u − u e^w − u² e^w].
/// The Weibull regression calls it directly for a sample whose every row is exact.
#[inline]
pub fn exact_terms(y: f64, eta: f64, s: f64, b: f64, shift: f64) -> [f64; 6] {
    let u = (y - eta) / b;
    let ew = (u + shift).exp();
    [-s + u + shift - ew, (ew - 1.0) / b, -1.0 - u + u * ew, -ew / (b * b), -(u * ew + ew - 1.0) / b, u - u * ew - u * u * ew]
}


#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_of_row_has_the_derivatives_of_its_likelihood() {
        // Central differences of ℓ in (η, s) against row_terms, for each kind and a tie shift.
        for (kind, ya, yb) in [(Censor::Exact, 0.3, f64::NAN), (Censor::Right, 0.2, f64::NAN), (Censor::Left, -0.1, f64::NAN), (Censor::Interval, -0.2, 0.05), (Censor::Interval, 0.1, 0.1004)] {
            for shift in [0.0, 0.4] {
                let at = |eta: f64, s: f64| row_terms(kind, ya, yb, eta, s, s.exp(), shift);
                let (eta, s) = (0.05, (0.12f64).ln());
                let t = at(eta, s);
                let h = 1e-5;
                let fd = |f: &dyn Fn(f64, f64) -> f64| [(f(eta + h, s) - f(eta - h, s)) / (2.0 * h), (f(eta, s + h) - f(eta, s - h)) / (2.0 * h)];
                let g = fd(&|e, s| at(e, s)[0]);
                let he = fd(&|e, s| at(e, s)[1]);
                let hs = fd(&|e, s| at(e, s)[2]);
                let close = |a: f64, b: f64| (a - b).abs() < 1e-5 * (1.0 + a.abs());
                assert!(close(t[1], g[0]) && close(t[2], g[1]), "{kind:?}: gradient {:?} vs {g:?}", &t[1..3]);
                assert!(close(t[3], he[0]) && close(t[4], he[1]) && close(t[4], hs[0]) && close(t[5], hs[1]), "{kind:?}: Hessian {:?} vs {he:?} {hs:?}", &t[3..]);
                // The value is the kind's log-probability (ln_prob), less the exact row's −y.
                let x = [ya.exp()];
                let c = crate::obs::Censoring { kind: vec![kind], upper: vec![yb.exp()], scheme: Default::default() };
                let lp = ln_prob(Obs { x: &x, censoring: Some(&c) }, 0, eta - shift * s.exp(), s.exp());
                let y = if kind == Censor::Exact { ya } else { 0.0 };
                assert!((t[0] - y - lp).abs() < 1e-12 * (1.0 + lp.abs()), "{kind:?}: {} vs {lp}", t[0] - y);
            }
        }
    }
}
