#!/usr/bin/env python3
"""Peer comparison: stickslip (GPU on whatever adapter wgpu finds, and its f64
CPU reference) against the same baseline model written the way a user would
write it without stickslip -- vectorised NumPy and Numba with parallel loops.

Workload (identical for everyone): Den Hartog's benchmark -- zeta = 0, no
noise, constant Coulomb friction mu = a, N0 = 10 N, paper rig mass and natural
frequency, U0 = 2.5 mm, eta = Omega/omega0 = 0.8, beta = 0.5 x the no-stop
threshold; R realisations from the frictionless steady state at t = 0, W
warm-up periods, then M measured periods with one peak (max x) per period.

Accuracy matching: every implementation is run at the smallest steps/period
whose error against Den Hartog's exact amplitude is <= the target, and timed
there. Run with --help for the knobs; benches/peers/run.sh is the one-command
entry point.
"""

import argparse
import csv
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import numba
from numba import njit, prange

# --------------------------------------------------------------------------
# The model and the workload
# --------------------------------------------------------------------------

MASS_KG = 1.028
F0_HZ = 10.05
U0_M = 0.0025
N0_N = 10.0


def den_hartog(eta, beta_fraction):
    """(beta, beta_stop, x0/U0) for Den Hartog's zeta = 0 Coulomb solution."""
    V = 1.0 / (1.0 - eta * eta)
    a = math.pi / eta
    U = math.sin(a) / (eta * (1.0 + math.cos(a)))
    beta_stop = eta * eta * abs(V) / math.sqrt(1.0 + eta ** 4 * U * U)
    beta = beta_fraction * beta_stop
    return beta, beta_stop, math.sqrt(V * V - beta * beta * U * U)


def make_workload(args):
    k = MASS_KG * (2.0 * math.pi * F0_HZ) ** 2
    beta, beta_stop, ratio = den_hartog(args.eta, args.beta_fraction)
    V = 1.0 / (1.0 - args.eta ** 2)
    return dict(
        m=MASS_KG, k=k, c=0.0,                      # zeta = 0
        U0=U0_M, omega=2.0 * math.pi * args.eta * F0_HZ,
        freq_hz=args.eta * F0_HZ,
        a=beta * k * U0_M / N0_N, b=0.0, cs=0.0, d=0.0,   # Coulomb: mu = a
        N0=N0_N, sig_mu=0.0, sig_N=0.0, tau_s=1.0 / 600.0,
        x_init=U0_M * V, v_init=0.0,                # frictionless steady state, zeta = 0
        beta=beta, beta_stop=beta_stop, x0=U0_M * ratio,
    )


# --------------------------------------------------------------------------
# Peer 1: Numba, @njit(parallel=True), prange over realisations.
# Fixed-step RK4 with sgn(v) friction evaluated at every stage; a stick check
# when v changes sign during a step (|k(u-x)| <= mu_s N -> hold, v = 0);
# breakaway from stick in the direction of k(u-x). Peak = max of the sampled x
# over the period. Full baseline law mu(|v|) = a + b/(1+c|v|) + d v^2 +
# sigma_mu xi_mu, N = N0 + sigma_N xi_N, noise held over intervals tau.
# --------------------------------------------------------------------------


@njit(inline="always")
def _acc(x, v, u, sdir, inv_m, k, c, a, b, cs, d, noise_mu, N):
    if v > 0.0:
        s = 1.0
    elif v < 0.0:
        s = -1.0
    else:
        s = sdir
    av = abs(v)
    mu = a + b / (1.0 + cs * av) + d * v * v + noise_mu
    return (k * (u - x) - c * v - mu * N * s) * inv_m


