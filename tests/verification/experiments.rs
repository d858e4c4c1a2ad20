//! The preposterior engine against closed forms.
//!
//! Normal–normal model: θ ~ N(μ₀, τ²), n observations y_i ~ N(θ, σ²) (sufficient statistic
//! ȳ ~ N(θ, σ²/n)). The posterior variance is τ_n² = (1/τ² + n/σ²)⁻¹ whatever the data, so the
//! preposterior (expected posterior) variance is τ_n². The posterior mean is distributed, before
//! the data, as N(μ₀, s²) with s² = τ² − τ_n². For the two-action decision "adopt" (loss −θ)
//! against "reject" (loss 0) the expected value of sample information is
//! EVSI = E[max(m, 0)] − max(μ₀, 0) = s φ(μ₀/s) − |μ₀| Φ(−|μ₀|/s)
//! (Raiffa & Schlaifer 1961; docs/reference.md). A decision that is already certain has EVSI 0.

use partlife::experiments::{Experiment, Knowledge, Settings, preposterior};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use statrs::distribution::{Continuous, ContinuousCDF, Normal as SNormal};

/// n observations of N(θ, σ²), summarised by their mean.
struct Means {
    theta: Vec<f64>,
    sigma: f64,
    n: f64,
}

impl Experiment for Means {
    type Data = f64;
    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> f64 {
        Normal::new(self.theta[truth], self.sigma / self.n.sqrt()).unwrap().sample(rng)
    }
    fn loglik(&self, ybar: &f64, k: usize) -> f64 {
        -self.n * (ybar - self.theta[k]).powi(2) / (2.0 * self.sigma * self.sigma)
    }
}

/// K stratified prior samples of N(μ₀, τ²) with the adopt/reject losses and θ as the quantity.
fn prior(mu0: f64, tau: f64, k: usize) -> (Vec<f64>, Knowledge) {
    let z = SNormal::new(0.0, 1.0).unwrap();
    let theta: Vec<f64> = (0..k).map(|i| mu0 + tau * z.inverse_cdf((i as f64 + 0.5) / k as f64)).collect();
    let loss: Vec<f64> = theta.iter().flat_map(|t| [-t, 0.0]).collect();
    let kn = Knowledge::new(vec![1.0; k], 2, loss, 1, theta.clone(), 1, vec![0; k]).unwrap();
    (theta, kn)
}

#[test]
fn normal_normal_preposterior_variance_and_evsi_match_their_closed_forms() {
    let (mu0, tau, sigma, n) = (0.3, 1.0, 1.0, 4.0);
    let (theta, kn) = prior(mu0, tau, 4000);
    let exp = Means { theta, sigma, n };
    let m = preposterior(&kn, &exp, Settings { outer: 8000, min_ess: 50.0, seed: 7, truth: None, active: None, scored: 0 }).unwrap();
    let tau_n2: f64 = 1.0 / (1.0 / (tau * tau) + n / (sigma * sigma));
    let s = (tau * tau - tau_n2).sqrt();
    let z = SNormal::new(0.0, 1.0).unwrap();
    let evsi = s * z.pdf(mu0 / s) - mu0.abs() * z.cdf(-mu0.abs() / s);
    eprintln!("E[var] {:?} (exact {tau_n2}), EVSI {:?} (exact {evsi}), E[mean] {:?}, PCS {:?} (prior {}), median ESS {}, collapsed {}", m.var[0], m.evsi, m.mean[0], m.pcs, m.prior_pcs, m.median_ess, m.collapsed);
    // Truths far in the prior's tail leave few samples near their data: a handful of
    // reweightings fall below the ESS threshold, never more than 1 %.
    assert!(m.collapsed + m.fallbacks <= m.draws.len() / 100, "{} collapsed", m.collapsed);
    // Monte Carlo tolerance: 4 standard errors of the outer average. The posterior variance is
    // the same for every dataset, so its standard error is only that of the reweighting; the
    // quadrature of 4000 stratified samples and leaving the truth out add a relative bias of
    // order 1/ESS (ESS ≈ 1500 here), hence the 0.5 % floor.
    assert!((m.var[0].mean - tau_n2).abs() < 4.0 * m.var[0].se + 0.005 * tau_n2, "{:?} vs {tau_n2}", m.var[0]);
    assert!((m.evsi.mean - evsi).abs() < 4.0 * m.evsi.se, "{:?} vs {evsi}", m.evsi);
    assert!(m.evsi.se < 0.05 * evsi, "too few outer draws to test: {:?}", m.evsi);
    // The posterior mean is a martingale: its expectation is the prior mean.
    assert!((m.mean[0].mean - mu0).abs() < 4.0 * m.mean[0].se, "{:?}", m.mean[0]);
    // The prior's PCS is P(θ > 0) = Φ(μ₀/τ); the data raise it.
    assert!((m.prior_pcs - z.cdf(mu0 / tau)).abs() < 1e-3, "{}", m.prior_pcs);
    assert!(m.pcs.mean > m.prior_pcs + 10.0 * m.pcs.se, "{:?}", m.pcs);
}

