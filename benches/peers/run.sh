#!/usr/bin/env bash
# Peer comparison in one command: stickslip (GPU via wgpu, and its f64 CPU
# reference) against the same model written without it -- NumPy and Numba
# (prange) fixed-step RK4, Numba (prange) with exact event location, and JAX
# (vmap + lax.scan) fixed-step RK4 -- on Den Hartog's case and on the noisy
# default, each tuned to the same accuracy.
# Usage: benches/peers/run.sh [peers.py options]   (see peers.py --help)
#        benches/peers/run.sh --quick              (small smoke run, not a benchmark)
# Output goes to the terminal and to benches/peers/last-run.txt
# (last-run-quick.txt for --quick).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="$here/.venv"
python="${PYTHON:-python3}"

# Versions this comparison was run with.
NUMPY_VERSION=2.4.6
NUMBA_VERSION=0.68.1
JAX_VERSION=0.10.2          # jax and jaxlib, CPU wheels

if [[ ! -x "$venv/bin/python" ]]; then
    echo "creating $venv" >&2
    "$python" -m venv "$venv"
fi
if ! "$venv/bin/python" -c "import numpy, numba, jax, jaxlib, sys; sys.exit(not (numpy.__version__ == '$NUMPY_VERSION' and numba.__version__ == '$NUMBA_VERSION' and jax.__version__ == '$JAX_VERSION' and jaxlib.__version__ == '$JAX_VERSION'))" 2>/dev/null; then
    "$venv/bin/python" -m pip install --quiet "numpy==$NUMPY_VERSION" "numba==$NUMBA_VERSION" \
        "jax==$JAX_VERSION" "jaxlib==$JAX_VERSION"
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
# A --quick smoke run must not overwrite the last real run.
log="$here/last-run.txt"
for arg in "$@"; do
    if [[ "$arg" == --quick ]]; then log="$here/last-run-quick.txt"; fi
done
echo "stickslip: $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo '?')$(git -C "$root" diff --quiet HEAD -- src shaders Cargo.toml 2>/dev/null || echo ' + uncommitted changes in src/shaders'), binary built $(date -r target/release/stickslip '+%F %T')" | tee "$log"

set +e
"$venv/bin/python" "$here/peers.py" --binary "$snap/stickslip" "$@" 2>&1 | tee -a "$log"
status=${PIPESTATUS[0]}
exit "$status"
