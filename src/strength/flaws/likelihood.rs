//! The two-population laws' log-likelihood and its analytic gradient, row by row: the density of
//! an exact row, the log-probability of what a censored or interval row says.
//!
//! With y_j = ln x − ln σ_j and e_j = (x/σ_j)^m_j:
//!
//! ```text
//! ∂ ln f_j/∂ ln σ_j = m_j (e_j − 1)          ∂ ln f_j/∂ ln m_j = 1 + m_j y_j (1 − e_j)
//! mixture:   ∂ℓ_i/∂θ_j = r_j ∂ ln f_j/∂θ_j,  ∂ℓ_i/∂ logit p = r_1 − p,   r_j = p_j f_j / f
//! competing: ∂ℓ_i/∂ ln σ_j = m_j (e_j − w_j),  ∂ℓ_i/∂ ln m_j = w_j (1 + m_j y_j) − m_j y_j e_j,
//!            w_j = h_j / (h_1 + h_2),  h_j = (m_j/σ_j)(x/σ_j)^(m_j−1)
//! ```
//!
//! **Censored and grouped rows** ([`crate::obs`]) add ln S, ln F or ln[S(x) − S(x_u)] of the law
//! (S = p S₁ + (1 − p) S₂ for the mixture, S₁ S₂ for competing risks), from ln S and its
//! gradient (with r_j the shares of p_j S_j in S for the mixture):
//!
//! ```text
//! ∂ ln S/∂ ln σ_j = r_j m_j e_j     ∂ ln S/∂ ln m_j = −r_j m_j y_j e_j     ∂ ln S/∂ logit p = r_1 − p
//! right: ∇ℓ = ∇ ln S(x)     left: ∇ℓ = −[S/(1 − S)] ∇ ln S(x)
//! interval: ∇ℓ = [∇ ln S(x) − ρ ∇ ln S(x_u)]/(1 − ρ),  ρ = S(x_u)/S(x)
//! ```
//!
//! (r_j = 1 for competing risks.)
//!
//! **The threshold law** (three-parameter Weibull), in coordinates ln γ, ln σ, ln m, with
//! x' = x e^(−η) the row's strength with its shift taken out, w = x' − γ, y = ln(w/σ) and
//! e = (w/σ)^m:
//!
//! ```text
//! ℓ_i = ln m − ln σ + (m − 1) y − e − η                    (exact row, w > 0; −∞ for w ≤ 0)
//! ∂ℓ_i/∂ ln σ = m (e − 1)      ∂ℓ_i/∂ ln m = 1 + m y (1 − e)
//! ∂ℓ_i/∂ ln γ = γ (m e − m + 1)/w      ∂ℓ_i/∂η = x' (m e − m + 1)/w − 1
//! ln S = −e (0 for w ≤ 0):  ∂/∂ ln σ = m e,  ∂/∂ ln m = −m y e,  ∂/∂ ln γ = γ m e/w,  ∂/∂η = x' m e/w
//! ```
//!
//! A row that says the specimen broke at or below a value the threshold has passed (exact,
//! left-censored, or an interval whose upper end is at or below γ) has probability 0: ℓ = −∞,
//! which the search's line search steps back from.
//!
//! Verified by the unit test below (the gradient against central differences, exact rows and
//! rows of every kind, with a scale-effect column).

use super::Populations;
use crate::obs::{Censor, Obs, ln_one_minus_exp};

/// The rows' log values (x scaled by its median), what each row says, and an interval's upper
/// log value: what the likelihood reads.
pub(super) struct Rows<'a> {
    pub(super) lnx: &'a [f64],
    /// Each row's kind (empty: every row exact).
    pub(super) kind: &'a [Censor],
    /// ln of an interval's upper end (NaN for the other rows; empty without censoring).
    pub(super) lnu: &'a [f64],
}

impl Rows<'_> {
    pub(super) fn exact(&self, i: usize) -> bool {
        self.kind.is_empty() || self.kind[i] == Censor::Exact
    }
}

/// The mixture's weight p and ln p_j at θ (logit p = θ₀), computed once per evaluation rather
/// than once per row; zero for the other laws.
#[derive(Clone, Copy)]
struct Weight {
    p: f64,
    lw: [f64; 2],
}

impl Weight {
    fn of(kind: Populations, t: &[f64]) -> Weight {
        match kind {
            Populations::Mixture => Weight { p: 1.0 / (1.0 + (-t[0]).exp()), lw: [-(1.0 + (-t[0]).exp()).ln(), -(1.0 + t[0].exp()).ln()] },
            Populations::Competing | Populations::Threshold => Weight { p: 0.0, lw: [0.0; 2] },
        }
    }
}

