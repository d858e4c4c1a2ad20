//! Generic effects of recorded factors (issue 33): hidden effects named through the generator —
//! a size effect, a scale per batch, a modulus per batch, a partially pooled batch effect in
//! batches of 25 … 1 specimens (and the spread of random batch offsets), a loading-rate effect
//! (ln-linear and power law), a weak second flaw population (a mixture, also beside a batch
//! effect), volume and surface flaws in every specimen (competing risks) —, parameters inside
//! their 90 % bands, no false naming with irrelevant or shuffled factors, and the shipped real data sets (Smith & Naylor glass fibres, Bader & Priest
//! carbon fibres) against the `reliability` package's fits (tests/bench/reliability/).
//!
//! Synthetic specimens: x_i = exp(ln σ_i + ln(−ln U)/m) with the effect in ln σ_i (the crate's
//! generator, `regress::draw_particles`, one draw per row), m = 8 — a typical ceramic — and
//! realistic campaign sizes: 90 specimens (three gauge lengths × 30, three batches × 30, a
//! loading-rate series of 90). The naming loop runs with 99 bootstrap replicates (the shipped
//! studies use 499) so that the sweeps fit in CI.

use partlife::discrepancy::workflow::{analyse, names};
use partlife::obs::Obs;
use partlife::strength::factors::{Factor, Form, SizeMeasure};
use partlife::strength::regress::draw_particles;
use partlife::strength::{Effect, NamingSettings, Sample};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const M: f64 = 8.0;
const N: usize = 90;

/// Columns of one synthetic campaign (before strengths are drawn): gauge length (10/20/50),
/// batch (A/B/C), loading rate (0.1…10, log-uniform), plus five irrelevant factors.
struct Campaign {
    length: Vec<f64>,
    batch: Vec<String>,
    rate: Vec<f64>,
    noise_num: Vec<Vec<f64>>,
    noise_cat: Vec<Vec<String>>,
}

fn campaign(rng: &mut ChaCha8Rng) -> Campaign {
    let length = (0..N).map(|i| [10.0, 20.0, 50.0][i % 3]).collect();
    let batch = (0..N).map(|i| ["A", "B", "C"][(i / 3) % 3].to_string()).collect();
    let rate = (0..N).map(|_| 10f64.powf(rng.random_range(-1.0..1.0))).collect();
    let noise_num = (0..2).map(|_| (0..N).map(|_| rng.random_range(1.0..5.0)).collect()).collect();
    let noise_cat = (0..3).map(|k| (0..N).map(|_| format!("L{}", rng.random_range(0..2 + k))).collect()).collect();
    Campaign { length, batch, rate, noise_num, noise_cat }
}

/// A sample of the campaign with strengths drawn at ln σ_i = ln 400 MPa + `effect(i)`; the
/// declared candidates: size(length), levels(batch), linear(rate), power(rate), and with
/// `noise` the five irrelevant factors' candidates too.
fn sample(c: &Campaign, effect: impl Fn(usize) -> f64, noise: bool, rng: &mut ChaCha8Rng) -> Sample {
    sample_with(c, effect, noise, &[Form::Linear, Form::Power], rng)
}

/// [`sample`] with the rate declared in the forms `rate_forms` only.
fn sample_with(c: &Campaign, effect: impl Fn(usize) -> f64, noise: bool, rate_forms: &[Form], rng: &mut ChaCha8Rng) -> Sample {
    sample_full(c, effect, |_| M, noise, rate_forms, rng)
}

/// [`sample_with`] with the modulus of each row.
fn sample_full(c: &Campaign, effect: impl Fn(usize) -> f64, modulus: impl Fn(usize) -> f64, noise: bool, rate_forms: &[Form], rng: &mut ChaCha8Rng) -> Sample {
    let ln_scale: Vec<f64> = (0..N).map(|i| (400e6f64).ln() + effect(i)).collect();
    // One draw per row, in row order: draw_particles picks rows at random, so draw each row's
    // strength from a one-row population.
    let strength: Vec<f64> = (0..N).map(|i| draw_particles(&ln_scale[i..=i], modulus(i), 1, rng)[0].1.exp()).collect();
    let mut s = Sample { source: "synthetic".into(), strength: strength.into_iter().collect(), ..Sample::default() };
    s.covariates.push(("length".into(), c.length.iter().map(|v| Some(*v)).collect()));
    s.covariates.push(("rate".into(), c.rate.iter().map(|v| Some(*v)).collect()));
    s.levels.push(("batch".into(), c.batch.clone()));
    s.factors = vec![
        Factor { column: "length".into(), form: Form::Size(SizeMeasure::GaugeLength) },
        Factor { column: "batch".into(), form: Form::Levels },
        Factor { column: "batch".into(), form: Form::Moduli },
    ];
    s.factors.extend(rate_forms.iter().map(|f| Factor { column: "rate".into(), form: *f }));
    if noise {
        for (k, v) in c.noise_num.iter().enumerate() {
            let name = format!("noise{k}");
            s.covariates.push((name.clone(), v.iter().map(|x| Some(*x)).collect()));
            s.factors.push(Factor { column: name.clone(), form: Form::Linear });
            s.factors.push(Factor { column: name, form: Form::Power });
        }
        for (k, v) in c.noise_cat.iter().enumerate() {
            let name = format!("group{k}");
            s.levels.push((name.clone(), v.clone()));
            s.factors.push(Factor { column: name.clone(), form: Form::Levels });
            s.factors.push(Factor { column: name, form: Form::Moduli });
        }
    }
    s
}

fn settings(seed: u64) -> NamingSettings {
    NamingSettings { bootstrap: 99, permutations: 99, cv_folds: 10, max_effects: 2, seed, ..NamingSettings::default() }
}

/// Runs `reps` campaigns with `effect` hidden; returns (named first, parameter inside its 90 %
/// band, named anything) counts. `truth` is the hidden coefficient β of the first regression
/// column of `hidden` (None: nothing hidden).
fn sweep(reps: usize, seed: u64, hidden: Option<(&Effect, f64)>, effect: impl Fn(&Campaign, usize) -> f64, noise: bool, shuffle_batch: bool) -> (usize, usize, usize) {
    sweep_with(reps, seed, hidden, effect, noise, shuffle_batch, &[Form::Linear, Form::Power])
}

fn sweep_with(reps: usize, seed: u64, hidden: Option<(&Effect, f64)>, effect: impl Fn(&Campaign, usize) -> f64, noise: bool, shuffle_batch: bool, rate_forms: &[Form]) -> (usize, usize, usize) {
    sweep_full(reps, seed, hidden, effect, |_, _| M, noise, shuffle_batch, rate_forms)
}

#[allow(clippy::too_many_arguments)]
fn sweep_full(reps: usize, seed: u64, hidden: Option<(&Effect, f64)>, effect: impl Fn(&Campaign, usize) -> f64, modulus: impl Fn(&Campaign, usize) -> f64, noise: bool, shuffle_batch: bool, rate_forms: &[Form]) -> (usize, usize, usize) {
    let (mut named, mut covered, mut any, mut wald, mut profile) = (0, 0, 0, 0, 0);
    for r in 0..reps {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let c = campaign(&mut rng);
        let mut s = sample_full(&c, |i| effect(&c, i), |i| modulus(&c, i), noise, rate_forms, &mut rng);
        if shuffle_batch {
            let v = &mut s.levels[0].1;
            for i in (1..v.len()).rev() {
                v.swap(i, rng.random_range(0..=i));
            }
        }
        let o = analyse(&s, &settings(seed ^ r as u64), false).unwrap();
        any += usize::from(!o.named.is_empty());
        if let Some((e, beta)) = hidden {
            if o.named.first() == Some(e) {
                named += 1;
                // The model of the round that named it (a later round may add a second effect).
                // Its exact 90 % band from the pivotal simulation (the band the report gives a
                // named effect; the Wald band b ± 1.645 se and the profile-likelihood interval,
                // both large-sample, undercover the power law's exponent at n = 90: 84.6 % and
                // 84.9 %); for a categorical factor the Wald band of the first level's offset.
                let m = &o.stages[1].model;
                let (b, se) = m.coefficient(e).unwrap();
                wald += usize::from((b - beta).abs() <= 1.645 * se);
                let band = m.profile_band(s.strength.view(), e, 0.90).map(|p| (p, m.pivotal_band(e, 0.90, 999, seed ^ r as u64).unwrap()));
                if let Some(((plo, phi), _)) = band {
                    profile += usize::from(plo <= beta && beta <= phi);
                }
                covered += usize::from(match band {
                    Some((_, (lo, hi))) => lo <= beta && beta <= hi,
                    None => (b - beta).abs() <= 1.645 * se,
                });
            }
        }
    }
    eprintln!("hidden {:?}: named first {named}/{reps}, inside the 90 % band {covered}/{named} (Wald {wald}, profile likelihood {profile}), anything named {any}/{reps}", hidden.map(|h| h.0.name()));
    (named, covered, any)
}

