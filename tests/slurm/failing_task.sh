#!/usr/bin/env bash
# A stand-in for the partlife binary in an array task that always fails, as a broken node or a
# crashing model would (tests/slurm.rs: a θ that fails every retry is recorded, not fatal).
echo "injected failure in array task ${SLURM_ARRAY_TASK_ID:-?} of job ${SLURM_ARRAY_JOB_ID:-?}" >&2
exit 7
