#!/usr/bin/env bash
# A stand-in for the partlife binary in an array task that cancels its own array job, as a user's
# scancel would (tests/slurm.rs: a cancelled array job is detected and reported).
scancel "${SLURM_ARRAY_JOB_ID:?}"
sleep 30
