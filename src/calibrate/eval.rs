//! The task side of the Slurm executor (`partlife eval`): one array task of a batch file
//! written by [`super::executor::Slurm`] — rebuild the model from the calibration study, evaluate
//! the task's θ's, store each result in the shared cache, write the task's timing record.

use std::path::Path;
use std::time::Instant;

use super::cache::Cached;
use super::executor::{Batch, TaskRecord, config_digest, task_record_path, unix_now};
use crate::error::{Error, Result};
use crate::io::write_atomic;
use crate::model::Simulator;

/// Runs task `task` of the batch file `batch_path` (`partlife eval`): rebuilds the model from
/// the study, evaluates the task's θ's in parallel, stores each in the cache and writes the
/// task's record. A θ the model fails at is stored as a failed entry (a property of θ); an
/// unreadable batch, a changed study or an unwritable cache is an error.
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
    let t1 = Instant::now();
    let results = sim.simulate_batch(thetas);
    let compute_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    for (t, r) in thetas.iter().zip(&results) {
        cached.store(t, r)?;
    }
    let record = TaskRecord {
        task,
        evaluations: thetas.len(),
        model_failures: results.iter().filter(|r| r.is_err()).count(),
        setup_s,
        compute_s,
        write_s: t2.elapsed().as_secs_f64(),
        started_unix_s: started,
        finished_unix_s: unix_now(),
    };
    let json = serde_json::to_vec(&record).map_err(|e| Error::numerical("task record", e.to_string()))?;
    write_atomic(&task_record_path(batch_path, task), &json)?;
    Ok(record)
}

