//! The module graph has no cycle: every `crate::<module>` path in `src/` (outside `#[cfg(test)]`
//! modules and comments) is an arrow from the file's top-level module to that module, and the
//! arrows form a directed acyclic graph (the layers are drawn in `src/lib.rs`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Top-level module → the top-level modules it names.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(&src).unwrap().to_string_lossy().into_owned();
        let top = rel.split('/').next().unwrap().trim_end_matches(".rs").to_string();
        if top == "main" || top == "lib" {
            continue;
        }
        let text = std::fs::read_to_string(&f).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        let entry = g.entry(top.clone()).or_default();
        for line in code.lines() {
            let line = line.split("//").next().unwrap();
            for (i, _) in line.match_indices("crate::") {
                let name: String = line[i + 7..].chars().take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_').collect();
                if !name.is_empty() && name != top {
                    entry.insert(name);
                }
            }
        }
    }
    g
}

/// A cycle through `v`, if any (depth-first search with colours).
fn find_cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(v: &str, g: &BTreeMap<String, BTreeSet<String>>, state: &mut BTreeMap<String, u8>, path: &mut Vec<String>) -> Option<Vec<String>> {
        state.insert(v.to_string(), 1);
        path.push(v.to_string());
        for w in g.get(v).into_iter().flatten().filter(|w| g.contains_key(*w)) {
            match state.get(w).copied().unwrap_or(0) {
                1 => {
                    let start = path.iter().position(|p| p == w).unwrap();
                    let mut c = path[start..].to_vec();
                    c.push(w.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(w, g, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(v.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for v in g.keys() {
        if state.get(v).copied().unwrap_or(0) == 0
            && let Some(c) = visit(v, g, &mut state, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

#[test]
fn the_module_graph_has_no_cycle() {
    let g = graph();
    assert!(g.len() > 20, "read only {} modules", g.len());
    assert!(g["runner"].contains("study") && g["uq"].contains("strength"), "the reader misses imports: {g:?}");
    if let Some(c) = find_cycle(&g) {
        panic!("import cycle: {}", c.join(" → "));
    }
    // Only the CLI and the benchmarks use the dispatch.
    let users: Vec<&String> = g.iter().filter(|(m, deps)| deps.contains("runner") && *m != "bench").map(|(m, _)| m).collect();
    assert!(users.is_empty(), "modules below the top import crate::runner: {users:?}");
}

/// Module → layer, from the table in `src/lib.rs` (lines `//! NN  a · b   description`).
fn layers() -> BTreeMap<String, u32> {
    let lib = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    let graph = lib.split("//! ## Module graph").nth(1).expect("a module graph section in src/lib.rs");
    let block = graph.split("//! ```text").nth(1).expect("a layer table in src/lib.rs").split("//! ```").next().unwrap();
    let mut out = BTreeMap::new();
    for line in block.lines() {
        let line = line.trim_start_matches("//!").trim();
        let Some((n, rest)) = line.split_once("  ") else { continue };
        let Ok(n) = n.trim().parse::<u32>() else { continue };
        let names = rest.trim().split("  ").next().unwrap();
        for m in names.split('·') {
            out.insert(m.trim().to_string(), n);
        }
    }
    out
}

#[test]
fn every_import_points_to_a_lower_layer_of_the_stated_graph() {
    let (g, layer) = (graph(), layers());
    assert!(layer.len() > 20, "read only {} layered modules: {layer:?}", layer.len());
    let missing: Vec<&String> = g.keys().filter(|m| !layer.contains_key(*m)).collect();
    assert!(missing.is_empty(), "modules missing from the layer table in src/lib.rs: {missing:?}");
    let mut wrong = Vec::new();
    for (m, deps) in &g {
        for d in deps.iter().filter(|d| layer.contains_key(*d)) {
            if layer[d] >= layer[m] {
                wrong.push(format!("{m} (layer {}) → {d} (layer {})", layer[m], layer[d]));
            }
        }
    }
    assert!(wrong.is_empty(), "imports that do not point down the stated layers: {wrong:?}");
}

#[test]
fn the_cycle_finder_finds_a_cycle() {
    let g: BTreeMap<String, BTreeSet<String>> = [("a", vec!["b"]), ("b", vec!["c"]), ("c", vec!["a"]), ("d", vec![])]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.into_iter().map(String::from).collect()))
        .collect();
    assert_eq!(find_cycle(&g).map(|c| c.len()), Some(4));
}