fn size() -> Effect {
    Effect::Factor(Factor { column: "length".into(), form: Form::Size(SizeMeasure::GaugeLength) })
}

#[test]
fn a_hidden_size_effect_is_named_with_its_exponent_and_the_weakest_link_test_follows_it() {
    // σ_θ ∝ L^(−α) with α = 3/m (stronger than weakest-link 1/m), 30 fibres at each of 10, 20, 50 mm.
    let alpha = 3.0 / M;
    let reps = 100;
    let (named, covered, _) = sweep(reps, 33_01, Some((&size(), -alpha)), |c, i| -alpha * (c.length[i] / 20.0).ln(), false, false);
    assert!(named as f64 >= 0.9 * reps as f64, "named {named}/{reps}");
    assert!(covered as f64 >= 0.85 * named as f64, "α inside its 90 % band in {covered}/{named}");
    // One campaign: the evidence carries the weakest-link test, which rejects α = 1/m here and
    // does not reject it when the data follow weakest-link scaling.
    for (a, supported) in [(3.0 / M, false), (1.0 / M, true)] {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let c = campaign(&mut rng);
        let s = sample(&c, |i| -a * (c.length[i] / 20.0).ln(), false, &mut rng);
        let o = analyse(&s, &settings(5), false).unwrap();
        let e = o.evidence.iter().find(|e| e.round == 0 && e.candidate == size()).unwrap();
        let w = e.weakest_link.unwrap();
        assert_eq!(w.supported, supported, "α = {a}: {w:?}");
        assert!(e.meaning.contains("weakest-link test"), "{}", e.meaning);
    }
}

/// `names` (what a "diagnosed" strength model, the power replicates and the experiments read)
/// leaves out only what a report reads: on samples where nothing, one effect, two effects and a
/// two-population law are named, its names are the full analysis's (with the residual-trend
/// diagnosis, which must not change them either).
#[test]
fn the_names_alone_are_the_full_analysis_names() {
    let mut rng = ChaCha8Rng::seed_from_u64(33_20);
    let c = campaign(&mut rng);
    let samples = [
        sample(&c, |_| 0.0, true, &mut rng),
        sample(&c, |i| -(3.0 / M) * (c.length[i] / 20.0).ln(), false, &mut rng),
        sample(&c, |i| if c.batch[i] == "B" { 0.8f64.ln() } else { 0.0 } + 0.08 * c.rate[i].ln(), false, &mut rng),
        two_populations(80, Flaws::Weak(0.3), &mut rng),
    ];
    let mut counts = Vec::new();
    for (k, s) in samples.iter().enumerate() {
        let full = analyse(s, &settings(k as u64), true).unwrap();
        assert_eq!(names(s, &settings(k as u64)).unwrap(), full.named, "sample {k}");
        counts.push(full.named.len());
    }
    // The comparison reaches every kind of round: none named, one, two, and a law.
    assert_eq!(counts, [0, 1, 2, 1], "names per sample");
}

#[test]
fn a_hidden_batch_effect_is_named_as_levels_and_a_rate_effect_as_linear_or_power() {
    // Batch B 15 % weaker than A and C (ln 0.85 = −0.163).
    let batch = Effect::Factor(Factor { column: "batch".into(), form: Form::Levels });
    let reps = 100;
    // Levels A, B, C of 30 each: the reference is A (the first of the largest), and the first
    // coefficient is B's.
    let (named, covered, _) = sweep(reps, 33_02, Some((&batch, 0.85f64.ln())), |c, i| if c.batch[i] == "B" { 0.85f64.ln() } else { 0.0 }, false, false);
    assert!(named as f64 >= 0.9 * reps as f64, "levels(batch) named {named}/{reps}");
    assert!(covered as f64 >= 0.85 * named as f64, "batch B's ln-scale offset inside its 90 % band in {covered}/{named}");
    // Strength ∝ rate^(1/(n+1)) (slow crack growth, n = 15: exponent 0.0625) over two decades
    // of loading rate: the power form is the truth. (At exponent 0.05 it is named in 89 of 100.)
    let power = Effect::Factor(Factor { column: "rate".into(), form: Form::Power });
    let (named, _, _) = sweep(reps, 33_03, Some((&power, 0.0625)), |c, i| 0.0625 * c.rate[i].ln(), false, false);
    assert!(named as f64 >= 0.9 * reps as f64, "power(rate) named {named}/{reps}");
    // Its band, over 300 campaigns with the rate declared as a power law only (100 are too few
    // to judge a coverage near the bar): the exact pivotal band the report gives a named effect
    // covers in 257 of 299 (86 %; the remaining shortfall from 90 % is the selection — the
    // exponent is judged where it was named first, which favours campaigns that overestimate
    // it). The large-sample bands miss the bar here: Wald 253 (84.6 %), profile likelihood 254
    // (84.9 %).
    let (named, covered, _) = sweep_with(300, 33_03, Some((&power, 0.0625)), |c, i| 0.0625 * c.rate[i].ln(), false, false, &[Form::Power]);
    assert!(covered as f64 >= 0.85 * named as f64, "exponent inside its 90 % band in {covered}/{named}");
    // ln σ linear in the rate (0.04 per unit over 0.1…10; at 0.03 it is named first in 89 of 100).
    let linear = Effect::Factor(Factor { column: "rate".into(), form: Form::Linear });
    let (named, covered, _) = sweep(reps, 33_04, Some((&linear, 0.04)), |c, i| 0.04 * c.rate[i], false, false);
    assert!(named as f64 >= 0.9 * reps as f64, "linear(rate) named {named}/{reps}");
    assert!(covered as f64 >= 0.85 * named as f64, "β inside its 90 % band in {covered}/{named}");
}

#[test]
fn a_hidden_modulus_per_batch_is_named_as_moduli() {
    // Batch B's strengths scatter more (m = 3.5 against 8, same scale): a processing fault that
    // widens the flaw-size distribution. 30 specimens per batch; the first γ is
    // ln(b_B/b_A) = ln(8/3.5). (At m = 4 against 8 it is named first in 83 of 100: the
    // detection limit at this campaign size is a modulus ratio of about 2.3.)
    let moduli = Effect::Factor(Factor { column: "batch".into(), form: Form::Moduli });
    let reps = 100;
    let (named, covered, _) = sweep_full(reps, 33_07, Some((&moduli, (M / 3.5f64).ln())), |_, _| 0.0, |c, i| if c.batch[i] == "B" { 3.5 } else { M }, false, false, &[Form::Linear, Form::Power]);
    assert!(named as f64 >= 0.9 * reps as f64, "moduli(batch) named {named}/{reps}");
    assert!(covered as f64 >= 0.85 * named as f64, "batch B's ln(1/m) offset inside its 90 % band in {covered}/{named}");
    // One campaign, diagnosed: the residuals' scatter (not their location) differs between the
    // batches, at B, and the gap falls once the modulus per batch is named.
    let mut rng = ChaCha8Rng::seed_from_u64(33_08);
    let c = campaign(&mut rng);
    let s = sample_full(&c, |_| 0.0, |i| if c.batch[i] == "B" { 3.5 } else { M }, false, &[Form::Linear, Form::Power], &mut rng);
    let o = analyse(&s, &settings(3), true).unwrap();
    assert_eq!(o.named.first(), Some(&moduli));
    let f = &o.stages[0].findings;
    let scatter = f.iter().find(|f| f.scatter && f.covariate == "batch").unwrap();
    let location = f.iter().find(|f| !f.scatter && f.covariate == "batch").unwrap();
    assert!(scatter.p < 0.05 && scatter.worst_level.as_deref() == Some("B") && scatter.p < location.p, "{scatter:?} {location:?}");
    assert!(o.stages[1].gap < o.stages[0].gap, "gap {} → {}", o.stages[0].gap, o.stages[1].gap);
}

