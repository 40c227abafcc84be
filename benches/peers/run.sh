#!/usr/bin/env bash
# Peer comparison in one command: stickslip (GPU via wgpu, and its f64 CPU
# reference) against vectorised NumPy and Numba-parallel versions of the same
# model, on the same Den Hartog workload, tuned to the same accuracy.
# Usage: benches/peers/run.sh [peers.py options]   (see peers.py --help)
# Output goes to the terminal and to benches/peers/last-run.txt.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="$here/.venv"
python="${PYTHON:-python3}"

# Versions this comparison was run with.
NUMPY_VERSION=2.4.6
NUMBA_VERSION=0.68.1

if [[ ! -x "$venv/bin/python" ]]; then
    echo "creating $venv" >&2
    "$python" -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import numpy, numba, sys; sys.exit(not (numpy.__version__ == '$NUMPY_VERSION' and numba.__version__ == '$NUMBA_VERSION'))" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet "numpy==$NUMPY_VERSION" "numba==$NUMBA_VERSION"
fi

cd "$root"
# Another build may hold cargo's lock for a while (cargo waits for it), or the
# tree may be mid-edit and fail to compile (retry a few times).
built=0
for attempt in 1 2 3 4; do
    if cargo build --release --quiet; then built=1; break; fi
    echo "cargo build --release failed (attempt $attempt)" >&2
    [[ $attempt == 4 ]] || sleep 20
done
if [[ $built == 0 ]]; then
    [[ -x target/release/stickslip ]] || exit 1
    echo "WARNING: benchmarking the existing target/release/stickslip, which may be stale" >&2
fi

# Benchmark a private copy, so that a concurrent rebuild cannot swap the
# binary in the middle of the run (the shaders are compiled into it).
snap="$(mktemp -d)"
trap 'rm -rf "$snap"' EXIT
cp target/release/stickslip "$snap/stickslip"
echo "stickslip: $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo '?')$(git -C "$root" diff --quiet HEAD -- src shaders Cargo.toml 2>/dev/null || echo ' + uncommitted changes in src/shaders'), binary built $(date -r target/release/stickslip '+%F %T')" | tee "$here/last-run.txt"

set +e
"$venv/bin/python" "$here/peers.py" --binary "$snap/stickslip" "$@" 2>&1 | tee -a "$here/last-run.txt"
status=${PIPESTATUS[0]}
exit "$status"
