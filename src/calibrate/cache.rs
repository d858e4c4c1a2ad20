//! A disk cache of simulator evaluations: a killed or repeated study reuses finished runs.
//!
//! [`Cached`] wraps any [`Simulator`]. An evaluation is stored as one small JSON file
//! `<dir>/<key>.json`, the key being the SHA-256 of the model's configuration text (for
//! example the serialised crush set-up: any change of the model makes new keys) and the exact
//! bit patterns of θ. Files are written atomically (temporary file + rename), so an interrupted
//! run leaves either a whole entry or none; a corrupt or foreign file is ignored and
//! recomputed. Failed evaluations are cached too (with their message), so a rerun does not
//! retry a θ known to fail.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::io::{sha256_hex, write_atomic};
use crate::model::{OutputSpec, Simulator};
use crate::params::ParamSpace;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Entry {
    theta: Vec<f64>,
    outputs: Option<Vec<f64>>,
    error: Option<String>,
}

/// A simulator whose evaluations are cached on disk.
pub struct Cached<S: Simulator> {
    inner: S,
    dir: PathBuf,
    config: String,
    hits: AtomicU64,
    misses: AtomicU64,
}

impl<S: Simulator> Cached<S> {
    /// Caches `inner` under `dir` (created if missing); `config` identifies the model's
    /// configuration.
    pub fn new(inner: S, dir: &Path, config: impl Into<String>) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
        Ok(Cached { inner, dir: dir.to_path_buf(), config: config.into(), hits: AtomicU64::new(0), misses: AtomicU64::new(0) })
    }

    /// (cache hits, evaluations run) so far.
    pub fn counts(&self) -> (u64, u64) {
        (self.hits.load(Ordering::Relaxed), self.misses.load(Ordering::Relaxed))
    }

    /// The wrapped simulator.
    pub fn inner(&self) -> &S {
        &self.inner
    }

    fn key(&self, theta: &[f64]) -> String {
        let mut bytes = self.config.as_bytes().to_vec();
        bytes.push(0);
        for t in theta {
            bytes.extend_from_slice(&t.to_bits().to_le_bytes());
        }
        sha256_hex(&bytes)
    }

    /// The entry file of θ.
    fn path(&self, theta: &[f64]) -> PathBuf {
        self.dir.join(format!("{}.json", self.key(theta)))
    }

    /// The cached result of θ, if a whole entry of this configuration and exactly this θ is on
    /// disk (a corrupt, foreign or mismatched file counts as none); counts nothing.
    pub fn lookup(&self, theta: &[f64]) -> Option<Result<Vec<f64>>> {
        let text = std::fs::read_to_string(self.path(theta)).ok()?;
        let e = serde_json::from_str::<Entry>(&text).ok()?;
        if !e.theta.iter().map(|v| v.to_bits()).eq(theta.iter().map(|v| v.to_bits())) {
            return None;
        }
        match (e.outputs, e.error) {
            (Some(y), _) if y.len() == self.outputs().len() => Some(Ok(y)),
            (_, Some(msg)) => Some(Err(Error::numerical("cached evaluation", msg))),
            _ => None,
        }
    }

    /// Stores the result of θ (atomically: a whole entry or none). A bad θ (wrong length, not
    /// finite: [`Error::Param`]) is not a property of the model and is not stored.
    pub fn store(&self, theta: &[f64], r: &Result<Vec<f64>>) -> Result<()> {
        let entry = match r {
            Ok(y) => Entry { theta: theta.to_vec(), outputs: Some(y.clone()), error: None },
            Err(Error::Param { .. }) => return Ok(()),
            Err(e) => Entry { theta: theta.to_vec(), outputs: None, error: Some(e.to_string()) },
        };
        let json = serde_json::to_vec(&entry).map_err(|e| Error::numerical("cache", e.to_string()))?;
        write_atomic(&self.path(theta), &json)
    }
}

impl<S: Simulator> Simulator for Cached<S> {
    fn space(&self) -> &ParamSpace {
        self.inner.space()
    }
    fn outputs(&self) -> &[OutputSpec] {
        self.inner.outputs()
    }
    fn simulate(&self, theta: &[f64]) -> Result<Vec<f64>> {
        if let Some(r) = self.lookup(theta) {
            self.hits.fetch_add(1, Ordering::Relaxed);
            return r;
        }
        self.misses.fetch_add(1, Ordering::Relaxed);
        let r = self.inner.simulate(theta);
        self.store(theta, &r)?;
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;
    use std::sync::atomic::AtomicUsize;

    struct Counting {
        space: ParamSpace,
        outputs: Vec<OutputSpec>,
        calls: AtomicUsize,
    }

    impl Simulator for Counting {
        fn space(&self) -> &ParamSpace {
            &self.space
        }
        fn outputs(&self) -> &[OutputSpec] {
            &self.outputs
        }
        fn simulate(&self, th: &[f64]) -> Result<Vec<f64>> {
            self.calls.fetch_add(1, Ordering::SeqCst);
            if th[0] < 0.0 {
                return Err(Error::numerical("counting", "negative"));
            }
            Ok(vec![th[0] * 2.0])
        }
    }

    fn model() -> Counting {
        Counting {
            space: ParamSpace::new(vec![Param::uniform("x", "-", -1.0, 1.0, 0.0)]).unwrap(),
            outputs: vec![OutputSpec::new("y", "-")],
            calls: AtomicUsize::new(0),
        }
    }

    #[test]
    fn repeated_and_resumed_evaluations_come_from_disk() {
        let dir = crate::io::TempDir::new("test").unwrap();
        let c = Cached::new(model(), dir.path(), "config A").unwrap();
        assert_eq!(c.simulate(&[0.25]).unwrap(), vec![0.5]);
        assert_eq!(c.simulate(&[0.25]).unwrap(), vec![0.5]);
        assert!(c.simulate(&[-0.5]).is_err());
        assert!(c.simulate(&[-0.5]).is_err());
        assert_eq!(c.inner().calls.load(Ordering::SeqCst), 2, "one run per distinct θ");
        assert_eq!(c.counts(), (2, 2));
        // A new process (a resumed study) reuses the files; another configuration does not.
        let again = Cached::new(model(), dir.path(), "config A").unwrap();
        assert_eq!(again.simulate(&[0.25]).unwrap(), vec![0.5]);
        assert_eq!(again.inner().calls.load(Ordering::SeqCst), 0);
        let other = Cached::new(model(), dir.path(), "config B").unwrap();
        other.simulate(&[0.25]).unwrap();
        assert_eq!(other.inner().calls.load(Ordering::SeqCst), 1);
        // The same θ many times in one parallel batch: every result right, one file.
        let batch = vec![vec![0.75]; 64];
        assert!(c.simulate_batch(&batch).into_iter().all(|r| r.unwrap() == vec![1.5]));
        // A corrupt entry is recomputed.
        for e in std::fs::read_dir(dir.path()).unwrap().flatten() {
            std::fs::write(e.path(), b"{ truncated").unwrap();
        }
        let fresh = Cached::new(model(), dir.path(), "config A").unwrap();
        assert_eq!(fresh.simulate(&[0.25]).unwrap(), vec![0.5]);
        assert_eq!(fresh.inner().calls.load(Ordering::SeqCst), 1);
    }
}