#[test]
fn nothing_is_named_when_nothing_is_hidden_even_among_irrelevant_and_shuffled_factors() {
    // Nothing hidden; the declared size, batch and rate plus two numeric and three categorical
    // irrelevant factors: 15 candidates in all (each categorical factor a scale and a modulus
    // per level), one family-wise guard.
    let reps = 100;
    let (_, _, any) = sweep(reps, 33_05, None, |_, _| 0.0, true, false);
    assert!(any as f64 <= 0.05 * reps as f64, "false naming in {any}/{reps}");
    // A real batch effect whose labels were shuffled is no effect.
    let (_, _, any) = sweep(reps, 33_06, None, |c, i| if c.batch[i] == "B" { 0.85f64.ln() } else { 0.0 }, false, true);
    // The strengths still carry the (now unrecorded) batch effect: only a mild extra scatter.
    assert!(any as f64 <= 0.05 * reps as f64, "shuffled factor named in {any}/{reps}");
}


mod common;

/// The `reliability` package's two-parameter Weibull MLE (tests/bench/reliability/fit.py,
/// reliability 0.9, values as the files hold them): (set, n, m, scale in GPa, log-likelihood in
/// the units of GPa).
const PEER: [(&str, usize, f64, f64, f64); 5] = [
    ("glass", 63, 5.7807009964, 1.6281134828, -15.2068404911),
    ("carbon_10mm", 63, 5.0494133824, 3.3147226247, -61.9569812988),
    ("carbon_20mm", 69, 5.5048507470, 2.6508590884, -49.5961351302),
    ("carbon_50mm", 65, 4.5390051206, 1.8298790868, -35.9354448443),
    ("carbon_pooled", 197, 3.3755215280, 2.6568614172, -226.1052397453),
];

/// The strengths (Pa) of a real data file, all of them or (carbon fibres) one gauge length's.
fn real(file: &str, strength: &str, filter: Option<&str>) -> Vec<f64> {
    use partlife::intake::{MapOrigin, Source};
    use partlife::strength::specimens::{Factors, read_specimens};
    let mut src = Source::file(common::root().join("datasets/real").join(file));
    src.columns.insert("strength".into(), strength.into());
    src.units.insert("strength".into(), "GPa".into());
    // The test temperature the shipped studies declare (the sources state none).
    src.temperature_c = Some(20.0);
    // The carbon file's gauge length is read as a numeric factor; the glass file has none.
    let factors = if file.starts_with("bader_priest") { Factors::Typed([("gauge_length_mm".to_string(), partlife::strength::factors::FactorType::Numeric)].into()) } else { Factors::default() };
    let s = read_specimens(&src, None, &factors, &MapOrigin { file: "test".into(), key: "data".into() }).unwrap();
    let keep: Vec<usize> = (0..s.sample.strength.len()).filter(|&i| filter.is_none_or(|f| s.sample.covariates.first().is_some_and(|(_, v)| v[i] == Some(f.parse().unwrap())))).collect();
    keep.iter().map(|&i| s.sample.strength.x[i]).collect()
}

#[test]
fn two_parameter_fits_of_the_real_data_equal_the_reliability_package() {
    use partlife::strength::regress::{Design, fit};
    for (set, n, m, scale, loglik) in PEER {
        let x = match set {
            "glass" => real("smith_naylor_glass_fibres.csv", "strength_original_units", None),
            "carbon_pooled" => real("bader_priest_carbon_fibres.csv", "strength_gpa", None),
            s => real("bader_priest_carbon_fibres.csv", "strength_gpa", Some(s.trim_start_matches("carbon_").trim_end_matches("mm"))),
        };
        assert_eq!(x.len(), n, "{set}");
        let f = fit(Obs::exact(&x), &Design::default()).unwrap();
        // Log-likelihood in Pa = in GPa − n ln 10⁹ (the density of x scales by 1/10⁹).
        let ours = f.loglik + n as f64 * 1e9f64.ln();
        assert!((ours - loglik).abs() < 1e-6, "{set}: ℓ {ours} vs reliability {loglik}");
        assert!((f.shape() / m - 1.0).abs() < 1e-6 && (f.mu.exp() / 1e9 / scale - 1.0).abs() < 1e-6, "{set}: m {} scale {}", f.shape(), f.mu.exp());
    }
}

