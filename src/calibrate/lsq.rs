//! Multi-start Levenberg–Marquardt least squares on a [`Simulator`].
//!
//! Minimises `½ Σ r_i²`, `r_i = (y_i(θ) − d_i)/σ_i`, in unit-cube coordinates u (θ = lower +
//! u (upper − lower)), so every parameter has the same scale. Each iteration solves
//! `(JᵀJ + λ diag(JᵀJ)) δ = −Jᵀr` (Marquardt's scaling) with J by forward differences in u
//! (step `fd_step`, columns evaluated in parallel through `simulate_batch`), clamps the step
//! into the cube, accepts it if the cost falls (λ /= 3) and otherwise raises λ (×4). It stops
//! when the relative cost change or the step falls below tolerance, or after `max_iterations`.
//! Starts: the nominal θ and `starts − 1` Sobol' points of the cube; the best end point wins.
//!
//! Uncertainty at the optimum: `Cov_u = s² (JᵀJ)⁻¹` (pseudo-inverse by SVD; s² = 1 for known σ,
//! `Σ r²/(n − p)` for [`Noise::Inferred`]), mapped to θ by the diagonal Jacobian of the cube map.
//! Identifiability: a parameter whose standard error is at least 0.9 of its prior standard
//! deviation (the data hardly narrow it), or whose correlation with another exceeds 0.95 in
//! magnitude, is named.
//!
//! Simulator failures are recorded (θ and message) and treated as an infinite cost: a failed
//! trial step is rejected, a failed start is skipped, a failed Jacobian column ends that start.
//!
//! Verified by `tests/verification/lsq.rs` (exact recovery without noise, coverage of the
//! reported intervals over seeds, a non-identifiable product).

use std::cell::RefCell;

use argmin::core::{CostFunction, Executor, Gradient};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::neldermead::NelderMead;
use argmin::solver::quasinewton::LBFGS;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::{Noise, Runner};
use crate::design::Sobol;
use crate::error::{Error, Result};
use crate::model::Simulator;

/// The optimiser of each start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LsqMethod {
    /// Levenberg–Marquardt on the residuals (the default; uses the least-squares structure).
    #[default]
    LevenbergMarquardt,
    /// argmin's Nelder–Mead simplex on the cost (gradient-free; robust to noisy simulators).
    NelderMead,
    /// argmin's L-BFGS with a Moré–Thuente line search on the cost, gradient Jᵀr by forward
    /// differences.
    Lbfgs,
}

/// Options of a least-squares fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LsqOptions {
    /// Optimiser of each start.
    pub method: LsqMethod,
    /// Number of starts (nominal + Sobol' points), ≥ 1.
    pub starts: usize,
    /// Iterations per start.
    pub max_iterations: usize,
    /// Forward-difference step in unit-cube coordinates.
    pub fd_step: f64,
    /// Relative cost-change tolerance.
    pub ftol: f64,
    /// Step-size tolerance (unit-cube norm).
    pub xtol: f64,
}

impl Default for LsqOptions {
    fn default() -> Self {
        LsqOptions { method: LsqMethod::LevenbergMarquardt, starts: 4, max_iterations: 100, fd_step: 1e-6, ftol: 1e-12, xtol: 1e-10 }
    }
}

/// One start and where it ended.
#[derive(Debug, Clone, PartialEq)]
pub struct StartResult {
    /// Start θ.
    pub start: Vec<f64>,
    /// End θ (None when the start itself failed).
    pub end: Option<Vec<f64>>,
    /// Cost ½Σr² at the end.
    pub cost: f64,
    /// Iterations used.
    pub iterations: usize,
}

