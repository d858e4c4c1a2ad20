//! The executor without a cluster: `--executor slurm` where Slurm's commands are missing, on a
//! study without a simulator ensemble, or with bad `[executor]` options is bad input (exit 2);
//! `partlife eval` evaluates a batch task into the cache, and a task killed at any moment leaves
//! only whole cache entries. The real-cluster test is `tests/slurm.rs`.

mod common;

use common::{Scratch, tiny_calibration};
use partlife::calibrate::executor::{Batch, config_digest};

#[test]
fn the_slurm_executor_without_slurm_or_on_the_wrong_study_is_bad_input() {
    let s = Scratch::new();
    tiny_calibration(&s, "");
    let empty = partlife::io::TempDir::new("no-slurm").unwrap();
    let out = s.run_env(&["run", "studies/cal.toml", "--quiet", "--executor", "slurm"], &[("PATH", &empty.path().display().to_string())]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    for e in ["--executor slurm", "sbatch", "not there"] {
        assert!(out.stderr.contains(e), "message lacks \"{e}\": {}", out.stderr);
    }
    assert!(s.report_files().iter().all(|f| f.starts_with(".cache")), "a refused run wrote {:?}", s.report_files());
    // A study kind without an ensemble.
    let out = s.run(&["run", "studies/lifetime.toml", "--quiet", "--executor", "slurm"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("lifetime.toml") && out.stderr.contains("only calibration studies"), "{}", out.stderr);
    // Bad [executor] options, named by key.
    for (line, key) in [("time_limit = \"one hour\"", "executor.time_limit"), ("evaluations_per_task = 0", "executor.evaluations_per_task"), ("partition = \"a b\"", "executor.partition"), ("poll_seconds = 0.0", "executor.poll_seconds"), ("kind = \"cloud\"", "unknown variant `cloud`")] {
        let s = Scratch::new();
        tiny_calibration(&s, line);
        let out = s.run(&["run", "studies/cal.toml", "--quiet"]);
        assert_eq!(out.code, 2, "{line}: {}", out.stderr);
        assert!(out.stderr.contains("cal.toml") && out.stderr.contains(key), "{line}: {}", out.stderr);
    }
}

/// A batch of `n` θ's of the tiny calibration, one task, its cache under `cache/`.
fn batch(s: &Scratch, n: usize) -> std::path::PathBuf {
    let path = s.path("studies/cal.toml");
    let file = partlife::schema::StudyFile::read(&path).unwrap();
    let study: partlife::calibrate::study::CalibrateStudy = file.parse().unwrap();
    let prep = study.prepare(&path, &|p: &str| file.resolve(std::path::Path::new(p))).unwrap();
    let space = partlife::model::Simulator::space(match &prep.built {
        partlife::calibrate::study::Built::Crush(m, _) => m,
        _ => unreachable!(),
    })
    .clone();
    let thetas = partlife::design::Sobol::points(space.len(), n, 7).unwrap().iter().map(|u| space.from_unit(u)).collect();
    let b = Batch { study: std::path::absolute(&path).unwrap(), cache_dir: std::path::absolute(s.path("cache")).unwrap(), config_sha256: config_digest(&prep.config), evaluations_per_task: n, thetas };
    let out = s.path("work/batch.json");
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    std::fs::write(&out, serde_json::to_vec(&b).unwrap()).unwrap();
    out
}

/// Every `*.json` under the cache is a whole entry (temporary files are dot-files).
fn whole_entries(s: &Scratch) -> usize {
    let Ok(rd) = std::fs::read_dir(s.path("cache")) else { return 0 };
    let mut n = 0;
    for e in rd.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        assert!(name.ends_with(".json"), "unexpected file {name}");
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(e.path()).unwrap()).unwrap_or_else(|err| panic!("{name} is not a whole entry: {err}"));
        assert!(v["theta"].as_array().is_some_and(|t| t.len() == 4) && (v["outputs"].is_array() || v["error"].is_string()), "{name}: {v}");
        n += 1;
    }
    n
}

