//! The discrepancy workflow on data with hidden effects (issue 7, item 6), end to end: the data
//! are made by `partlife datasets synth` with an effect switched on in the generator, and
//! `partlife discrepancy --data` (the Weibull–Hertz model, which lacks every effect) must name it
//! and shrink the gap. The false-positive rate uses the same generator through the library.

mod common;

use common::{Scratch, bl_generator as settings, root};
use partlife::contact::{ContactOptions, Elastic};
use partlife::discrepancy::workflow::names;
use partlife::strength::{Effect, NamingSettings, sample_of};
use partlife::synth::{SynthSettings, generate};

/// Generates with the CLI, runs `partlife discrepancy --data`, returns the verdict.
fn verdict_of(s: &Scratch, generator: &str) -> serde_json::Value {
    verdict_with(s, generator, &[])
}

/// [`verdict_of`] with more arguments of `partlife discrepancy`.
fn verdict_with(s: &Scratch, generator: &str, more: &[&str]) -> serde_json::Value {
    s.write("datasets/hidden.toml", generator);
    let out = s.run(&["datasets", "synth", "--settings", "datasets/hidden.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let mut args = vec!["discrepancy", "--data", "datasets/hidden.csv", "--youngs-modulus-pa", "112e9", "--poisson-ratio", "0.25", "--density-kg-m3", "3600", "--quiet"];
    args.extend(more);
    let out = s.run(&args);
    assert_eq!(out.code, 0, "{}", out.stderr);
    serde_json::from_str(&s.read("reports/discrepancy-hidden/verdict.json")).unwrap()
}

fn named(v: &serde_json::Value) -> Vec<String> {
    v["effects_named"]["hidden"].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect()
}

fn gaps(v: &serde_json::Value) -> (f64, f64) {
    (v["gap_before"]["hidden"].as_f64().unwrap(), v["gap_after"]["hidden"].as_f64().unwrap())
}

fn modulus(v: &serde_json::Value, stage: usize) -> f64 {
    v["materials"][0]["stages"][stage]["weibull_modulus"].as_f64().unwrap()
}

#[test]
fn hidden_roundness_is_named_and_the_gap_halves() {
    let s = Scratch::new();
    let v = verdict_of(&s, &settings(1.0, 0.0, 60, 71, "20.0", ""));
    // Named first. (This seed also adds sphericity in round 2 at p_family = 0.034: a false
    // discovery after the true effect, which the guard allows at 5 %; its rate is checked
    // below over 40 seeds.)
    assert_eq!(named(&v)[0], "roundness", "{}", v["evidence"]);
    let (before, after) = gaps(&v);
    assert!(after <= 0.5 * before, "gap {before} → {after}");
    // The modulus rises once the roundness scatter is explained (truth m = 22).
    let (m0, m1) = (modulus(&v, 0), modulus(&v, 1));
    assert!(m1 > m0 + 2.0 && (m1 - 22.0).abs() < 7.0, "m {m0} → {m1}");
    // The fitted curvature exponent covers the truth q = 1 within 3 standard errors.
    let e = v["evidence"]["hidden"].as_array().unwrap().iter().find(|e| e["named"] == true).unwrap();
    let (q, se) = (e["parameter"]["value"].as_f64().unwrap(), e["parameter"]["se"].as_f64().unwrap());
    assert!((q - 1.0).abs() < 3.0 * se, "q = {q} ± {se}");
    // Every figure of the report exists in the three formats.
    for f in ["discrepancy_residuals_hidden", "discrepancy_probability_hidden", "discrepancy_gap", "discrepancy_evidence", "discrepancy_lifetime", "discrepancy_power"] {
        for ext in ["svg", "png", "pdf"] {
            assert!(s.path(&format!("reports/discrepancy-hidden/{f}.{ext}")).is_file(), "{f}.{ext}");
        }
    }
}

#[test]
fn hidden_size_effect_is_named() {
    let s = Scratch::new();
    // The material's name in the report from the command line (else the file's material column).
    let v = verdict_with(&s, &settings(0.0, 0.5, 60, 72, "20.0", ""), &["--label", "BL 16/30 Charge 7"]);
    assert_eq!(named(&v), ["size"], "{}", v["evidence"]);
    assert!(s.read("reports/discrepancy-hidden/summary.md").contains("**BL 16/30 Charge 7** (60 particles)"));
    let (before, after) = gaps(&v);
    assert!(after <= 0.5 * before, "gap {before} → {after}");
}

#[test]
fn two_hidden_effects_are_named_in_order_of_strength() {
    // ln-scale spread of the size effect 0.5 · sd(ln d) ≈ 0.079 against (2/3) · sd(ln r) ≈ 0.046
    // for roundness: size is the stronger and must come first.
    let s = Scratch::new();
    let v = verdict_of(&s, &settings(1.0, 0.5, 60, 73, "20.0", ""));
    assert_eq!(named(&v), ["size", "roundness"], "{}", v["evidence"]);
    let (before, after) = gaps(&v);
    assert!(after <= 0.5 * before, "gap {before} → {after}");
}

#[test]
fn temperatures_mixed_in_one_file_are_named() {
    let s = Scratch::new();
    let soft = "softening = { reference_c = 20.0, strength_per_100c = 0.04, stiffness_per_100c = 0.03 }";
    // Without the temperature the lifetime is for: refused before the loop runs.
    s.write("datasets/hidden.toml", &settings(0.0, 0.0, 60, 74, "[20.0, 800.0]", soft));
    assert_eq!(s.run(&["datasets", "synth", "--settings", "datasets/hidden.toml"]).code, 0);
    let out = s.run(&["discrepancy", "--data", "datasets/hidden.csv", "--youngs-modulus-pa", "112e9", "--poisson-ratio", "0.25", "--density-kg-m3", "3600", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("--operating-temperature-c") && out.stderr.contains("20 °C (30) and 800 °C (30)"), "{}", out.stderr);
    let v = verdict_with(&s, &settings(0.0, 0.0, 60, 74, "[20.0, 800.0]", soft), &["--operating-temperature-c", "800"]);
    assert_eq!(named(&v), ["temperature"], "{}", v["evidence"]);
    // The report says where the particles were tested and what the lifetime after it is for.
    let summary = s.read("reports/discrepancy-hidden/summary.md");
    assert!(summary.contains("Tested at 20 °C (30) and 800 °C (30). Its lifetime after the named effects is at the study's predict.temperature_c = 800"), "{summary}");
    let e = v["evidence"]["hidden"].as_array().unwrap().iter().find(|e| e["named"] == true).unwrap();
    let per_100 = e["parameter"]["value"].as_f64().unwrap();
    assert!(per_100 < 1.0, "strength falls with temperature: {}", e["parameter"]);
    // The rate per 100 °C turned into what it means at the operating temperature.
    let at = format!("strength × {per_100:.3} per 100 °C; at the study's operating temperature, 800 °C, the strength is × {:.3} of its strength at 20 °C.", per_100.powf(7.8));
    assert!(summary.contains(&at), "{at}\n{summary}");
}

/// Runs the naming loop on `seeds` datasets with roundness hidden at exponent `q` (0: nothing
/// hidden); returns how many named anything other than roundness.
fn false_positives(seeds: std::ops::Range<u64>, count: usize, q: f64) -> usize {
    let text = settings(q, 0.0, count, 0, "20.0", "");
    let mut generator: SynthSettings = toml::from_str(&text).unwrap();
    let elastic = Elastic { youngs_modulus_pa: 112e9, poisson_ratio: 0.25 };
    let mut hits = 0;
    for seed in seeds {
        generator.seed = 5000 + seed;
        let records = generate(&generator, 0).unwrap().into_iter().map(|p| p.record).collect();
        let data = partlife::data::CrushData::new("hidden.csv", records);
        let sample = sample_of(&data, &elastic, &ContactOptions::default()).unwrap();
        let named = names(&sample, &NamingSettings { bootstrap: 199, seed, ..NamingSettings::default() }).unwrap();
        hits += usize::from(named.iter().any(|c| *c != Effect::Roundness));
    }
    hits
}

/// The sequential bootstrap (a round stops at 99 or 199 of its 499 replicates once every
/// decision is settled) names what drawing all 499 names. Over 40 campaigns of 50 particles
/// with roundness hidden weakly (exponent 0.5: named in some campaigns, not in others, so
/// decisions near α occur), both name the same effects in at least 39, and the sequential
/// loop draws under 60 % of the replicates. Fails if the pretest stopped on unsettled
/// decisions, or never stopped early.
#[test]
fn the_sequential_bootstrap_names_what_drawing_every_replicate_names() {
    let text = settings(0.5, 0.0, 50, 0, "20.0", "");
    let mut generator: SynthSettings = toml::from_str(&text).unwrap();
    let elastic = Elastic { youngs_modulus_pa: 112e9, poisson_ratio: 0.25 };
    let (mut agree, mut named, mut drawn, mut every) = (0, 0, 0, 0);
    for seed in 0..40u64 {
        generator.seed = 8100 + seed;
        let records = generate(&generator, 0).unwrap().into_iter().map(|p| p.record).collect();
        let data = partlife::data::CrushData::new("hidden.csv", records);
        let sample = sample_of(&data, &elastic, &ContactOptions::default()).unwrap();
        let run = |sequential: bool| partlife::discrepancy::workflow::decide(&sample, &NamingSettings { seed, sequential, ..NamingSettings::default() }).unwrap();
        let (a, b) = (run(true), run(false));
        agree += usize::from(a.named == b.named);
        named += usize::from(!b.named.is_empty());
        drawn += a.stages.iter().map(|st| st.replicates).sum::<usize>();
        every += b.stages.iter().map(|st| st.replicates).sum::<usize>();
        // Every evidence row's p comes from the replicates its round drew.
        assert!(a.evidence.iter().filter(|e| e.skipped.is_none()).all(|e| e.replicates == a.stages[e.round].replicates));
        // A round that drew every replicate says which decision made it; one that stopped
        // early, and every round drawn in full by choice, says nothing.
        for st in &a.stages {
            assert_eq!(st.unsettled.is_some(), st.replicates == 499, "{} replicates: {:?}", st.replicates, st.unsettled);
            assert!(st.unsettled.as_ref().is_none_or(|w| (w.starts_with("at 199 replicates ") || w.starts_with("at 499 replicates ")) && w.contains("near")), "{:?}", st.unsettled);
        }
        assert!(b.stages.iter().all(|st| st.unsettled.is_none()));
    }
    eprintln!("sequential against every replicate: same names in {agree} of 40 (all 499 named something in {named}); replicates drawn {drawn} of {every}");
    assert!(agree >= 39, "same names in {agree} of 40");
    assert!((5..=35).contains(&named), "the weak effect should be named in some campaigns and not in others: {named} of 40");
    assert!((drawn as f64) < 0.6 * every as f64, "drawn {drawn} of {every}");
}

/// The two family-wise guards on one sweep of campaigns (`count` particles, roundness hidden
/// at exponent `q`, seeds 8100 + `seeds`), with or without the two-population laws offered:
/// per guard (min-P, max-T), how many campaigns name roundness, and how many name anything
/// else.
fn power_by_guard(seeds: std::ops::Range<u64>, count: usize, q: f64, laws: bool) -> [(usize, usize); 2] {
    use partlife::strength::FamilyGuard;
    use partlife::strength::flaws::Populations;
    let mut generator: SynthSettings = toml::from_str(&settings(q, 0.0, count, 0, "20.0", "")).unwrap();
    let elastic = Elastic { youngs_modulus_pa: 112e9, poisson_ratio: 0.25 };
    let mut out = [(0, 0); 2];
    for seed in seeds {
        generator.seed = 8100 + seed;
        let records = generate(&generator, 0).unwrap().into_iter().map(|p| p.record).collect();
        let data = partlife::data::CrushData::new("hidden.csv", records);
        let mut sample = sample_of(&data, &elastic, &ContactOptions::default()).unwrap();
        if laws {
            sample.populations = vec![Populations::Mixture, Populations::Competing];
        }
        for (k, guard) in [FamilyGuard::MinP, FamilyGuard::MaxT].into_iter().enumerate() {
            let named = names(&sample, &NamingSettings { seed, guard, ..NamingSettings::default() }).unwrap();
            out[k].0 += usize::from(named.contains(&Effect::Roundness));
            out[k].1 += usize::from(named.iter().any(|c| *c != Effect::Roundness));
        }
    }
    out
}

/// Issue 53, item 5: the power change of min-P against max-T on the weak hidden-roundness
/// sweep (40 campaigns of 50 particles, exponent 0.5), with and without the two-population laws
/// offered. Measured (29 Nov 2026): roundness named in 29 and 29 of 40 without the laws, 28 and 28
/// with them; other effects named in 3 and 2, 1 and 1. Min-P moves each candidate's bar — the
/// factors' down, the laws' up — but on this sweep names as often as max-T. Fails if min-P loses
/// power (more than 2 campaigns fewer) or names other effects in more than 4 of 40.
#[test]
#[ignore = "slow: 160 naming loops of 50 particles, half of them with both two-population laws (about 3 min on 2 cores); the guard's unit tests show the mechanism fast"]
fn min_p_names_the_hidden_roundness_as_often_as_max_t() {
    let plain = power_by_guard(0..40, 50, 0.5, false);
    let laws = power_by_guard(0..40, 50, 0.5, true);
    eprintln!("roundness named of 40 (other effects named): without the laws min-P {} ({}), max-T {} ({}); with the laws min-P {} ({}), max-T {} ({})", plain[0].0, plain[0].1, plain[1].0, plain[1].1, laws[0].0, laws[0].1, laws[1].0, laws[1].1);
    for (what, r) in [("without the laws", plain), ("with the laws", laws)] {
        assert!(r[0].0 + 2 >= r[1].0, "{what}: min-P names roundness in {} of 40, max-T in {}", r[0].0, r[1].0);
        assert!(r[0].1 <= 4, "{what}: min-P names another effect in {} of 40", r[0].1);
    }
}

#[test]
fn nothing_hidden_names_nothing_in_at_least_95_percent_of_40_seeds() {
    let fp = false_positives(0..40, 50, 0.0);
    assert!(fp <= 2, "{fp} of 40 datasets without a hidden effect had one named");
}

#[test]
fn after_the_hidden_effect_no_spurious_one_is_added_in_at_least_95_percent_of_40_seeds() {
    let fp = false_positives(100..140, 50, 1.0);
    assert!(fp <= 2, "{fp} of 40 datasets with roundness hidden had another effect named");
}

#[test]
fn false_positive_rate_over_400_seeds_is_at_the_guard_level() {
    let fp = false_positives(1000..1400, 50, 0.0);
    let rate = fp as f64 / 400.0;
    eprintln!("false-positive rate over 400 seeds: {fp}/400 = {rate:.4}");
    // 5 % plus two binomial standard errors at n = 400.
    assert!(rate <= 0.05 + 2.0 * (0.05f64 * 0.95 / 400.0).sqrt(), "false-positive rate {rate}");
}

/// The guard's size: over null campaigns (the generator with no hidden effect, `count`
/// particles), the share whose smallest family-wise p of round 0 is below α = 0.05, with the
/// particle candidates alone or with the two-population laws offered too (`laws`).
fn round_zero_size(seeds: std::ops::Range<u64>, count: usize, laws: bool, bootstrap: usize) -> (usize, usize) {
    use partlife::strength::flaws::Populations;
    let mut generator: SynthSettings = toml::from_str(&settings(0.0, 0.0, count, 0, "20.0", "")).unwrap();
    let elastic = Elastic { youngs_modulus_pa: 112e9, poisson_ratio: 0.25 };
    let (mut below, mut campaigns) = (0, 0);
    for seed in seeds {
        generator.seed = 70_000 + seed;
        let records = generate(&generator, 0).unwrap().into_iter().map(|p| p.record).collect();
        let data = partlife::data::CrushData::new("null.csv", records);
        let mut sample = sample_of(&data, &elastic, &ContactOptions::default()).unwrap();
        if laws {
            sample.populations = vec![Populations::Mixture, Populations::Competing];
        }
        let outcome = partlife::discrepancy::workflow::decide(&sample, &NamingSettings { bootstrap, seed, max_effects: 1, ..NamingSettings::default() }).unwrap();
        let p = outcome.evidence.iter().filter(|e| e.round == 0 && e.p_family.is_finite()).map(|e| e.p_family).fold(1.0, f64::min);
        below += usize::from(p < 0.05);
        campaigns += 1;
    }
    (below, campaigns)
}

/// Issue 53's size test: over 200 null campaigns of 60 particles the round-0 smallest family p
/// falls below 0.05 in 2–9 % of them, with and without the two-population laws offered (whose
/// likelihood ratio does not follow Wilks' χ²: the bootstrap must calibrate it). Measured with
/// the default min-P guard (29 Nov 2026): 15 and 14 of 200; with max-T before it, 14 and 15.
#[test]
#[ignore = "slow: 400 naming loops at 199 bootstrap replicates (about 2 min on 2 cores); the fast sibling runs 30 campaigns with the laws"]
fn the_guard_s_size_over_200_null_campaigns_is_near_alpha_with_and_without_the_laws() {
    for laws in [false, true] {
        let (below, n) = round_zero_size(0..200, 60, laws, 199);
        eprintln!("round-0 size, laws offered {laws}: {below} of {n} campaigns = {:.3}", below as f64 / n as f64);
        assert!((4..=18).contains(&below), "laws offered {laws}: {below} of {n} null campaigns below α");
    }
}

/// Fast sibling: 30 null campaigns with the two-population laws offered, 99 replicates; at a
/// size of 5 % six or more below α happen with probability 0.016.
#[test]
fn the_guard_with_the_laws_offered_rarely_fires_on_null_campaigns() {
    let (below, n) = round_zero_size(500..530, 60, true, 99);
    eprintln!("round-0 size with the laws offered: {below} of {n}");
    assert!(below <= 5, "{below} of {n} null campaigns below α with the laws offered");
}

#[test]
fn missing_covariates_skip_their_candidates_and_few_particles_are_refused() {
    let s = Scratch::new();
    // No roundness and sphericity columns: those candidates are skipped with the reason.
    let text = std::fs::read_to_string(root().join("datasets/crush_gen4.csv")).unwrap();
    let stripped: String = text
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            format!("{},{},{},{},{}\n", f[0], f[1], f[2], f[3], f[6])
        })
        .collect();
    s.write("datasets/bare.csv", &stripped);
    let out = s.run(&["discrepancy", "--data", "datasets/bare.csv", "--youngs-modulus-pa", "112e9", "--poisson-ratio", "0.25", "--density-kg-m3", "3600", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: serde_json::Value = serde_json::from_str(&s.read("reports/discrepancy-bare/verdict.json")).unwrap();
    // The lifetime's material constants are the ones given, stated in the summary.
    assert!(s.read("reports/discrepancy-bare/summary.md").contains("particles with E = 112 GPa, ν = 0.25, ρ = 3600 kg/m³"));
    let ev = v["evidence"]["bare"].as_array().unwrap();
    for c in ["roundness", "sphericity"] {
        let e = ev.iter().find(|e| e["candidate"] == c).unwrap();
        assert!(e["skipped"].as_str().unwrap().contains(&format!("no `{c}` values")), "{e}");
    }
    // Without the particles' constants no material is assumed (before, Gen 4's were, silently):
    // refused naming the options missing.
    let out = s.run(&["discrepancy", "--data", "datasets/bare.csv", "--youngs-modulus-pa", "90e9", "--quiet", "--reports-dir", "other"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("--poisson-ratio, --density-kg-m3") && out.stderr.contains("no material is assumed"), "{}", out.stderr);
    assert!(!s.path("other").exists());
    // Nine particles: refused, exit 2, nothing written.
    let nine: String = text.lines().take(10).map(|l| format!("{l}\n")).collect();
    s.write("datasets/nine.csv", &nine);
    let out = s.run(&["discrepancy", "--data", "datasets/nine.csv", "--youngs-modulus-pa", "112e9", "--poisson-ratio", "0.25", "--density-kg-m3", "3600", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("nine.csv") && out.stderr.contains("too few"), "{}", out.stderr);
    assert!(!s.path("reports/discrepancy-nine").exists());
    // A non-finite value: exit 2 naming the file, row and column.
    let bad = text.replacen("0.853", "inf", 1);
    s.write("datasets/bad.csv", &bad);
    let out = s.run(&["discrepancy", "--data", "datasets/bad.csv", "--youngs-modulus-pa", "112e9", "--poisson-ratio", "0.25", "--density-kg-m3", "3600", "--quiet"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("bad.csv") && out.stderr.contains("row 1") && out.stderr.contains("roundness"), "{}", out.stderr);
    assert!(!out.stderr.contains("panicked"));
}

#[test]
fn shipped_crush_data_reveal_the_generators_hidden_effects() {
    // datasets/synth_crush.toml hides a size effect (α = 0.5) and roundness curvature (q = 1) in
    // both files; Gen 4's modulus 8.5 leaves its roundness effect below the 45-particle power.
    let s = Scratch::new();
    s.write("studies/discrepancy_crush.toml", &std::fs::read_to_string(root().join("studies/discrepancy_crush.toml")).unwrap());
    // The one-thread run for the determinism check below, side by side with the first (the
    // one-thread run would otherwise leave a core idle for its whole length).
    let t = Scratch::new();
    t.write("studies/discrepancy_crush.toml", &s.read("studies/discrepancy_crush.toml"));
    let one_thread = std::thread::scope(|scope| {
        let h = scope.spawn(|| t.run(&["discrepancy", "studies/discrepancy_crush.toml", "--quiet", "--threads", "1"]));
        let out = s.run(&["discrepancy", "studies/discrepancy_crush.toml", "--quiet"]);
        assert_eq!(out.code, 0, "{}", out.stderr);
        h.join().unwrap()
    });
    let v: serde_json::Value = serde_json::from_str(&s.read("reports/discrepancy_crush/verdict.json")).unwrap();
    assert_eq!(v["effects_named"]["bl1630"], serde_json::json!(["size", "roundness"]));
    assert_eq!(v["effects_named"]["gen4"][0], "size");
    for k in ["bl1630", "gen4"] {
        let (b, a) = (v["gap_before"][k].as_f64().unwrap(), v["gap_after"][k].as_f64().unwrap());
        assert!(a < 0.5 * b, "{k}: gap {b} → {a}");
    }
    let manifest: serde_json::Value = serde_json::from_str(&s.read("reports/discrepancy_crush/manifest.json")).unwrap();
    assert_eq!(manifest["failures"].as_array().map(|f| f.len()), Some(0), "{}", manifest["failures"]);
    // The report opens with the answer — per material, the effects named with the family-wise p
    // that named each (at its floor 1/(B + 1) written "≤"), and whether the Weibull law fits
    // once they are in (the final stage's AD and KS p) — and shows the evidence figure.
    let summary = s.read("reports/discrepancy_crush/summary.md");
    let ev = s.path("reports/discrepancy_crush/evidence.csv");
    let (mat, cand, pf, reps, named) = (common::table_text(&ev, "material"), common::table_text(&ev, "candidate"), common::table_f64(&ev, "p_family"), common::table_f64(&ev, "bootstrap_replicates"), common::table_text(&ev, "named"));
    let st = s.path("reports/discrepancy_crush/stages.csv");
    let (st_mat, p_ad, p_ks, st_reps) = (common::table_text(&st, "material"), common::table_f64(&st, "p_anderson_darling"), common::table_f64(&st, "p_kolmogorov_smirnov"), common::table_f64(&st, "bootstrap_replicates"));
    for (key, label, n) in [("bl1630", "BL 16/30", 50), ("gen4", "Gen 4", 45)] {
        let parts: Vec<String> = (0..mat.len())
            .filter(|&i| mat[i] == key && named[i] == "true")
            .map(|i| {
                let p = if pf[i] <= 1.0 / (reps[i] + 1.0) + 1e-12 { format!("≤ {:.3}", pf[i]) } else { format!("{:.3}", pf[i]) };
                format!("`{}` (family-wise p {p})", cand[i])
            })
            .collect();
        let (first, last) = ((0..st_mat.len()).find(|&i| st_mat[i] == key).unwrap(), (0..st_mat.len()).rfind(|&i| st_mat[i] == key).unwrap());
        let below = |p: f64| if p < 0.05 { " (below 0.05)" } else { "" };
        let fit_at = |i: usize| p_ad[i] >= 0.05 && p_ks[i] >= 0.05;
        let fits = if fit_at(last) { "fits these data" } else { "fits these data poorly" };
        // "as without" where the base model's verdict was the same.
        let with = format!("{}{}", if parts.len() == 1 { "with it" } else { "with them" }, if fit_at(first) == fit_at(last) { ", as without," } else { "" });
        // A p at its floor 1/(B + 1) reads "≤".
        let eq = |p: f64| if p <= 1.0 / (st_reps[last] + 1.0) + 1e-12 { format!("≤ {p:.3}") } else { format!("= {p:.3}") };
        let sentence = format!("**{label}** ({n} particles): the Weibull–Hertz model misses {}; {with} the Weibull law {fits} (Anderson–Darling p {}{}, Kolmogorov–Smirnov p {}{}", parts.join(", then "), eq(p_ad[last]), below(p_ad[last]), eq(p_ks[last]), below(p_ks[last]));
        assert!(summary.contains(&format!("## Answer\n\n* **BL 16/30**")) && summary.contains(&sentence), "{sentence}\n{summary}");
    }
    // The power table's comment: the false positives over every size, from power.csv, against α.
    let pw = s.path("reports/discrepancy_crush/power.csv");
    let (pw_mat, scen, reps_pw, rate) = (common::table_text(&pw, "material"), common::table_text(&pw, "scenario"), common::table_f64(&pw, "replicates"), common::table_f64(&pw, "rate_all"));
    let none: Vec<usize> = (0..pw_mat.len()).filter(|&i| pw_mat[i] == "bl1630" && scen[i] == "none").collect();
    let (k, n) = (none.iter().map(|&i| (rate[i] * reps_pw[i]).round() as usize).sum::<usize>(), none.iter().map(|&i| reps_pw[i] as usize).sum::<usize>());
    assert!(n > 0 && summary.contains(&format!("With no effect in the data the loop named one in {k} of {n} datasets over all sizes")), "{k} of {n}\n{summary}");
    let (page, figures) = common::first_page(&s.path("reports/discrepancy_crush"));
    // Size, named first for BL 16/30, with no replicate reaching its Λ: p at its floor 1/(B + 1)
    // of the replicates its round drew.
    let size = (0..mat.len()).find(|&i| mat[i] == "bl1630" && cand[i] == "size" && named[i] == "true").unwrap();
    assert!(page.contains(&format!("BL 16/30 (50 particles): the Weibull–Hertz model misses size (family-wise p ≤ {:.3})", 1.0 / (reps[size] + 1.0))), "{page}");
    // The answer comes before the method's paragraphs, which have their own section.
    assert!(summary.find("## Answer").unwrap() < summary.find("## How the workflow decides").unwrap(), "{summary}");
    assert_eq!(figures, ["discrepancy_evidence"]);
    // The gap's expectation with nothing missing is each round's own (its bootstrap mean): near
    // Σ df for the base model, which fits no covariate, and below it once effects are fitted
    // (a fitted covariate's term falls near 0; before, Σ df was written for every round). Each
    // is a Monte Carlo mean over the 99–499 replicates its round drew, with an error of about
    // √(2 Σdf / B) ≈ 0.15–0.25 here, so every later round lies below Σ df and their mean falls
    // below it by more than 0.5.
    let stages = s.path("reports/discrepancy_crush/stages.csv");
    let (round, expected, df) = (common::table_f64(&stages, "round"), common::table_f64(&stages, "gap_expected"), common::table_f64(&stages, "gap_degrees_of_freedom"));
    let mut later = Vec::new();
    for i in 0..round.len() {
        if round[i] == 0.0 {
            assert!((expected[i] - df[i]).abs() < 0.25 * df[i], "base model: expected G {} against Σ df {}", expected[i], df[i]);
        } else {
            assert!(expected[i] < df[i], "round {}: expected G {} against Σ df {}", round[i], expected[i], df[i]);
            later.push(expected[i] - df[i]);
        }
    }
    let mean = later.iter().sum::<f64>() / later.len() as f64;
    assert!(later.len() >= 3 && mean < -0.5, "after the base model, expected G less Σ df: {later:?}");
    // The printed critical Λ is the decision's (the study's α is 0.05).
    assert!(common::guard_agrees_with_critical(&s.path("reports/discrepancy_crush/evidence.csv"), 0.05) > 10);
    // The power-vs-sample-size figure is in the report; power rises with the number of tests.
    assert!(s.path("reports/discrepancy_crush/discrepancy_power.pdf").is_file());
    let p = partlife::io::read_table(&s.path("reports/discrepancy_crush/power.csv")).unwrap();
    let path = s.path("reports/discrepancy_crush/power.csv");
    let (sc, rate) = (partlife::io::col_str(&p, &path, "scenario").unwrap(), partlife::io::col_f64(&p, &path, "rate_all").unwrap());
    let eff: Vec<f64> = (0..sc.len()).filter(|&i| sc[i] == "effects").map(|i| rate[i]).collect();
    assert!(eff.len() == 8 && eff[0] < eff[3] && eff[3] >= 0.9 && eff[4] < eff[7], "{eff:?}");
    // Every figure of the document has a caption read from its numbers; the power figure's gives
    // the first material's rate at the fewest particles, as the table holds it.
    let captions = common::figure_captions(&s.path("reports/discrepancy_crush"));
    let (_, power) = captions.iter().find(|(stem, _)| stem == "discrepancy_power").expect("a power caption");
    // The evidence figure numbers its rounds as the caption and evidence.csv do (from 0), and
    // where it numbers the candidates the caption says which is which.
    let (_, evidence) = captions.iter().find(|(stem, _)| stem == "discrepancy_evidence").expect("an evidence caption");
    let svg = s.read("reports/discrepancy_crush/discrepancy_evidence.svg");
    assert!(svg.contains("round 0 Λ") && svg.contains("round 0 critical") && evidence.contains("round 0"), "{evidence}");
    assert_eq!(svg.contains("Candidate (numbered"), evidence.contains("Candidates by number on the axis — "), "{evidence}");
    assert!(power.contains(&format!("in {} of the data sets at 20 particles", partlife::report::captions::percent(eff[0]))), "{power}");
    // Redrawn from the tables alone: the same figures.
    let before = s.read("reports/discrepancy_crush/discrepancy_gap.svg");
    let out = s.run(&["report", "discrepancy_crush"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert_eq!(before, s.read("reports/discrepancy_crush/discrepancy_gap.svg"));
    // Deterministic on one thread too.
    assert_eq!(one_thread.code, 0, "{}", one_thread.stderr);
    for f in ["verdict.json", "evidence.csv", "stages.csv", "power.csv", "lifetime.csv", "residuals.csv"] {
        let a = s.read(&format!("reports/discrepancy_crush/{f}"));
        let b = t.read(&format!("reports/discrepancy_crush/{f}"));
        assert_eq!(a, b, "{f} differs between 2 threads and 1");
    }
}

#[test]
fn damage_from_prior_impacts_is_named_and_its_ratio_recovered() {
    // Up to 100 impacts at E_k/E_m = 0.1 before the crush test (Tavares–King, γ = 5): the most
    // impacted particles keep 80 % of their strength. The counts are in the `impacts` column.
    // Run as a study without the power part: refitting the damage ratio by profile likelihood
    // in every bootstrap replicate makes the 320-dataset power study take about 2 min here,
    // against 1.8 s for the naming loop and the lifetime bands.
    let s = Scratch::new();
    let damage = "prior_impacts = { max = 100, ratio = 0.1, gamma = 5.0 }";
    s.write("datasets/hidden.toml", &settings(0.0, 0.0, 60, 75, "20.0", damage));
    assert_eq!(s.run(&["datasets", "synth", "--settings", "datasets/hidden.toml"]).code, 0);
    let study = std::fs::read_to_string(root().join("studies/discrepancy_crush.toml")).unwrap();
    let study = common::edited(&study[..study.find("[[material]]").unwrap()], &[("replicates = 40", "replicates = 0")]);
    s.write("studies/damage.toml", &format!("{study}[[material]]\nkey = \"hidden\"\nlabel = \"BL 16/30\"\ndata = \"../datasets/hidden.csv\"\nelastic = {{ youngs_modulus_pa = 112e9, poisson_ratio = 0.25 }}\ndensity_kg_m3 = 3060\n"));
    let out = s.run(&["discrepancy", "studies/damage.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: serde_json::Value = serde_json::from_str(&s.read("reports/damage/verdict.json")).unwrap();
    assert_eq!(named(&v), ["damage"], "{}", v["evidence"]);
    let e = v["evidence"]["hidden"].as_array().unwrap().iter().find(|e| e["named"] == true).unwrap();
    let x = e["parameter"]["value"].as_f64().unwrap();
    assert!((x / 0.1 - 1.0).abs() < 0.3, "ratio {x}");
    let (before, after) = gaps(&v);
    assert!(after <= 0.5 * before, "gap {before} → {after}");
}
