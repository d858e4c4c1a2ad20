//! The fitted strength model ([`ModelFit`]) and its maximum-likelihood fit at given terms
//! ([`fit_at`]): the Weibull regression with each effect's columns ([`super::regress`]), the
//! Tavares–King damage ratio profiled (golden section on ln x), a two-population law fitted in
//! place of the Weibull law ([`super::flaws`]), partially pooled factors at a given spread τ
//! (the τ search is [`super::pooling`]; the entry points are [`super::fit::fit_model`] and
//! [`super::fit::fit_model_near`]).

use super::effects::{Effect, Term};
use super::regress::{Design, RegFit, fit, fit_from};
use crate::error::{Error, Result};
use crate::obs::Obs;
use crate::lifetime::damage::tk_ratio_path;
use crate::stats::golden_max;

/// A fitted model: the base Weibull plus zero or more effects.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelFit {
    /// The effects, in the order they were added.
    pub effects: Vec<Effect>,
    /// Regression columns of each effect, in the order of `effects` (1 for a linear effect,
    /// L − 1 for the levels of a categorical factor, 0 for damage and for a modulus per level).
    pub widths: Vec<usize>,
    /// Scale columns of each effect, in the order of `effects` (L − 1 for a modulus per level,
    /// 0 for the others).
    pub scale_widths: Vec<usize>,
    /// The scale columns (ln b_i = ln b + Σ γ_j v_ij), in the order of the moduli effects.
    pub scale_columns: Vec<Vec<f64>>,
    /// Ridge precision 1/τ² of each regression column (0 unless partially pooled).
    pub penalty: Vec<f64>,
    /// The regression (β in the order of the linear effects).
    pub reg: RegFit,
    /// Linear columns, in the order of the linear effects.
    pub columns: Vec<Vec<f64>>,
    /// The damage offset at the fitted ratio, if damage is an effect.
    pub offset: Option<Vec<f64>>,
    /// Fitted Tavares–King ratio x, if damage is an effect.
    pub damage_ratio: Option<f64>,
    /// Number of particles fitted.
    pub n: usize,
    /// Whether every specimen fitted broke at its recorded value (no censored or interval row):
    /// C1239's pivots and unbiasing factor assume it.
    pub complete: bool,
    /// A two-population law in place of the Weibull law (then `reg` is the plain two-parameter
    /// fit, kept for the reference scale, and the likelihood, CDF and draws are the law's; the
    /// linear effects beside it shift both populations' scales by the law's own β over
    /// `columns`).
    pub law: Option<crate::strength::flaws::FlawFit>,
}

