//! The test build reuses the release build's dependencies: `cargo test --release` after
//! `cargo build --release` must not compile polars (or anything else) a second time. That holds
//! when every dependency resolves the same features with and without dev-dependencies; a
//! dev-dependency that switches on one more feature of a shared crate (tempfile did, for
//! bitflags) rebuilds everything above it.

use std::collections::BTreeMap;
use std::process::Command;

/// `cargo tree` lines `name version features` of the given edge kinds, by `name version`.
fn resolved(edges: &str) -> BTreeMap<String, String> {
    let out = Command::new(env!("CARGO"))
        .args(["tree", "--offline", "--locked", "--prefix", "none", "--format", "{p}|{f}", "-e", edges])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "cargo tree -e {edges} failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        // Repeats end with " (*)"; the root package names its path in parentheses.
        .filter_map(|l| l.trim_end_matches(" (*)").split_once('|'))
        .map(|(p, f)| (p.split(" (").next().unwrap().to_string(), f.to_string()))
        .collect()
}

#[test]
fn test_and_release_builds_resolve_the_same_dependency_features() {
    let normal = resolved("normal");
    let with_dev = resolved("normal,dev");
    assert!(normal.len() > 100, "cargo tree listed only {} packages", normal.len());
    let changed: Vec<String> = normal
        .iter()
        .filter_map(|(p, f)| with_dev.get(p).filter(|g| *g != f).map(|g| format!("{p}: [{f}] → [{g}]")))
        .collect();
    assert!(changed.is_empty(), "dev-dependencies change the features of shared dependencies, so `cargo test --release` recompiles them:\n{}", changed.join("\n"));
}
