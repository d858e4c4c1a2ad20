//! Sobol' points against the reference generated with SciPy's unscrambled engine (same
//! Joe–Kuo direction numbers): the first 32 points in 64 dimensions, exactly.

use partlife::design::Sobol;
use partlife::io::{col_f64, read_table};

#[test]
fn sobol_matches_the_joe_kuo_reference() {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/reference/sobol_joe_kuo_64d_32.csv");
    let df = read_table(&p).unwrap();
    let pts = Sobol::points(64, 32, 0).unwrap();
    for d in 0..64 {
        let col = col_f64(&df, &p, &format!("d{}", d + 1)).unwrap();
        for (i, (&v, q)) in col.iter().zip(&pts).enumerate() {
            assert_eq!(q[d], v, "point {i}, dimension {}", d + 1);
        }
    }
}

/// Far points (indices up to 2²² − 1) exercise direction numbers of every bit up to 22.
#[test]
fn sobol_far_points_match_the_reference() {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/reference/sobol_joe_kuo_64d_far.csv");
    let df = read_table(&p).unwrap();
    let idx = col_f64(&df, &p, "index").unwrap();
    let mut s = Sobol::new(64).unwrap();
    let mut n = 0usize;
    for (row, &target) in idx.iter().enumerate() {
        let mut q = Vec::new();
        while n <= target as usize {
            q = s.next_point();
            n += 1;
        }
        for (d, &qd) in q.iter().enumerate() {
            let v = col_f64(&df, &p, &format!("d{}", d + 1)).unwrap()[row];
            assert_eq!(qd, v, "point {target}, dimension {}", d + 1);
        }
    }
}