/// The fit.
#[derive(Debug, Clone)]
pub struct LsqResult {
    /// Best θ.
    pub theta: Vec<f64>,
    /// Cost ½Σr² at θ.
    pub cost: f64,
    /// Weighted residuals at θ.
    pub residuals: Vec<f64>,
    /// Residual variance factor s² used in the covariance.
    pub scale: f64,
    /// Covariance of θ (units of θ²).
    pub covariance: DMatrix<f64>,
    /// Standard errors of θ.
    pub std_error: Vec<f64>,
    /// Correlation matrix.
    pub correlation: DMatrix<f64>,
    /// Standard error / prior standard deviation per parameter.
    pub width_ratio: Vec<f64>,
    /// Parameters the data do not determine, with the reason.
    pub unidentified: Vec<String>,
    /// Every start.
    pub starts: Vec<StartResult>,
    /// Simulator evaluations.
    pub evaluations: u64,
    /// Failed evaluations: θ and the error.
    pub failures: Vec<(Vec<f64>, String)>,
}

struct Problem<'a, S: Simulator> {
    runs: Runner<'a, S>,
    data: &'a [f64],
    sigma: Vec<f64>,
}

impl<S: Simulator> Problem<'_, S> {
    fn theta(&self, u: &[f64]) -> Vec<f64> {
        self.runs.sim.space().from_unit(u)
    }

    fn residuals_of(&self, y: &[f64]) -> Vec<f64> {
        y.iter().zip(self.data).zip(&self.sigma).map(|((y, d), s)| (y - d) / s).collect()
    }

    /// Residuals at several points (in parallel); None where the model failed.
    fn residuals(&mut self, us: &[Vec<f64>]) -> Result<Vec<Option<Vec<f64>>>> {
        let thetas: Vec<Vec<f64>> = us.iter().map(|u| self.theta(u)).collect();
        Ok(self.runs.run(&thetas)?.into_iter().map(|y| y.map(|y| self.residuals_of(&y))).collect())
    }

    /// Jacobian of r in u by forward differences (steps towards the cube's interior).
    fn jacobian(&mut self, u: &[f64], r: &[f64], h: f64) -> Result<Option<DMatrix<f64>>> {
        let p = u.len();
        let steps: Vec<f64> = u.iter().map(|&x| if x + h <= 1.0 { h } else { -h }).collect();
        let pts: Vec<Vec<f64>> = (0..p)
            .map(|j| {
                let mut v = u.to_vec();
                v[j] += steps[j];
                v
            })
            .collect();
        let cols = self.residuals(&pts)?;
        let mut jac = DMatrix::zeros(r.len(), p);
        for (j, c) in cols.into_iter().enumerate() {
            let Some(c) = c else { return Ok(None) };
            for i in 0..r.len() {
                jac[(i, j)] = (c[i] - r[i]) / steps[j];
            }
        }
        Ok(Some(jac))
    }
}

/// Levenberg–Marquardt from `u` (residuals `r`): end point, residuals, cost, iterations and the
/// last Jacobian.
#[allow(clippy::type_complexity)]
fn levenberg_marquardt<S: Simulator>(pb: &mut Problem<'_, S>, u0: Vec<f64>, r0: Vec<f64>, opts: &LsqOptions) -> Result<(Vec<f64>, Vec<f64>, f64, usize, Option<DMatrix<f64>>)> {
    let p = u0.len();
    let mut r = r0;
        let mut u = u0;
        let mut c = cost(&r);
        let mut lambda = 1e-3;
        let mut it = 0;
        let mut jac = None;
        let mut converged = false;
        while it < opts.max_iterations && !converged {
            it += 1;
            let Some(j) = pb.jacobian(&u, &r, opts.fd_step)? else { break };
            let jtj = j.transpose() * &j;
            let g = j.transpose() * DVector::from_column_slice(&r);
            jac = Some(j);
            let mut accepted = false;
            for _ in 0..30 {
                let mut a = jtj.clone();
                for k in 0..p {
                    a[(k, k)] += lambda * jtj[(k, k)].max(1e-12);
                }
                let Some(delta) = a.lu().solve(&(-&g)) else {
                    lambda *= 4.0;
                    continue;
                };
                let trial: Vec<f64> = u.iter().zip(delta.iter()).map(|(x, d)| (x + d).clamp(0.0, 1.0)).collect();
                let step: f64 = trial.iter().zip(&u).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
                let rt = pb.residuals(std::slice::from_ref(&trial))?.pop().flatten();
                match rt {
                    Some(rt) if cost(&rt) < c => {
                        let ct = cost(&rt);
                        let rel = (c - ct) / c.max(f64::MIN_POSITIVE);
                        u = trial;
                        r = rt;
                        c = ct;
                        lambda = (lambda / 3.0).max(1e-12);
                        accepted = true;
                        converged = rel < opts.ftol || step < opts.xtol;
                        break;
                    }
                    _ => {
                        lambda *= 4.0;
                        if step < opts.xtol {
                            break;
                        }
                    }
                }
            }
            if !accepted || c == 0.0 {
                break;
            }
        }
        Ok((u, r, c, it, jac))
}