/// With the truth conditioned on a label ("if θ > 0 …") the prior PCS and the value are taken
/// over those truths, against the action one would take without the experiment (adopt, as
/// μ₀ > 0): where θ > 0 adopting is already right, so PCS₀ = 1 and the data can only mislead
/// (value ≤ 0); where θ ≤ 0 PCS₀ = 0 and the data can only help (value ≥ 0). Weighted by the
/// labels' prior probabilities the two values make the unconditioned EVSI (≥ 0, the closed
/// form). Before, the conditioned runs used the unconditioned prior's PCS and risk.
#[test]
fn a_conditioned_truth_gets_its_own_prior_pcs_and_value() {
    let (mu0, tau, sigma, n) = (0.3, 1.0, 1.0, 4.0);
    let (theta, _) = prior(mu0, tau, 4000);
    let labels: Vec<u32> = theta.iter().map(|t| u32::from(*t > 0.0)).collect();
    let kn = Knowledge::new(vec![1.0; theta.len()], 2, theta.iter().flat_map(|t| [-t, 0.0]).collect(), 1, theta.clone(), 1, labels).unwrap();
    let exp = Means { theta: theta.clone(), sigma, n };
    let run = |truth| preposterior(&kn, &exp, Settings { outer: 4000, min_ess: 50.0, seed: 9, truth, active: None, scored: 0 }).unwrap();
    let (all, above, below) = (run(None), run(Some((0, 1))), run(Some((0, 0))));
    assert!((above.prior_pcs - 1.0).abs() < 1e-12 && below.prior_pcs.abs() < 1e-12, "{} {}", above.prior_pcs, below.prior_pcs);
    assert!(above.evsi.mean <= 1e-12 && below.evsi.mean >= -1e-12, "{:?} {:?}", above.evsi, below.evsi);
    let p_above = theta.iter().filter(|t| **t > 0.0).count() as f64 / theta.len() as f64;
    let mixed = p_above * above.evsi.mean + (1.0 - p_above) * below.evsi.mean;
    let se = (p_above * above.evsi.se).hypot((1.0 - p_above) * below.evsi.se).hypot(all.evsi.se);
    assert!(all.evsi.mean >= 0.0 && (all.evsi.mean - mixed).abs() < 4.0 * se, "EVSI {:?} against Σ P(label) value = {mixed} (se {se})", all.evsi);
}

#[test]
fn a_decision_that_is_already_certain_has_no_value_of_information() {
    // θ ~ N(5, 0.1²): adopting is best for every prior sample, whatever the data say.
    let (theta, kn) = prior(5.0, 0.1, 2000);
    let exp = Means { theta, sigma: 1.0, n: 10.0 };
    let m = preposterior(&kn, &exp, Settings { outer: 500, min_ess: 50.0, seed: 11, truth: None, active: None, scored: 0 }).unwrap();
    assert!((m.prior_pcs - 1.0).abs() < 1e-12, "{}", m.prior_pcs);
    assert_eq!(m.pcs.mean, 1.0);
    assert!(m.evsi.mean.abs() <= 4.0 * m.evsi.se + 1e-12, "{:?}", m.evsi);
}

#[test]
fn the_result_does_not_depend_on_the_thread_count() {
    let (theta, kn) = prior(0.1, 1.0, 500);
    let exp = Means { theta, sigma: 2.0, n: 3.0 };
    let settings = Settings { outer: 200, min_ess: 10.0, seed: 3, truth: None, active: None, scored: 0 };
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| preposterior(&kn, &exp, settings).unwrap());
    let many = preposterior(&kn, &exp, settings).unwrap();
    assert_eq!(one, many);
}

/// An experiment that rules out almost every sample: the reweighting collapses and is counted.
struct Sharp(Vec<f64>);

impl Experiment for Sharp {
    type Data = f64;
    fn simulate(&self, truth: usize, rng: &mut ChaCha8Rng) -> f64 {
        self.0[truth] + 1e-4 * rng.random::<f64>()
    }
    fn loglik(&self, y: &f64, k: usize) -> f64 {
        -((y - self.0[k]) / 1e-4).powi(2)
    }
}

#[test]
fn collapsed_reweighting_is_counted() {
    let (theta, kn) = prior(0.0, 1.0, 300);
    let m = preposterior(&kn, &Sharp(theta), Settings { outer: 50, min_ess: 20.0, seed: 5, truth: None, active: None, scored: 0 }).unwrap();
    assert_eq!(m.collapsed, 50, "median ESS {}", m.median_ess);
    assert!(m.median_ess < 20.0);
}

/// The main study's state of knowledge with fewer strength draws (test speed).
fn main_study_state(k: usize) -> partlife::experiments::State {
    state_of(k, false)
}

/// The state of knowledge of the main study, or with the deliverable's strength model only.
fn state_of(k: usize, deliverable_only: bool) -> partlife::experiments::State {
    use partlife::schema::StudyFile;
    use partlife::uq::{run::weighed, setup::Shared, study::UqStudy};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/gen4_vs_bl.toml");
    let loaded = StudyFile::read(&path).unwrap();
    let mut s: UqStudy = loaded.parse().unwrap();
    s.strength.draws = 400;
    if deliverable_only {
        s.strength.effects = Default::default();
        s.model_form.strength = vec![Default::default()];
        s.strength.draws = 4000;
    }
    let shared = Shared::new(&s, &path, std::path::Path::new("reports")).unwrap();
    let forms = weighed(&s, &path, &shared).unwrap();
    let n = forms[0].setup.models.len();
    partlife::experiments::State::new(forms, vec![1.0 / n as f64; n], 0, 1.0, k, 17).unwrap()
}

