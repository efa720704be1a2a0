#!/bin/bash
# Renders one frame on a Slurm cluster: an array of SHARDS tasks, each a share of the samples, and a merge job
# that runs once all of them succeeded. Prints the two job ids; with --wait, returns when the merge has ended.
#   deploy/slurm/submit.sh [--wait] SCENE OUTPUT SHARDS [strata render options...]
#   deploy/slurm/submit.sh scenes/showcase.toml showcase.png 16 --size 3840x2160 --spp 1024
# With --frames or --turntable the shards split the frames, written as OUTPUT numbered: no merge job.
# PARTS_DIR (default: OUTPUT's directory/OUTPUT.parts) must be on storage every node sees. STRATA names the
# strata binary (default: strata on PATH); SBATCH_OPTIONS adds options to both sbatch calls (partition, ...).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
wait=
if [ "${1:-}" = --wait ]; then wait=--wait; shift; fi
if [ $# -lt 3 ]; then
    sed -n '2,8p' "$0" >&2
    exit 2
fi
scene=$1 output=$2 shards=$3
shift 3
case $shards in ''|*[!0-9]*) echo "submit.sh: SHARDS must be a number, got '$shards'" >&2; exit 2;; esac
for option in "$@"; do
    case $option in
        --frames|--frames=*|--turntable|--turntable=*)
            # shellcheck disable=SC2086
            array=$(sbatch --parsable $wait ${SBATCH_OPTIONS:-} --array="0-$((shards - 1))" \
                "$here/strata-shard.sbatch" "$(dirname "$output")" "$scene" -o "$output" "$@")
            echo "frames: job ${array%%;*} ($shards tasks) -> $output, numbered"
            exit 0 ;;
    esac
done
parts=${PARTS_DIR:-$output.parts}
mkdir -p "$parts"
# shellcheck disable=SC2086 # SBATCH_OPTIONS is a list of options
array=$(sbatch --parsable ${SBATCH_OPTIONS:-} --array="0-$((shards - 1))" "$here/strata-shard.sbatch" "$parts" "$scene" "$@")
array=${array%%;*}
echo "shards: job $array ($shards tasks) -> $parts"
# shellcheck disable=SC2086
merge=$(sbatch --parsable $wait ${SBATCH_OPTIONS:-} --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    "$here/strata-merge.sbatch" "$parts" "$output" --remove-parts)
echo "merge: job ${merge%%;*} -> $output"