/// The cost ½Σr² in unit-cube coordinates for argmin, with a quadratic penalty outside the cube
/// (the residuals are evaluated at the clamped point) so unconstrained solvers stay inside.
struct ArgminCost<'p, 'a, S: Simulator> {
    pb: RefCell<&'p mut Problem<'a, S>>,
    error: &'p RefCell<Option<Error>>,
    fd_step: f64,
}

impl<S: Simulator> ArgminCost<'_, '_, S> {
    fn clamped(v: &DVector<f64>) -> (Vec<f64>, f64) {
        let u: Vec<f64> = v.iter().map(|x| x.clamp(0.0, 1.0)).collect();
        let out: f64 = v.iter().zip(&u).map(|(x, c)| (x - c).powi(2)).sum();
        (u, out)
    }

    /// Residuals at the clamped point (None: the simulator failed or an error was kept).
    fn residuals(&self, u: &[f64]) -> Option<Vec<f64>> {
        match self.pb.borrow_mut().residuals(&[u.to_vec()]) {
            Ok(mut v) => v.pop().flatten(),
            Err(e) => {
                self.error.borrow_mut().get_or_insert(e);
                None
            }
        }
    }
}

impl<S: Simulator> CostFunction for ArgminCost<'_, '_, S> {
    type Param = DVector<f64>;
    type Output = f64;
    fn cost(&self, v: &DVector<f64>) -> std::result::Result<f64, argmin::core::Error> {
        let (u, out) = Self::clamped(v);
        Ok(self.residuals(&u).map_or(f64::INFINITY, |r| cost(&r) * (1.0 + 1e3 * out) + 1e3 * out))
    }
}

impl<S: Simulator> Gradient for ArgminCost<'_, '_, S> {
    type Param = DVector<f64>;
    type Gradient = DVector<f64>;
    fn gradient(&self, v: &DVector<f64>) -> std::result::Result<DVector<f64>, argmin::core::Error> {
        let (u, _) = Self::clamped(v);
        let Some(r) = self.residuals(&u) else { return Err(argmin::core::Error::msg("the simulator failed at the gradient's base point")) };
        let jac = match self.pb.borrow_mut().jacobian(&u, &r, self.fd_step) {
            Ok(Some(j)) => j,
            Ok(None) => return Err(argmin::core::Error::msg("the simulator failed in a gradient column")),
            Err(e) => {
                self.error.borrow_mut().get_or_insert(e);
                return Err(argmin::core::Error::msg("gradient"));
            }
        };
        let mut g = jac.transpose() * DVector::from_column_slice(&r);
        // The penalty's gradient outside the cube.
        for (k, (x, c)) in v.iter().zip(&u).enumerate() {
            g[k] += 2e3 * (x - c) * (1.0 + cost(&r));
        }
        Ok(g)
    }
}