/// With data generated under Tavares–King damage, repeated impacts (counts 1, 10, 100, 1000 at
/// 15 m/s) must give Tavares–King a higher expected posterior weight than single impacts on as
/// many particles, and so rank first for model discrimination.
#[test]
fn repeated_impacts_identify_tavares_king_damage_and_rank_first_for_discrimination() {
    use partlife::experiments::ImpactTest;
    use partlife::lifetime::damage::DamageModel;
    let state = main_study_state(8000);
    let tk = state.damage.iter().position(|d| *d == DamageModel::TavaresKing).unwrap() as u32;
    let settings = Settings { outer: 300, min_ess: 50.0, seed: 1, truth: Some((0, tk)), active: Some(4000), scored: 0 };
    let candidates = [("single impact", vec![1]), ("repeated impacts", vec![1, 10, 100, 1000])];
    let weight: Vec<(f64, f64, f64)> = candidates
        .iter()
        .map(|(_, counts)| {
            let m = preposterior(&state.knowledge, &ImpactTest::new(&state, 0, 100, 15.0, counts.clone()).unwrap(), settings).unwrap();
            (m.true_label_weight[0].mean, m.true_label_weight[0].se, m.prior_true_label_weight[0])
        })
        .collect();
    eprintln!("expected posterior weight of Tavares–King: {weight:?}");
    let best = (0..candidates.len()).max_by(|&a, &b| weight[a].0.total_cmp(&weight[b].0)).unwrap();
    assert_eq!(candidates[best].0, "repeated impacts", "{weight:?}");
    let (single, repeated) = (weight[0], weight[1]);
    assert!(repeated.0 - single.0 > 4.0 * (single.1.hypot(repeated.1)), "{weight:?}");
    // Single impacts barely move the prior weight (1/3); repeated impacts at least double it.
    assert!(repeated.0 > 2.0 * repeated.2, "{weight:?}");
}

/// Measuring η n times with lognormal error s on the main study's state: ln η's prior is
/// N(ln 0.1, 0.5²) (truncated far out, at ±4.6 sd), so its expected posterior variance is the
/// normal–normal (1/0.5² + n/s²)⁻¹.
#[test]
fn an_energy_fraction_measurement_narrows_ln_eta_as_the_conjugate_model_says() {
    use partlife::experiments::{Measured, Measurement};
    let state = main_study_state(8000);
    let (n, sd) = (4, 0.5);
    let m = preposterior(&state.knowledge, &Measurement::new(&state, Measured::EnergyFraction, n, sd).unwrap(), Settings { outer: 400, min_ess: 50.0, seed: 2, truth: None, active: Some(4000), scored: 0 }).unwrap();
    let q = state.ln_eta_quantity();
    let exact = 1.0 / (1.0 / 0.25 + n as f64 / (sd * sd));
    eprintln!("E[var ln η] {:?} (conjugate {exact}), prior var {}, median ESS {}", m.var[q], m.prior.var[q], m.median_ess);
    assert!((m.prior.var[q] - 0.25).abs() < 0.02, "prior var {}", m.prior.var[q]);
    // 4 standard errors plus the O(1/ESS) bias of reweighting (ESS ≈ 1800 here): 2 %.
    assert!((m.var[q].mean - exact).abs() < 4.0 * m.var[q].se + 0.02 * exact, "{:?} vs {exact}", m.var[q]);
    assert!(m.evsi.mean >= -4.0 * m.evsi.se, "{:?}", m.evsi);
}

/// With the deliverable's strength model (one Weibull law per material, pivotal-bootstrap
/// uncertainty from the n₀ crush tests), crushing n more particles must narrow the modulus'
/// 90 % band as ASTM C1239's pivotal interval narrows from N = n₀ to N = n₀ + n: its relative
/// width 1/q₀.₀₅ − 1/q₀.₉₅ (q = m̂/m, simulated pivots).
#[test]
fn crush_tests_narrow_the_modulus_band_as_the_c1239_pivotal_interval() {
    use partlife::experiments::{CrushOptions, CrushTest};
    use partlife::weibull::simulate_pivotal;
    let state = state_of(8000, true);
    for j in 0..2 {
        let q = state.weibull_m_quantity(j);
        let n0 = state.forms[0].setup.materials[j].sample.strength.len();
        let rel = |n: usize| {
            let p = simulate_pivotal(n, 20000, 5).unwrap();
            1.0 / p.q_quantile(0.05) - 1.0 / p.q_quantile(0.95)
        };
        for n in [n0, 2 * n0] {
            let test = CrushTest::new(&state, j, n, &CrushOptions::default()).unwrap();
            let m = preposterior(&state.knowledge, &test, Settings { outer: 300, min_ess: 50.0, seed: 9, truth: None, active: Some(4000), scored: 0 }).unwrap();
            let got = m.width90[q].mean / m.mean[q].mean;
            let c1239 = rel(n0 + n);
            eprintln!("material {j}: n0 {n0} + {n}: E[width90 m]/E[m] {got:.4} ± {:.4}; C1239 relative width at N = {}: {c1239:.4}; prior {:.4}; ESS {:.0}, fallbacks {}, collapsed {}", m.width90[q].se / m.mean[q].mean, n0 + n, m.prior.width90[q] / m.prior.mean[q], m.median_ess, m.fallbacks, m.collapsed);
            // The posterior band is Bayesian, the pivotal interval frequentist; they agree to
            // O(1/N), and the simulated pivots' 5 % and 95 % quantiles carry ≈ 1 % Monte Carlo
            // error: 3 % relative, plus 4 standard errors of the outer average.
            assert!((got - c1239).abs() < 0.03 * c1239 + 4.0 * m.width90[q].se / m.mean[q].mean, "material {j}, n = {n}: {got} vs C1239 {c1239}");
            assert!(m.collapsed <= m.draws.len() / 100, "{} collapsed", m.collapsed);
        }
        // The prior itself is the pivotal band at n₀.
        let prior = state.knowledge.summarise(&state.knowledge.weights);
        assert!((prior.width90[q] / prior.mean[q] - rel(n0)).abs() < 0.03 * rel(n0), "prior {} vs C1239 {}", prior.width90[q] / prior.mean[q], rel(n0));
    }
}

