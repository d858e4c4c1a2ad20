//! The main study's state of knowledge as weighted samples for experiment design.
//!
//! Each sample carries everything uncertain in the main study (`kind = "uq"`): a strength model
//! M (drawn with its stacking weight), a damage model D (drawn with its prior weight), and, under
//! M, one joint draw of both materials' strength parameters with their population weights, η, V,
//! impacts per year and γ ([`crate::uq::setup::Setup`] in joint mode, so no second copy of the
//! chain). Its outputs are both materials' P_break at every horizon under D.
//!
//! The decision is which particle to choose for a plant: action 0 = the candidate, 1 = the
//! reference. Choosing the particle that breaks more at the decision horizon costs the declared
//! loss L; a tie costs nothing. The quantities are P_break itself per material and horizon,
//! ln η and ln V, each material's Weibull modulus m, and the indicator that the candidate breaks
//! more (its posterior mean is the posterior P(candidate worse)); the labels are D and M.
//!
//! # Why P and not log10 P
//!
//! Vogel–Peukert's threshold gives P = 0 exactly for many samples, and a band of log10 P then
//! reaches −∞: its width exists only above a floor, and the floor, not the data, sets how much
//! a test "narrows" it (a review found the shipped ranking of plans moved with it). Bands of P
//! itself need no floor: the 90 % band of P_break is a probability interval whose lower end may
//! be 0. The log-band widths at the floors [`LOG_FLOORS`] are still derived, exactly ([`State::band_narrowing`]), from the
//! same posterior quantiles (a weighted quantile commutes with the non-decreasing map
//! P ↦ log10 max(P, floor)), so the summary can show whether a ranking by them depends on the
//! floor.
//!
//! # Moves
//!
//! Resample-move ([`super::smc`]) moves a sample in the normal scores z = Φ⁻¹(u) of its unit
//! point, given its two models; the prior is standard normal in z. A coordinate that picks one
//! of a strength model's K joint draws would jump between unrelated draws at the smallest step
//! if the draws kept their order, so its score places the draws in the order of a Hilbert curve
//! through the ranks of their scale at the mean covariates and their modulus (2¹⁰ cells a side):
//! neighbouring scores are draws of similar scale and modulus. A prior sample keeps its inputs;
//! only its score is taken at its draw's place in that order (at the same place within its cell,
//! so the scores are standard normal). A moved sample's P_break is computed only when its row is
//! needed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, Normal};

use super::preposterior::{Knowledge, Metrics};
use super::smc::{Row, Space};
use crate::error::{Error, Result};
use crate::lifetime::damage::DamageModel;
use crate::stats::Categorical;
use crate::uq::run::Weighed;
use crate::uq::setup::Mode;

/// Floors of P_break at which the widths of the log10 P bands are shown, to show whether a
/// ranking by them depends on the floor (module docs).
pub const LOG_FLOORS: [f64; 3] = [1e-9, 1e-12, 1e-15];

/// Width in decades of the band [lo, hi] of P_break on a log scale, with P floored at `floor`.
pub fn log_width(band: (f64, f64), floor: f64) -> f64 {
    band.1.max(floor).log10() - band.0.max(floor).log10()
}

/// One sample of the state of knowledge.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSample {
    /// Strength model (index into [`State::forms`]).
    pub form: usize,
    /// Damage model (index into [`State::damage`]).
    pub damage: usize,
    /// Normal scores z = Φ⁻¹(u) of the unit point u over the setup's varying inputs (joint
    /// mode): the prior is standard normal in z, given the two models (the coordinates that
    /// resample-move changes, [`super::smc`]).
    pub z: Vec<f64>,
    /// The setup's inputs (joint mode).
    pub x: Vec<f64>,
    /// P_break of material j at horizon h under the sample's damage model, at j·H + h (empty
    /// for a moved sample until its row is needed).
    pub p: Vec<f64>,
}

/// The state of knowledge.
pub struct State {
    /// The strength models with their stacking weights.
    pub forms: Vec<Weighed>,
    /// The damage models.
    pub damage: Vec<DamageModel>,
    /// Their prior weights.
    pub damage_weights: Vec<f64>,
    /// Horizons (years).
    pub years: Vec<f64>,
    /// Index of the decision's horizon.
    pub horizon: usize,
    /// The samples.
    pub samples: Vec<StateSample>,
    /// Names of the quantities, in [`Knowledge`] order.
    pub quantity_names: Vec<String>,
    /// The weighted samples with the decision's losses.
    pub knowledge: Knowledge,
    /// Range of the Tavares–King γ.
    pub gamma_range: (f64, f64),
    /// The decision's loss for choosing the particle that breaks more.
    pub loss: f64,
    /// Per strength model and varying input, the order of a joint-draw index along the normal
    /// score (module docs, "Moves"); None for other inputs.
    orders: Vec<Vec<Option<DrawOrder>>>,
}