/// Nelder–Mead or L-BFGS (argmin) from `u0`: end point, residuals, cost and iterations. A
/// solver that stops on an error (a failed simulator run inside a line search) ends at its best
/// point so far; errors of the Problem (wrong output length, non-finite outputs) propagate.
fn with_argmin<S: Simulator>(pb: &mut Problem<'_, S>, u0: Vec<f64>, r0: Vec<f64>, opts: &LsqOptions) -> Result<(Vec<f64>, Vec<f64>, f64, usize)> {
    let p = u0.len();
    let start = DVector::from_column_slice(&u0);
    let kept = RefCell::new(None);
    let problem = ArgminCost { pb: RefCell::new(&mut *pb), error: &kept, fd_step: opts.fd_step };
    let err = |e: argmin::core::Error| Error::numerical("least squares", e.to_string());
    let (best, iterations) = match opts.method {
        LsqMethod::NelderMead => {
            let mut simplex = vec![start.clone()];
            for k in 0..p {
                let mut v = start.clone();
                v[k] += if v[k] + 0.1 <= 1.0 { 0.1 } else { -0.1 };
                simplex.push(v);
            }
            let solver = NelderMead::new(simplex).with_sd_tolerance(opts.ftol.max(1e-14)).map_err(err)?;
            let res = Executor::new(problem, solver).configure(|s| s.max_iters(opts.max_iterations as u64 * 20)).run();
            match res {
                Ok(res) => (res.state().best_param.clone(), res.state().iter as usize),
                Err(_) => (None, 0),
            }
        }
        _ => {
            let ls = MoreThuenteLineSearch::new();
            let solver = LBFGS::new(ls, 7).with_tolerance_cost(opts.ftol).map_err(err)?.with_tolerance_grad(1e-10).map_err(err)?;
            let res = Executor::new(problem, solver).configure(|s| s.param(start).max_iters(opts.max_iterations as u64)).run();
            match res {
                Ok(res) => (res.state().best_param.clone(), res.state().iter as usize),
                // A failed simulator run inside the line search: the start is kept.
                Err(_) => (None, 0),
            }
        }
    };
    if let Some(e) = kept.into_inner() {
        return Err(e);
    }
    let u = best.map(|b| ArgminCost::<S>::clamped(&b).0).unwrap_or(u0.clone());
    let r = match pb.residuals(std::slice::from_ref(&u))?.pop().flatten() {
        Some(r) => r,
        None => r0.clone(),
    };
    let (u, r) = if cost(&r) <= cost(&r0) { (u, r) } else { (u0, r0) };
    let c = cost(&r);
    Ok((u, r, c, iterations))
}

/// The best end point so far: u, residuals, cost, Jacobian.
struct Best {
    u: Vec<f64>,
    r: Vec<f64>,
    cost: f64,
    jac: DMatrix<f64>,
}

fn cost(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|x| x * x).sum::<f64>()
}