impl ModelFit {
    /// The regression design of the fitted model.
    pub fn design(&self) -> Design<'_> {
        Design { columns: &self.columns, offset: self.offset.as_deref(), scale_columns: &self.scale_columns, penalty: &self.penalty }
    }

    /// Number of parameters: μ, b, and each effect's (one; L − 1 for levels or moduli, also
    /// when partially pooled); a two-population law's own (4 or 5) plus one per column of the scale
    /// effects beside it.
    pub fn parameters(&self) -> usize {
        if let Some(l) = &self.law {
            return l.kind.parameters() + l.beta.len();
        }
        2 + self.widths.iter().zip(&self.effects).map(|(w, e)| if *e == Effect::Damage { 1 } else { *w }).sum::<usize>() + self.scale_columns.len() - self.pooled_effects()
    }

    /// [`ModelFit::parameters`] with each partially pooled factor counted at its effective
    /// degrees of freedom (between 0 and L − 1) instead of L − 1: what ΔBIC charges.
    pub fn effective_parameters(&self) -> f64 {
        let pooled_columns = self.penalty.iter().filter(|l| **l > 0.0).count();
        if self.law.is_some() || pooled_columns == 0 {
            return self.parameters() as f64;
        }
        // parameters() counts each pooled factor at L − 1: take its columns out, its edf in.
        (self.parameters() + self.pooled_effects() - pooled_columns) as f64 + self.reg.edf_penalised
    }

    /// ln τ of each partially pooled factor, in the order of the effects.
    pub fn pooled_ln_tau(&self) -> Vec<f64> {
        self.effects.iter().filter_map(|e| self.beta_range(e)).filter(|r| !r.is_empty()).filter_map(|r| self.penalty.get(r.start).copied()).filter(|l| *l > 0.0).map(|l| -0.5 * l.ln()).collect()
    }

    /// Number of partially pooled factors.
    fn pooled_effects(&self) -> usize {
        self.effects.iter().filter(|e| self.beta_range(e).is_some_and(|r| !r.is_empty() && self.penalty.get(r.start).is_some_and(|l| *l > 0.0))).count()
    }

    /// Weibull modulus (of the reference level when a factor has a modulus per level; NaN for a
    /// two-population law, which has two).
    pub fn shape(&self) -> f64 {
        if self.law.is_some() { f64::NAN } else { self.reg.shape() }
    }

    /// The smallest and largest Weibull modulus over the fitted specimens: (m, m) with one
    /// modulus, the range over the levels with a modulus per level, the two populations'
    /// moduli for a two-population law.
    pub fn modulus_range(&self) -> (f64, f64) {
        if let Some(l) = &self.law {
            return (l.first.1.min(l.second.1), l.first.1.max(l.second.1));
        }
        let d = self.design();
        (0..self.n).map(|i| 1.0 / self.reg.b_at(&d, i)).fold((self.reg.shape(), self.reg.shape()), |(lo, hi), m| (lo.min(m), hi.max(m)))
    }

    /// The scale-effect coefficients β, in the order of the columns: the regression's, or those
    /// fitted beside a two-population law.
    pub fn beta(&self) -> &[f64] {
        self.law.as_ref().map_or(&self.reg.beta, |l| &l.beta)
    }

    /// Maximised log-likelihood.
    pub fn loglik(&self) -> f64 {
        self.law.as_ref().map_or(self.reg.loglik, |l| l.loglik)
    }

    /// Fitted CDF of specimen i at x.
    pub fn cdf(&self, i: usize, x: f64) -> f64 {
        match &self.law {
            Some(l) => l.cdf(x * (-l.shift(&self.columns, i)).exp()),
            None => self.reg.cdf(&self.design(), i, x),
        }
    }

    /// The linear effects, in the order of β.
    pub fn linear(&self) -> Vec<Effect> {
        self.effects.iter().zip(&self.widths).filter(|(e, w)| **e != Effect::Damage && **w > 0).map(|(e, _)| e.clone()).collect()
    }

    /// The positions in γ (the scale coefficients) of a modulus-per-level effect.
    pub fn gamma_range(&self, c: &Effect) -> Option<std::ops::Range<usize>> {
        let k = self.effects.iter().position(|e| e == c)?;
        let start: usize = self.scale_widths[..k].iter().sum();
        Some(start..start + self.scale_widths[k])
    }

    /// The positions in β of an effect's coefficients.
    pub fn beta_range(&self, c: &Effect) -> Option<std::ops::Range<usize>> {
        let k = self.effects.iter().position(|e| e == c)?;
        let start: usize = self.widths[..k].iter().sum();
        Some(start..start + self.widths[k])
    }

    /// The profile-likelihood interval at `level` of a single-column effect's β (`x`: the
    /// fitted strengths; [`super::regress::profile_interval`]); for a two-population law the
    /// interval of its reported parameter ([`super::flaws::FlawFit::profile_band`]); None for a
    /// categorical factor, a modulus per level and damage.
    pub fn profile_band(&self, x: Obs, c: &Effect, level: f64) -> Option<(f64, f64)> {
        if let Some(l) = &self.law {
            return if matches!(c, Effect::Populations(_)) { l.profile_band(x, &self.columns, level) } else { None };
        }
        if self.damage_ratio.is_some() {
            return None;
        }
        let r = self.beta_range(c)?;
        if r.len() != 1 {
            return None;
        }
        super::regress::profile_interval(x, &self.design(), &self.reg, r.start, level)
    }

    /// β of a linear effect (or the ratio x for damage), with its standard error (NaN for
    /// damage); the first coefficient of a categorical factor's levels; the first γ (ln of the
    /// level's 1/m over the reference's) of a modulus per level.
    pub fn coefficient(&self, c: &Effect) -> Option<(f64, f64)> {
        if *c == Effect::Damage {
            return self.damage_ratio.map(|x| (x, f64::NAN));
        }
        if let Some(r) = self.gamma_range(c).filter(|r| !r.is_empty()) {
            return Some((*self.reg.gamma.get(r.start)?, self.reg.gamma_se[r.start]));
        }
        let j = self.beta_range(c)?.start;
        if let Some(l) = &self.law {
            return Some((*l.beta.get(j)?, f64::NAN));
        }
        Some((*self.reg.beta.get(j)?, self.reg.beta_se[j]))
    }
}

