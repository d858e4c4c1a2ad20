//! Speed figures (`partlife bench`), measured in a benchmark rather than a timed test:
//!
//! * σ̄(V) + P_N evaluations per second on one core (goal ≥ 2·10⁷/s);
//! * Weibull MLE + 10⁴-sample pivotal bounds for N = 50 (goal < 50 ms), on all threads and on one;
//! * the lifetime study end to end (goal < 5 s), when a study file is given.

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::contact::{AveragingDomain, Elastic, Sphere};
use crate::error::Result;
use crate::lifetime::{BreakageCurve, ImpactLoad, Lifetime};
use crate::weibull::{Weibull, fit_mle, simulate_pivotal};

/// One measured figure.
#[derive(Debug, Clone)]
pub struct Figure {
    /// What was measured.
    pub what: String,
    /// The value.
    pub value: f64,
    /// Its unit.
    pub unit: String,
    /// The goal, in words.
    pub goal: String,
}

/// σ̄(V) + P_N evaluations per second on the calling thread, through the precomputed
/// [`BreakageCurve`] (`fast = true`) or the general [`Lifetime`] path.
pub fn lifetime_evaluations_per_second(min_time: Duration, fast: bool) -> Result<f64> {
    let e = Elastic::new(112e9, 0.25)?;
    let sphere = Sphere { diameter: 0.9e-3, density: 3600.0, elastic: e };
    let load = ImpactLoad::on_wall(&sphere, &Elastic::new(210e9, 0.3)?, 0.1, AveragingDomain::default());
    let life = Lifetime { load, strength: Weibull::new(7.0, 800e6)? };
    let curve = BreakageCurve::new(&life);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let velocities: Vec<f64> = (0..4096).map(|_| rng.random_range(0.5..20.0)).collect();
    let mut evals = 0u64;
    let mut acc = 0.0;
    let start = Instant::now();
    while start.elapsed() < min_time {
        if fast {
            for &v in &velocities {
                let (sigma, p) = curve.evaluate(black_box(v), black_box(7300.0));
                acc += sigma + p;
            }
        } else {
            for &v in &velocities {
                acc += life.load.at_velocity(black_box(v))?.mean_tensile + life.p_after(black_box(v), black_box(7300.0))?;
            }
        }
        evals += velocities.len() as u64;
    }
    black_box(acc);
    Ok(evals as f64 / start.elapsed().as_secs_f64())
}

/// Median wall time (ms) of a Weibull fit + pivotal bounds for N = 50 with 10⁴ replicates.
pub fn weibull_fit_with_bounds_ms(repeats: usize) -> Result<f64> {
    let w = Weibull::new(9.0, 700e6)?;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let data: Vec<f64> = (0..50).map(|_| w.sample(&mut rng)).collect();
    let mut times = Vec::with_capacity(repeats);
    for r in 0..repeats {
        let start = Instant::now();
        let fit = fit_mle(&data)?;
        let piv = simulate_pivotal(fit.n, 10_000, r as u64)?;
        black_box(piv.bounds(&fit, 0.9)?);
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(crate::stats::median(&times))
}

/// Runs every benchmark and returns the figures.
pub fn run_all(study: Option<&Path>) -> Result<Vec<Figure>> {
    // Seven trials of 0.3 s: the best is the code's speed, the median shows the machine's noise.
    let trials = |fast: bool| -> Result<(f64, f64)> {
        let mut v = (0..7).map(|_| lifetime_evaluations_per_second(Duration::from_millis(300), fast)).collect::<Result<Vec<f64>>>()?;
        v.sort_by(f64::total_cmp);
        Ok((v[6], v[3]))
    };
    let (fast_best, fast_median) = trials(true)?;
    let (slow_best, slow_median) = trials(false)?;
    let mut out = vec![
        Figure {
            what: "σ̄(V) + P_N evaluations, one core, precomputed BreakageCurve, best of 7".into(),
            value: fast_best,
            unit: format!("evaluations/s (median {fast_median:.3e})"),
            goal: "≥ 2e7/s".into(),
        },
        Figure {
            what: "σ̄(V) + P_N evaluations, one core, general path (as in the Simulator), best of 7".into(),
            value: slow_best,
            unit: format!("evaluations/s (median {slow_median:.3e})"),
            goal: "(reference)".into(),
        },
    ];
    out.push(Figure {
        what: format!("Weibull MLE + 10^4 pivotal bounds, N = 50, {} threads", rayon::current_num_threads()),
        value: weibull_fit_with_bounds_ms(11)?,
        unit: "ms (median of 11)".into(),
        goal: "< 50 ms".into(),
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| crate::Error::numerical("thread pool", e.to_string()))?;
    out.push(Figure {
        what: "Weibull MLE + 10^4 pivotal bounds, N = 50, 1 thread".into(),
        value: pool.install(|| weibull_fit_with_bounds_ms(11))?,
        unit: "ms (median of 11)".into(),
        goal: "< 50 ms".into(),
    });
    if let Some(path) = study {
        let root = std::env::temp_dir().join(format!("partlife-bench-{}", std::process::id()));
        let start = Instant::now();
        let res = crate::runner::run_file(path, &crate::runner::RunOptions { reports_root: root.clone(), progress: false });
        let secs = start.elapsed().as_secs_f64();
        let _ = std::fs::remove_dir_all(&root);
        res?;
        out.push(Figure {
            what: format!("study {} end to end (in process)", path.display()),
            value: secs,
            unit: "s".into(),
            goal: "< 5 s".into(),
        });
    }
    Ok(out)
}
