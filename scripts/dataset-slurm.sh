#!/usr/bin/env bash
# One shard of an ltmsim dataset per task of a Slurm job array (docs/dataset.md, "Scale-out"):
#   jid=$(sbatch --parsable --array=1-64 --cpus-per-task=4 scripts/dataset-slurm.sh SPEC.yaml DIR)
#   sbatch --dependency=afterany:$jid --wrap "build/ltmsim dataset DIR --index"
# Submit from the ltmsim folder (the script finds build/ltmsim there; or set LTMSIM). Each task
# renders shard (task - first task + 1) of (number of tasks) with --resume, so a requeued or
# preempted task continues where it stopped; the bytes of the dataset do not depend on how it
# was split.
#SBATCH --job-name=ltmsim-dataset
#SBATCH --cpus-per-task=4
set -euo pipefail
if (( $# != 2 )); then
  echo "usage: sbatch --array=1-N $0 SPEC.yaml DIR" >&2
  exit 2
fi
: "${SLURM_ARRAY_TASK_ID:?not a Slurm array task: submit with sbatch --array=1-N}"
first=${SLURM_ARRAY_TASK_MIN:-1}
count=${SLURM_ARRAY_TASK_COUNT:?not a Slurm array task: submit with sbatch --array=1-N}
ltmsim=${LTMSIM:-${SLURM_SUBMIT_DIR:-$PWD}/build/ltmsim}
exec "$ltmsim" dataset "$1" -o "$2" --shard "$(( SLURM_ARRAY_TASK_ID - first + 1 ))/$count" --resume \
  --threads "${SLURM_CPUS_PER_TASK:-0}"