#[test]
fn the_shipped_real_data_studies_say_what_the_readme_reports_and_a_lab_export_agrees() {
    let s = common::Scratch::new();
    std::fs::create_dir_all(s.path("datasets/real")).unwrap();
    for f in ["smith_naylor_glass_fibres.csv", "bader_priest_carbon_fibres.csv"] {
        std::fs::copy(common::root().join("datasets/real").join(f), s.path("datasets/real").join(f)).unwrap();
    }
    for f in ["strength_glass_fibres.toml", "strength_carbon_fibres.toml"] {
        std::fs::copy(common::root().join("studies").join(f), s.path("studies").join(f)).unwrap();
    }
    let glass = s.read("studies/strength_glass_fibres.toml");
    // A lab's export of the carbon fibres: semicolon, decimal comma, MPa, German headers.
    let text = std::fs::read_to_string(s.path("datasets/real/bader_priest_carbon_fibres.csv")).unwrap();
    let mut lab = String::from("Probe;Messlänge [mm];Festigkeit [MPa]\n");
    for line in text.lines().skip(1) {
        let v: Vec<&str> = line.split(',').collect();
        let mpa = (v[3].parse::<f64>().unwrap() * 1000.0).to_string().replace('.', ",");
        lab.push_str(&format!("{};{};{}\n", v[0], v[2], mpa));
    }
    s.write("datasets/real/carbon_lab.csv", &lab);
    let study = s.read("studies/strength_carbon_fibres.toml")
        .replace("data = { file = \"../datasets/real/bader_priest_carbon_fibres.csv\", temperature_c = 20 }", "data = { file = \"../datasets/real/carbon_lab.csv\", columns = { strength = \"Festigkeit [MPa]\", id = \"Probe\" }, temperature_c = 20 }")
        .replace("column = \"gauge_length_mm\"", "column = \"Messlänge\"");
    s.write("studies/carbon_lab.toml", &study);
    // A lab's export of the glass fibres: semicolon, decimal comma, its own headers.
    let text = std::fs::read_to_string(s.path("datasets/real/smith_naylor_glass_fibres.csv")).unwrap();
    let mut lab = String::from("Nr.;Bruchspannung [GPa]\n");
    for line in text.lines().skip(1) {
        let v: Vec<&str> = line.split(',').collect();
        lab.push_str(&format!("{};{}\n", v[0], v[3].replace('.', ",")));
    }
    s.write("datasets/real/glass_lab.csv", &lab);
    let glass_lab = glass.replace(
        "data = { file = \"../datasets/real/smith_naylor_glass_fibres.csv\", columns = { strength = \"strength_original_units\" }, units = { strength = \"GPa\" }, temperature_c = 20 }",
        "data = { file = \"../datasets/real/glass_lab.csv\", columns = { id = \"Nr.\", strength = \"Bruchspannung [GPa]\" }, temperature_c = 20 }",
    );
    assert_ne!(glass_lab, glass);
    s.write("studies/glass_lab.toml", &glass_lab);
    let mut verdicts = Vec::new();
    for (name, _) in [("strength_glass_fibres", 0), ("strength_carbon_fibres", 1), ("carbon_lab", 2), ("glass_lab", 3)] {
        let out = s.run(&["run", &format!("studies/{name}.toml"), "--reports-dir", "reports", "--quiet"]);
        assert_eq!(out.code, 0, "{name}: {}", out.stderr);
        // The printed critical Λ is the decision's (α 0.05 in both studies).
        common::guard_agrees_with_critical(&s.path(&format!("reports/{name}/evidence.csv")), 0.05);
        let v: serde_json::Value = serde_json::from_str(&s.read(&format!("reports/{name}/verdict.json"))).unwrap();
        verdicts.push((v, s.read(&format!("reports/{name}/summary.md"))));
    }
    // Glass: nothing recorded, nothing named; the two-parameter law is rejected by the bootstrap AD.
    let (g, md) = &verdicts[0];
    assert_eq!(g["effects_named"]["glass"], serde_json::json!([]));
    let p_ad = g["materials"][0]["stages"][0]["p_anderson_darling"].as_f64().unwrap();
    assert!(p_ad < 0.05, "AD p {p_ad}");
    assert!(md.contains("**The Weibull law fits these data poorly**") && md.contains("nothing recorded in the data explains the misfit"), "{md}");
    // Two flaw populations were tried and not named (the mixture comes close: ΔBIC +0.3).
    let ev = g["evidence"]["glass"].as_array().unwrap();
    let names: Vec<&str> = ev.iter().map(|e| e["candidate"].as_str().unwrap()).collect();
    assert_eq!(names, ["mixture", "competing_risks"]);
    assert!(ev.iter().all(|e| !e["named"].as_bool().unwrap()));
    assert!(ev[0]["delta_bic"].as_f64().unwrap() > 0.0 && ev[0]["likelihood_ratio"].as_f64().unwrap() > 12.0, "{}", ev[0]);
    // Carbon: the size effect is named and weakest-link scaling rejected (α > 1/m).
    let (c, md) = &verdicts[1];
    assert_eq!(c["effects_named"]["carbon"], serde_json::json!(["size(gauge_length_mm)"]));
    let w = &c["evidence"]["carbon"][0]["weakest_link"];
    assert!(!w["supported"].as_bool().unwrap() && w["alpha"].as_f64().unwrap() > w["predicted"].as_f64().unwrap(), "{w}");
    assert!(md.contains("stronger than weakest-link scaling allows: rejected"), "{md}");
    // The lab export: the same verdict and the same numbers (the size effect is named under
    // the lab's column name).
    let (l, _) = &verdicts[2];
    assert_eq!(l["effects_named"]["carbon"], serde_json::json!(["size(Messlänge)"]));
    let wl = &l["evidence"]["carbon"][0]["weakest_link"];
    for k in ["alpha", "predicted", "lr", "p"] {
        let (a, b) = (w[k].as_f64().unwrap(), wl[k].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-9 * a.abs().max(1e-12), "{k}: {a} vs {b}");
    }
    assert_eq!(c["gap_before"]["carbon"], l["gap_before"]["carbon"]);
    // The glass export: nothing named, the same fit, the same bootstrap test and the same
    // two-population evidence.
    let (gl, _) = &verdicts[3];
    assert_eq!(gl["effects_named"]["glass"], serde_json::json!([]));
    let (a, b) = (&g["materials"][0]["stages"][0], &gl["materials"][0]["stages"][0]);
    for k in ["log_likelihood", "anderson_darling", "p_anderson_darling", "weibull_modulus"] {
        let (x, y) = (a[k].as_f64().unwrap(), b[k].as_f64().unwrap());
        assert!((x - y).abs() <= 1e-9 * x.abs().max(1.0), "{k}: {x} vs {y}");
    }
    let evl = gl["evidence"]["glass"].as_array().unwrap();
    for (e, f) in ev.iter().zip(evl) {
        assert_eq!(e["candidate"], f["candidate"]);
        assert!((e["likelihood_ratio"].as_f64().unwrap() - f["likelihood_ratio"].as_f64().unwrap()).abs() < 1e-9 && !f["named"].as_bool().unwrap(), "{f}");
    }
}

/// The `reliability` package's two-population fits (Fit_Weibull_Mixture, Fit_Weibull_CR;
/// tests/bench/reliability/fit.py): (set, law, log-likelihood in GPa units).
const PEER_FLAWS: [(&str, &str, f64); 4] = [
    ("glass", "mixture", -11.5659798028),
    ("glass", "competing_risks", -13.7329572114),
    ("carbon_pooled", "mixture", -224.3883105484),
    ("carbon_pooled", "competing_risks", -226.1052400761),
];

#[test]
fn two_population_fits_of_the_real_data_against_the_reliability_package() {
    use partlife::strength::flaws::{Populations, fit};
    for (set, law, peer) in PEER_FLAWS {
        let x = match set {
            "glass" => real("smith_naylor_glass_fibres.csv", "strength_original_units", None),
            _ => real("bader_priest_carbon_fibres.csv", "strength_gpa", None),
        };
        let kind = if law == "mixture" { Populations::Mixture } else { Populations::Competing };
        let f = fit(kind, Obs::exact(&x)).unwrap();
        let ours = f.loglik + x.len() as f64 * 1e9f64.ln();
        eprintln!("{set} {law}: ours ℓ = {ours:.10} ({:?}), reliability {peer:.10}; p = {:.6}, first = ({:.6e}, {:.6}), second = ({:.6e}, {:.6})", f.identifiable, f.p, f.first.0, f.first.1, f.second.0, f.second.1);
        // Never below the peer's optimum; equal to 1e-6 where both reach the same one.
        assert!(ours >= peer - 1e-6, "{set} {law}: ℓ {ours} below reliability's {peer}");
        match (set, law) {
            // reliability stops at a local optimum (a 7.5 % weak population, ℓ −11.566); the
            // higher one is a broad and a narrow population of about equal weight (scipy gives
            // ℓ −9.13418 at these parameters).
            ("glass", "mixture") => {
                assert!(ours - peer > 2.0 && (f.p - 0.45).abs() < 0.01 && f.identifiable.is_ok(), "{f:?}");
            }
            // Equal moduli: the two risks are one Weibull law (the two-parameter fit's ℓ), a ridge
            // reported as not identified; reliability's point on it is 3e-7 lower.
            ("carbon_pooled", "competing_risks") => {
                assert!((ours - peer).abs() < 1e-6, "{ours} vs {peer}");
                assert!(f.identifiable.as_ref().is_err_and(|w| w.contains("same modulus")), "{:?}", f.identifiable);
            }
            _ => {
                assert!((ours - peer).abs() < 1e-6, "{set} {law}: {ours} vs {peer}");
                assert!(f.identifiable.is_ok(), "{set} {law}: {:?}", f.identifiable);
            }
        }
    }
}

/// A second flaw population hidden in synthetic specimens.
#[derive(Clone, Copy)]
enum Flaws {
    /// One population: 400 MPa, m = 12.
    None,
    /// A fraction of the specimens from a population at 0.6 × the scale (m = 12 both): a
    /// mixture with weaker share `0`.
    Weak(f64),
    /// Every specimen holds volume flaws (400 MPa, m = 20) and surface flaws (600 MPa, m = 4),
    /// and breaks at the weaker: competing risks, weaker-scale modulus 20.
    Both,
}

/// `n` synthetic specimens with `flaws`. Candidates: the mixture and the competing-risks law.
fn two_populations(n: usize, flaws: Flaws, rng: &mut ChaCha8Rng) -> Sample {
    use partlife::strength::flaws::Populations;
    let strength = (0..n)
        .map(|_| match flaws {
            Flaws::Both => {
                let volume = draw_particles(&[f64::ln(400e6)], 20.0, 1, rng)[0].1;
                let surface = draw_particles(&[f64::ln(600e6)], 4.0, 1, rng)[0].1;
                volume.min(surface).exp()
            }
            Flaws::None | Flaws::Weak(_) => {
                let weak = if let Flaws::Weak(w) = flaws { w } else { 0.0 };
                let s = if rng.random::<f64>() < weak { 0.6 * 400e6 } else { 400e6 };
                draw_particles(&[f64::ln(s)], 12.0, 1, rng)[0].1.exp()
            }
        })
        .collect();
    Sample { source: "synthetic".into(), strength, populations: vec![Populations::Mixture, Populations::Competing], ..Sample::default() }
}

