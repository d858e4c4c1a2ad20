//! JH-2 single-point paths with the Johnson & Holmquist (1994) illustrative ceramic
//! (docs/reference.md, mechanics §1.7–1.8): uniaxial-strain compression (elastic slope 2G/K1, meeting the
//! intact surface), the three damage cases, the hydrostatic EOS, the tensile cut-off, the rate
//! factor and SFMAX. Tolerances are stated per test.

use partlife::fem::material::{Jh2Params, MaterialParams, PointState};

struct Path {
    p: Vec<f64>,
    q: Vec<f64>,
    d: Vec<f64>,
    mu: Vec<f64>,
}

/// Uniaxial-strain compression (ε_zz < 0, ε_rr = ε_θθ = 0) to `strain` (log) in `n` increments.
fn uniaxial(j: Jh2Params, strain: f64, n: usize) -> (Path, PointState) {
    let m = MaterialParams::Jh2(j).build();
    let mut st = PointState::default();
    let de = strain / n as f64;
    let mut path = Path { p: vec![0.0], q: vec![0.0], d: vec![0.0], mu: vec![0.0] };
    for k in 1..=n {
        let e = de * k as f64;
        let mu = e.exp() - 1.0; // V₀/V − 1 with V/V₀ = exp(−e)
        m.update(&mut st, &[0.0, -de, 0.0, 0.0], 0.0, mu, 0.0);
        path.p.push(st.p);
        path.q.push(st.von_mises());
        path.d.push(st.damage);
        path.mu.push(mu);
    }
    (path, st)
}

fn intact(j: &Jh2Params, p: f64) -> f64 {
    j.sigma_hel() * j.a * ((p + j.t) / j.phel).powf(j.n)
}

#[test]
fn elastic_slope_is_2g_over_k1() {
    let j = Jh2Params::jh1994();
    let (path, _) = uniaxial(j, 1e-4, 10);
    let slope = path.q[1] / path.p[1];
    // 2G/K1 = 1.377 (small-strain); the log-strain path differs by O(ε) = 1e-5.
    assert!((slope - 2.0 * j.g / j.k1).abs() < 1e-3, "slope {slope}");
    assert!((2.0 * j.g / j.k1 - 1.377).abs() < 5e-4);
}

#[test]
fn path_meets_the_intact_surface_at_the_reference_point() {
    let j = Jh2Params::jh1994();
    // Analytic crossing of σ = 2G ε and P = K1 (e^ε − 1) with the intact surface.
    let (mut lo, mut hi) = (0.0, 0.05);
    for _ in 0..100 {
        let e = 0.5 * (lo + hi);
        if 2.0 * j.g * e < intact(&j, j.k1 * (e.exp() - 1.0)) { lo = e } else { hi = e }
    }
    let (p_x, q_x) = (j.k1 * (lo.exp() - 1.0), 2.0 * j.g * lo);
    // docs/reference.md, mechanics §1.8: σ ≈ 2.0 GPa at P ≈ 1.48 GPa (two printed digits).
    assert!((q_x - 2.0e9).abs() < 0.05e9 && (p_x - 1.48e9).abs() < 0.05e9, "crossing at P = {p_x:e}, σ = {q_x:e}");
    let (path, _) = uniaxial(j, 0.03, 3000);
    let k = path.d.iter().position(|&d| d > 0.0).expect("the path yields");
    // The first damaged point lies on the intact surface (within one increment, 1e-5 strain).
    assert!((path.p[k] - p_x).abs() < 0.01e9 && (path.q[k] - q_x).abs() < 0.01e9, "yield at P = {:e}, σ = {:e}", path.p[k], path.q[k]);
}

