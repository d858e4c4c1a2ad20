//! The task side of the Slurm executor (`partlife eval`): one array task of a batch file
//! written by [`super::executor::Slurm`] — rebuild the model from the calibration study, evaluate
//! the task's θ's, store each result in the shared cache, write the task's timing record.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::cache::Cached;
use super::executor::{Batch, TaskRecord, config_digest, task_record_path, unix_now};
use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::model::Simulator;

/// Runs task `task` of the batch file `batch_path` (`partlife eval`): rebuilds the model from
/// the study, evaluates in parallel those of the task's θ's that the cache does not hold yet,
/// stores each result as soon as it is computed — a task killed halfway keeps what it finished,
/// and its rerun does only the rest — and writes the task's record. A θ the model fails at is
/// stored as a failed entry (a property of θ); an unreadable batch, a changed study or an
/// unwritable cache is an error.
pub fn eval_task(batch_path: &Path, task: usize) -> Result<TaskRecord> {
    let started = unix_now();
    let clock = Instant::now();
    let text = crate::io::read_input_text(batch_path)?;
    let batch: Batch = serde_json::from_str(&text).map_err(|e| Error::data_file(batch_path, "file", format!("not a partlife batch file: {e}")))?;
    if task >= batch.tasks() {
        return Err(Error::config(batch_path.display().to_string(), "task", format!("the batch has {} tasks (0…{}), got task {task}", batch.tasks(), batch.tasks().saturating_sub(1))));
    }
    let loaded = crate::schema::StudyFile::read(&batch.study)?;
    let study: super::study::CalibrateStudy = loaded.parse()?;
    let prep = study.prepare(&batch.study, &|p: &str| loaded.resolve(Path::new(p)))?;
    if config_digest(&prep.config) != batch.config_sha256 {
        return Err(Error::config(batch.study.display().to_string(), "model", format!("the model's configuration changed since {} was written: resubmit from the driver", batch_path.display())));
    }
    let sim: &dyn Simulator = match &prep.built {
        super::study::Built::Crush(model, _) => model,
        super::study::Built::Dem(model) => model.as_ref(),
    };
    let cached = Cached::new(sim, &batch.cache_dir, prep.config.clone())?;
    let setup_s = clock.elapsed().as_secs_f64();
    let thetas = &batch.thetas[batch.slice(task)];
    let todo: Vec<&Vec<f64>> = thetas.iter().filter(|t| cached.lookup(t).is_none()).collect();
    let (compute_ns, write_ns) = (AtomicU64::new(0), AtomicU64::new(0));
    let failed: Vec<bool> = todo
        .par_iter()
        .map(|t| {
            let t0 = Instant::now();
            let r = sim.simulate(t);
            let t1 = Instant::now();
            cached.store(t, &r)?;
            compute_ns.fetch_add((t1 - t0).as_nanos() as u64, Ordering::Relaxed);
            write_ns.fetch_add(t1.elapsed().as_nanos() as u64, Ordering::Relaxed);
            Ok(r.is_err())
        })
        .collect::<Result<_>>()?;
    let record = TaskRecord {
        task,
        evaluations: todo.len(),
        already_cached: thetas.len() - todo.len(),
        model_failures: failed.iter().filter(|&&f| f).count(),
        setup_s,
        compute_s: compute_ns.load(Ordering::Relaxed) as f64 * 1e-9,
        write_s: write_ns.load(Ordering::Relaxed) as f64 * 1e-9,
        started_unix_s: started,
        finished_unix_s: unix_now(),
    };
    let json = serde_json::to_vec(&record).map_err(|e| Error::numerical("task record", e.to_string()))?;
    write_atomic(&task_record_path(batch_path, task), &json)?;
    Ok(record)
}