/// Runs `reps` samples of `n`; returns (the right law named first, its reported parameter — the
/// weaker share of a mixture, the weaker-scale risk's modulus of competing risks — inside its
/// 90 % profile-likelihood band, anything named).
fn population_sweep(reps: usize, seed: u64, n: usize, flaws: Flaws) -> (usize, usize, usize) {
    use partlife::strength::flaws::Populations;
    let (right, truth) = match flaws {
        Flaws::Weak(w) => (Some(Effect::Populations(Populations::Mixture)), w),
        Flaws::Both => (Some(Effect::Populations(Populations::Competing)), 20.0),
        Flaws::None => (None, f64::NAN),
    };
    let (mut named, mut covered, mut any) = (0, 0, 0);
    for r in 0..reps {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let s = two_populations(n, flaws, &mut rng);
        let o = analyse(&s, &settings(seed ^ r as u64), false).unwrap();
        any += usize::from(!o.named.is_empty());
        if o.named.first() != right.as_ref() {
            for e in o.evidence.iter().filter(|e| e.round == 0) {
                eprintln!("  sample {r}: {} Λ {:.2} crit {:.2} p {:.3} ΔBIC {:.2} ΔCV {:.2} passed {} named {} {}", e.candidate.name(), e.lr, e.lr_critical, e.p_family, e.delta_bic, e.delta_cv, e.passed, e.named, e.meaning);
            }
        }
        if right.is_some() && o.named.first() == right.as_ref() {
            named += 1;
            let e = o.evidence.iter().find(|e| e.named).unwrap();
            let (lo, hi) = e.band.expect("a named two-population law has its profile band");
            covered += usize::from(lo <= truth && truth <= hi);
        }
    }
    eprintln!("{n} specimens, hidden {:?}: named first {named}/{reps}, inside the 90 % band {covered}/{named}, anything named {any}/{reps}", right.map(|e| e.name()));
    (named, covered, any)
}

#[test]
fn a_hidden_weak_flaw_population_is_named_as_a_mixture() {
    // 80 specimens, 30 % from a population at 0.6 × the scale: fast sibling of the sweep below.
    let (mixture, _, _) = population_sweep(2, 33_07, 80, Flaws::Weak(0.3));
    assert_eq!(mixture, 2);
    let (_, _, any) = population_sweep(2, 33_08, 80, Flaws::None);
    assert_eq!(any, 0);
}

#[test]
#[ignore = "slow: 40 + 40 naming loops refitting two-population laws in every bootstrap replicate (about a minute on two cores); fast sibling a_hidden_weak_flaw_population_is_named_as_a_mixture"]
fn a_hidden_weak_flaw_population_is_named_at_90_percent_and_one_population_at_most_5() {
    let (mixture, covered, _) = population_sweep(40, 33_09, 80, Flaws::Weak(0.3));
    assert!(mixture >= 36, "mixture named {mixture}/40");
    assert!(covered as f64 >= 0.85 * mixture as f64, "weaker share inside its band {covered}/{mixture}");
    let (_, _, any) = population_sweep(40, 33_10, 80, Flaws::None);
    assert!(any <= 2, "a one-population sample named something in {any}/40");
}

#[test]
fn volume_and_surface_flaws_in_every_specimen_are_named_as_competing_risks() {
    // 200 specimens: fast sibling of the sweep below (the mixture fits these data closely too;
    // the lower BIC must pick competing risks).
    let (named, covered, _) = population_sweep(2, 33_11, 200, Flaws::Both);
    assert_eq!((named, covered), (2, 2));
}

#[test]
#[ignore = "slow: 40 naming loops on 200 specimens refitting two-population laws in every bootstrap replicate (about 40 s on two cores); fast sibling volume_and_surface_flaws_in_every_specimen_are_named_as_competing_risks"]
fn competing_risks_are_named_at_90_percent_with_the_modulus_inside_its_band_at_85() {
    // At 120 specimens the departure is found in 35 of 40 samples and competing risks named
    // first in 33 (in two a few low strengths make a small weak mixture component the lower
    // BIC); at 200, 40 of 40.
    let (named, covered, _) = population_sweep(40, 33_12, 200, Flaws::Both);
    assert!(named >= 36, "competing risks named first {named}/40");
    assert!(covered as f64 >= 0.85 * named as f64, "the weaker-scale modulus inside its 90 % band {covered}/{named}");
}

/// `n` specimens in three batches (batch B's scale × 0.85), each holding a 30 % weaker flaw
/// population (0.6 × the scale, m = 12 both): whether the loop names both the batch's scale and
/// the mixture beside it (in either order) among its first two effects.
fn batch_and_mixture_sweep(reps: usize, seed: u64, n: usize) -> usize {
    use partlife::strength::flaws::Populations;
    let batch_effect = Effect::Factor(Factor { column: "batch".into(), form: Form::Levels });
    let mixture = Effect::Populations(Populations::Mixture);
    let mut both = 0;
    for r in 0..reps {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let batch: Vec<String> = (0..n).map(|i| ["A", "B", "C"][i % 3].to_string()).collect();
        let strength = batch
            .iter()
            .map(|b| {
                let s = 400e6 * if b == "B" { 0.85 } else { 1.0 } * if rng.random::<f64>() < 0.3 { 0.6 } else { 1.0 };
                draw_particles(&[f64::ln(s)], 12.0, 1, &mut rng)[0].1.exp()
            })
            .collect();
        let mut s = Sample { source: "synthetic".into(), strength, populations: vec![Populations::Mixture, Populations::Competing], ..Sample::default() };
        s.levels.push(("batch".into(), batch));
        s.factors = vec![Factor { column: "batch".into(), form: Form::Levels }, Factor { column: "batch".into(), form: Form::Moduli }];
        let named = names(&s, &settings(seed ^ r as u64)).unwrap();
        let first_two = &named[..named.len().min(2)];
        both += usize::from(first_two.contains(&batch_effect) && first_two.contains(&mixture));
        if !(first_two.contains(&batch_effect) && first_two.contains(&mixture)) {
            eprintln!("  sample {r}: named {:?}", named.iter().map(|e| e.name()).collect::<Vec<_>>());
        }
    }
    eprintln!("{n} specimens, a batch's scale and a weak flaw population: both named {both}/{reps}");
    both
}

#[test]
fn a_batch_effect_and_a_weak_flaw_population_are_both_named() {
    // Fast sibling of the sweep below: a two-population law fitted beside a scale per level.
    assert_eq!(batch_and_mixture_sweep(2, 33_16, 150), 2);
}

#[test]
#[ignore = "slow: 40 naming loops refitting two-population laws beside a batch's scales in every bootstrap replicate; fast sibling a_batch_effect_and_a_weak_flaw_population_are_both_named"]
fn a_batch_effect_and_a_weak_flaw_population_are_both_named_at_90_percent() {
    let both = batch_and_mixture_sweep(40, 33_17, 150);
    assert!(both >= 36, "both named in {both}/40");
}

#[test]
#[ignore = "slow: 40 naming loops with 15 factor candidates and both two-population laws refitted in every bootstrap replicate (about a minute on two cores); fast siblings a_hidden_weak_flaw_population_is_named_as_a_mixture (nothing named with one population) and nothing_is_named_when_nothing_is_hidden_even_among_irrelevant_and_shuffled_factors"]
fn nothing_is_named_among_irrelevant_factors_and_the_two_population_laws() {
    use partlife::strength::flaws::Populations;
    let reps = 40;
    let (mut any, mut candidates) = (0, 0);
    for r in 0..reps {
        let mut rng = ChaCha8Rng::seed_from_u64(33_13);
        rng.set_stream(r as u64 + 1);
        let c = campaign(&mut rng);
        let mut s = sample(&c, |_| 0.0, true, &mut rng);
        s.populations = vec![Populations::Mixture, Populations::Competing];
        let o = analyse(&s, &settings(33_13 ^ r as u64), false).unwrap();
        any += usize::from(!o.named.is_empty());
        candidates = o.evidence.iter().filter(|e| e.round == 0).count();
        if !o.named.is_empty() {
            eprintln!("  sample {r}: named {:?}", o.named.iter().map(|e| e.name()).collect::<Vec<_>>());
        }
    }
    eprintln!("nothing hidden, {candidates} candidates: named anything {any}/{reps}");
    assert!(any as f64 <= 0.05 * reps as f64, "false naming in {any}/{reps}");
}