@njit(parallel=True, fastmath=False)
def simulate_numba(R, W, M, S, m, k, c, U0, a, b, cs, d, N0, sig_mu, sig_N,
                   tau_s, period_s, x_init, v_init):
    h = period_s / S
    inv_m = 1.0 / m
    # base displacement at the step's start, middle and end (2S+1 samples)
    uh = np.empty(2 * S + 1)
    for i in range(2 * S + 1):
        uh[i] = U0 * math.cos(math.pi * i / S)
    peaks = np.empty((R, M))
    stuck_steps = np.zeros(R, dtype=np.int64)
    noisy = sig_mu != 0.0 or sig_N != 0.0
    for r in prange(R):
        x = x_init
        v = v_init
        stuck = v == 0.0
        sdir = 1.0 if v >= 0.0 else -1.0
        xi_mu = 0.0
        xi_N = 0.0
        interval = -1
        n_stuck = 0
        for p in range(W + M):
            pk = x
            for j in range(S):
                if noisy:
                    iv = int(((p * S + j) * h) / tau_s)
                    if iv != interval:
                        interval = iv
                        xi_mu = np.random.standard_normal()
                        xi_N = np.random.standard_normal()
                nmu = sig_mu * xi_mu
                N = N0 + sig_N * xi_N
                mu_s_N = (a + b + nmu) * N
                u0 = uh[2 * j]
                u1 = uh[2 * j + 1]
                u2 = uh[2 * j + 2]
                if stuck:
                    fs = k * (u0 - x)
                    if abs(fs) > mu_s_N:
                        stuck = False
                        sdir = 1.0 if fs > 0.0 else -1.0
                    else:
                        n_stuck += 1
                        continue
                k1x = v
                k1v = _acc(x, v, u0, sdir, inv_m, k, c, a, b, cs, d, nmu, N)
                k2x = v + 0.5 * h * k1v
                k2v = _acc(x + 0.5 * h * k1x, k2x, u1, sdir, inv_m, k, c, a, b, cs, d, nmu, N)
                k3x = v + 0.5 * h * k2v
                k3v = _acc(x + 0.5 * h * k2x, k3x, u1, sdir, inv_m, k, c, a, b, cs, d, nmu, N)
                k4x = v + h * k3v
                k4v = _acc(x + h * k3x, k4x, u2, sdir, inv_m, k, c, a, b, cs, d, nmu, N)
                x = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
                vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
                if vn * sdir <= 0.0:
                    # the velocity reversed (or reached zero) during the step
                    if abs(k * (u2 - x)) <= mu_s_N:
                        stuck = True
                        vn = 0.0
                    else:
                        sdir = -sdir
                v = vn
                if x > pk:
                    pk = x
            if p >= W:
                peaks[r, p - W] = pk
        stuck_steps[r] = n_stuck
    return peaks, stuck_steps


# --------------------------------------------------------------------------
# Peer 2: vectorised NumPy -- arrays over realisations, a Python loop over
# time steps. The same algorithm as the Numba peer, written with masks.
# --------------------------------------------------------------------------


