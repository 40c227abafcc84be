#!/usr/bin/env bash
# The GPU measurements (issue 44) as one call on a lent GPU machine, whose time is short.
#
#   bash benches/gpu-machine.sh prepare    # here: builds and strips the binaries and fetches
#                                          # the Vulkan loader into target/gpu-machine
#   bash benches/gpu-machine.sh run        # there, with target/gpu-machine carried over;
#                                          # results go to $OUT (default target/gpu-machine/out)
#
# The run measures, in order of importance, each step under its own time limit:
#   - the adapter (`stickslip check-gpu`) and the machine;
#   - the main job on the GPU and on the CPU reference, and how far their peak means differ;
#   - an 18-run independent set (seed 7's set 12) diagnosed with records from the CPU
#     reference (`--backend auto`) and from the kernel (`--backend gpu`), its time and verdict;
#   - the integration tests on the hardware adapter;
#   - the kernel's realisation-steps/s (`throughput --bench gpu`).
# Set-up that made an NVIDIA machine's Vulkan driver start (H100 and H200 so far): Debian's
# libvulkan1 and libglvnd libraries unpacked into /, and VK_DRIVER_FILES pointing at the
# NVIDIA ICD that the machine's driver installs.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
kit="$root/target/gpu-machine"

prepare() {
    set -e
    cd "$root"
    cargo build --release
    cargo test --release --no-run
    cargo bench --bench throughput --no-run
    rm -rf "$kit" && mkdir -p "$kit/bin" "$kit/debs"
    strip -o "$kit/bin/stickslip" target/release/stickslip
    local newest
    for name in integration throughput; do
        newest=$(ls -t target/release/deps/"$name"-* | grep -v '\.d$' | head -1)
        strip -o "$kit/bin/$name" "$newest"
    done
    # The test binary runs the CLI and reads data/ by the paths it was built with.
    pwd > "$kit/built-in"
    (cd "$kit/debs" && apt-get download libvulkan1 libglvnd0 libegl1 libgl1 libglx0 libgles2 libopengl0)
    du -sh "$kit"
}

run() {
    local out="${OUT:-$kit/out}" bin="$kit/bin" start
    mkdir -p "$out"
    start=$(date +%s)
    for deb in "$kit"/debs/*.deb; do dpkg -x "$deb" /; done
    ldconfig
    export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json}"
    chmod +x "$bin"/*
    {
        nproc
        lscpu | grep "Model name"
        nvidia-smi --query-gpu=name,clocks.max.sm,driver_version --format=csv
        "$bin/stickslip" check-gpu
    } > "$out/machine.txt" 2>&1
    cat "$out/machine.txt"
    # step NAME LIMIT_S COMMAND...: its output in NAME.log, its wall time in times.txt.
    step() {
        local name=$1 limit=$2 t0 t1 rc
        shift 2
        echo "[$(($(date +%s) - start)) s] $name"
        t0=$(date +%s.%N)
        timeout "$limit" "$@" > "$out/$name.log" 2>&1
        rc=$?
        t1=$(date +%s.%N)
        echo "$name rc=$rc wall_s=$(awk "BEGIN { print $t1 - $t0 }")" | tee -a "$out/times.txt"
    }
    local work=/tmp/gpu-machine
    rm -rf "$work" && mkdir -p "$work"
    step sweep-auto 60 "$bin/stickslip" sweep --out "$work/sweep-auto"
    step sweep-cpu 60 "$bin/stickslip" sweep --backend cpu --no-plots --out "$work/sweep-cpu"
    python3 - "$work" > "$out/sweep-agreement.txt" 2>&1 <<'EOF'
import csv, sys
rows = lambda b: {(r["excitation_frequency_hz"], r["normal_force_n"]): float(r["peak_mean_m"])
                  for r in csv.DictReader(open(f"{sys.argv[1]}/sweep-{b}/sweep.csv"))}
g, c = rows("auto"), rows("cpu")
worst = max(abs(g[k] - c[k]) / abs(c[k]) for k in c if k in g and c[k] != 0)
print(f"{len(c)} points; largest relative difference of peak_mean_m {worst:.2e}")
EOF
    local set="--generator independent --nulls 6 --pairs 3 --phase-only 0 --levels 0 --frequency-ratios 0.6,0.7,0.8,0.9,1.1,1.2 --duration 50 --seed 7 --sets 12"
    # shellcheck disable=SC2086
    step diagnose-auto 240 "$bin/stickslip" benchmark-diagnosis $set --backend auto --out "$work/auto"
    step diagnose-gpu 150 "$bin/stickslip" diagnose "$work/auto/set-012/data" --seed $((7 ^ 0xD1A6)) \
        --backend gpu --out "$work/gpu"
    for d in auto/set-012/diagnosis gpu; do
        cp "$work/$d/report.json" "$out/report-${d%%/*}.json" 2>/dev/null
    done
    # The test binary's paths are those of the machine it was built on.
    local built
    built=$(cat "$kit/built-in")
    [ -e "$built" ] || { mkdir -p "$(dirname "$built")" && ln -s "$root" "$built"; }
    mkdir -p "$built/target/release" && cp "$bin/stickslip" "$built/target/release/stickslip"
    (cd "$built" && step tests 200 "$bin/integration" --test-threads "$(nproc)")
    STICKSLIP_BENCH_GPU_SIZES=65536,262144,1048576 step throughput 120 "$bin/throughput" --bench gpu
    echo "[$(($(date +%s) - start)) s] done"
    cat "$out/times.txt" "$out/sweep-agreement.txt"
    grep -h "test result" "$out/tests.log"
}

case "${1:-}" in
    prepare) prepare ;;
    run) run ;;
    *) echo "usage: $0 prepare|run" >&2; exit 2 ;;
esac