#[test]
fn a_task_killed_at_any_moment_leaves_only_whole_cache_entries() {
    let s = Scratch::new();
    tiny_calibration(&s, "");
    let b = batch(&s, 8);
    let bs = b.display().to_string();
    // Killed at several moments of its work: never a partial entry under an entry's name. The
    // task stores each result as it finishes and a rerun skips what is stored, so the kills fall
    // before, between and during writes; at least one must leave the work half done (some
    // entries, not all), or the test did not kill a task at work.
    let mut mid_work = 0;
    for delay_ms in [30u64, 300, 500, 700, 900, 1100] {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_partlife")).args(["--threads", "1", "eval", &bs, "--task", "0"]).current_dir(s.dir.path()).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::null()).spawn().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = child.kill();
        let _ = child.wait();
        let n = whole_entries(&s);
        mid_work += usize::from(n > 0 && n < 8);
    }
    assert!(mid_work > 0, "no kill fell while the task was working");
    // Run to the end: the rest is evaluated, every θ has its entry and the task its record.
    let before = whole_entries(&s);
    let out = s.run(&["eval", &bs, "--task", "0"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains(&format!("task 0: {} evaluations", 8 - before)) && out.stdout.contains(&format!("{before} already in the cache")), "{}", out.stdout);
    assert_eq!(whole_entries(&s), 8);
    assert!(s.path("work/task-0.json").is_file());
    // A task index beyond the batch, and a study changed since submission, are refused.
    let out = s.run(&["eval", &bs, "--task", "1"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("batch.json") && out.stderr.contains("task"), "{}", out.stderr);
    s.write("studies/cal.toml", &s.read("studies/cal.toml").replace("refinement = 4.0", "refinement = 5.0"));
    let out = s.run(&["eval", &bs, "--task", "0"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("cal.toml") && out.stderr.contains("changed since"), "{}", out.stderr);
}

/// A stub Slurm in `dir`: `sbatch` runs an array's tasks at once except task 1 (as if it were
/// cancelled before it started), `squeue` finds nothing queued, `scontrol` always fails (a
/// controller that does not answer), and `sacct` reports task 1 CANCELLED and the rest
/// COMPLETED — or fails too when `dir/sacct_fails` exists. `dir/count` counts the sbatch calls.
fn stub_slurm(dir: &std::path::Path) {
    let scripts = [
        (
            "sbatch",
            r#"stub="$(dirname "$0")"
for a in "$@"; do case "$a" in --array=*) arr="${a#--array=}";; --output=*) out="${a#--output=}";; --wrap=*) wrap="${a#--wrap=}";; esac; done
n=$(( $(cat "$stub/count" 2>/dev/null || echo 0) + 1 )); echo "$n" > "$stub/count"
id=$((1000 + n)); last="${arr#0-}"; echo "$last" > "$stub/job_$id"
for t in $(seq 0 "$last"); do
  [ "$t" = 1 ] && continue
  SLURM_ARRAY_TASK_ID=$t bash -c "$wrap" > "${out//%a/$t}" 2>&1
done
echo "$id""#,
        ),
        ("squeue", "exit 0"),
        ("scontrol", r#"echo "slurm_load_jobs error: Unable to contact slurm controller (connect failure)" >&2; exit 1"#),
        (
            "sacct",
            r#"stub="$(dirname "$0")"
[ -e "$stub/sacct_fails" ] && { echo "sacct: error: Slurm accounting storage is disabled" >&2; exit 1; }
id="${@: -1}"; last=$(cat "$stub/job_$id")
for t in $(seq 0 "$last"); do if [ "$t" = 1 ]; then echo "${id}_$t|CANCELLED by 0"; else echo "${id}_$t|COMPLETED"; fi; done"#,
        ),
    ];
    for (name, body) in scripts {
        let p = dir.join(name);
        std::fs::write(&p, format!("#!/bin/bash\n{body}\n")).unwrap();
        std::fs::set_permissions(&p, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    }
}

/// Where `scontrol` fails, the states come from `sacct`: the task it reports CANCELLED is not
/// resubmitted. Where both fail, a task without its result has an unknown state, which is
/// reported as such and not resubmitted blindly. (Before, a failed scontrol made every task
/// UNKNOWN and resubmitted the cancelled ones.)
#[test]
fn task_states_come_from_sacct_when_scontrol_fails_and_unknown_states_are_not_resubmitted() {
    // The stub runs the array's tasks one after another on one core: the two cases side by side.
    std::thread::scope(|scope| {
        for sacct_fails in [false, true] {
            scope.spawn(move || sacct_case(sacct_fails));
        }
    });
}

/// One case of the test above: sacct answering, or failing too.
fn sacct_case(sacct_fails: bool) {
    let s = Scratch::new();
    tiny_calibration(&s, "kind = \"slurm\"\nevaluations_per_task = 1\npoll_seconds = 0.05\nretries = 2");
    let stub = s.path("stub");
    std::fs::create_dir_all(&stub).unwrap();
    stub_slurm(&stub);
    if sacct_fails {
        std::fs::write(stub.join("sacct_fails"), "").unwrap();
    }
    let path = format!("{}:{}", stub.display(), std::env::var("PATH").unwrap_or_default());
    let out = s.run_env(&["run", "studies/cal.toml", "--quiet"], &[("PATH", &path)]);
    assert_eq!(out.code, 0, "sacct fails: {sacct_fails}: {}", out.stderr);
    let attempts = common::table_f64(&s.path("reports/cal/executor.csv"), "attempt");
    assert!(!attempts.is_empty() && attempts.iter().all(|&a| a == 0.0), "sacct fails: {sacct_fails}: resubmitted: attempts {attempts:?}");
    let manifest = s.read("reports/cal/manifest.json");
    let expect: &[&str] = if sacct_fails { &["state unknown", "Unable to contact slurm controller", "accounting storage is disabled", "not resubmitted"] } else { &["was cancelled", "not resubmitted"] };
    for e in expect {
        assert!(manifest.contains(e), "sacct fails: {sacct_fails}: the manifest lacks \"{e}\"");
    }
    assert!(!manifest.contains("ended UNKNOWN"), "sacct fails: {sacct_fails}");
}