def simulate_numpy(R, W, M, S, m, k, c, U0, a, b, cs, d, N0, sig_mu, sig_N,
                   tau_s, period_s, x_init, v_init, seed=1, steps_limit=None):
    """Returns (peaks[R, M], stuck_steps[R]); with steps_limit, stops after that
    many steps (for timing a prefix of the run) and returns (None, None)."""
    h = period_s / S
    inv_m = 1.0 / m
    uh = U0 * np.cos(np.pi * np.arange(2 * S + 1) / S)
    rng = np.random.default_rng(seed)
    x = np.full(R, x_init)
    v = np.full(R, v_init)
    stuck = v == 0.0
    sdir = np.where(v >= 0.0, 1.0, -1.0)
    xi_mu = np.zeros(R)
    xi_N = np.zeros(R)
    noisy = sig_mu != 0.0 or sig_N != 0.0
    interval = -1
    peaks = np.empty((R, M))
    stuck_steps = np.zeros(R, dtype=np.int64)

    def acc(x, v, u, sdir, nmu, N):
        s = np.where(v != 0.0, np.sign(v), sdir)
        mu = a + b / (1.0 + cs * np.abs(v)) + d * v * v + nmu
        return (k * (u - x) - c * v - mu * N * s) * inv_m

    n = 0
    for p in range(W + M):
        pk = x.copy()
        for j in range(S):
            if steps_limit is not None and n >= steps_limit:
                return None, None
            n += 1
            if noisy:
                iv = int(((p * S + j) * h) / tau_s)
                if iv != interval:
                    interval = iv
                    xi_mu = rng.standard_normal(R)
                    xi_N = rng.standard_normal(R)
            nmu = sig_mu * xi_mu
            N = N0 + sig_N * xi_N
            mu_s_N = (a + b + nmu) * N
            u0, u1, u2 = uh[2 * j], uh[2 * j + 1], uh[2 * j + 2]
            # breakaway from stick
            fs = k * (u0 - x)
            brk = stuck & (np.abs(fs) > mu_s_N)
            sdir = np.where(brk, np.where(fs > 0.0, 1.0, -1.0), sdir)
            stuck = stuck & ~brk
            stuck_steps += stuck
            # RK4 on every path; stuck paths are put back afterwards
            k1x = v
            k1v = acc(x, v, u0, sdir, nmu, N)
            k2x = v + 0.5 * h * k1v
            k2v = acc(x + 0.5 * h * k1x, k2x, u1, sdir, nmu, N)
            k3x = v + 0.5 * h * k2v
            k3v = acc(x + 0.5 * h * k2x, k3x, u1, sdir, nmu, N)
            k4x = v + h * k3v
            k4v = acc(x + h * k3x, k4x, u2, sdir, nmu, N)
            xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x)
            vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
            x = np.where(stuck, x, xn)
            vn = np.where(stuck, 0.0, vn)
            # velocity reversal during the step: stick or turn round
            rev = ~stuck & (vn * sdir <= 0.0)
            hold = rev & (np.abs(k * (u2 - x)) <= mu_s_N)
            vn = np.where(hold, 0.0, vn)
            stuck = stuck | hold
            sdir = np.where(rev & ~hold, -sdir, sdir)
            v = vn
            np.maximum(pk, x, out=pk)
        if p >= W:
            peaks[:, p - W] = pk
    return peaks, stuck_steps


# --------------------------------------------------------------------------
# Harness
# --------------------------------------------------------------------------


def peer_args(wl, R, W, M, S):
    return (R, W, M, S, wl["m"], wl["k"], wl["c"], wl["U0"], wl["a"], wl["b"],
            wl["cs"], wl["d"], wl["N0"], wl["sig_mu"], wl["sig_N"], wl["tau_s"],
            2.0 * math.pi / wl["omega"], wl["x_init"], wl["v_init"])


def errors(peaks, x0):
    rel = peaks / x0 - 1.0
    return float(np.max(np.abs(rel))), float(abs(np.mean(peaks) / x0 - 1.0))


def log(*a):
    print(*a, flush=True)


def machine_info():
    model = "?"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return os.cpu_count(), model


def cpu_busy(sample_s=1.0):
    """Share of all cores busy over sample_s (this process sleeps meanwhile)."""
    def snap():
        with open("/proc/stat") as f:
            vals = [int(v) for v in f.readline().split()[1:]]
        return sum(vals), vals[3] + vals[4]          # total, idle + iowait
    t0, i0 = snap()
    time.sleep(sample_s)
    t1, i1 = snap()
    return 1.0 - (i1 - i0) / max(t1 - t0, 1)


QUIET = dict(waited_s=0.0, retried=0, worst=0.0)


def wait_quiet(limit_s=120.0, threshold=0.15):
    """Before a timed run: wait until other processes leave the cores idle (the
    machine may be shared), at most limit_s."""
    start = time.perf_counter()
    while True:
        busy = cpu_busy()
        if busy < threshold:
            break
        if time.perf_counter() - start > limit_s:
            log(f"  (warning: cores still {busy:.0%} busy with other work after {limit_s:.0f} s; timing anyway)")
            break
        if time.perf_counter() - start < 1.5:
            log(f"  (cores {busy:.0%} busy with other work; waiting for them to go idle)")
    QUIET["waited_s"] += time.perf_counter() - start


def _jiffies_busy():
    with open("/proc/stat") as f:
        vals = [int(v) for v in f.readline().split()[1:]]
    return (sum(vals) - vals[3] - vals[4]) / os.sysconf("SC_CLK_TCK")