/// ln S at ln x (less the row's shift) and its gradient: the law's coordinates in `gs[..k0]`,
/// ∂/∂η (= Σ_j ∂/∂ ln σ_j) in `gs[k0]`.
fn ln_sf_grad(kind: Populations, lx: f64, t: &[f64], w: Weight, gs: &mut [f64; 6]) -> f64 {
    let k0 = kind.parameters();
    gs.iter_mut().for_each(|v| *v = 0.0);
    match kind {
        Populations::Mixture => {
            let Weight { p, lw } = w;
            let (u, m) = ([t[1], t[3]], [t[2].exp(), t[4].exp()]);
            let (y, e) = standardised(lx, u, m);
            let (ls, r) = log_sum_and_shares([lw[0] - e[0], lw[1] - e[1]]);
            gs[0] = r[0] - p;
            for j in 0..2 {
                gs[1 + 2 * j] = r[j] * m[j] * e[j];
                gs[2 + 2 * j] = -r[j] * m[j] * y[j] * e[j];
                gs[k0] += r[j] * m[j] * e[j];
            }
            ls
        }
        Populations::Competing => {
            let (u, m) = ([t[0], t[2]], [t[1].exp(), t[3].exp()]);
            let (y, e) = standardised(lx, u, m);
            for j in 0..2 {
                gs[2 * j] = m[j] * e[j];
                gs[2 * j + 1] = -m[j] * y[j] * e[j];
                gs[k0] += m[j] * e[j];
            }
            -e[0] - e[1]
        }
        Populations::Threshold => {
            let (g, m, x) = (t[0].exp(), t[2].exp(), lx.exp());
            let w = x - g;
            if w <= 0.0 {
                return 0.0;
            }
            let y = w.ln() - t[1];
            let e = (m * y).exp();
            gs[0] = g * m * e / w;
            gs[1] = m * e;
            gs[2] = -m * y * e;
            gs[k0] = x * m * e / w;
            -e
        }
    }
}

/// A censored or interval row's ℓ and its gradient into `g` (the law's coordinates, then one β
/// per column of `z`; module docs).
fn censored_row(kind: Populations, rows: &Rows, i: usize, h: f64, z: &[Vec<f64>], t: &[f64], w: Weight, g: &mut [f64]) -> f64 {
    let k0 = kind.parameters();
    let (mut ga, mut gb) = ([0.0; 6], [0.0; 6]);
    let (l, wa, wb) = match rows.kind[i] {
        Censor::Right => (ln_sf_grad(kind, rows.lnx[i] - h, t, w, &mut ga), 1.0, 0.0),
        Censor::Left => {
            let lb = ln_sf_grad(kind, rows.lnx[i] - h, t, w, &mut gb);
            let l = ln_one_minus_exp(lb);
            (l, 0.0, -(lb - l).exp())
        }
        Censor::Interval => {
            let la = ln_sf_grad(kind, rows.lnx[i] - h, t, w, &mut ga);
            let lb = ln_sf_grad(kind, rows.lnu[i] - h, t, w, &mut gb);
            let rho = (lb - la).exp();
            (la + ln_one_minus_exp(lb - la), 1.0 / (1.0 - rho), -rho / (1.0 - rho))
        }
        Censor::Exact => unreachable!("exact rows are the density's"),
    };
    for c in 0..k0 {
        g[c] += wa * ga[c] + wb * gb[c];
    }
    let geta = wa * ga[k0] + wb * gb[k0];
    for (k, col) in z.iter().enumerate() {
        g[k0 + k] += geta * col[i];
    }
    l
}