/// [`super::fit::fit_model_near`] with each pooled factor's spread fixed at e^(ln_tau).
pub(super) fn fit_at(x: Obs, terms: &[(Effect, Term)], hint: Option<f64>, ln_tau: &[f64], start: Option<&RegFit>) -> Result<ModelFit> {
    let mut columns = Vec::new();
    let mut damage = None;
    let mut effects = Vec::new();
    let mut widths = Vec::new();
    let mut penalty = Vec::new();
    let mut pooled = 0;
    if let Some(kind) = terms.iter().find_map(|(_, t)| if let Term::Populations(k) = t { Some(*k) } else { None }) {
        // Beside a two-population law: scale effects of recorded columns (one ln-linear or
        // power column, or one scale per level), shifting both populations alike.
        for (c, t) in terms {
            match t {
                Term::Linear(z) => {
                    columns.push(z.clone());
                    widths.push(1);
                }
                Term::Levels { columns: z, .. } => {
                    columns.extend(z.iter().cloned());
                    widths.push(z.len());
                }
                Term::Populations(_) => widths.push(0),
                _ => return Err(Error::numerical("two flaw populations", format!("`{}` is not fitted beside a two-population law (only scale effects of recorded columns and levels are)", c.name()))),
            }
            effects.push(c.clone());
        }
        let law = crate::strength::flaws::fit_shifted(kind, x, &columns)?;
        let reg = fit(x, &Design::default())?;
        let k = effects.len();
        return Ok(ModelFit { effects, widths, scale_widths: vec![0; k], scale_columns: Vec::new(), penalty: vec![0.0; columns.len()], reg, columns, offset: None, damage_ratio: None, n: x.len(), complete: x.complete(), law: Some(law) });
    }
    let mut scale_columns = Vec::new();
    let mut scale_widths = Vec::new();
    for (c, t) in terms {
        effects.push(c.clone());
        match t {
            Term::Linear(z) => {
                columns.push(z.clone());
                widths.push(1);
                penalty.push(0.0);
            }
            Term::Levels { columns: z, .. } => {
                columns.extend(z.iter().cloned());
                widths.push(z.len());
                penalty.extend(std::iter::repeat_n(0.0, z.len()));
            }
            Term::Pooled { columns: z, .. } => {
                let tau = ln_tau.get(pooled).copied().unwrap_or((0.1f64).ln()).exp();
                pooled += 1;
                columns.extend(z.iter().cloned());
                widths.push(z.len());
                penalty.extend(std::iter::repeat_n(1.0 / (tau * tau), z.len()));
            }
            Term::Moduli { columns: v, .. } => {
                scale_columns.extend(v.iter().cloned());
                widths.push(0);
            }
            Term::Damage { impacts, gamma } => {
                damage = Some((impacts, *gamma));
                widths.push(0);
            }
            Term::Populations(_) => unreachable!("handled above"),
        }
        scale_widths.push(if let Term::Moduli { columns: v, .. } = t { v.len() } else { 0 });
    }
    // Linear effects first in `effects`' β order; damage (if any) is profiled.
    let Some((impacts, gamma)) = damage else {
        let reg = fit_from(x, &Design { columns: &columns, offset: None, scale_columns: &scale_columns, penalty: &penalty }, start)?;
        return Ok(ModelFit { effects, widths, scale_widths, scale_columns, penalty, reg, columns, offset: None, damage_ratio: None, n: x.len(), complete: x.complete(), law: None });
    };
    let n_max = impacts.iter().copied().max().unwrap_or(0);
    // One Tavares–King trajectory per trial ratio serves every particle.
    let offsets = |lx: f64| -> Option<Vec<f64>> {
        let path = tk_ratio_path(lx.exp(), gamma, n_max)?;
        Some(impacts.iter().map(|&n| (lx - path[n as usize]) / 5.0).collect())
    };
    let profile = |lx: f64| -> f64 {
        offsets(lx)
            .and_then(|o| fit(x, &Design { columns: &columns, offset: Some(&o), scale_columns: &scale_columns, penalty: &penalty }).ok())
            .map_or(f64::NEG_INFINITY, |r| r.loglik)
    };
    let (lo, hi) = ((1e-4f64).ln(), (0.99f64).ln());
    let golden = |a: f64, b: f64, tol: f64| golden_max(&profile, a, b, tol);
    // Near a hint (a bootstrap refit of a fitted ratio): golden section on ln x ± 1, kept
    // unless the optimum sits at the edge of that bracket.
    let local = hint.filter(|h| h.is_finite() && *h > 0.0).map(|h| {
        let (a, b) = ((h.ln() - 1.0).max(lo), (h.ln() + 1.0).min(hi));
        let lx = golden(a, b, 1e-3);
        let inside = (lx - a > 1e-2 || a == lo) && (b - lx > 1e-2 || b == hi);
        (lx, inside && profile(lx).is_finite())
    });
    let lx = match local {
        Some((lx, true)) => lx,
        _ => {
            // Coarse scan of ln x over [ln 10⁻⁴, ln 0.99] (ratios that break a particle score
            // −∞), then golden section around the best point to 10⁻⁴ in ln x.
            let grid: Vec<f64> = (0..=16).map(|k| lo + (hi - lo) * k as f64 / 16.0).collect();
            let vals: Vec<f64> = grid.iter().map(|&g| profile(g)).collect();
            let best = (0..grid.len()).max_by(|&a, &b| vals[a].total_cmp(&vals[b])).unwrap_or(0);
            if !vals[best].is_finite() {
                return Err(Error::numerical("damage effect", "every trial damage ratio breaks a particle or fails to fit"));
            }
            golden(grid[best.saturating_sub(1)], grid[(best + 1).min(grid.len() - 1)], 1e-4)
        }
    };
    let off = offsets(lx).ok_or_else(|| Error::numerical("damage effect", "the fitted ratio breaks a particle"))?;
    let reg = fit(x, &Design { columns: &columns, offset: Some(&off), scale_columns: &scale_columns, penalty: &penalty })?;
    // `effects` keeps damage wherever it was added; β follow the linear effects' order.
    Ok(ModelFit { effects, widths, scale_widths, scale_columns, penalty, reg, columns, offset: Some(off), damage_ratio: Some(lx.exp()), n: x.len(), complete: x.complete(), law: None })
}