/// Joint draws in Hilbert-curve order of their (scale at the mean covariates, modulus) ranks.
#[derive(Debug, Clone, PartialEq)]
struct DrawOrder {
    /// The draw at each position.
    draw: Vec<u32>,
    /// The position of each draw.
    position: Vec<u32>,
}

impl DrawOrder {
    /// The order of material j's draws of `setup`.
    fn new(setup: &crate::uq::setup::Setup, j: usize) -> DrawOrder {
        let mat = &setup.materials[j];
        let k = mat.draws.len();
        let centre = &mat.model.fit.centre;
        let mu_c: Vec<f64> = mat.draws.iter().map(|d| d.mu + centre.iter().zip(&d.beta).map(|(c, b)| c * b).sum::<f64>()).collect();
        let m: Vec<f64> = mat.draws.iter().map(|d| d.shape).collect();
        let (rx, ry) = (crate::stats::ranks(&mu_c), crate::stats::ranks(&m));
        let cell = |r: f64| (((r - 1.0) / k as f64 * HILBERT_SIDE as f64) as u64).min(HILBERT_SIDE - 1);
        let mut draw: Vec<u32> = (0..k as u32).collect();
        draw.sort_by_key(|&d| (hilbert(cell(rx[d as usize]), cell(ry[d as usize])), d));
        let mut position = vec![0; k];
        for (p, &d) in draw.iter().enumerate() {
            position[d as usize] = p as u32;
        }
        DrawOrder { draw, position }
    }
}

/// Side of the Hilbert curve's grid.
const HILBERT_SIDE: u64 = 1 << 10;

