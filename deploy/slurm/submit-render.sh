#!/usr/bin/env bash
# deploy/slurm/submit-render.sh -- queues an animation render on Slurm: N array tasks (one segment
# each, deploy/slurm/render.sbatch) and the merge after them (deploy/slurm/merge.sbatch). Prints
# the two job ids. --out must be a directory every node sees (shared storage).
#
#   deploy/slurm/submit-render.sh N [--video FILE.mp4] -- RENDER_ARGS...
#   deploy/slurm/submit-render.sh 8 --video /shared/orbit.mp4 -- --anim orbit --out /shared/orbit
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
n=${1:?usage: submit-render.sh N [--video FILE.mp4] -- RENDER_ARGS...}
shift
merge_args=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do merge_args+=("$1"); shift; done
[ "${1:-}" = -- ] && shift
out=
args=("$@")
for ((i = 0; i < ${#args[@]}; i++)); do [ "${args[i]}" = --out ] && out=${args[i + 1]:-}; done
[ -n "$out" ] || { echo "submit-render.sh: RENDER_ARGS need --out DIR (shared storage)" >&2; exit 64; }
array=$(sbatch --parsable --array=0-$((n - 1)) "$here/render.sbatch" "$@")
merge=$(sbatch --parsable --dependency=afterok:"$array" "$here/merge.sbatch" "$out" "${merge_args[@]}")
echo "render array job $array ($n segments), merge job $merge"
