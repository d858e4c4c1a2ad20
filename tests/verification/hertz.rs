//! Hertz contact: docs/reference.md, mechanics §2.1 (effective moduli), §2.4 (crush table), §3.2 (tensile
//! onset and inner integrals), §3.3 (averages), §3.4 (impact table and closed forms).

use partlife::contact::*;

fn bauxite() -> Elastic {
    Elastic::new(112e9, 0.25).unwrap()
}
fn steel() -> Elastic {
    Elastic::new(210e9, 0.3).unwrap()
}

/// |got − want| ≤ half a unit of the last printed digit (`ulp`) plus 0.1 % of the value: the
/// reference tables were computed from rounded intermediates (σ_r(a) = 1.31 at 100 N is
/// (1 − 2ν)/3 × 7.83 with p0 already rounded; δ_m = 1.45 is 1.44499… rounded half up).
fn close(got: f64, want: f64, ulp: f64, what: &str) {
    let tol = 0.5 * ulp + 1e-3 * want.abs();
    assert!((got - want).abs() <= tol, "{what}: got {got}, reference {want} (±{tol})");
}

#[test]
fn effective_moduli_section_2_1() {
    close(effective_modulus_rigid(&bauxite()) / 1e9, 119.5, 0.1, "E* rigid platen");
    close(effective_modulus(&bauxite(), &steel()) / 1e9, 78.7, 0.1, "E* steel platen");
    close(effective_modulus(&bauxite(), &bauxite()) / 1e9, 59.7, 0.1, "E* particle");
}

#[test]
fn crush_table_section_2_4() {
    // F, a (µm), δ per contact (µm), δ_tot (µm), p0 (GPa), σ_r(a) (GPa), a/R, 0.9F/d² (MPa)
    let rows = [
        (50.0, 62.0, 7.7, 15.4, 6.21, 1.04, 0.12, 45.0),
        (100.0, 78.1, 12.2, 24.4, 7.83, 1.31, 0.16, 90.0),
        (150.0, 89.4, 16.0, 32.0, 8.96, 1.49, 0.18, 135.0),
        (200.0, 98.4, 19.4, 38.7, 9.86, 1.64, 0.20, 180.0),
    ];
    let r = 0.5e-3;
    let crush = Crush::new(&bauxite(), &steel(), r);
    let zone = TensileZone::new(0.25);
    for (f, a, d, dt, p0, sra, ar, hir) in rows {
        let c = crush.contact;
        close(c.contact_radius(f) * 1e6, a, 0.1, "a");
        close(c.approach(f) * 1e6, d, 0.1, "δ");
        close(crush.total_displacement(f) * 1e6, dt, 0.1, "δ_tot");
        close(c.peak_pressure(f) / 1e9, p0, 0.01, "p0");
        close(zone.edge_factor() * c.peak_pressure(f) / 1e9, sra, 0.01, "σ_r(a)");
        close(c.contact_radius(f) / r, ar, 0.01, "a/R");
        close(0.9 * f / (2.0 * r).powi(2) / 1e6, hir, 1.0, "0.9F/d²");
        // Inverse: F at the total displacement.
        assert!((crush.force_at_displacement(crush.total_displacement(f)) / f - 1.0).abs() < 1e-12);
    }
}

#[test]
fn tensile_zone_section_3_2() {
    // ν, s0, (1−2ν)/3, I_in, J_in
    let rows = [
        (0.20, 0.9783, 0.200, 0.00142, 0.00884),
        (0.22, 0.9813, 0.187, 0.00114, 0.00714),
        (0.25, 0.9853, 0.167, 0.00080, 0.00504),
        (0.27, 0.9877, 0.153, 0.00062, 0.00390),
        (0.30, 0.9908, 0.133, 0.00041, 0.00254),
    ];
    for (nu, s0, k, i_in, j_in) in rows {
        let z = TensileZone::new(nu);
        close(z.s0, s0, 1e-4, "s0");
        close(z.edge_factor(), k, 1e-3, "(1−2ν)/3");
        close(z.i_in, i_in, 1e-5, "I_in");
        close(z.j_in, j_in, 1e-5, "J_in");
        // σ_r vanishes at s0 and is tensile beyond.
        assert!(surface_stress(z.s0, nu).radial.abs() < 1e-12);
        assert!(surface_stress(z.s0 + 1e-6, nu).radial > 0.0);
    }
}

