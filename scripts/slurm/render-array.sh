#!/usr/bin/env bash
# Submit a mislab render split into N parts as a Slurm job array, plus a merge job that runs when every part
# has succeeded (docs/cluster.md).
#
#   scripts/slurm/render-array.sh [-n N] [-d DIR] [-m MISLAB] [-c SECONDS] [-s "SBATCH ARGS"] -- RENDER ARGS…
#
# RENDER ARGS are those of `mislab render` (scene, --spp, settings; not -o/--state/--part). Task K of the array
# runs `mislab render … --part K/N` into DIR/part-K.state (checkpointing every SECONDS, and resuming from its
# checkpoint when Slurm requeues it); the merge job writes DIR/merged.exr and DIR/merged.state. Prints the
# array's and the merge's job ids ("ARRAY MERGE") on stdout.
set -euo pipefail

parts=4 dir=mislab-parts mislab=mislab every=300 extra=""
while getopts "n:d:m:c:s:h" opt; do
    case $opt in
        n) parts=$OPTARG ;;
        d) dir=$OPTARG ;;
        m) mislab=$OPTARG ;;
        c) every=$OPTARG ;;
        s) extra=$OPTARG ;;
        *) sed -n '2,12p' "$0"; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
[ "${1:-}" = "--" ] && shift
if [ $# -eq 0 ]; then echo "render-array.sh: give the render arguments after --" >&2; exit 2; fi
if ! [[ $parts =~ ^[1-9][0-9]*$ ]]; then echo "render-array.sh: -n $parts: need a positive number of parts" >&2; exit 2; fi
command -v sbatch >/dev/null || { echo "render-array.sh: sbatch not found (is this a Slurm login node?)" >&2; exit 2; }

mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
render_args=$(printf '%q ' "$@")
mislab_q=$(printf '%q' "$mislab")
dir_q=$(printf '%q' "$dir")

# sbatch --wrap runs /bin/sh: plain POSIX shell below. A requeued task (preemption, node failure, time
# limit with --requeue) resumes from its last checkpoint.
task="s=$dir_q/part-\$SLURM_ARRAY_TASK_ID.state; \
if [ -f \"\$s\" ]; then from=--resume; else from=--state; fi; \
exec $mislab_q render $render_args --part \$SLURM_ARRAY_TASK_ID/$parts --checkpoint-every $every \
-o $dir_q/part-\$SLURM_ARRAY_TASK_ID.exr \"\$from\" \"\$s\""

# shellcheck disable=SC2086 # $extra is a list of sbatch options
array=$(sbatch --parsable $extra --job-name=mislab-part --array=0-$((parts - 1)) \
    --output="$dir/part-%a.log" --wrap="$task")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable $extra --job-name=mislab-merge --dependency=afterok:"$array" --kill-on-invalid-dep=yes \
    --output="$dir/merge.log" \
    --wrap="$mislab_q merge $dir_q/part-*.state -o $dir_q/merged.exr && $mislab_q merge --status $dir_q")
merge=${merge%%;*}
echo "$array $merge"
