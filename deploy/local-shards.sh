#!/usr/bin/env bash
# Runs a sharded sweep on this machine, one shard after another, then merges:
#
#   deploy/local-shards.sh N OUTDIR [SWEEP ARGS...]
#
# runs `stickslip sweep SWEEP ARGS --shard K/N --out OUTDIR/shard-K` for
# K = 0..N-1 and `stickslip merge --out OUTDIR/merged OUTDIR/shard-*`.
# With CHECK=1 it also runs the same sweep unsharded into OUTDIR/unsharded
# and compares it with the merge byte for byte (all files but sweep.json,
# which records timing). STICKSLIP picks the binary (default: the repo's
# target/release/stickslip if built, else stickslip on PATH).
#
# Smoke test:
#   CHECK=1 deploy/local-shards.sh 3 /tmp/ss --frequencies 6:8:5 --normal-forces 4,16.39 \
#       --realisations 8 --warmup-cycles 5 --cycles 10 --backend cpu
set -euo pipefail

die() { echo "local-shards: $*" >&2; exit 1; }
(($# >= 2)) || die "usage: $0 N OUTDIR [SWEEP ARGS...]"
N=$1 OUTDIR=$2
shift 2
[[ $N =~ ^[1-9][0-9]*$ ]] || die "N must be a positive integer, got '$N'"
for a in "$@"; do
    case $a in --shard|--shard=*|--out|--out=*) die "$a is set by this script" ;; esac
done

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [[ -z ${STICKSLIP:-} ]]; then
    if [[ -x $root/target/release/stickslip ]]; then STICKSLIP=$root/target/release/stickslip; else STICKSLIP=stickslip; fi
fi
if compgen -G "$OUTDIR/shard-*" >/dev/null; then
    die "$OUTDIR already has shard directories; use a fresh OUTDIR"
fi

for ((K = 0; K < N; K++)); do
    echo "== shard $K/$N" >&2
    "$STICKSLIP" sweep "$@" --shard "$K/$N" --out "$OUTDIR/shard-$K"
done
shards=()
for ((K = 0; K < N; K++)); do shards+=("$OUTDIR/shard-$K"); done
echo "== merge" >&2
"$STICKSLIP" merge --out "$OUTDIR/merged" "${shards[@]}"
echo "merged: $OUTDIR/merged" >&2

if [[ ${CHECK:-0} == 1 ]]; then
    echo "== unsharded reference" >&2
    "$STICKSLIP" sweep "$@" --out "$OUTDIR/unsharded"
    checked=0
    for f in "$OUTDIR"/unsharded/*; do
        name=${f##*/}
        [[ -f $f && $name != sweep.json ]] || continue
        [[ -f $OUTDIR/merged/$name ]] || die "the merge has no $name (the unsharded run has)"
        cmp "$f" "$OUTDIR/merged/$name" || die "merged $name differs from the unsharded run's"
        checked=$((checked + 1))
    done
    ((checked > 0)) || die "the unsharded run wrote nothing to compare"
    echo "check: $checked file(s) of the merge identical to the unsharded run" >&2
fi
