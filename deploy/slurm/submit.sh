#!/usr/bin/env bash
# Submits the shard array, then the merge with --dependency=afterok on it.
#
#   NSHARDS=8 OUTDIR=/scratch/stickslip/run1 FREQUENCIES=5:15:41 deploy/slurm/submit.sh [SBATCH OPTIONS...]
#
# The environment (sweep arguments, NSHARDS, OUTDIR, STICKSLIP; see the top of
# sweep-array.sbatch) is exported to every task, so all shards get the same
# arguments. SBATCH OPTIONS apply to the array only; put site options meant
# for both jobs in SBATCH_PARTITION / SBATCH_ACCOUNT, which sbatch reads itself.
# MAX_PARALLEL=P limits how many shards run at once (--array=0-(N-1)%P).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
NSHARDS=${NSHARDS:-8}
OUTDIR=${OUTDIR:-$PWD/out/sweep-sharded}
[[ $NSHARDS =~ ^[1-9][0-9]*$ ]] || { echo "submit: NSHARDS must be a positive integer" >&2; exit 1; }
[[ $OUTDIR == /* ]] || OUTDIR=$PWD/$OUTDIR
export NSHARDS OUTDIR

if compgen -G "$OUTDIR/shard-*" >/dev/null; then
    echo "submit: warning: $OUTDIR already has shard directories; stale ones from another run make merge fail" >&2
fi

array=0-$((NSHARDS - 1))${MAX_PARALLEL:+%$MAX_PARALLEL}
array_id=$(sbatch --parsable --export=ALL --array="$array" "$@" "$here/sweep-array.sbatch")
array_id=${array_id%%;*}   # --parsable prints "jobid[;cluster]"
merge_id=$(sbatch --parsable --export=ALL --dependency="afterok:$array_id" --kill-on-invalid-dep=yes \
    "$here/merge.sbatch")
merge_id=${merge_id%%;*}

echo "array job $array_id: $NSHARDS shards -> $OUTDIR/shard-*"
echo "merge job $merge_id (after all shards succeed) -> $OUTDIR/merged"