def timed(fn, attempts=3, max_foreign=0.10):
    """Runs fn() when the cores are idle and times it. Also measures how much
    CPU other processes took meanwhile (all cores' busy time minus this
    process's and its children's); if that exceeds max_foreign of the machine,
    the timing is contaminated and is taken again (at most `attempts` times;
    the least contaminated is kept). Returns (seconds, fn's result, foreign share)."""
    ncpu = os.cpu_count() or 1
    best = None
    for i in range(attempts):
        wait_quiet()
        b0, o0, t0 = _jiffies_busy(), sum(os.times()[:4]), time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t0
        b1, o1 = _jiffies_busy(), sum(os.times()[:4])
        foreign = max(0.0, (b1 - b0) - (o1 - o0)) / (dt * ncpu)
        if best is None or foreign < best[2]:
            best = (dt, out, foreign)
        if foreign <= max_foreign:
            break
        QUIET["retried"] += 1
        log(f"  (other processes took {foreign:.0%} of the cores during that timing ({dt:.1f} s); "
            f"{'timing again' if i + 1 < attempts else 'keeping the least disturbed'})")
    QUIET["worst"] = max(QUIET["worst"], best[2])
    return best


def run_stickslip(binary, wl, backend, R, W, M, S, out_dir):
    cmd = [binary, "sweep", "--backend", backend,
           "--frequencies", repr(wl["freq_hz"]), "--normal-forces", repr(wl["N0"]),
           "--realisations", str(R), "--warmup-cycles", str(W), "--cycles", str(M),
           "--seed", "1", "--out", out_dir,
           "--set", "rig.damping_ratio=0", "--set", "friction.b=0",
           "--set", "friction.sigma=0", "--set", "normal_force.sigma=0",
           "--set", f"friction.a={wl['a']!r}", "--set", f"solver.steps_per_period={S}"]
    for attempt in range(30):
        if os.path.exists(binary):
            wall, p, foreign = timed(lambda: subprocess.run(cmd, capture_output=True, text=True))
            if p.returncode == 0:
                break
            # a concurrent rebuild can replace the binary under us: retry
            log(f"  (stickslip exited {p.returncode}; retrying) {p.stderr.strip()[-300:]}")
        time.sleep(10)
    else:
        raise SystemExit("stickslip did not run: " + " ".join(cmd))
    row = next(csv.DictReader(open(os.path.join(out_dir, "sweep.csv"))))
    side = json.load(open(os.path.join(out_dir, "sweep.json")))
    adapter = next((l for l in p.stderr.splitlines() if l.startswith("backend:")), "backend: ?")
    x0 = wl["x0"]
    return dict(
        cmd=cmd, wall_s=wall, foreign=foreign, run_s=float(side["timings"]["run_s"]), adapter=adapter,
        err_mean=abs(float(row["peak_mean_m"]) / x0 - 1.0),
        err_p05=abs(float(row["peak_p05_m"]) / x0 - 1.0),
        err_p95=abs(float(row["peak_p95_m"]) / x0 - 1.0),
        rel_sd=math.sqrt(max(float(row["peak_var_m2"]), 0.0)) / x0,
        stick_fraction=float(row["stick_fraction"]),
    )