/// The position of cell (x, y) along the Hilbert curve over a [`HILBERT_SIDE`]² grid.
fn hilbert(mut x: u64, mut y: u64) -> u64 {
    let mut d = 0;
    let mut s = HILBERT_SIDE / 2;
    while s > 0 {
        let rx = u64::from(x & s > 0);
        let ry = u64::from(y & s > 0);
        d += s * s * ((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                x = HILBERT_SIDE - 1 - x;
                y = HILBERT_SIDE - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s /= 2;
    }
    d
}

/// Unit points are kept this far inside (0, 1) before their normal scores are taken (a draw of
/// exactly 0 would have the score −∞).
const U_CLAMP: f64 = 1e-16;

fn std_normal() -> Normal {
    Normal::new(0.0, 1.0).expect("the standard normal")
}

/// The sample of strength model `form` (of `forms`) and damage model `d` at the unit point `u`
/// (normal scores `z`): its inputs and, when `with_p`, P_break per material and horizon (else
/// empty: [`p_of`] when needed).
fn sample_of(forms: &[Weighed], years: &[f64], form: usize, d: usize, z: Vec<f64>, u: &[f64], with_p: bool) -> Result<StateSample> {
    let x = forms[form].setup.values(u, Mode::Joint);
    let mut s = StateSample { form, damage: d, z, x, p: Vec::new() };
    if with_p {
        s.p = p_of(forms, years.len(), &s)?;
    }
    Ok(s)
}

/// P_break of sample `s` per material and horizon (material-major).
fn p_of(forms: &[Weighed], h_n: usize, s: &StateSample) -> Result<Vec<f64>> {
    let st = &forms[s.form].setup;
    let mut all = vec![0.0; st.outputs()];
    st.evaluate_into(&s.x, Mode::Joint, &mut all)?;
    Ok((0..2).flat_map(|j| (0..h_n).map(move |h| (j, h))).map(|(j, h)| all[st.slot(j, h, s.damage)]).collect())
}

/// [`State::row`] before the state exists.
fn row_of(forms: &[Weighed], h_n: usize, horizon: usize, loss: f64, s: &StateSample) -> Result<([f64; 2], Vec<f64>, [u32; 2])> {
    let mut values = if s.p.is_empty() { p_of(forms, h_n, s)? } else { s.p.clone() };
    let (a, b) = (values[horizon], values[h_n + horizon]);
    let st = &forms[s.form].setup;
    values.extend([s.x[st.shared(0)].ln(), s.x[st.shared(1)].ln(), st.params(0, &s.x, Mode::Joint).0.shape, st.params(1, &s.x, Mode::Joint).0.shape]);
    values.push(if a > b { 1.0 } else { 0.0 });
    Ok(([if a > b { loss } else { 0.0 }, if b > a { loss } else { 0.0 }], values, [s.damage as u32, s.form as u32]))
}

impl State {
    /// `k` samples of the state of knowledge of the weighed strength models `forms` (damage
    /// models `damage` with prior weights `damage_weights`), the decision at horizon index
    /// `horizon` with loss `loss` for choosing the particle that breaks more.
    pub fn new(forms: Vec<Weighed>, damage_weights: Vec<f64>, horizon: usize, loss: f64, k: usize, seed: u64) -> Result<State> {
        let first = &forms.first().ok_or_else(|| Error::numerical("state of knowledge", "no strength model"))?.setup;
        let (years, damage) = (first.years.clone(), first.models.clone());
        if damage_weights.len() != damage.len() || horizon >= years.len() {
            return Err(Error::numerical("state of knowledge", format!("{} damage weights for {} models, horizon {horizon} of {}", damage_weights.len(), damage.len(), years.len())));
        }
        let gamma = &first.inputs[first.shared(3)].marginal;
        let gamma_range = (gamma.quantile(0.0), gamma.quantile(1.0));
        let form_weights: Vec<f64> = forms.iter().map(|f| f.weight).collect();
        let bad = |what: &str, w: &[f64]| Error::numerical("state of knowledge", format!("{what} weights {w:?}: need non-negative weights, one positive"));
        let form_draw = Categorical::new(&form_weights).ok_or_else(|| bad("strength-model", &form_weights))?;
        let damage_draw = Categorical::new(&damage_weights).ok_or_else(|| bad("damage-model", &damage_weights))?;
        let orders: Vec<Vec<Option<DrawOrder>>> = forms
            .iter()
            .map(|f| {
                let st = &f.setup;
                st.varying(Mode::Joint).into_iter().map(|i| (0..2).find(|&j| st.strength_input(j) == i).map(|j| DrawOrder::new(st, j))).collect()
            })
            .collect();
        let samples: Vec<StateSample> = (0..k)
            .into_par_iter()
            .map(|i| {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                rng.set_stream(i as u64 + 1);
                let form = form_draw.draw(rng.random());
                let d = damage_draw.draw(rng.random());
                let st = &forms[form].setup;
                let u: Vec<f64> = (0..st.varying(Mode::Joint).len()).map(|_| rng.random()).collect();
                // The score of a joint-draw index is that of its position in the draws' order,
                // at the same place within its cell.
                let z = u
                    .iter()
                    .zip(&orders[form])
                    .map(|(&u, order)| {
                        let v = match order {
                            None => u,
                            Some(o) => {
                                let k = o.draw.len() as f64;
                                let cell = (u * k).floor().min(k - 1.0);
                                (o.position[cell as usize] as f64 + (u * k - cell)) / k
                            }
                        };
                        std_normal().inverse_cdf(v.clamp(U_CLAMP, 1.0 - U_CLAMP))
                    })
                    .collect();
                sample_of(&forms, &years, form, d, z, &u, true)
            })
            .collect::<Result<_>>()?;
        let keys = [first.materials[0].model.key.clone(), first.materials[1].model.key.clone()];
        let mut quantity_names: Vec<String> = (0..2).flat_map(|j| years.iter().map(move |y| (j, y))).map(|(j, y)| format!("p_{}_{y}yr", keys[j])).collect();
        quantity_names.extend(["ln_energy_fraction".to_string(), "ln_velocity".to_string(), format!("weibull_m_{}", keys[0]), format!("weibull_m_{}", keys[1])]);
        quantity_names.push(format!("{}_worse_{}yr", keys[0], years[horizon]));
        let q = quantity_names.len();
        let mut loss_v = Vec::with_capacity(2 * k);
        let mut values = Vec::with_capacity(q * k);
        let mut labels = Vec::with_capacity(2 * k);
        for s in &samples {
            let (l, v, c) = row_of(&forms, years.len(), horizon, loss, s)?;
            loss_v.extend(l);
            values.extend(v);
            labels.extend(c);
        }
        let knowledge = Knowledge::new(vec![1.0; k], 2, loss_v, q, values, 2, labels)?;
        Ok(State { forms, damage, damage_weights, years, horizon, loss, samples, quantity_names, knowledge, gamma_range, orders })
    }

    /// The sample of strength model `form` and damage model `damage` at normal scores `z`, its
    /// P_break left to be computed when its row is needed ([`State::row`]).
    pub fn sample_at(&self, form: usize, damage: usize, z: Vec<f64>) -> Result<StateSample> {
        let u: Vec<f64> = z
            .iter()
            .zip(&self.orders[form])
            .map(|(&z, order)| {
                let u = std_normal().cdf(z);
                match order {
                    None => u,
                    // The draw at the score's position, at the middle of its cell.
                    Some(o) => {
                        let k = o.draw.len();
                        (o.draw[((u * k as f64) as usize).min(k - 1)] as f64 + 0.5) / k as f64
                    }
                }
            })
            .collect();
        sample_of(&self.forms, &self.years, form, damage, z, &u, false)
    }

    /// The sample's row of the [`Knowledge`]: the losses of the two actions, the quantities
    /// (in [`State::quantity_names`] order) and the labels (damage model, strength model).
    pub fn row(&self, s: &StateSample) -> Result<([f64; 2], Vec<f64>, [u32; 2])> {
        row_of(&self.forms, self.years.len(), self.horizon, self.loss, s)
    }

    /// Index of the quantity "candidate breaks more at the decision horizon".
    pub fn worse_quantity(&self) -> usize {
        self.quantity_names.len() - 1
    }

    /// Index of the quantity ln η (ln V is the next).
    pub fn ln_eta_quantity(&self) -> usize {
        2 * self.years.len()
    }

    /// Index of the quantity "Weibull modulus m of material j".
    pub fn weibull_m_quantity(&self, j: usize) -> usize {
        2 * self.years.len() + 2 + j
    }

    /// The narrowing of the 90 % bands of P_break at the last horizon, summed over both materials,
    /// with its Monte Carlo error, for the band width `width` (P itself: `hi − lo`; log10 P above a
    /// floor: [`log_width`]). The two materials' widths come from the same simulated
    /// datasets, so the error is that of the per-draw sum.
    pub fn band_narrowing(&self, m: &Metrics, width: &dyn Fn((f64, f64)) -> f64) -> (f64, f64) {
        let e = super::preposterior::Estimate::of(&self.band_narrowing_per_draw(m, width));
        (e.mean, e.se)
    }

    /// Per outer draw of `m`, the prior's summed band width less the draw's posterior's (the
    /// values [`State::band_narrowing`] averages).
    pub fn band_narrowing_per_draw(&self, m: &Metrics, width: &dyn Fn((f64, f64)) -> f64) -> Vec<f64> {
        let h = self.years.len() - 1;
        let q = [self.p_quantity(0, h), self.p_quantity(1, h)];
        let prior: f64 = q.iter().map(|&q| width(m.prior.band90[q])).sum();
        m.draws.iter().map(|d| prior - q.iter().map(|&q| width(d.posterior.band90[q])).sum::<f64>()).collect()
    }

    /// Index of the quantity P_break of material j at horizon h.
    pub fn p_quantity(&self, j: usize, h: usize) -> usize {
        j * self.years.len() + h
    }
}

impl Space for State {
    type Point = StateSample;

    fn point(&self, k: usize) -> &StateSample {
        &self.samples[k]
    }

    fn scores<'a>(&self, p: &'a StateSample) -> &'a [f64] {
        &p.z
    }

    fn indexes(&self, p: &StateSample, c: usize) -> bool {
        self.orders[p.form][c].is_some()
    }

    fn draws_key(&self, p: &StateSample) -> u64 {
        let st = &self.forms[p.form].setup;
        let k = |j: usize| p.x[st.strength_input(j)] as u64;
        (p.form as u64) << 48 | k(0) << 24 | k(1)
    }

    fn moved(&self, p: &StateSample, z: Vec<f64>) -> Result<StateSample> {
        self.sample_at(p.form, p.damage, z)
    }

    fn row(&self, p: &StateSample) -> Result<Row> {
        let (loss, values, labels) = State::row(self, p)?;
        Ok(Row { loss: loss.to_vec(), values, labels: labels.to_vec() })
    }
}

#[cfg(test)]
mod tests {
    use super::super::preposterior::Knowledge;
    use super::*;

    /// The log-band width at a floor derived from the band of P equals the width of the band of
    /// log10 max(P, floor) computed directly, for weights and values with many exact zeros.
    #[test]
    fn log_widths_from_the_band_of_p_are_exact() {
        let k = 200;
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let p: Vec<f64> = (0..k).map(|_| if rng.random::<f64>() < 0.4 { 0.0 } else { 10f64.powf(-20.0 * rng.random::<f64>()) }).collect();
        let w: Vec<f64> = (0..k).map(|_| rng.random::<f64>()).collect();
        for floor in LOG_FLOORS {
            let values: Vec<f64> = p.iter().flat_map(|&x| [x, x.max(floor).log10()]).collect();
            let kn = Knowledge::new(w.clone(), 1, vec![0.0; k], 2, values, 0, vec![]).unwrap();
            let post = kn.summarise(&kn.weights);
            assert_eq!(log_width(post.band90[0], floor), post.width90[1], "floor {floor}");
            assert!(post.band90[0].0 == 0.0 && post.width90[0] == post.band90[0].1, "{:?}", post.band90[0]);
        }
    }
}
