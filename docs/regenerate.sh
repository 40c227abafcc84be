#!/usr/bin/env bash
# Re-runs the README's commands and rewrites what the README quotes from them:
# every number between <!-- num:NAME --> and <!-- /num --> and the figures in
# docs/*.png. Nothing in the README is typed in by hand that this script
# produces.
#
#   docs/regenerate.sh            run the commands, rewrite README.md and docs/*.png
#   docs/regenerate.sh --check    run the deterministic commands only (on the f64 CPU
#                                 reference) and fail when a quoted result differs from
#                                 what the code gives now; writes nothing (CI runs this)
#   docs/regenerate.sh --builds   also time a clean `cargo install`, the test build and
#                                 the Python wheel build in a fresh clone (about 15 min
#                                 on 2 cores) and rewrite those numbers
#
# Results (sweep statistics at a fixed seed, grid sizes) are deterministic: --check
# accepts a difference of at most one unit in the last digit the README shows (a
# rounding that flips on the last bits of another libm or a GPU's f32). Timings are
# not checked; they are quoted with the machine they were measured on (the `machine`
# span), which this script fills in from lscpu.
#
# STICKSLIP=/path/to/stickslip uses that binary; by default the repository's release
# build (built here with `cargo build --release` when missing or older than the source).
set -euo pipefail
cd "$(dirname "$0")/.."

mode=write
builds=0
for arg in "$@"; do
    case "$arg" in
        --check) mode=check ;;
        --builds) builds=1 ;;
        *) echo "regenerate: unknown argument '$arg' (--check, --builds)" >&2; exit 2 ;;
    esac
done

if [ -z "${STICKSLIP:-}" ]; then
    cargo build --release --quiet
    STICKSLIP=$PWD/target/release/stickslip
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "regenerate: the README's commands ($mode), with $STICKSLIP" >&2
cut -d' ' -f1 /proc/loadavg >"$work/load.txt" 2>/dev/null || echo 0 >"$work/load.txt"
if [ "$mode" = check ]; then
    backend=(--backend cpu --no-plots)
else
    backend=()
fi

# The main job (README, "The first hour", 1).
"$STICKSLIP" -q sweep "${backend[@]}" --out "$work/sweep" >"$work/sweep.txt"
# The Figure 8 workflow (README, "Figures").
"$STICKSLIP" -q sweep "${backend[@]}" --frequencies 7 --normal-forces 7.519,11.5,15.3,16.39 --realisations 256 \
    --out "$work/fig8" >"$work/fig8.txt"
# The Python example's sweep, from the command line (the same engine, settings and seed:
# stickslip.sweep([7.0], [16.39], realisations=64, cycles=350)).
"$STICKSLIP" -q sweep --backend cpu --no-plots --frequencies 7 --normal-forces 16.39 --cycles 350 \
    --out "$work/python" >"$work/python.txt"

if [ "$mode" = write ]; then
    # The first hour, 2 and 3; the figures the README shows.
    "$STICKSLIP" -q plot "$work/sweep" --measured data/figure8 >/dev/null
    "$STICKSLIP" -q plot "$work/fig8" --measured data/figure8 >/dev/null
    cp "$work/fig8/fig8.png" docs/fig8-measured.png
    cp "$work/fig8/fig9a.png" docs/fig9a-measured.png
    cp "$work/sweep/fig9a.png" docs/fig9a-main.png
    "$STICKSLIP" -q diagnose data/figure8 --out "$work/figure8" >"$work/diagnose.txt"
    (
        started=$(date +%s.%N)
        cargo test --release --quiet >"$work/test.log" 2>&1
        ended=$(date +%s.%N)
        echo "$started $ended" >"$work/test.time"
    ) || { echo "regenerate: cargo test --release failed; see its log:" >&2; tail -30 "$work/test.log" >&2; exit 1; }
fi

if [ "$builds" = 1 ] && [ "$mode" = write ]; then
    clone="$work/clone"
    git clone -q . "$clone"
    ( cd "$clone"
      t0=$(date +%s)
      CARGO_TARGET_DIR="$clone/target" cargo install --locked --quiet --path . --root "$work/root" >/dev/null 2>&1
      t1=$(date +%s)
      cargo test --release --quiet --no-run >/dev/null 2>&1
      t2=$(date +%s)
      python3 -m venv "$work/venv"
      "$work/venv/bin/pip" install -q --upgrade pip >/dev/null
      "$work/venv/bin/pip" install -q maturin >/dev/null
      t3=$(date +%s)
      "$work/venv/bin/pip" install -q ./python >/dev/null
      t4=$(date +%s)
      echo "$((t1 - t0)) $((t2 - t1)) $((t4 - t3))" >"$work/builds.txt" )
fi

python3 - "$mode" "$work" <<'PY'
import csv, math, os, re, subprocess, sys

mode, work = sys.argv[1], sys.argv[2]

def rows(name):
    with open(os.path.join(work, name, "sweep.csv")) as f:
        return list(csv.DictReader(f))

def at(rs, f, n):
    for r in rs:
        if float(r["excitation_frequency_hz"]) == f and float(r["normal_force_n"]) == n:
            return r
    raise SystemExit(f"regenerate: no grid point at {f} Hz, {n} N")

def seconds(name):
    text = open(os.path.join(work, name)).read()
    m = re.search(r" in ([0-9.]+) s", text)
    return float(m.group(1))

def trim(x, digits):
    return f"{x:.{digits}f}"

def signed(p):
    text = f"{abs(p):.2f}" if abs(p) < 0.1 else f"{abs(p):.1f}"
    return ("−" if p < 0 else "+") + text

checked, timed = {}, {}