#[test]
fn case1_instant_failure() {
    let j = Jh2Params { b: 0.0, d1: 0.0, ..Jh2Params::jh1994() };
    let (path, st) = uniaxial(j, 0.03, 3000);
    let k = path.d.iter().position(|&d| d > 0.0).unwrap();
    assert_eq!(path.d[k], 1.0, "D1 = 0 fails at the first yield");
    assert!(path.q[k] < 1e-6 * j.g, "strength drops to zero at once: σ = {:e}", path.q[k]);
    assert!(st.von_mises() < 1e-6 * j.g);
}

#[test]
fn case2_gradual_softening() {
    let j = Jh2Params { b: 0.0, d1: 0.005, ..Jh2Params::jh1994() };
    let (path, _) = uniaxial(j, 0.05, 5000);
    let partial = path.d.iter().filter(|&&d| d > 0.0 && d < 1.0).count();
    // ε_p^f = D1 (P* + T*) ≈ 0.006: D grows over hundreds of increments of 1e-5.
    assert!(partial > 100, "only {partial} partially damaged increments");
    assert!(path.d.windows(2).all(|w| w[1] >= w[0]), "damage never decreases");
    let peak = path.q.iter().cloned().fold(0.0, f64::max);
    assert!(*path.d.last().unwrap() == 1.0 && *path.q.last().unwrap() < 1e-6 * peak, "softens to zero strength");
}

#[test]
fn case3_softens_onto_the_fractured_surface_with_bulking() {
    let j = Jh2Params::jh1994(); // B = 0.31, M = 0.6, D1 = 0.005, β = 1
    let (path, st) = uniaxial(j, 0.05, 5000);
    assert_eq!(st.damage, 1.0);
    let fractured = j.sigma_hel() * j.b * (st.p / j.phel).powf(j.m);
    assert!((st.von_mises() - fractured).abs() < 1e-3 * fractured, "σ = {:e} vs fractured surface {fractured:e}", st.von_mises());
    // Bulking: P exceeds the EOS value K1 μ.
    let mu = *path.mu.last().unwrap();
    assert!(st.bulking > 0.0 && st.p > j.k1 * mu * 1.001, "P = {:e}, K1 μ = {:e}", st.p, j.k1 * mu);
    // Energy: bulking energy bounded by β ΔU (ΔP² / 2K1 ≤ ΔU_total = σ_y(0)²/6G at most).
    let du_max = intact(&j, st.p).powi(2) / (6.0 * j.g);
    assert!(st.bulking.powi(2) / (2.0 * j.k1) <= j.beta * du_max);
}

#[test]
fn hydrostatic_eos() {
    // Float glass (docs/reference.md, mechanics §1.7, K2/K3 in GPa): P = K1 μ + K2 μ² + K3 μ³, no deviator.
    let j = Jh2Params { k1: 45.4e9, k2: -138e9, k3: 290e9, g: 30.4e9, ..Jh2Params::jh1994() };
    let m = MaterialParams::Jh2(j).build();
    let mut st = PointState::default();
    let n = 400;
    let mut ev = 0.0;
    for _ in 0..n {
        let de = -0.1 / n as f64 / 3.0;
        ev += 3.0 * de;
        let mu = (-ev).exp() - 1.0;
        m.update(&mut st, &[de, de, de, 0.0], 0.0, mu, 0.0);
        let exact = j.k1 * mu + j.k2 * mu * mu + j.k3 * mu.powi(3);
        assert!((st.p - exact).abs() < 1e-9 * exact.abs().max(1.0), "μ {mu}: {} vs {exact}", st.p);
        assert!(st.von_mises() < 1e-3, "no deviator on a hydrostatic path");
    }
}

#[test]
fn tension_is_capped_at_t_times_one_minus_d() {
    let j = Jh2Params::jh1994();
    let m = MaterialParams::Jh2(j).build();
    for d0 in [0.0, 0.5] {
        let mut st = PointState { damage: d0, ..Default::default() };
        let mut ev = 0.0;
        for _ in 0..200 {
            let de = 1e-4 / 3.0;
            ev += 3.0 * de;
            m.update(&mut st, &[de, de, de, 0.0], 0.0, (-ev).exp() - 1.0, 0.0);
        }
        let cap = -j.t * (1.0 - d0);
        assert!((st.p - cap).abs() < 1e-9 * j.t, "D = {d0}: P = {:e} vs −T(1−D) = {cap:e}", st.p);
    }
}