/// Brute-force nested refitting: for each outer draw's truth, n more strengths of material j
/// simulated from it (seed `seed` + the draw's index), pooled with the measured ones and refitted
/// by maximum likelihood; the expected width of ASTM C1239's pivotal 90 % interval of m at
/// N = n₀ + n.
fn nested_widths(state: &partlife::experiments::State, j: usize, n: usize, draws: &[partlife::experiments::Draw], seed: u64) -> partlife::experiments::Estimate {
    use partlife::uq::setup::Mode;
    use partlife::weibull::{fit_mle, simulate_pivotal};
    use rand::SeedableRng;
    let measured = &state.forms[0].setup.materials[j].sample.strength;
    let pivots = simulate_pivotal(measured.len() + n, 20000, 8).unwrap();
    let widths: Vec<f64> = draws
        .iter()
        .enumerate()
        .map(|(d, draw)| {
            let s = &state.samples[draw.truth];
            let (p, _) = state.forms[s.form].setup.params(j, &s.x, Mode::Joint);
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed + d as u64);
            assert!(measured.view().complete(), "the shipped crush data are complete");
            let mut pooled = measured.x.clone();
            pooled.extend((0..n).map(|_| p.mu.exp() * (-rng.random::<f64>().max(f64::MIN_POSITIVE).ln()).powf(1.0 / p.shape)));
            let b = pivots.bounds(&fit_mle(&pooled).unwrap(), 0.90).unwrap();
            b.shape.1 - b.shape.0
        })
        .collect();
    partlife::experiments::Estimate::of(&widths)
}

/// Importance reweighting against brute-force nested refitting on a small case: with the
/// deliverable's strength model, each outer draw's truth generates n more BL 16/30 crush
/// strengths; the brute-force route pools them with the n₀ measured ones, refits by maximum
/// likelihood and takes ASTM C1239's pivotal 90 % interval of m at N = n₀ + n; the
/// preposterior engine reweights the prior draws instead. Their expected widths must agree.
#[test]
fn reweighting_agrees_with_brute_force_nested_refitting() {
    use partlife::experiments::{CrushOptions, CrushTest};
    let state = state_of(8000, true);
    let (j, n) = (1, 50);
    let q = state.weibull_m_quantity(j);
    let m = preposterior(&state.knowledge, &CrushTest::new(&state, j, n, &CrushOptions::default()).unwrap(), Settings { outer: 300, min_ess: 50.0, seed: 21, truth: None, active: Some(4000), scored: 0 }).unwrap();
    let nested = nested_widths(&state, j, n, &m.draws, 1000);
    eprintln!("E[90 % width of m]: reweighting {:?}, nested refits {:?}", m.width90[q], nested);
    // Both average over the same 300 truths; the Bayesian band and the pivotal interval agree
    // to O(1/N) (3 %, as against the C1239 tables above), plus 4 combined standard errors.
    assert!((m.width90[q].mean - nested.mean).abs() < 0.03 * nested.mean + 4.0 * m.width90[q].se.hypot(nested.se), "{:?} vs {nested:?}", m.width90[q]);
}