/// Fits `model` to `data` with `noise`.
pub fn fit<S: Simulator>(model: &S, data: &[f64], noise: &Noise, opts: &LsqOptions) -> Result<LsqResult> {
    let space = model.space();
    let p = space.len();
    if model.outputs().len() != data.len() {
        return Err(Error::config("<calibration>", "data", format!("{} data for {} model outputs", data.len(), model.outputs().len())));
    }
    if data.len() < p {
        return Err(Error::config("<calibration>", "data", format!("{} data cannot determine {p} parameters", data.len())));
    }
    if opts.starts == 0 || !(opts.fd_step > 0.0 && opts.fd_step < 0.1) {
        return Err(Error::config("<calibration>", "least_squares", "starts ≥ 1 and 0 < fd_step < 0.1 required"));
    }
    let mut pb = Problem { runs: Runner::new(model), data, sigma: noise.sigmas(data)? };
    let mut start_us = vec![space.to_unit(&space.nominal())];
    start_us.extend(Sobol::points(p, opts.starts.saturating_sub(1), 1)?);
    let mut starts = Vec::new();
    let mut best: Option<Best> = None;
    for u0 in start_us {
        let theta0 = pb.theta(&u0);
        let Some(Some(r)) = pb.residuals(std::slice::from_ref(&u0))?.pop() else {
            starts.push(StartResult { start: theta0, end: None, cost: f64::INFINITY, iterations: 0 });
            continue;
        };
        let (u, r, c, it, mut jac) = match opts.method {
            LsqMethod::LevenbergMarquardt => levenberg_marquardt(&mut pb, u0, r, opts)?,
            LsqMethod::NelderMead | LsqMethod::Lbfgs => {
                let (u, r, c, it) = with_argmin(&mut pb, u0, r, opts)?;
                (u, r, c, it, None)
            }
        };
        // The Jacobian at the end point.
        if let Some(j) = pb.jacobian(&u, &r, opts.fd_step)? {
            jac = Some(j);
        }
        let theta = pb.theta(&u);
        starts.push(StartResult { start: theta0, end: Some(theta.clone()), cost: c, iterations: it });
        if let Some(jac) = jac
            && best.as_ref().is_none_or(|b| c < b.cost)
        {
            best = Some(Best { u, r, cost: c, jac });
        }
    }
    let Some(Best { u, r, cost: c, jac: j }) = best else {
        return Err(Error::numerical("least squares", format!("every start failed ({} failures recorded)", pb.runs.failures.len())));
    };
    let n = r.len();
    let scale = match noise {
        Noise::Inferred => 2.0 * c / (n.saturating_sub(p)).max(1) as f64,
        _ => 1.0,
    };
    // Covariance in u by SVD pseudo-inverse of JᵀJ; infinite variance along null directions.
    let jtj = j.transpose() * &j;
    let svd = jtj.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let mut cov_u = DMatrix::zeros(p, p);
    let mut null = vec![false; p];
    if let (Some(uu), Some(vt)) = (&svd.u, &svd.v_t) {
        for k in 0..p {
            let s = svd.singular_values[k];
            if s > 1e-12 * smax {
                cov_u += (vt.row(k).transpose() * uu.column(k).transpose()) / s;
            } else {
                for i in 0..p {
                    if vt[(k, i)].abs() > 1e-3 {
                        null[i] = true;
                    }
                }
            }
        }
    }
    let widths: Vec<f64> = space.params().iter().map(|q| q.upper - q.lower).collect();
    let mut cov = DMatrix::zeros(p, p);
    for a in 0..p {
        for b in 0..p {
            cov[(a, b)] = scale * cov_u[(a, b)] * widths[a] * widths[b];
        }
    }
    let std_error: Vec<f64> = (0..p).map(|k| if null[k] { f64::INFINITY } else { cov[(k, k)].max(0.0).sqrt() }).collect();
    let mut corr = DMatrix::identity(p, p);
    for a in 0..p {
        for b in 0..p {
            if a != b && std_error[a].is_finite() && std_error[b].is_finite() && std_error[a] > 0.0 && std_error[b] > 0.0 {
                corr[(a, b)] = cov[(a, b)] / (std_error[a] * std_error[b]);
            }
        }
    }
    let prior_sd: Vec<f64> = space.params().iter().map(|q| q.prior_sd()).collect();
    let width_ratio: Vec<f64> = std_error.iter().zip(&prior_sd).map(|(s, ps)| s / ps).collect();
    let names: Vec<&str> = space.params().iter().map(|q| q.name.as_str()).collect();
    let mut unidentified = Vec::new();
    for k in 0..p {
        if null[k] {
            unidentified.push(format!("{}: lies in a direction the data do not constrain (singular JᵀJ)", names[k]));
        } else if width_ratio[k] >= 0.9 {
            unidentified.push(format!("{}: standard error {:.3e} is {:.0} % of its prior width", names[k], std_error[k], 100.0 * width_ratio[k]));
        }
        for m in k + 1..p {
            if corr[(k, m)].abs() > 0.95 {
                unidentified.push(format!("{} and {}: correlation {:+.3}", names[k], names[m], corr[(k, m)]));
            }
        }
    }
    let theta = pb.theta(&u);
    Ok(LsqResult {
        theta,
        cost: c,
        residuals: r,
        scale,
        covariance: cov,
        std_error,
        correlation: corr,
        width_ratio,
        unidentified,
        starts,
        evaluations: pb.runs.evaluations,
        failures: pb.runs.failures,
    })
}