main = rows("sweep")
freqs = sorted({float(r["excitation_frequency_hz"]) for r in main})
checked["main-points"] = str(len(main))
checked["main-frequencies"] = str(len(freqs))
checked["main-added"] = str(len(freqs) - 41)
for load, key in ((4.0, "4n"), (16.39, "1639n")):
    curve = [r for r in main if float(r["normal_force_n"]) == load]
    top = max(curve, key=lambda r: float(r["peak_mean_m"]))
    checked[f"peak-{key}-hz"] = f"{float(top['excitation_frequency_hz']):g}"
    checked[f"peak-{key}-mm"] = f"{float(top['peak_mean_m']) * 1e3:.0f}"
    checked[f"at10-{key}-mm"] = f"{float(at(main, 10.0, load)['peak_mean_m']) * 1e3:.0f}"
for f, key in ((11.0, "11"), (12.0, "12")):
    checked[f"stick-{key}hz"] = trim(float(at(main, f, 16.39)["stick_fraction"]), 2)

measured = {}
with open("data/figure8/summary.csv") as fh:
    for r in csv.DictReader(fh):
        measured[float(r["normal_force_mean_n"])] = float(r["peak_mean_m"])
fig8 = rows("fig8")
for load, key in ((7.519, "7519"), (11.5, "115"), (15.3, "153"), (16.39, "1639")):
    sim = float(at(fig8, 7.0, load)["peak_mean_m"])
    checked[f"fig8-sim-{key}-mm"] = f"{sim * 1e3:.3f}"
    checked[f"fig8-miss-{key}"] = signed(100.0 * (sim / measured[load] - 1.0))

py = at(rows("python"), 7.0, 16.39)
checked["py-mean-mm"] = f"{float(py['peak_mean_m']) * 1e3:.3f}"
checked["py-var"] = f"{float(py['peak_var_m2']):.2e}".replace("e-0", "e-")

if mode == "write":
    timed["main-job-s"] = f"{seconds('sweep.txt'):.1f}"
    timed["diagnose-s"] = f"{seconds('diagnose.txt'):.0f}"
    t0, t1 = map(float, open(os.path.join(work, "test.time")).read().split())
    timed["test-min"] = f"{(t1 - t0) / 60:.1f}"
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        model = re.search(r"Model name:\s*(.+)", lscpu).group(1).strip()
        family = re.search(r"CPU family:\s*(.+)", lscpu)
        cores = os.cpu_count()
        # The CPU reference's speed follows its widest vectors: name them.
        flags = re.search(r"Flags:\s*(.+)", lscpu)
        flags = flags.group(1).split() if flags else []
        vectors = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "no AVX2"
        about = ([f"CPU family {family.group(1).strip()}"] if family else []) + [vectors]
        timed["machine"] = f"a {cores}-core {model} ({', '.join(about)})"
    except Exception:
        timed["machine"] = f"a {os.cpu_count()}-core machine"
    # A machine shared with other work makes every timing longer: say so.
    load = float(open(os.path.join(work, "load.txt")).read().split()[0])
    if load > 0.5 * (os.cpu_count() or 1):
        timed["machine"] += f", shared with other work (load average {load:.1f} at the start)"
    builds = os.path.join(work, "builds.txt")
    if os.path.exists(builds):
        install, test_build, wheel = map(int, open(builds).read().split())
        timed["install-min"] = f"{install / 60:.1f}"
        timed["test-build-min"] = f"{test_build / 60:.1f}"
        timed["wheel-min"] = f"{wheel / 60:.1f}"

readme = open("README.md", encoding="utf-8").read()
span = re.compile(r"<!-- num:([a-z0-9-]+) -->(.*?)<!-- /num -->", re.S)
quoted = {m.group(1): m.group(2) for m in span.finditer(readme)}

def close(name, shown, value):
    """Equal, or at most one unit apart in the last digit shown."""
    if shown == value:
        return True
    number = re.compile(r"[−+-]?[0-9.]+(?:e[−+-]?[0-9]+)?")
    a, b = number.search(shown), number.search(value)
    if not (a and b):
        return False
    to_float = lambda s: float(s.replace("−", "-"))
    text = a.group(0).replace("−", "-")
    mantissa = text.split("e")[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    unit = 10.0 ** (-decimals) * (10.0 ** int(text.split("e")[1]) if "e" in text else 1.0)
    return abs(to_float(a.group(0)) - to_float(b.group(0))) <= unit * 1.000001

if mode == "check":
    bad = []
    for name, value in checked.items():
        if name not in quoted:
            continue
        if not close(name, quoted[name], value):
            bad.append(f"  {name}: the README says {quoted[name]!r}, the code gives {value!r}")
    unknown = [n for n in quoted if n not in checked and n not in (
        "machine", "main-job-s", "diagnose-s", "test-min", "install-min", "test-build-min", "wheel-min")]
    for n in unknown:
        bad.append(f"  {n}: quoted in the README, but this script does not produce it")
    if bad:
        print("regenerate --check: the README's numbers are stale (run docs/regenerate.sh):", file=sys.stderr)
        print("\n".join(bad), file=sys.stderr)
        sys.exit(1)
    print(f"regenerate --check: {sum(1 for n in checked if n in quoted)} quoted results match the code", file=sys.stderr)
else:
    values = {**checked, **timed}
    missing = [n for n in quoted if n not in values]
    if missing:
        print(f"regenerate: kept as they are (not measured in this run): {', '.join(missing)}", file=sys.stderr)
    readme = span.sub(lambda m: f"<!-- num:{m.group(1)} -->{values.get(m.group(1), m.group(2))}<!-- /num -->", readme)
    open("README.md", "w", encoding="utf-8").write(readme)
    print(f"regenerate: rewrote {sum(1 for n in quoted if n in values)} numbers in README.md and the docs/*.png figures", file=sys.stderr)
PY