/// The shape measurement. Under the deliverable's strength model (no covariate effects) every
/// particle has the same scale, so crush tests with and without each particle's roundness and
/// sphericity measured carry the same information: identical metrics. Under the main study's
/// strength models, with the truth drawn from the shape model (roundness and sphericity as
/// contact curvature), the measured test must identify that model better than the unmeasured
/// one (whose likelihood mixes over the population's shapes), and the unmeasured one must still
/// narrow the modulus band.
#[test]
fn the_shape_measurement_is_worth_what_the_shape_effects_explain() {
    use partlife::experiments::{CrushOptions, CrushTest};
    use partlife::strength::Effect;
    let options = |shape_measured| CrushOptions { shape_measured, ..Default::default() };
    let settings = Settings { outer: 200, min_ess: 50.0, seed: 31, truth: None, active: Some(4000), scored: 0 };
    let state = state_of(8000, true);
    // Both tests' likelihoods against an independent sum: under sample k every particle is
    // Weibull(m_k, e^μ_k), so ln p(s | k) = Σ_i [ln m_k + m_k (y_i − μ_k) − e^(m_k (y_i − μ_k))],
    // y_i = ln s_i (up to the Jacobian, common to every k). (Before, the two tests were only
    // compared with each other, and with one scale per sample they run the same code.)
    let (measured, unmeasured) = (CrushTest::new(&state, 0, 100, &options(true)).unwrap(), CrushTest::new(&state, 0, 100, &options(false)).unwrap());
    let mut rng = <ChaCha8Rng as rand::SeedableRng>::seed_from_u64(5);
    let data = measured.simulate(3, &mut rng);
    for k in [0, 1, 7, 1234, 7999] {
        let s = &state.samples[k];
        let (p, _) = state.forms[s.form].setup.params(0, &s.x, partlife::uq::setup::Mode::Joint);
        let direct: f64 = data.iter().map(|c| p.shape.ln() + p.shape * (c.ln_sigma - p.mu) - (p.shape * (c.ln_sigma - p.mu)).exp()).sum();
        for (what, t) in [("measured", &measured), ("not measured", &unmeasured)] {
            let ll = t.loglik(&data, k);
            assert!((ll - direct).abs() < 1e-9 * direct.abs().max(1.0), "sample {k}, {what}: {ll} against the direct sum {direct}");
        }
    }
    let run = |t: &CrushTest| preposterior(&state.knowledge, t, settings).unwrap();
    assert_eq!(run(&measured), run(&unmeasured));

    let state = main_study_state(8000);
    let shape = state.forms.iter().position(|f| f.setup.materials[0].model.fit.linear() == [Effect::Roundness, Effect::Sphericity]).expect("the main study has the shape model") as u32;
    let settings = Settings { truth: Some((1, shape)), ..settings };
    let run = |measured| preposterior(&state.knowledge, &CrushTest::new(&state, 0, 100, &options(measured)).unwrap(), settings).unwrap();
    let (with, without) = (run(true), run(false));
    let (w, wo) = (with.true_label_weight[1], without.true_label_weight[1]);
    let q = state.weibull_m_quantity(0);
    eprintln!("true strength-model weight: prior {:.4}, measured {w:?}, not measured {wo:?}; width90 m: prior {:.3}, measured {:?}, not {:?}", with.prior_true_label_weight[1], with.prior.width90[q], with.width90[q], without.width90[q]);
    assert!(w.mean - wo.mean > 3.0 * w.se.hypot(wo.se), "measured {w:?} vs not measured {wo:?}");
    // Unmeasured, the data still carry some evidence (the shape model's mixture of scales).
    assert!(wo.mean - with.prior_true_label_weight[1] > 3.0 * wo.se, "not measured {wo:?} vs prior {}", with.prior_true_label_weight[1]);
    // The README's figures (0.05 → 0.96 measured, → 0.11 not measured).
    assert!((with.prior_true_label_weight[1] - 0.05).abs() < 0.01 && (w.mean - 0.96).abs() < 0.03 && (wo.mean - 0.11).abs() < 0.03, "README figures: prior {}, {w:?}, {wo:?}", with.prior_true_label_weight[1]);
    assert!(without.width90[q].mean < 0.9 * without.prior.width90[q], "{:?} vs prior {}", without.width90[q], without.prior.width90[q]);
}

/// The naming loop's verdict, asked of the same simulated crush data as the Bayesian
/// reweighting (Gen 4, 25 and 100 more particles, 60 campaigns each).
///
/// With the truth drawn from the diagnosed model (the size effect, which today's 45 particles
/// already name at family-wise p = 0.002), the loop must name exactly that effect unless its
/// guard lets a false extra effect through (α = 0.05 per round), so in ≥ 0.95 of campaigns up
/// to Monte Carlo error, and the two rules must agree within their errors.
///
/// With the truth drawn from the shape model the rules part: the reweighting compares the
/// fitted models and gives the true one most of the weight, while the loop must get each effect
/// past its family-wise guard on the pooled data — with 25 more particles today's size signal
/// still dominates, with 100 the weak sphericity term mostly fails the guard. The loop's
/// verdict must still rise with the number of tests.
#[test]
fn the_naming_loop_and_the_reweighting_judge_the_same_crush_data() {
    use partlife::experiments::{CrushOptions, CrushTest, Estimate};
    use partlife::strength::{Effect, NamingSettings};
    let state = main_study_state(8000);
    // The main study's naming settings for Gen 4 (material index 1 of studies/gen4_vs_bl.toml).
    let naming = NamingSettings { seed: 20261121u64.wrapping_add(7919), ..Default::default() };
    let options = CrushOptions { naming: Some(naming), ..Default::default() };
    let form = |effects: &[Effect]| state.forms.iter().position(|f| f.setup.materials[0].model.fit.linear() == effects).unwrap() as u32;
    let run = |effects: &[Effect], n: usize| -> (Estimate, Estimate) {
        let settings = Settings { outer: 60, min_ess: 50.0, seed: 41, truth: Some((1, form(effects))), active: Some(4000), scored: 60 };
        let m = preposterior(&state.knowledge, &CrushTest::new(&state, 0, n, &options).unwrap(), settings).unwrap();
        let sc = m.score.unwrap();
        assert_eq!(sc.draws, 60);
        let (verdict, weight) = (sc.mean, sc.true_label_weight[1]);
        eprintln!("{effects:?}, {n} more: naming loop names the truth's effects {verdict:?}; expected weight of the true model {weight:?}");
        (verdict, weight)
    };
    for n in [25, 100] {
        let (verdict, weight) = run(&[Effect::Size], n);
        assert!(verdict.mean >= 0.95 - 3.0 * verdict.se, "diagnosed truth, {n} more: {verdict:?}");
        assert!((weight.mean - verdict.mean).abs() < 3.0 * weight.se.hypot(verdict.se), "diagnosed truth, {n} more: loop {verdict:?}, weight {weight:?}");
    }
    let shape = [Effect::Roundness, Effect::Sphericity];
    let ((v25, w25), (v100, w100)) = (run(&shape, 25), run(&shape, 100));
    for (v, w) in [(v25, w25), (v100, w100)] {
        assert!(w.mean - v.mean > 3.0 * w.se.hypot(v.se), "shape truth: loop {v:?}, weight {w:?}");
    }
    assert!(v100.mean - v25.mean > 2.0 * v100.se.hypot(v25.se), "shape truth: loop {v25:?} → {v100:?}");
    // The README's figures (shape truth, 100 more: weight 0.94, the loop 0.20).
    assert!((w100.mean - 0.94).abs() < 0.03 && (v100.mean - 0.20).abs() < 0.05, "README figures: {w100:?}, {v100:?}");
}

