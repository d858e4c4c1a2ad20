//! The experiments study end to end (fewer samples than the shipped study) and its bad inputs.

mod common;
use common::{Scratch, edited, root};

/// A scratch project with the main study and the experiments study, the latter made fast.
fn scratch() -> Scratch {
    let s = Scratch::new();
    for f in ["gen4_vs_bl.toml", "experiments.toml"] {
        std::fs::copy(root().join("studies").join(f), s.path("studies").join(f)).unwrap();
    }
    let text = s.read("studies/experiments.toml");
    s.write(
        "studies/experiments.toml",
        &edited(&text, &[("samples = 4000", "samples = 1500"), ("reserve = 4000", "reserve = 1500"), ("outer = 300", "outer = 60"), ("sizes = [5, 20, 50]", "sizes = [5, 50]")]),
    );
    s
}

#[test]
fn experiments_study_writes_ranked_plans_allocation_summary_and_figure() {
    let s = scratch();
    let out = s.run(&["run", "studies/experiments.toml", "--quiet"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let dir = s.path("reports/experiments");
    for f in ["plans.csv", "allocation.csv", "prior.csv", "materials.csv", "damage_models.csv", "summary.md", "manifest.json"] {
        assert!(dir.join(f).is_file(), "missing {f}");
    }
    for ext in ["svg", "png", "pdf"] {
        assert!(dir.join(format!("experiments_metrics.{ext}")).is_file());
    }
    let pdf = String::from_utf8_lossy(&std::fs::read(dir.join("experiments_metrics.pdf")).unwrap()).into_owned();
    assert!(pdf.contains("/FontFile2"), "the PDF embeds no font");
    // Every candidate at every size, ranked 1..n by objective per cost.
    let p = dir.join("plans.csv");
    let df = partlife::io::read_table(&p).unwrap();
    let (rank, obj, cost) = (partlife::io::col_f64(&df, &p, "rank").unwrap(), partlife::io::col_f64(&df, &p, "objective").unwrap(), partlife::io::col_f64(&df, &p, "cost").unwrap());
    assert_eq!(rank.len(), 2 * 3 + 3 * 3 + 2 * 2);
    let best = (0..rank.len()).min_by(|&a, &b| rank[a].total_cmp(&rank[b])).unwrap();
    assert!((0..rank.len()).all(|i| obj[i] / cost[i] <= obj[best] / cost[best]), "rank 1 is not the largest objective per cost");
    // The README's finding: repeated impacts on Gen 4 narrow the lifetime bands most per cost.
    let names = partlife::io::col_str(&df, &p, "candidate").unwrap();
    assert_eq!(names[best], "repeated impacts Gen 4");
    // The summary's headline sentence states the first allocation step's numbers.
    let a = dir.join("allocation.csv");
    let alloc = partlife::io::read_table(&a).unwrap();
    let (added, pcs, dmw) = (partlife::io::col_str(&alloc, &a, "added").unwrap(), partlife::io::col_f64(&alloc, &a, "pcs").unwrap(), partlife::io::col_f64(&alloc, &a, "true_damage_model_weight").unwrap());
    let summary = s.read("reports/experiments/summary.md");
    let line = summary.lines().find(|l| l.starts_with("With a budget of 15000 EUR")).unwrap_or_else(|| panic!("no budget sentence in\n{summary}"));
    assert!(line.contains(&format!("the most informative next step is {}", added[0])), "{line}");
    assert!(line.contains(&format!("{:.3}", dmw[0])) || line.contains(&format!("{:.2}", dmw[0])), "{line} vs {}", dmw[0]);
    assert!(line.contains(&format!("{:.3}", pcs[0])) || line.contains(&format!("{:.4}", pcs[0])), "{line} vs {}", pcs[0]);
    // The README's other finding: the choice itself is already settled.
    assert!(summary.contains("No candidate's expected value of information exceeds 1 % of the loss"), "{summary}");
    // The allocation spends within the budget, each step more.
    let spent = partlife::io::col_f64(&alloc, &a, "cost").unwrap();
    assert!(spent.windows(2).all(|w| w[1] > w[0]) && spent.last().is_none_or(|c| *c <= 15000.0), "{spent:?}");
}

#[test]
fn bad_experiments_inputs_exit_2_naming_the_key() {
    let study = "studies/experiments.toml";
    let cases: [(&str, &str, &[&str]); 8] = [
        ("sizes = [25, 50, 100]\ncost_per_unit = 40           # one crush", "sizes = [0, 50, 100]\ncost_per_unit = 40           # one crush", &["candidate[0].sizes", "≥ 1"]),
        ("cost_per_unit = 40           # one crush", "cost_per_unit = -40           # one crush", &["candidate[0].cost_per_unit", "> 0"]),
        ("velocity_m_s = 15            # fast enough", "velocity_m_s = 0            # fast enough", &["candidate[2].velocity_m_s"]),
        ("counts = [1, 10, 100, 1000]  # broken", "counts = [1, 100, 10, 1000]  # broken", &["candidate[3].counts", "increasing"]),
        ("material = \"gen4\"\nsizes = [25, 50, 100]", "material = \"gen5\"\nsizes = [25, 50, 100]", &["candidate[0].material", "unknown material \"gen5\""]),
        ("sd_log = 0.3", "sd_log = 0.0", &["candidate[5].sd_log", "> 0"]),
        ("total = 15000", "total = 100", &["budget.total", "cheapest"]),
        ("horizon_years = 1", "horizon_years = 3", &["decision.horizon_years", "horizons"]),
    ];
    for (from, to, expect) in cases {
        let s = scratch();
        s.expect_bad_study(study, from, to, expect);
    }
}

#[test]
fn a_sieve_fraction_without_crushed_particles_is_bad_input() {
    let s = scratch();
    let text = s.read("studies/experiments.toml");
    s.write("studies/experiments.toml", &edited(&text, &[("fixed_cost = 500\n\n[[candidate]]\nname = \"crush BL 16/30\"", "fixed_cost = 500\ndiameter_m = [0.002, 0.003]\n\n[[candidate]]\nname = \"crush BL 16/30\"")]));
    s.expect_bad_study("studies/experiments.toml", "seed = 20261124", "seed = 20261124", &["candidate[0]", "no crushed particle", "diameter range"]);
}