/// Batches of uneven size, as a campaign's records often are (90 specimens): two large ones, a
/// few middling and three of one or two specimens, whose scales can only be partially pooled.
const UNEVEN: [(&str, usize); 9] = [("K1", 25), ("K2", 20), ("K3", 15), ("K4", 12), ("K5", 8), ("K6", 5), ("K7", 2), ("K8", 2), ("K9", 1)];

/// A sample of 90 specimens in the uneven batches, batch `b`'s ln-scale offset `offset(b)`,
/// candidates levels(batch) (pooled) and, with `noise`, two irrelevant numeric factors.
fn uneven_sample(offset: impl Fn(usize) -> f64, noise: bool, rng: &mut ChaCha8Rng) -> Sample {
    let batch: Vec<usize> = UNEVEN.iter().enumerate().flat_map(|(b, (_, k))| std::iter::repeat_n(b, *k)).collect();
    let strength: Vec<f64> = batch.iter().map(|&b| draw_particles(&[(400e6f64).ln() + offset(b)], M, 1, rng)[0].1.exp()).collect();
    let mut s = Sample { source: "synthetic".into(), strength: strength.into_iter().collect(), ..Sample::default() };
    s.levels.push(("batch".into(), batch.iter().map(|&b| UNEVEN[b].0.to_string()).collect()));
    s.factors = vec![Factor { column: "batch".into(), form: Form::Levels }];
    if noise {
        for k in 0..2 {
            let name = format!("noise{k}");
            s.covariates.push((name.clone(), (0..batch.len()).map(|_| Some(rng.random_range(1.0..5.0))).collect()));
            s.factors.push(Factor { column: name.clone(), form: Form::Linear });
        }
    }
    s
}

/// Runs `reps` uneven campaigns with the batch offsets `offsets`; returns how often
/// levels(batch) was named and how often anything was.
fn uneven_sweep(reps: usize, seed: u64, offsets: [f64; 9]) -> (usize, usize) {
    let batch = Effect::Factor(Factor { column: "batch".into(), form: Form::Levels });
    let (mut named, mut any) = (0, 0);
    for r in 0..reps {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let s = uneven_sample(|b| offsets[b], true, &mut rng);
        let o = names(&s, &settings(seed ^ r as u64)).unwrap();
        named += usize::from(o.first() == Some(&batch));
        any += usize::from(!o.is_empty());
    }
    eprintln!("uneven batches {offsets:?}: levels(batch) named first {named}/{reps}, anything named {any}/{reps}");
    (named, any)
}

/// The batch offsets of the pooled hidden-effect test: a 10 % batch-to-batch scatter of the
/// scale (sd of the offsets 0.10, ±15 % at the extremes).
const BATCH_OFFSETS: [f64; 9] = [0.10, -0.12, 0.0, 0.14, -0.15, 0.05, -0.10, 0.12, 0.0];

#[test]
fn batches_too_small_for_their_own_scale_are_partially_pooled_and_named_when_they_differ() {
    // Nine batches of 25 … 1 specimens (three of one or two): the scales are partially pooled.
    // Fast sibling of the 100-campaign sweeps below (40 each here).
    let reps = 40;
    let (named, _) = uneven_sweep(reps, 33_10, BATCH_OFFSETS);
    assert!(named as f64 >= 0.9 * reps as f64, "pooled levels(batch) named {named}/{reps}");
    let (_, any) = uneven_sweep(reps, 33_11, [0.0; 9]);
    assert!(any <= 2, "false naming in {any}/{reps}");
    // What the evidence says of one campaign: the levels pooled, τ and each level's scale.
    let mut rng = ChaCha8Rng::seed_from_u64(33_12);
    let s = uneven_sample(|b| BATCH_OFFSETS[b], false, &mut rng);
    let o = analyse(&s, &settings(1), false).unwrap();
    let e = &o.evidence[0];
    assert!(e.meaning.contains("partially pooled") && e.meaning.contains("K9 ×") && e.meaning.contains("(1)"), "{}", e.meaning);
    assert_eq!(e.parameters, 8, "nominal L − 1");
}

/// Campaigns in the uneven batches whose nine ln-scale offsets are drawn afresh from N(0, τ²)
/// (a random batch effect, the pooled model's own assumption): (pooled levels named first, τ
/// inside the reported 90 % band when named, τ inside the band over all campaigns).
fn random_batches_sweep(reps: usize, seed: u64, tau: f64) -> (usize, usize, usize) {
    use rand_distr::{Distribution, Normal};
    let batch = Effect::Factor(Factor { column: "batch".into(), form: Form::Levels });
    let (mut named, mut covered, mut covered_all) = (0, 0, 0);
    for r in 0..reps {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(r as u64 + 1);
        let offsets: Vec<f64> = (0..UNEVEN.len()).map(|_| Normal::new(0.0, tau).unwrap().sample(&mut rng)).collect();
        let s = uneven_sample(|b| offsets[b], false, &mut rng);
        let o = analyse(&s, &settings(seed ^ r as u64), false).unwrap();
        let e = o.evidence.iter().find(|e| e.round == 0 && e.candidate == batch).unwrap();
        let (lo, hi) = e.band.expect("a pooled factor's τ has its profile band");
        assert_eq!(e.parameter.as_ref().unwrap().0, "tau");
        let inside = lo <= tau && tau <= hi;
        covered_all += usize::from(inside);
        if o.named.first() == Some(&batch) {
            named += 1;
            covered += usize::from(inside);
        }
    }
    eprintln!("random batch effect τ = {tau}: pooled levels named first {named}/{reps}, τ inside its 90 % band {covered}/{named} ({covered_all}/{reps} over all campaigns)");
    (named, covered, covered_all)
}

#[test]
fn a_random_batch_effect_is_pooled_and_its_spread_reported_with_a_band() {
    // Fast sibling of the 100-campaign sweep below.
    let (_, _, covered_all) = random_batches_sweep(4, 33_14, 0.1);
    assert!(covered_all >= 3, "τ inside its band in {covered_all}/4");
}

#[test]
#[ignore = "slow: 100 naming loops with the pooled factor's τ searched in every bootstrap refit and profiled (about 10 s on two cores); fast sibling a_random_batch_effect_is_pooled_and_its_spread_reported_with_a_band"]
fn the_spread_of_a_random_batch_effect_is_inside_its_band_at_85_percent() {
    // Measured: named first 84/100, τ inside 78 of those 84 (92.9 %). Over all 100 campaigns
    // 82: where the drawn offsets happen to be small the levels are not named and τ is
    // underestimated (the band counted, like every other effect's, where the effect is named).
    let (named, covered, _) = random_batches_sweep(100, 33_15, 0.1);
    assert!(covered as f64 >= 0.85 * named as f64, "τ inside its band {covered}/{named}");
}

#[test]
#[ignore = "slow: 100 + 100 naming loops with the pooled factor's τ searched in every bootstrap refit (about a minute on two cores); fast sibling batches_too_small_for_their_own_scale_are_partially_pooled_and_named_when_they_differ"]
fn pooled_batches_are_named_at_90_percent_and_falsely_at_most_5() {
    let reps = 100;
    let (named, _) = uneven_sweep(reps, 33_10, BATCH_OFFSETS);
    assert!(named as f64 >= 0.9 * reps as f64, "pooled levels(batch) named {named}/{reps}");
    let (_, any) = uneven_sweep(reps, 33_11, [0.0; 9]);
    assert!(any as f64 <= 0.05 * reps as f64, "false naming in {any}/{reps}");
}