/// A line of points θ = μ₀ + τ z (z the normal score): the normal–normal model as a space whose
/// samples resample-move can move.
struct Line {
    mu0: f64,
    tau: f64,
    points: Vec<Vec<f64>>,
}

impl partlife::experiments::smc::Space for Line {
    type Point = Vec<f64>;
    fn point(&self, k: usize) -> &Vec<f64> {
        &self.points[k]
    }
    fn scores<'a>(&self, p: &'a Vec<f64>) -> &'a [f64] {
        p
    }
    fn moved(&self, _p: &Vec<f64>, z: Vec<f64>) -> partlife::error::Result<Vec<f64>> {
        Ok(z)
    }
    fn row(&self, p: &Vec<f64>) -> partlife::error::Result<partlife::experiments::smc::Row> {
        let theta = self.mu0 + self.tau * p[0];
        Ok(partlife::experiments::smc::Row { loss: vec![-theta, 0.0], values: vec![theta], labels: vec![0] })
    }
}

impl partlife::experiments::smc::Movable<Line> for Means {
    fn loglik_at(&self, line: &Line, ybar: &f64, p: &Vec<f64>) -> f64 {
        let theta = line.mu0 + line.tau * p[0];
        -self.n * (ybar - theta).powi(2) / (2.0 * self.sigma * self.sigma)
    }
}

/// Where reweighting collapses, resample-move holds: 10 000 observations of N(θ, 1) shrink the
/// prior N(0.3, 1) to a posterior 100 times narrower than it, so 2000 prior samples reweighted
/// leave an effective sample size of ≈ 20 — below the threshold of 50 in nearly every outer draw.
/// Tempered in with pCN moves, the posteriors must have the closed forms' expected variance
/// τ_n² and EVSI, with no draw below the threshold.
#[test]
fn resample_move_holds_where_reweighting_collapses_normal_normal() {
    use partlife::experiments::smc::{Moves, extend, start};
    let (mu0, tau, sigma, n) = (0.3, 1.0, 1.0, 10_000.0);
    let (theta, kn) = prior(mu0, tau, 2000);
    let z = SNormal::new(0.0, 1.0).unwrap();
    let line = Line { mu0, tau, points: theta.iter().map(|t| vec![(t - mu0) / tau]).collect() };
    let exp = Means { theta, sigma, n };
    let settings = Settings { outer: 1000, min_ess: 50.0, seed: 41, truth: None, active: None, scored: 0 };
    let run = |moves| {
        let tracks = start::<Line, Means>(&kn, &settings).unwrap();
        extend(&kn, &line, &tracks, &[], &exp, &settings, moves, 77, false).unwrap().0
    };
    let plain = run(None);
    let moved = run(Some(Moves { particles: 400, sweeps: 2 }));
    // Each outer draw tempers and moves on its own random stream: the thread count does not matter.
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| run(Some(Moves { particles: 400, sweeps: 2 })));
    assert_eq!(one, moved, "resample-move depends on the thread count");
    let tau_n2: f64 = 1.0 / (1.0 / (tau * tau) + n / (sigma * sigma));
    let s = (tau * tau - tau_n2).sqrt();
    let evsi = s * z.pdf(mu0 / s) - mu0.abs() * z.cdf(-mu0.abs() / s);
    eprintln!("reweighting: median ESS {:.1}, collapsed {}, E[var] {:?}; resample-move: median ESS {:.1}, moved {}, collapsed {}, E[var] {:?} (exact {tau_n2}), EVSI {:?} (exact {evsi})", plain.median_ess, plain.collapsed, plain.var[0], moved.median_ess, moved.moved, moved.collapsed, moved.var[0], moved.evsi);
    assert!(plain.collapsed >= 900, "the case must defeat reweighting: {} of 1000 collapsed", plain.collapsed);
    assert!(moved.collapsed == 0 && moved.moved >= 900 && moved.median_ess >= 100.0, "moved {}, collapsed {}, median ESS {}", moved.moved, moved.collapsed, moved.median_ess);
    // The moved posteriors are MCMC samples (correlated within a draw): 4 standard errors of the
    // outer average plus 5 % for the finite population's bias.
    assert!((moved.var[0].mean - tau_n2).abs() < 4.0 * moved.var[0].se + 0.05 * tau_n2, "{:?} vs {tau_n2}", moved.var[0]);
    assert!((moved.evsi.mean - evsi).abs() < 4.0 * moved.evsi.se + 0.01 * evsi, "{:?} vs {evsi}", moved.evsi);
    // Paired, on the same truths: with a posterior this sharp, the Bayes action is the truth's
    // best action, so each draw's value is max(θ_t, 0) − max(μ₀, 0) up to the posterior's
    // O(τ_n) error — the Monte Carlo noise of the truths cancels.
    let paired: f64 = moved.draws.iter().map(|d| (mu0 + tau * line.points[d.truth][0]).max(0.0) - mu0.max(0.0)).sum::<f64>() / moved.draws.len() as f64;
    assert!((moved.evsi.mean - paired).abs() < 3e-3, "EVSI {:?} vs the truths' own {paired}", moved.evsi);
}