/// Log-likelihood at unconstrained θ of the rows `rows`, and its gradient in `g` (−∞,
/// gradient unset, where the likelihood is not finite). θ is the law's coordinates followed by
/// one β per column of `z`: row i's scales are shifted by η_i = Σ_k β_k z_k,i, so an exact row's
/// ℓ_i = ℓ_law(ln x_i − η_i) − η_i and ∂ℓ_i/∂η_i = Σ_j ∂ℓ_i/∂ ln σ_j; a censored row's ℓ is ln S,
/// ln F or a class's probability of the shifted law ([`censored_row`]).
pub(super) fn loglik_grad(kind: Populations, rows: &Rows, z: &[Vec<f64>], t: &[f64], g: &mut [f64]) -> f64 {
    g.iter_mut().for_each(|v| *v = 0.0);
    let mut l = 0.0;
    let k0 = kind.parameters();
    let eta = |i: usize| shift_at(z, &t[k0..], i);
    let lnx = rows.lnx;
    if kind == Populations::Threshold {
        return threshold_loglik_grad(rows, z, t, g);
    }
    // The populations' ln σ_j (u), ln m_j (v) and where their gradient goes: the mixture's
    // weight logit comes first.
    let at = match kind {
        Populations::Mixture => 1,
        Populations::Competing | Populations::Threshold => 0,
    };
    let (u, v) = ([t[at], t[at + 2]], [t[at + 1], t[at + 3]]);
    let m = [v[0].exp(), v[1].exp()];
    let weight = Weight::of(kind, t);
    let Weight { p, lw } = weight;
    // ln m_j − ln σ_j: the part of ln f_j that is the same for every row.
    let c = [0, 1].map(|j| v[j] - u[j]);
    for (i, &lx0) in lnx.iter().enumerate() {
        let h = eta(i);
        if !rows.exact(i) {
            l += censored_row(kind, rows, i, h, z, t, weight, g);
            continue;
        }
        let (y, e) = standardised(lx0 - h, u, m);
        let mut gu = 0.0;
        match kind {
            Populations::Mixture => {
                let a = [0, 1].map(|j| lw[j] + c[j] + (m[j] - 1.0) * y[j] - e[j]);
                // ln(e^a₀ + e^a₁) and the responsibilities from one exponential.
                let (li, r) = log_sum_and_shares(a);
                l += li - h;
                g[0] += r[0] - p;
                for j in 0..2 {
                    if r[j] > 0.0 {
                        let du = r[j] * m[j] * (e[j] - 1.0);
                        g[at + 2 * j] += du;
                        gu += du;
                        g[at + 1 + 2 * j] += r[j] * (1.0 + m[j] * y[j] * (1.0 - e[j]));
                    }
                }
            }
            Populations::Competing => {
                // h_j = (m_j/σ_j)(x/σ_j)^(m_j − 1) = m_j e_j / x, so ln(h₁ + h₂) = ln(m₁e₁ + m₂e₂) − ln x
                // and the shares are m_j e_j / Σ; in logs where that sum under- or overflows.
                let me = [m[0] * e[0], m[1] * e[1]];
                let sum = me[0] + me[1];
                let (lht, share) = if sum > 1e-280 && sum < 1e280 {
                    (sum.ln() - (lx0 - h), [me[0] / sum, me[1] / sum])
                } else {
                    log_sum_and_shares([0, 1].map(|j| c[j] + (m[j] - 1.0) * y[j]))
                };
                l += lht - e[0] - e[1] - h;
                for j in 0..2 {
                    let w = share[j];
                    let du = m[j] * (e[j] - w);
                    g[at + 2 * j] += du;
                    gu += du;
                    g[at + 1 + 2 * j] += w * (1.0 + m[j] * y[j]) - m[j] * y[j] * e[j];
                }
            }
            Populations::Threshold => unreachable!("the threshold law's own loop"),
        }
        for (k, c) in z.iter().enumerate() {
            g[k0 + k] += gu * c[i];
        }
    }
    if l.is_finite() && g.iter().all(|v| v.is_finite()) { l } else { f64::NEG_INFINITY }
}

/// [`loglik_grad`] of the threshold law (module docs): θ = (ln γ, ln σ, ln m, β…).
fn threshold_loglik_grad(rows: &Rows, z: &[Vec<f64>], t: &[f64], g: &mut [f64]) -> f64 {
    let kind = Populations::Threshold;
    let k0 = kind.parameters();
    let (gam, u, m) = (t[0].exp(), t[1], t[2].exp());
    let (ln_m, weight) = (m.ln(), Weight::of(kind, t));
    let mut l = 0.0;
    for (i, &lx) in rows.lnx.iter().enumerate() {
        let h = shift_at(z, &t[k0..], i);
        if !rows.exact(i) {
            l += censored_row(kind, rows, i, h, z, t, weight, g);
            continue;
        }
        let x = (lx - h).exp();
        let w = x - gam;
        if w <= 0.0 {
            return f64::NEG_INFINITY;
        }
        let y = w.ln() - u;
        let e = (m * y).exp();
        l += ln_m - u + (m - 1.0) * y - e - h;
        let a = (m * e - m + 1.0) / w;
        g[0] += gam * a;
        g[1] += m * (e - 1.0);
        g[2] += 1.0 + m * y * (1.0 - e);
        let geta = x * a - 1.0;
        for (k, c) in z.iter().enumerate() {
            g[k0 + k] += geta * c[i];
        }
    }
    if l.is_finite() && g.iter().all(|v| v.is_finite()) { l } else { f64::NEG_INFINITY }
}

/// Row i's scale shift η_i = Σ_k β_k z_k,i.
pub(super) fn shift_at(z: &[Vec<f64>], beta: &[f64], i: usize) -> f64 {
    z.iter().zip(beta).map(|(c, b)| b * c[i]).sum()
}