#[test]
fn a_lab_file_with_uneven_lots_and_a_scattering_lab_runs_from_its_study_file_alone() {
    // A lab's tab-separated bend-bar export written here: 120 bars, powder lots of 30, 25, 20,
    // 15, 12, 10, 5, 2 and 1 bars (lot offsets in the scale), tested in four labs of which
    // "Köln" scatters more (m = 4 against 10), decimal commas, MPa, German headers. The study
    // names the two columns and nothing else.
    let s = common::Scratch::new();
    let lots: [(&str, usize, f64); 9] = [("P-1", 30, 0.0), ("P-2", 25, -0.10), ("P-3", 20, 0.08), ("P-4", 15, 0.12), ("P-5", 12, -0.12), ("P-6", 10, 0.05), ("P-7", 5, -0.08), ("P-8", 2, 0.10), ("P-9", 1, 0.0)];
    let labs = ["Jülich", "Almería", "Köln", "Odeillo"];
    let mut rng = ChaCha8Rng::seed_from_u64(33_20);
    let mut text = String::from("Probe\tCharge\tLabor\tFestigkeit [MPa]\n");
    let mut k = 0;
    for (lot, n, d) in lots {
        for _ in 0..n {
            let lab = labs[k % 4];
            let m = if lab == "Köln" { 4.0 } else { 10.0 };
            let x = draw_particles(&[(420.0f64).ln() + d], m, 1, &mut rng)[0].1.exp();
            text.push_str(&format!("B{:03}\t{lot}\t{lab}\t{}\n", k + 1, format!("{x:.1}").replace('.', ",")));
            k += 1;
        }
    }
    std::fs::create_dir_all(s.path("data")).unwrap();
    s.write("data/biegung.tsv", &text);
    s.write(
        "studies/bars.toml",
        "kind = \"discrepancy\"\nseed = 5\n[discrepancy]\nbootstrap = 199\npermutations = 199\n[power]\nreplicates = 0\n[[strength]]\nkey = \"bars\"\nlabel = \"Bend bars\"\ndata = { file = \"../data/biegung.tsv\", columns = { strength = \"Festigkeit [MPa]\", id = \"Probe\" }, temperature_c = 20 }\nfactors = [\"Charge\", \"Labor\"]\n",
    );
    let out = s.run(&["run", "studies/bars.toml", "--reports-dir", "reports", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: serde_json::Value = serde_json::from_str(&s.read("reports/bars/verdict.json")).unwrap();
    let named: Vec<&str> = v["effects_named"]["bars"].as_array().unwrap().iter().map(|e| e.as_str().unwrap()).collect();
    assert!(named.contains(&"levels(Charge)") && named.contains(&"moduli(Labor)"), "{named:?}");
    let md = s.read("reports/bars/summary.md");
    assert!(md.contains("partially pooled") && md.contains("P-9 ×") && md.contains("Weibull modulus of each level of `Labor`"), "{md}");
    // The lots of 2 and 1 bars cannot have their own modulus: that candidate is skipped, saying why.
    assert!(md.contains("moduli(Charge)") && md.contains("at least 5 per level are needed to give it its own modulus"), "{md}");
    let findings = s.read("reports/bars/findings.csv");
    assert!(findings.lines().any(|l| l.starts_with("bars,0,Labor,") && l.contains(",scatter,")), "{findings}");
}

/// The Jahanmir (1996) silicon nitride bars (`datasets/real/`, values read as MPa): all 480 or one
/// batch's 240 strengths (Pa).
fn jahanmir(batch: Option<&str>) -> Vec<f64> {
    use partlife::intake::{MapOrigin, Source};
    use partlife::strength::factors::FactorType;
    use partlife::strength::specimens::{Factors, read_specimens};
    let mut src = Source::file(common::root().join("datasets/real/jahanmir_silicon_nitride_bend_bars.csv"));
    src.columns.insert("strength".into(), "strength_original_units".into());
    src.units.insert("strength".into(), "MPa".into());
    src.temperature_c = Some(20.0);
    let s = read_specimens(&src, None, &Factors::Typed([("batch".to_string(), FactorType::Categorical)].into()), &MapOrigin { file: "test".into(), key: "data".into() }).unwrap();
    let levels = &s.sample.levels[0].1;
    (0..levels.len()).filter(|&i| batch.is_none_or(|b| levels[i] == b)).map(|i| s.sample.strength.x[i]).collect()
}

/// The `reliability` package on the Jahanmir bars (tests/bench/reliability/fit.py; original units):
/// two-parameter fits (set, n, m, scale, ℓ) and its mixture and competing-risks ℓ.
const PEER_JAHANMIR: [(&str, usize, f64, f64, f64); 3] = [
    ("all", 480, 10.0676399646, 682.6511127286, -2746.9904924711),
    ("1", 240, 14.0396658684, 715.7666014840, -1318.6577709147),
    ("2", 240, 9.7884258609, 639.1252312052, -1348.3423766034),
];
const PEER_JAHANMIR_FLAWS: [(&str, f64); 2] = [("mixture", -2747.0064693345), ("competing_risks", -2746.9904926052)];

#[test]
fn fits_of_the_jahanmir_bars_against_the_reliability_package() {
    use partlife::strength::flaws::{Populations, fit as fit_law};
    use partlife::strength::regress::{Design, fit};
    // ℓ in Pa = ℓ in MPa − n ln 10⁶.
    let in_mpa = |l: f64, n: usize| l + n as f64 * 1e6f64.ln();
    for (set, n, m, scale, loglik) in PEER_JAHANMIR {
        let x = jahanmir(if set == "all" { None } else { Some(set) });
        assert_eq!(x.len(), n, "{set}");
        let f = fit(Obs::exact(&x), &Design::default()).unwrap();
        assert!((in_mpa(f.loglik, n) - loglik).abs() < 1e-6, "{set}: ℓ {} vs {loglik}", in_mpa(f.loglik, n));
        assert!((f.shape() / m - 1.0).abs() < 1e-6 && (f.mu.exp() / 1e6 / scale - 1.0).abs() < 1e-6, "{set}: m {} scale {}", f.shape(), f.mu.exp());
    }
    let x = jahanmir(None);
    for (law, peer) in PEER_JAHANMIR_FLAWS {
        let f = fit_law(if law == "mixture" { Populations::Mixture } else { Populations::Competing }, Obs::exact(&x)).unwrap();
        let ours = in_mpa(f.loglik, x.len());
        eprintln!("jahanmir {law}: ours ℓ = {ours:.10} ({:?}), reliability {peer:.10}; p = {:.6}, first = ({:.6e}, {:.6}), second = ({:.6e}, {:.6})", f.identifiable, f.p, f.first.0, f.first.1, f.second.0, f.second.1);
        assert!(ours >= peer - 1e-6, "{law}: ℓ {ours} below reliability's {peer}");
        if law == "mixture" {
            // reliability's mixture collapses onto one population (p = 10⁻⁴, ℓ below even the
            // two-parameter fit's); the bimodal bars (two batches) have a far higher optimum.
            assert!(ours - peer > 10.0 && f.identifiable.is_ok(), "{f:?}");
            // The README's figures: ℓ −2728.881, 24 % of the bars in the weaker population.
            assert!((ours + 2728.8807).abs() < 1e-3 && (f.p - 0.2408).abs() < 1e-3, "{ours} {}", f.p);
        } else {
            // reliability's second risk never acts (scale 9·10⁴): its optimum is the
            // two-parameter fit. Ours is 0.40 higher with a second risk of modulus at the bound
            // 100 cutting off the strongest bars — a spike, reported as not identified.
            assert!(ours - peer > 0.3 && ours - peer < 1.0, "{ours} vs {peer}");
            assert!(f.identifiable.as_ref().is_err_and(|w| w.contains("edge")), "{:?}", f.identifiable);
        }
    }
}

/// The shipped Jahanmir study (at 99 bootstrap replicates and without the two-population
/// candidates, which cost two minutes here; the README reports the shipped run) and a lab's
/// export of the same bars: the batch's scale and then its modulus are named, the final model is
/// the two batches fitted apart (reliability's ℓ and moduli), no laboratory or machining factor
/// passes the guard, and the Weibull law still fits poorly.
#[test]
fn the_jahanmir_study_names_the_batch_and_a_lab_export_agrees() {
    let s = common::Scratch::new();
    std::fs::create_dir_all(s.path("datasets/real")).unwrap();
    std::fs::copy(common::root().join("datasets/real/jahanmir_silicon_nitride_bend_bars.csv"), s.path("datasets/real/jahanmir_silicon_nitride_bend_bars.csv")).unwrap();
    let study = std::fs::read_to_string(common::root().join("studies/strength_ceramic_jahanmir.toml")).unwrap();
    // The shipped study at 99 bootstrap replicates, and without the two-population laws (the
    // recorded factors alone).
    let fast = common::edited(&study, &[("bootstrap = 499", "bootstrap = 99"), ("permutations = 999", "permutations = 199")]);
    s.write("studies/jahanmir.toml", &fast);
    let factors_only = common::edited(&fast, &[("populations = [\"mixture\", \"competing_risks\"]", "populations = []")]);
    s.write("studies/jahanmir_factors.toml", &factors_only);
    // The lab's export: semicolon, decimal comma, German headers, strength in GPa.
    let text = s.read("datasets/real/jahanmir_silicon_nitride_bend_bars.csv");
    let mut lab = String::from("Probe;Labor;Charge;Tischvorschub;Zustellung;Körnung;Biegefestigkeit [GPa]\n");
    for line in text.lines().skip(1) {
        let v: Vec<&str> = line.split(',').collect();
        let gpa = format!("{}", v[7].parse::<f64>().unwrap() / 1000.0).replace('.', ",");
        lab.push_str(&format!("{};L{};{};{};{};{};{gpa}\n", v[0], v[2], v[3], v[4], v[5], v[6]));
    }
    s.write("datasets/real/jahanmir_lab.csv", &lab);
    let lab_study = common::edited(
        &fast,
        &[
            ("data = { file = \"../datasets/real/jahanmir_silicon_nitride_bend_bars.csv\", columns = { strength = \"strength_original_units\" }, units = { strength = \"MPa\" }, temperature_c = 20 }", "data = { file = \"../datasets/real/jahanmir_lab.csv\", columns = { strength = \"Biegefestigkeit [GPa]\", id = \"Probe\" }, temperature_c = 20 }"),
            ("factors = { lab = \"categorical\", batch = \"categorical\", table_speed = \"categorical\", down_feed_rate = \"categorical\", wheel_grit = \"categorical\" }", "factors = { Labor = \"categorical\", Charge = \"categorical\", Tischvorschub = \"categorical\", Zustellung = \"categorical\", \"Körnung\" = \"categorical\" }"),
        ],
    );
    s.write("studies/jahanmir_lab.toml", &lab_study);
    let mut runs = Vec::new();
    for name in ["jahanmir_factors", "jahanmir", "jahanmir_lab"] {
        let out = s.run(&["run", &format!("studies/{name}.toml"), "--quiet"]);
        assert_eq!(out.code, 0, "{name}: {}", out.stderr);
        assert!(common::guard_agrees_with_critical(&s.path(&format!("reports/{name}/evidence.csv")), 0.05) > 5, "{name}");
        let v: serde_json::Value = serde_json::from_str(&s.read(&format!("reports/{name}/verdict.json"))).unwrap();
        runs.push((v, s.read(&format!("reports/{name}/summary.md"))));
    }
    let (v, md) = &runs[0];
    assert_eq!(v["effects_named"]["si3n4"], serde_json::json!(["levels(batch)", "moduli(batch)"]));
    let last = v["materials"][0]["stages"].as_array().unwrap().last().unwrap().clone();
    // The final model is the batches fitted apart: ℓ (Pa) = Σ reliability's per-batch ℓ − n ln 10⁶.
    let want = PEER_JAHANMIR[1].4 + PEER_JAHANMIR[2].4 - 480.0 * 1e6f64.ln();
    assert!((last["log_likelihood"].as_f64().unwrap() - want).abs() < 1e-5, "{last}");
    assert!((last["weibull_modulus_max"].as_f64().unwrap() / PEER_JAHANMIR[1].2 - 1.0).abs() < 1e-6 && (last["weibull_modulus_min"].as_f64().unwrap() / PEER_JAHANMIR[2].2 - 1.0).abs() < 1e-6, "{last}");
    assert!(last["p_anderson_darling"].as_f64().unwrap() < 0.05, "{last}");
    assert!(md.contains("**The Weibull law fits these data poorly**") && md.contains("even with the named effects"), "{md}");
    assert!(md.contains("Weibull modulus of each level of `batch`: 1 14.04, 2 9.79"), "{md}");
    assert!(md.contains("σ_θ of each level of `batch` relative to \"1\" (the level with the most specimens; among equals the first in the file): 1 ×1.000, 2 ×0.905"), "{md}");
    // The numbers the README reports that do not depend on the bootstrap count: Λ and ΔBIC of
    // the named candidates, the gap before and after.
    let ev = v["evidence"]["si3n4"].as_array().unwrap();
    let at = |round: u64, name: &str| ev.iter().find(|e| e["round"].as_u64() == Some(round) && e["candidate"] == name).unwrap().clone();
    let (batch, moduli) = (at(0, "levels(batch)"), at(1, "moduli(batch)"));
    assert!((batch["likelihood_ratio"].as_f64().unwrap() - 132.73).abs() < 0.005 && (batch["delta_bic"].as_f64().unwrap() + 126.55).abs() < 0.005, "{batch}");
    assert!((moduli["likelihood_ratio"].as_f64().unwrap() - 27.26).abs() < 0.005, "{moduli}");
    assert!((v["gap_before"]["si3n4"].as_f64().unwrap() - 194.3).abs() < 0.05 && (v["gap_after"]["si3n4"].as_f64().unwrap() - 53.9).abs() < 0.05, "{}", v["gap_after"]);
    assert_eq!(v["gap_before"]["si3n4"], runs[2].0["gap_before"]["si3n4"]);
    // With the two-population laws (the shipped study): after the batch's scale a mixture beside
    // it explains the lower tail better than a modulus per batch (Λ 62.2 against 27.3), and then
    // the table speed's scale; the final model fits (bootstrap AD p > 0.05).
    let (p, md) = &runs[1];
    assert_eq!(p["effects_named"]["si3n4"], serde_json::json!(["levels(batch)", "mixture", "levels(table_speed)"]));
    let last = p["materials"][0]["stages"].as_array().unwrap().last().unwrap().clone();
    assert!(last["p_anderson_darling"].as_f64().unwrap() > 0.05, "{last}");
    let ev = p["evidence"]["si3n4"].as_array().unwrap();
    let at = |round: u64, name: &str| ev.iter().find(|e| e["round"].as_u64() == Some(round) && e["candidate"] == name).unwrap().clone();
    let (mixture, moduli) = (at(1, "mixture"), at(1, "moduli(batch)"));
    assert!((mixture["likelihood_ratio"].as_f64().unwrap() - 62.15).abs() < 0.01 && (moduli["likelihood_ratio"].as_f64().unwrap() - 27.26).abs() < 0.005, "{mixture} {moduli}");
    assert!(md.contains("scales at the reference of the scale effects beside the law"), "{md}");
    assert!(!md.contains("**The Weibull law fits these data poorly**"), "{md}");
    // Its lab export: the same verdict under the lab's names, the same final ℓ.
    let (l, _) = &runs[2];
    assert_eq!(l["effects_named"]["si3n4"], serde_json::json!(["levels(Charge)", "mixture", "levels(Tischvorschub)"]));
    let ll = l["materials"][0]["stages"].as_array().unwrap().last().unwrap()["log_likelihood"].as_f64().unwrap();
    assert!((ll - last["log_likelihood"].as_f64().unwrap()).abs() < 1e-6, "{ll} vs {}", last["log_likelihood"]);
}