#[test]
fn averages_section_3_3() {
    let zone = TensileZone::new(0.25);
    // L/a, σ̄_line/p0, σ̄_area/p0
    let rows = [(1.5, 0.1095, 0.1069), (2.0, 0.0829, 0.0768), (3.0, 0.0555, 0.0458), (5.0, 0.0334, 0.0224), (10.0, 0.0167, 0.0078)];
    for (kappa, line, area) in rows {
        let l = AveragingDomain { measure: AveragingMeasure::Line, outer: OuterLimit::ContactMultiple, kappa };
        let a = AveragingDomain { measure: AveragingMeasure::Area, outer: OuterLimit::ContactMultiple, kappa };
        close(l.ratio_to_peak_pressure(&zone).unwrap(), line, 1e-4, "σ̄_line/p0");
        close(a.ratio_to_peak_pressure(&zone).unwrap(), area, 1e-4, "σ̄_area/p0");
    }
    // Crush example: F = 150 N, d = 1 mm, L = R: σ̄_line = 268 MPa, σ̄_area = 170 MPa.
    let r = 0.5e-3;
    let h = Hertz::sphere_on_flat(&bauxite(), &steel(), r);
    for (measure, want) in [(AveragingMeasure::Line, 268.0), (AveragingMeasure::Area, 170.0)] {
        let d = AveragingDomain { measure, outer: OuterLimit::ParticleRadius, kappa: 2.0 };
        let s = ContactStress::new(h, d, r).at_force(150.0).unwrap();
        close(s.mean_tensile / 1e6, want, 1.0, "crush example σ̄");
        close(r / s.radius, 5.59, 0.01, "L/a");
    }
}

#[test]
fn impact_table_section_3_4() {
    let sphere = Sphere { diameter: 1e-3, density: 3600.0, elastic: bauxite() };
    close(sphere.mass(), 1.885e-6, 0.001e-6, "particle mass");
    // η, V, δ_m (µm), F_max (N), t_c (µs), a (µm), p0 (GPa)
    let rows = [
        (1.0, 5.0, Some(3.63), 16.2, Some(2.14), 42.6, 4.27),
        (1.0, 10.0, Some(6.32), 37.3, Some(1.86), 56.2, 5.63),
        (0.1, 5.0, Some(1.45), 4.08, Some(2.69), 26.9, 2.69),
        (0.1, 10.0, Some(2.52), 9.37, Some(2.34), 35.5, 3.55),
        (0.1, 20.0, None, 21.5, None, 46.8, 4.69),
    ];
    for (eta, v, dm, fmax, tc, a, p0) in rows {
        let imp = Impact::sphere_on_wall(&sphere, &steel(), 0.5e-3, eta);
        if let Some(dm) = dm {
            close(imp.max_approach(v) * 1e6, dm, 0.01, "δ_m");
        }
        let f = imp.max_force(v);
        let fulp = if fmax < 10.0 { 0.01 } else { 0.1 };
        close(f, fmax, fulp, "F_max");
        if let Some(tc) = tc {
            close(imp.contact_time(v) * 1e6, tc, 0.01, "t_c");
        }
        close(imp.hertz.contact_radius(f) * 1e6, a, 0.1, "a_m");
        close(imp.hertz.peak_pressure(f) / 1e9, p0, 0.01, "p0,max");
        // Closed forms of §3.4 (their 4-digit coefficients: 1e-3 relative).
        let fc = 3.029 * 3600f64.powf(0.6) * imp.hertz.e_star.powf(0.4) * 0.5e-3f64.powi(2) * (eta * v * v).powf(0.6);
        let pc = 0.8370 * imp.hertz.e_star.powf(0.8) * (3600.0 * eta * v * v).powf(0.2);
        assert!((f / fc - 1.0).abs() < 1e-3, "F_max closed form");
        assert!((imp.hertz.peak_pressure(f) / pc - 1.0).abs() < 1e-3, "p0 closed form");
    }
    // Particle–particle, V = 5 m/s relative, η = 1: F_max = 8.35 N, t_c = 2.08 µs.
    let pp = Impact::sphere_on_sphere(&sphere, 0.5e-3, 1.0);
    close(pp.max_force(5.0), 8.35, 0.01, "particle–particle F_max");
    close(pp.contact_time(5.0) * 1e6, 2.08, 0.01, "particle–particle t_c");
}

#[test]
fn impact_stress_is_size_independent_on_a_wall() {
    // p0,max = 0.8370 E*^(4/5) (ρηV²)^(1/5) does not depend on R (docs/reference.md, mechanics §3.4).
    let p = |d: f64| {
        let s = Sphere { diameter: d, density: 3600.0, elastic: bauxite() };
        let imp = Impact::sphere_on_wall(&s, &steel(), 0.5 * d, 0.1);
        imp.hertz.peak_pressure(imp.max_force(5.0))
    };
    assert!((p(0.6e-3) / p(1.2e-3) - 1.0).abs() < 1e-12);
}