/// Resample-move against brute-force nested refitting and the conjugate model on the main
/// study's state: 200 more BL 16/30 crush tests and 100 measurements of η at ±10 % — a plan
/// whose reweighted posteriors collapse. The expected 90 % width of BL 16/30's modulus must be
/// ASTM C1239's pivotal width of the pooled refit (as for reweighting above), and the expected
/// posterior variance of ln η the conjugate (1/0.5² + n/s²)⁻¹ — the η measurement does not
/// inform m, nor the crush tests η.
#[test]
fn resample_move_agrees_with_nested_refits_and_the_conjugate_model_on_a_whole_plan() {
    use partlife::experiments::plan::Candidate;
    use partlife::experiments::smc::{Moves, extend, start};
    use partlife::experiments::{CrushOptions, CrushTest, Measured, Measurement};
    let state = state_of(8000, true);
    let (j, n, n_eta, sd) = (1, 200, 100, 0.1);
    let crush = Candidate::Crush(CrushTest::new(&state, j, n, &CrushOptions::default()).unwrap());
    let eta = Candidate::Measure(Measurement::new(&state, Measured::EnergyFraction, n_eta, sd).unwrap());
    let settings = Settings { outer: 150, min_ess: 50.0, seed: 23, truth: None, active: Some(4000), scored: 0 };
    let plan = |moves| {
        let tracks = start::<_, Candidate>(&state.knowledge, &settings).unwrap();
        let (_, tracks) = extend(&state.knowledge, &state, &tracks, &[], &crush, &settings, moves, 5, true).unwrap();
        extend(&state.knowledge, &state, &tracks.unwrap(), &[&crush], &eta, &settings, moves, 6, false).unwrap().0
    };
    let plain = plan(None);
    let m = plan(Some(Moves { particles: 400, sweeps: 2 }));
    let q = state.weibull_m_quantity(j);
    let nested = nested_widths(&state, j, n, &m.draws, 2000);
    let (qe, conjugate) = (state.ln_eta_quantity(), 1.0 / (1.0 / 0.25 + n_eta as f64 / (sd * sd)));
    eprintln!(
        "reweighting: median ESS {:.1}, collapsed {}; resample-move: median ESS {:.1}, moved {}, collapsed {}; E[90 % width of m] {:?} vs nested refits {nested:?}; E[var ln η] {:?} vs conjugate {conjugate}",
        plain.median_ess, plain.collapsed, m.median_ess, m.moved, m.collapsed, m.width90[q], m.var[qe]
    );
    assert!(plain.collapsed >= 75, "the plan must defeat reweighting: {} of 150 collapsed", plain.collapsed);
    assert!(m.collapsed < 8 && m.median_ess >= 100.0, "collapsed {}, median ESS {}", m.collapsed, m.median_ess);
    assert!((m.width90[q].mean - nested.mean).abs() < 0.03 * nested.mean + 4.0 * m.width90[q].se.hypot(nested.se), "{:?} vs {nested:?}", m.width90[q]);
    assert!((m.var[qe].mean - conjugate).abs() < 4.0 * m.var[qe].se + 0.05 * conjugate, "{:?} vs {conjugate}", m.var[qe]);
}