def parse_list(text, kind=int):
    return [kind(v) for v in text.split(",") if v.strip()]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default="target/release/stickslip")
    ap.add_argument("--eta", type=float, default=0.8)
    ap.add_argument("--beta-fraction", type=float, default=0.5)
    ap.add_argument("--realisations", type=int, default=4096)
    ap.add_argument("--warmup", type=int, default=200)
    ap.add_argument("--cycles", type=int, default=50)
    ap.add_argument("--targets", default="1e-4,1e-3",
                    help="relative errors vs Den Hartog every implementation must reach (the first is the headline)")
    ap.add_argument("--stickslip-steps", default="16,32,64,128,256,512")
    ap.add_argument("--peer-steps", default="128,192,256,384,512,768,1024,1536,2048,3072,4096,6144,8192,"
                                            "12288,16384,24576,32768,49152,65536")
    ap.add_argument("--repeats", type=int, default=2, help="timed runs per measurement; the best is reported")
    ap.add_argument("--budget-s", type=float, default=40.0,
                    help="a peer run predicted to take longer than this is timed on a reduced workload "
                         "(Numba: fewer realisations; NumPy: a prefix of the time steps, all realisations) "
                         "and scaled linearly to the full workload")
    ap.add_argument("--skip-cpu", action="store_true", help="skip stickslip's CPU reference")
    args = ap.parse_args()

    wl = make_workload(args)
    R, W, M, x0 = args.realisations, args.warmup, args.cycles, wl["x0"]
    targets = parse_list(args.targets, float)
    work = R * (W + M)                   # realisation-periods
    ncpu, cpu_model = machine_info()
    log("== stickslip peer comparison ==")
    log(f"machine: nproc={ncpu}, cpu='{cpu_model}', python {platform.python_version()}, "
        f"numpy {np.__version__}, numba {numba.__version__} ({numba.config.NUMBA_NUM_THREADS} threads)")
    log(f"workload: Den Hartog, eta={args.eta}, f={wl['freq_hz']!r} Hz, zeta=0, no noise, "
        f"mu=a={wl['a']!r}, N0={wl['N0']} N, beta={wl['beta']:.6g} "
        f"(= {args.beta_fraction} x no-stop threshold {wl['beta_stop']:.6g})")
    log(f"          x(0)={wl['x_init']:.6e} m, v(0)=0 (frictionless steady state); exact amplitude x0={x0:.12e} m")
    log(f"          R={R} realisations x ({W} warm-up + {M} measured) periods; "
        f"targets {', '.join(f'{t:g}' for t in targets)}; best of {args.repeats} timed runs")
    log("")
    tmp = tempfile.mkdtemp(prefix="stickslip-peers-")

    # ---- stickslip GPU: accuracy search on the full workload -----------------
    log("-- stickslip GPU: accuracy search (full workload; error = |mean peak/x0 - 1|) --")
    gpu_runs = {}
    need = max(targets)
    for S in parse_list(args.stickslip_steps):
        res = run_stickslip(args.binary, wl, "gpu", R, W, M, S, os.path.join(tmp, f"gpu{S}"))
        gpu_runs[S] = res
        log(f"  S={S:6d}: mean err {res['err_mean']:.2e}  (p05 {res['err_p05']:.1e}, p95 {res['err_p95']:.1e}, "
            f"sd/x0 {res['rel_sd']:.1e}, stick {res['stick_fraction']:g})  run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
        if res["err_mean"] <= min(targets):
            break
    adapter = next(iter(gpu_runs.values()))["adapter"]
    log(f"  {adapter}")
    ss_S = {}
    for t in targets:
        ok = [S for S, r in gpu_runs.items() if r["err_mean"] <= t]
        if not ok:
            raise SystemExit(f"stickslip did not reach {t:g} at any steps/period tried")
        ss_S[t] = min(ok)
    for S in sorted(set(ss_S.values())):
        for _ in range(args.repeats - 1):
            res = run_stickslip(args.binary, wl, "gpu", R, W, M, S, os.path.join(tmp, f"gpu{S}r"))
            log(f"  repeat S={S}: mean err {res['err_mean']:.2e}, run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
            if res["run_s"] < gpu_runs[S]["run_s"]:
                gpu_runs[S] = res
        log("  command: " + " ".join(["target/release/stickslip"] + gpu_runs[S]["cmd"][1:]))

    cpu_runs = {}
    if not args.skip_cpu:
        log("-- stickslip CPU reference (f64, rayon) at the same steps/period --")
        for S in sorted(set(ss_S.values())):
            for _ in range(args.repeats):
                res = run_stickslip(args.binary, wl, "cpu", R, W, M, S, os.path.join(tmp, f"cpu{S}"))
                log(f"  S={S}: mean err {res['err_mean']:.2e}  run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
                if S not in cpu_runs or res["run_s"] < cpu_runs[S]["run_s"]:
                    cpu_runs[S] = res
    log("")

    # ---- Numba: compile; accuracy search on one realisation ------------------
    log("-- Numba peer: accuracy search (one realisation -- without noise all are the same path -- "
        "full W + M; error = max over measured peaks) --")
    t0 = time.perf_counter()
    simulate_numba(*peer_args(wl, 2, 1, 1, 16))
    compile_s = time.perf_counter() - t0
    log(f"  JIT compile (excluded from every timing): {compile_s:.2f} s")
    search = {}
    for S in parse_list(args.peer_steps):
        pk, _ = simulate_numba(*peer_args(wl, 1, W, M, S))
        search[S] = errors(pk, x0)
        log(f"  S={S:6d}: max err {search[S][0]:.2e}  mean err {search[S][1]:.2e}")
        if search[S][0] <= min(targets):
            break
    peer_S = {}
    for t in targets:
        ok = [S for S, e in search.items() if e[0] <= t]
        if not ok:
            raise SystemExit(f"the peers did not reach {t:g} at any steps/period tried")
        peer_S[t] = min(ok)
    for S in sorted(set(peer_S.values())):
        pk, _ = simulate_numba(*peer_args(wl, 1, 0, 4 * W + M, S))
        e = np.abs(pk[0] / x0 - 1.0)
        log(f"  settling at S={S}: max err over periods [{W},{W + M}) {e[W:W + M].max():.2e}, "
            f"[{W // 2},{W // 2 + M}) {e[W // 2:W // 2 + M].max():.2e}, "
            f"[{4 * W},{4 * W + M}) {e[4 * W:].max():.2e}")

    numba_runs = {}
    for S in sorted(set(peer_S.values())):
        probe_R = max(2 * ncpu, min(R, int(2e6 / S)))
        dt, _, _ = timed(lambda: simulate_numba(*peer_args(wl, probe_R, W, M, S)), attempts=1)
        predicted = dt * R / probe_R
        Rt = R if predicted <= args.budget_s else max(2 * ncpu, int(R * args.budget_s / predicted / 2) // ncpu * ncpu)
        best = None
        for _ in range(args.repeats):
            m = timed(lambda: simulate_numba(*peer_args(wl, Rt, W, M, S)))
            if best is None or m[0] < best[0]:
                best = m
        dt, (pk, st), foreign = best
        emax, emean = errors(pk, x0)
        scaled = dt * R / Rt
        note = "full workload" if Rt == R else f"timed R={Rt}, scaled x{R / Rt:.2f} to R={R}"
        log(f"  timed S={S}: R={Rt} in {dt:.2f} s -> {scaled:.2f} s for R={R} ({note}); "
            f"error max {emax:.2e}, mean {emean:.2e}; stuck steps {int(st.sum())}")
        numba_runs[S] = dict(time_s=scaled, err=emax, foreign=foreign,
                             note=note + f"; compile {compile_s:.1f} s excluded")
    log("")

    # ---- NumPy: same algorithm (checked against Numba), then timed ------------
    log("-- NumPy peer --")
    S_chk = 256
    pk_np, _ = simulate_numpy(*peer_args(wl, 4, W, M, S_chk))
    pk_nb, _ = simulate_numba(*peer_args(wl, 4, W, M, S_chk))
    diff = float(np.max(np.abs(pk_np - pk_nb))) / x0
    log(f"  same paths as the Numba peer? S={S_chk}, R=4, full run: max |peak diff|/x0 = {diff:.1e}")
    numpy_runs = {}
    for S in sorted(set(peer_S.values())):
        total = (W + M) * S
        probe = min(total, 1000)
        dt, _, _ = timed(lambda: simulate_numpy(*peer_args(wl, R, W, M, S), steps_limit=probe), attempts=1)
        predicted = dt / probe * total
        steps = total if predicted <= args.budget_s else max(probe, int(total * args.budget_s / predicted / 2))
        limit = None if steps == total else steps
        best = None
        for _ in range(args.repeats):
            m = timed(lambda: simulate_numpy(*peer_args(wl, R, W, M, S), steps_limit=limit))
            if best is None or m[0] < best[0]:
                best = m
        dt, (pk, _), foreign = best
        scaled = dt * total / steps
        if limit is None:
            emax, _ = errors(pk, x0)
            note = "full workload"
            log(f"  timed S={S}: full workload in {dt:.2f} s; error max {emax:.2e}")
        else:
            emax = numba_runs[S]["err"]          # same arithmetic as the Numba peer (checked above)
            note = f"timed {steps} of {total} steps (all R), scaled x{total / steps:.1f}; error of the Numba run"
            log(f"  timed S={S}: {steps}/{total} steps at R={R} in {dt:.2f} s -> {scaled:.1f} s for the full workload")
        numpy_runs[S] = dict(time_s=scaled, err=emax, foreign=foreign, note=note)
    log("")

    # ---- tables ---------------------------------------------------------------
    log(f"== results: R={R} realisations x {W}+{M} periods, eta={args.eta}, {ncpu} cores ({cpu_model}) ==")
    log(adapter)
    hdr = (f"{'target':>7s}  {'implementation':30s} {'steps/period':>12s} {'error vs DH':>16s} "
           f"{'time s':>9s} {'real-steps/s':>12s} {'GPU speedup':>11s}  note")
    log(hdr)
    log("-" * len(hdr))
    headline = []
    for t in targets:
        g = gpu_runs[ss_S[t]]
        rows = [("stickslip GPU (wgpu, f32)", ss_S[t], g["err_mean"], "mean", g["run_s"],
                 f"run_s; process wall {g['wall_s']:.2f} s", g["foreign"])]
        if ss_S[t] in cpu_runs:
            c = cpu_runs[ss_S[t]]
            rows.append(("stickslip CPU (f64 reference)", ss_S[t], c["err_mean"], "mean", c["run_s"],
                         f"run_s; process wall {c['wall_s']:.2f} s", c["foreign"]))
        nb, npy = numba_runs[peer_S[t]], numpy_runs[peer_S[t]]
        rows.append(("Numba prange RK4 (f64)", peer_S[t], nb["err"], "max", nb["time_s"], nb["note"], nb["foreign"]))
        rows.append(("NumPy vectorised RK4 (f64)", peer_S[t], npy["err"], "max", npy["time_s"], npy["note"],
                     npy["foreign"]))
        for name, S, err, kind, secs, note, foreign in rows:
            if foreign > 0.10:
                note += f"; DISTURBED: other processes took {foreign:.0%} of the cores"
            rate = work * S / secs
            log(f"{t:7.0e}  {name:30s} {S:12d} {err:11.2e} {kind:>4s} {secs:9.2f} {rate:12.3e} "
                f"{secs / g['run_s']:10.2f}x  {note}")
        best_peer = min(nb["time_s"], npy["time_s"])
        which = "Numba" if nb["time_s"] <= npy["time_s"] else "NumPy"
        step_ratio = peer_S[t] / ss_S[t]
        rate_ratio = (work * peer_S[t] / best_peer) / (work * ss_S[t] / g["run_s"])
        headline.append((t, which, best_peer / g["run_s"], best_peer / g["wall_s"], step_ratio, rate_ratio))
        log("")
    log("GPU speedup = that row's time / stickslip GPU time (sweep.json run_s, start-up excluded).")
    for t, which, r_run, r_wall, step_ratio, rate_ratio in headline:
        log(f"target {t:g}: best peer {which}; stickslip GPU is {r_run:.1f}x faster on run_s "
            f"({r_wall:.1f}x on whole-process wall time) -- the >= 10x goal is "
            f"{'MET' if r_run >= 10 else 'NOT MET'}")
        log(f"    = {step_ratio:.0f}x fewer steps (event location) / {rate_ratio:.1f}x the peer's "
            f"realisation-steps per second")
    log("errors: stickslip = |mean peak/x0 - 1| (every realisation is the same path; p05/p95/sd above); "
        "peers = max over all measured peaks of |peak/x0 - 1|.")
    log("peer error vs steps/period (max, mean): " +
        ", ".join(f"{S}: {e[0]:.1e}/{e[1]:.1e}" for S, e in search.items()))
    log(f"shared-machine guard: waited {QUIET['waited_s']:.0f} s in all for idle cores; {QUIET['retried']} timings "
        f"retaken because other processes used > 10% of the cores; reported timings had at most "
        f"{QUIET['worst']:.0%} of the cores taken by other processes")


if __name__ == "__main__":
    main()