/// JH-2 yield strength written out from Johnson & Holmquist (1994), independently of the
/// crate: σ_y = σ_HEL [R (1 − D) A (P* + T*)^N + D min(R B P*^M, SFMAX)], R = 1 + C ln(ε̇/ε̇₀)
/// for ε̇ > ε̇₀ (else 1), P* = P/P_HEL, T* = T/P_HEL.
fn jh2_yield(j: &Jh2Params, p: f64, d: f64, rate_eq: f64) -> f64 {
    let r = if rate_eq > j.epsi { 1.0 + j.c * (rate_eq / j.epsi).ln() } else { 1.0 };
    let ps = p / j.phel;
    let intact = if ps + j.t / j.phel > 0.0 { j.a * (ps + j.t / j.phel).powf(j.n) } else { 0.0 };
    let fractured = if ps > 0.0 { (r * j.b * ps.powf(j.m)).min(j.sfmax) } else { 0.0 };
    j.sigma_hel() * (r * (1.0 - d) * intact + d * fractured)
}

/// The rate law exercised through the material update: on a uniaxial-strain path at
/// ε̇ = 10³ ε̇₀, every increment that yields ends on the rate-enhanced surface (formula above,
/// to 1e-9), and the first-yield stress exceeds the quasi-static path's by the rate factor's
/// order (1 + C ln 10³ = 1.069 for C = 0.01).
#[test]
fn rate_factor_through_the_material_update() {
    let j = Jh2Params { c: 0.01, beta: 0.0, ..Jh2Params::jh1994() };
    let m = MaterialParams::Jh2(j).build();
    let first_yield = |rate_eq: f64| -> f64 {
        let mut st = PointState::default();
        let de = 1e-5;
        let mut first = None;
        for k in 1..=3000 {
            let mu = (de * k as f64).exp() - 1.0;
            let before = st.plastic_strain;
            m.update(&mut st, &[0.0, -de, 0.0, 0.0], 0.0, mu, rate_eq);
            if st.plastic_strain > before {
                let want = jh2_yield(&j, st.p, st.damage, rate_eq);
                assert!((st.von_mises() - want).abs() < 1e-9 * want, "ε̇ = {rate_eq:e}, step {k}: q = {:e}, surface {want:e} (D = {})", st.von_mises(), st.damage);
                first.get_or_insert(st.von_mises());
            }
        }
        first.expect("the path yields")
    };
    let (slow, fast) = (first_yield(0.0), first_yield(1e3 * j.epsi));
    let r = 1.0 + j.c * 1e3f64.ln();
    // The yield points lie at different pressures (the fast path yields later), so the ratio is
    // the rate factor times the intact surface's rise, (P*+T*)^N: between R and 1.1 R.
    assert!(fast / slow > r && fast / slow < 1.1 * r, "first yield {fast:e} vs {slow:e}: ratio {} (R = {r})", fast / slow);
}

#[test]
fn sfmax_caps_the_fractured_strength() {
    // B = 10 at P* = 2 would give 15.2, capped at SFMAX = 0.5.
    let j = Jh2Params { b: 10.0, sfmax: 0.5, ..Jh2Params::jh1994() };
    let m = MaterialParams::Jh2(j).build();
    let s = m.jh2_strength(&j, 2.0 * j.phel, 1.0, 1.0);
    assert!((s - 0.5 * j.sigma_hel()).abs() < 1e-9 * s);
    assert!((s - jh2_yield(&j, 2.0 * j.phel, 1.0, 0.0)).abs() < 1e-9 * s);
}