/// A rig's force limit (issue 52: "a proposed test may have a force limit"). A particle whose σ̄
/// at break would exceed the σ̄ its diameter gives at the limit is recorded as not broken there
/// (type I censoring). With the deliverable's strength model (one Weibull law per material):
/// 1. the test's likelihood equals an independent sum — each broken particle's Weibull log
///    density of ln σ̄, each unbroken one's ln S = −(σ̄_lim/σ_θ)^m at its own diameter's σ̄_lim
///    (computed here from the main study's elastic constants and contact) — with and without the
///    shape measured, and the recorded particles are censored where they should be;
/// 2. a limit far above every break changes nothing: the metrics equal the test without one;
/// 3. at the material's median crush force, the share of unbroken particles in the simulated
///    tests matches the prior's expectation, and the test carries less than the uncensored one
///    (a wider expected band of m, paired over the same truths and random numbers) but still
///    narrows the prior's band.
#[test]
fn a_force_limit_censors_the_proposed_crush_test_and_costs_information() {
    use partlife::experiments::{CrushOptions, CrushTest, ForceLimit};
    use partlife::schema::StudyFile;
    use partlife::uq::study::UqStudy;
    let state = state_of(8000, true);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("studies/gen4_vs_bl.toml");
    let u: UqStudy = StudyFile::read(&path).unwrap().parse().unwrap();
    let (j, n) = (0, 60);
    let index = u.order()[j];
    let spec = &u.material[index];
    let mut forces = spec.read_data(&path, index).unwrap().forces();
    forces.sort_by(f64::total_cmp);
    let median = forces[forces.len() / 2];
    let limit = |force_n: f64| ForceLimit { force_n, elastic: spec.elastic, contact: u.contact.clone() };
    let test = |force_n: Option<f64>, shape_measured: bool| CrushTest::new(&state, j, n, &CrushOptions { shape_measured, force_limit: force_n.map(limit), ..Default::default() }).unwrap();
    let diameters: Vec<f64> = state.forms[0].setup.materials[j].sample.covariates.iter().find(|(c, _)| c == "diameter_m").unwrap().1.iter().map(|d| d.unwrap()).collect();
    let ln_limit = |row: usize| partlife::strength::crush_contact(&spec.elastic, &u.contact, diameters[row]).at_force(median).unwrap().mean_tensile.ln();

    // 1. The likelihood against the independent sum.
    let (measured, unmeasured) = (test(Some(median), true), test(Some(median), false));
    let mut rng = <ChaCha8Rng as rand::SeedableRng>::seed_from_u64(11);
    let data = measured.simulate(5, &mut rng);
    let unbroken = data.iter().filter(|c| !c.broke).count();
    assert!(unbroken > 5 && unbroken < n - 5, "{unbroken} of {n} unbroken at the median force");
    for c in &data {
        let l = ln_limit(c.row);
        assert!(if c.broke { c.ln_sigma <= l } else { (c.ln_sigma - l).abs() < 1e-12 }, "{c:?} against ln σ̄_lim {l}");
    }
    for k in [0, 5, 1234, 7999] {
        let s = &state.samples[k];
        let (p, _) = state.forms[s.form].setup.params(j, &s.x, partlife::uq::setup::Mode::Joint);
        let z = |y: f64| p.shape * (y - p.mu);
        let direct: f64 = data.iter().map(|c| if c.broke { p.shape.ln() + z(c.ln_sigma) - z(c.ln_sigma).exp() } else { -z(c.ln_sigma).exp() }).sum();
        for (what, t) in [("measured", &measured), ("not measured", &unmeasured)] {
            let ll = t.loglik(&data, k);
            assert!((ll - direct).abs() < 1e-9 * direct.abs().max(1.0), "sample {k}, {what}: {ll} against the direct sum {direct}");
        }
    }

    // 2. A limit far above every break: the same numbers as no limit.
    let settings = Settings { outer: 300, min_ess: 50.0, seed: 41, truth: None, active: Some(4000), scored: 0 };
    let run = |t: &CrushTest| preposterior(&state.knowledge, t, settings).unwrap();
    let free = run(&test(None, true));
    assert_eq!(run(&test(Some(1e3 * forces[forces.len() - 1]), true)), free);

    // 3. At the median force.
    let censored = run(&measured);
    let q = state.weibull_m_quantity(j);
    let expected = measured.expected_unbroken(&state.knowledge.weights).unwrap();
    let mut rng = <ChaCha8Rng as rand::SeedableRng>::seed_from_u64(12);
    let shares: Vec<f64> = censored.draws.iter().map(|d| measured.simulate(d.truth, &mut rng).iter().filter(|c| !c.broke).count() as f64 / n as f64).collect();
    let share = partlife::experiments::Estimate::of(&shares);
    let diff: Vec<f64> = censored.draws.iter().zip(&free.draws).map(|(a, b)| a.posterior.width90[q] - b.posterior.width90[q]).collect();
    let wider = partlife::experiments::Estimate::of(&diff);
    eprintln!(
        "limit {median:.1} N: unbroken share expected {expected:.3}, simulated {share:?}; E[width90 m]: prior {:.3}, no limit {:?}, at the limit {:?}, paired difference {wider:?}",
        free.prior.width90[q], free.width90[q], censored.width90[q]
    );
    // The simulated tests' truths are the outer draws' (drawn from the prior): 4 standard errors.
    assert!((share.mean - expected).abs() < 4.0 * share.se, "simulated {share:?} vs expected {expected}");
    assert!(wider.mean > 4.0 * wider.se, "the censored test is not less informative: {wider:?}");
    assert!(censored.width90[q].mean < free.prior.width90[q] - 4.0 * censored.width90[q].se, "the censored test does not narrow the prior band: {:?} vs {}", censored.width90[q], free.prior.width90[q]);
    // The README's figures: 122 N, 51 % unbroken, band 2.68 → 2.04 (1.75 without a limit).
    assert!((median - 122.0).abs() < 0.5 && (100.0 * expected).round() == 51.0, "README: {median} N, {expected}");
    for (got, readme) in [(free.prior.width90[q], 2.68), (censored.width90[q].mean, 2.04), (free.width90[q].mean, 1.75)] {
        assert!((got - readme).abs() < 0.005, "README figure {readme} vs {got}");
    }
}