/// y_j = ln x − ln σ_j and e_j = e^(m_j y_j) = (x/σ_j)^m_j of both populations at ln x.
#[inline]
fn standardised(lx: f64, u: [f64; 2], m: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let y = [lx - u[0], lx - u[1]];
    (y, [(m[0] * y[0]).exp(), (m[1] * y[1]).exp()])
}

/// ln(e^a₀ + e^a₁) and the shares e^(a_j) / (e^a₀ + e^a₁), from one exponential.
pub(super) fn log_sum_and_shares(a: [f64; 2]) -> (f64, [f64; 2]) {
    let (hi, lo) = if a[0] >= a[1] { (0, 1) } else { (1, 0) };
    let q = (a[lo] - a[hi]).exp();
    let mut share = [0.0; 2];
    share[hi] = 1.0 / (1.0 + q);
    share[lo] = q * share[hi];
    (a[hi] + q.ln_1p(), share)
}

/// The likelihood's view of `x` scaled by `med`: log values, kinds, upper log values.
pub(super) fn scaled(x: Obs, med: f64) -> (Vec<f64>, Vec<Censor>, Vec<f64>) {
    let lnx = x.x.iter().map(|v| (v / med).ln()).collect();
    if x.complete() {
        return (lnx, Vec::new(), Vec::new());
    }
    let n = x.len();
    ((lnx), (0..n).map(|i| x.kind(i)).collect(), (0..n).map(|i| (x.upper(i) / med).ln()).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_analytic_gradient_equals_central_differences() {
        let x = [0.6f64, 0.8, 0.9, 1.0, 1.05, 1.1, 1.3, 0.4].map(f64::ln);
        let z = vec![vec![0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.5, -1.0]];
        // Every row exact, then rows of every kind (right, left, interval among exact ones).
        let kinds = [Censor::Exact, Censor::Right, Censor::Exact, Censor::Left, Censor::Interval, Censor::Exact, Censor::Right, Censor::Interval];
        let upper = [f64::NAN, f64::NAN, f64::NAN, f64::NAN, 1.2f64.ln(), f64::NAN, f64::NAN, 0.7f64.ln()];
        for rows in [Rows { lnx: &x, kind: &[], lnu: &[] }, Rows { lnx: &x, kind: &kinds, lnu: &upper }] {
            for (kind, t) in [(Populations::Mixture, vec![0.3, -0.2, 1.5, 0.1, 2.2, 0.15]), (Populations::Competing, vec![-0.1, 1.2, 0.2, 2.5, -0.2]), (Populations::Threshold, vec![0.15f64.ln(), 0.1, 1.1, 0.05])] {
                let mut g = vec![0.0; t.len()];
                let mut scratch = g.clone();
                let l = loglik_grad(kind, &rows, &z, &t, &mut g);
                assert!(l.is_finite());
                for k in 0..t.len() {
                    let (mut a, mut b) = (t.clone(), t.clone());
                    a[k] += 1e-6;
                    b[k] -= 1e-6;
                    let fd = (loglik_grad(kind, &rows, &z, &a, &mut scratch) - loglik_grad(kind, &rows, &z, &b, &mut scratch)) / 2e-6;
                    assert!((fd - g[k]).abs() < 1e-6 * (1.0 + fd.abs()), "{kind:?} coordinate {k}: analytic {} vs difference {fd}", g[k]);
                }
            }
        }
    }

    #[test]
    fn competing_risks_hazards_far_below_and_far_above_both_scales_keep_their_logs() {
        // ℓ = ln(h₁ + h₂) − e₁ − e₂ with ln h_j = ln m_j − ln σ_j + (m_j − 1)(ln x − ln σ_j):
        // at ln x = −300 both m_j e_j underflow and ln(m₁e₁ + m₂e₂) must come from the logs; at
        // ln x = 1.5 the sum is ordinary.
        let t = [0.1f64, 1.2, -0.2, 0.9];
        for lx in [-300.0f64, 1.5] {
            let ln_h = [0, 1].map(|j| t[2 * j + 1] - t[2 * j] + (t[2 * j + 1].exp() - 1.0) * (lx - t[2 * j]));
            let e = [0, 1].map(|j| (t[2 * j + 1].exp() * (lx - t[2 * j])).exp());
            let hi = ln_h[0].max(ln_h[1]);
            let expected = hi + ((ln_h[0] - hi).exp() + (ln_h[1] - hi).exp()).ln() - e[0] - e[1];
            let mut g = [0.0; 4];
            let l = loglik_grad(Populations::Competing, &Rows { lnx: &[lx], kind: &[], lnu: &[] }, &[], &t, &mut g);
            assert!((l - expected).abs() < 1e-9 * expected.abs().max(1.0), "ln x = {lx}: {l} against {expected}");
            assert!(g.iter().all(|v| v.is_finite()));
        }
    }
}
