#!/usr/bin/env bash
# Applies the shared volume and the sweep's Indexed Job with the shard count N
# set in one place, here: NSHARDS is written into both the Job's
# spec.completions and its pods' NSHARDS env var, which must agree.
#
#   NSHARDS=16 PARALLELISM=4 deploy/kubernetes/submit.sh
#   kubectl wait --for=condition=complete --timeout=24h job/stickslip-sweep
#   kubectl apply -f deploy/kubernetes/merge-job.yaml
#
# Sweep arguments (frequencies, loads, seed, ...) are the env block of
# sweep-indexed-job.yaml; KUBECTL overrides the kubectl command.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
NSHARDS=${NSHARDS:-8}
PARALLELISM=${PARALLELISM:-4}
KUBECTL=${KUBECTL:-kubectl}
[[ $NSHARDS =~ ^[1-9][0-9]*$ ]] || { echo "submit: NSHARDS must be a positive integer, not '$NSHARDS'" >&2; exit 1; }
[[ $PARALLELISM =~ ^[1-9][0-9]*$ ]] || { echo "submit: PARALLELISM must be a positive integer, not '$PARALLELISM'" >&2; exit 1; }

manifest=$(sed -E \
    -e "s/^(  completions: )[0-9]+/\1$NSHARDS/" \
    -e "s/^(  parallelism: )[0-9]+/\1$PARALLELISM/" \
    -e "s/^(              value: )\"[0-9]+\"( +# N, written by submit.sh)/\1\"$NSHARDS\"\2/" \
    "$here/sweep-indexed-job.yaml")
# Both places must have been rewritten; a changed layout of the manifest
# would otherwise apply with the committed N.
grep -qE "^  completions: $NSHARDS( |$)" <<<"$manifest" \
    && grep -qE "^              value: \"$NSHARDS\" +# N, written by submit.sh" <<<"$manifest" \
    || { echo "submit: could not set N in sweep-indexed-job.yaml (its layout changed?)" >&2; exit 1; }

$KUBECTL apply -f "$here/pvc.yaml"
$KUBECTL apply -f - <<<"$manifest"
echo "sweep job stickslip-sweep: $NSHARDS shards, $PARALLELISM at a time -> /data/shard-*"
