#!/usr/bin/env python3
"""Peer comparison: stickslip (GPU on whatever adapter wgpu finds, and its f64
CPU reference) against the same baseline model written the way a user would
write it without stickslip:

  - NumPy, vectorised over realisations, fixed-step RK4 (this file);
  - Numba, @njit(parallel=True) with prange, fixed-step RK4 (this file);
  - Numba, prange, with stickslip's exact event location (event_numba.py);
  - JAX on the CPU, vmap + lax.scan, fixed-step RK4 (jax_peer.py).

Two workloads, in one run:

1. Den Hartog's benchmark -- zeta = 0, no noise, constant Coulomb friction
   mu = a, N0 = 10 N, paper rig mass and natural frequency, U0 = 2.5 mm,
   eta = 0.8, beta = 0.5 x the no-stop threshold; R realisations from the
   frictionless steady state, W warm-up periods, then M measured periods with
   one peak (max x) per period. Every implementation is timed at the smallest
   steps/period whose error against Den Hartog's exact amplitude is <= the
   target.
2. The noisy default -- stickslip's embedded default model (read back from
   its sweep.json) at 7 Hz and 16.39 N. Every implementation is timed at the
   smallest steps/period whose ensemble mean and variance of the peak agree
   with stickslip's f64 reference (256 steps/period, independent seeds) within
   the combined sampling error.

Run with --help for the knobs; benches/peers/run.sh is the one-command entry
point. --quick is a small smoke run for development.
"""

import argparse
import csv
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np
import numba
from numba import njit, prange

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import event_numba  # noqa: E402
import peer_rng  # noqa: E402
import jax_peer  # noqa: E402  (imports jax only when configured)

# --------------------------------------------------------------------------
# The model and the workloads
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
    """Den Hartog's workload."""
    k = MASS_KG * (2.0 * math.pi * F0_HZ) ** 2
    beta, beta_stop, ratio = den_hartog(args.eta, args.beta_fraction)
    V = 1.0 / (1.0 - args.eta ** 2)
    a = beta * k * U0_M / N0_N
    return dict(
        m=MASS_KG, k=k, c=0.0,                      # zeta = 0
        U0=U0_M, omega=2.0 * math.pi * args.eta * F0_HZ,
        freq_hz=args.eta * F0_HZ,
        a=a, b=0.0, cs=0.0, d=0.0,                  # Coulomb: mu = a
        N0=N0_N, sig_mu=0.0, sig_N=0.0, tau_s=1.0 / 600.0,
        x_init=U0_M * V, v_init=0.0,                # frictionless steady state, zeta = 0
        beta=beta, beta_stop=beta_stop, x0=U0_M * ratio,
        sets=["rig.damping_ratio=0", "friction.b=0", "friction.sigma=0", "normal_force.sigma=0",
              f"friction.a={a!r}"],
    )


BASELINE_TABLES = {"rig", "excitation", "friction", "normal_force", "noise", "solver"}


def noisy_workload(model, freq_hz, N0):
    """The noisy workload from the model stickslip reports in sweep.json (its
    embedded default unless overridden), at one grid point."""
    extra = set(model) - BASELINE_TABLES
    if extra:
        raise SystemExit(f"the model has tables the peers do not implement: {sorted(extra)}")
    rig, fr = model["rig"], model["friction"]
    m = rig["mass_kg"]
    k = m * (2.0 * math.pi * rig["natural_frequency_hz"]) ** 2
    c = 2.0 * rig["damping_ratio"] * math.sqrt(k * m)
    U0 = model["excitation"]["amplitude_m"]
    omega = 2.0 * math.pi * freq_hz
    # frictionless steady state at t = 0: x = Re{X e^{i Omega t}}, X = k U0 / (k - m Omega^2 + i c Omega)
    re, im = k - m * omega * omega, c * omega
    scale = k * U0 / (re * re + im * im)
    return dict(
        m=m, k=k, c=c, U0=U0, omega=omega, freq_hz=freq_hz,
        a=fr["a"], b=fr["b"], cs=fr["c"], d=fr["d"],
        N0=N0, sig_mu=fr["sigma"], sig_N=model["normal_force"]["sigma"], tau_s=model["noise"]["interval_s"],
        x_init=scale * re, v_init=omega * scale * im,
        sets=[],
    )


# --------------------------------------------------------------------------
# Peer 1: Numba, @njit(parallel=True), prange over realisations.
# Fixed-step RK4 with sgn(v) friction evaluated at every stage; a stick check
# when v changes sign during a step (|k(u-x)| <= mu_s N -> hold, v = 0);
# breakaway from stick in the direction of k(u-x). Peak = max of the sampled x
# over the period. Full baseline law mu(|v|) = a + b/(1+c|v|) + d v^2 +
# sigma_mu xi_mu and N = N0 + sigma_N xi_N, each clipped at 0, breakaway at
# mu_s = a + b + sigma_mu xi_mu; noise held over intervals tau (a step takes the
# interval of its start), drawn from the peers' own counter-based generator
# (peer_rng.py). stuck_steps counts the measured periods' stuck steps.
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
    mu = max(a + b / (1.0 + cs * av) + d * v * v + noise_mu, 0.0)
    return (k * (u - x) - c * v - mu * N * s) * inv_m


@njit(parallel=True, fastmath=False)
def simulate_numba(R, W, M, S, m, k, c, U0, a, b, cs, d, N0, sig_mu, sig_N,
                   tau_s, period_s, x_init, v_init, seed):
    h = period_s / S
    inv_m = 1.0 / m
    steps_per_tau = h / tau_s           # step n lies in noise interval floor(n h / tau)
    # base displacement at the step's start, middle and end (2S+1 samples)
    uh = np.empty(2 * S + 1)
    for i in range(2 * S + 1):
        uh[i] = U0 * math.cos(math.pi * i / S)
    peaks = np.empty((R, M))
    stuck_steps = np.zeros(R, dtype=np.int64)
    noisy = sig_mu != 0.0 or sig_N != 0.0
    for r in prange(R):
        key = peer_rng.path_key(seed, r)
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
                    iv = int((p * S + j) * steps_per_tau)
                    if iv != interval:
                        interval = iv
                        xi_mu, xi_N = peer_rng.gaussian_pair(key, iv)
                nmu = sig_mu * xi_mu
                N = max(N0 + sig_N * xi_N, 0.0)
                mu_s_N = max(a + b + nmu, 0.0) * N
                u0 = uh[2 * j]
                u1 = uh[2 * j + 1]
                u2 = uh[2 * j + 2]
                if stuck:
                    fs = k * (u0 - x)
                    if abs(fs) > mu_s_N:
                        stuck = False
                        sdir = 1.0 if fs > 0.0 else -1.0
                    else:
                        if p >= W:
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
# time steps. The same algorithm and noise as the Numba peer, written with
# masks; the harness checks that it follows the Numba peer's paths.
# --------------------------------------------------------------------------


def simulate_numpy(R, W, M, S, m, k, c, U0, a, b, cs, d, N0, sig_mu, sig_N,
                   tau_s, period_s, x_init, v_init, seed, steps_limit=None):
    """Returns (peaks[R, M], stuck_steps[R]); with steps_limit, stops after that
    many steps (for timing a prefix of the run) and returns (None, None)."""
    h = period_s / S
    inv_m = 1.0 / m
    steps_per_tau = h / tau_s
    uh = U0 * np.cos(np.pi * np.arange(2 * S + 1) / S)
    keys = peer_rng.path_keys_np(seed, R)
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
        mu = np.maximum(a + b / (1.0 + cs * np.abs(v)) + d * v * v + nmu, 0.0)
        return (k * (u - x) - c * v - mu * N * s) * inv_m

    n = 0
    for p in range(W + M):
        pk = x.copy()
        for j in range(S):
            if steps_limit is not None and n >= steps_limit:
                return None, None
            n += 1
            if noisy:
                iv = int((p * S + j) * steps_per_tau)
                if iv != interval:
                    interval = iv
                    xi_mu, xi_N = peer_rng.gaussian_pair_np(keys, iv)
            nmu = sig_mu * xi_mu
            N = np.maximum(N0 + sig_N * xi_N, 0.0)
            mu_s_N = np.maximum(a + b + nmu, 0.0) * N
            u0, u1, u2 = uh[2 * j], uh[2 * j + 1], uh[2 * j + 2]
            # breakaway from stick
            fs = k * (u0 - x)
            brk = stuck & (np.abs(fs) > mu_s_N)
            sdir = np.where(brk, np.where(fs > 0.0, 1.0, -1.0), sdir)
            stuck = stuck & ~brk
            if p >= W:
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


def peer_args(wl, R, W, M, S, seed=1):
    """Arguments of the fixed-step peers (Numba, NumPy, JAX)."""
    return (R, W, M, S, wl["m"], wl["k"], wl["c"], wl["U0"], wl["a"], wl["b"],
            wl["cs"], wl["d"], wl["N0"], wl["sig_mu"], wl["sig_N"], wl["tau_s"],
            2.0 * math.pi / wl["omega"], wl["x_init"], wl["v_init"], seed)


def event_args(wl, R, W, M, S, seed=1):
    """Arguments of the event-locating Numba peer."""
    return (R, W, M, S, wl["m"], wl["k"], wl["c"], wl["U0"], wl["omega"], wl["a"], wl["b"],
            wl["cs"], wl["d"], wl["N0"], wl["sig_mu"], wl["sig_N"], wl["tau_s"],
            wl["x_init"], wl["v_init"], seed)


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


QUIET = dict(waited_s=0.0, retried=0, worst=0.0, limit_s=120.0)


def wait_quiet(threshold=0.15):
    """Before a timed run: wait until other processes leave the cores idle (the
    machine may be shared), at most QUIET['limit_s']."""
    limit_s = QUIET["limit_s"]
    if limit_s <= 0:
        return
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


def timed_scaled_R(prepare, R, budget_s, repeats, probe_R, quantum):
    """Times a peer on R realisations, or, when a probe predicts more than
    budget_s, on fewer (a multiple of `quantum`) and scales linearly in R.
    prepare(Rt) does any untimed set-up (JIT compilation) and returns the
    zero-argument run. Returns (Rt, best (seconds, result, foreign))."""
    probe_R = min(R, max(quantum, probe_R // quantum * quantum))
    run = prepare(probe_R)
    probe = timed(run, attempts=1)
    predicted = probe[0] * R / probe_R
    Rt = R if predicted <= budget_s else min(R, max(quantum, int(R * budget_s / predicted / 2) // quantum * quantum))
    best = None
    if Rt == probe_R:
        best = probe if probe[2] <= 0.10 else None      # the probe counts as a timing if undisturbed
    else:
        run = prepare(Rt)
    for _ in range(repeats - (best is not None)):
        m = timed(run)
        if best is None or m[0] < best[0]:
            best = m
    return Rt, best


def run_stickslip(binary, wl, backend, R, W, M, S, seed, out_dir, timing=True):
    """Runs `stickslip sweep` at one grid point and reads back its statistics
    and run_s. With timing=False (runs whose time is not reported), it does not
    wait for idle cores or retake disturbed runs."""
    cmd = [binary, "sweep", "--backend", backend,
           "--frequencies", repr(wl["freq_hz"]), "--normal-forces", repr(wl["N0"]),
           "--realisations", str(R), "--warmup-cycles", str(W), "--cycles", str(M),
           "--seed", str(seed), "--out", out_dir]
    for s in wl["sets"] + [f"solver.steps_per_period={S}"]:
        cmd += ["--set", s]
    if backend == "gpu":
        # The kernel is timed on whatever adapter there is: lavapipe, where
        # there is no GPU, is refused without this flag.
        cmd.append("--allow-software-gpu")
    for attempt in range(30):
        if os.path.exists(binary):
            if timing:
                wall, p, foreign = timed(lambda: subprocess.run(cmd, capture_output=True, text=True))
            else:
                t0 = time.perf_counter()
                p = subprocess.run(cmd, capture_output=True, text=True)
                wall, foreign = time.perf_counter() - t0, 0.0
            if p.returncode == 0:
                break
            # a concurrent rebuild can replace the binary under us: retry
            log(f"  (stickslip exited {p.returncode}; retrying) {p.stderr.strip()[-300:]}")
        time.sleep(10)
    else:
        raise SystemExit("stickslip did not run: " + " ".join(cmd))
    with open(os.path.join(out_dir, "sweep.csv")) as f:
        row = next(csv.DictReader(f))
    with open(os.path.join(out_dir, "sweep.json")) as f:
        side = json.load(f)
    adapter = next((l for l in p.stderr.splitlines() if l.startswith("backend:")), "backend: ?")
    out = dict(cmd=cmd, wall_s=wall, foreign=foreign, run_s=float(side["timings"]["run_s"]), adapter=adapter,
               model=side.get("model"), S=S, seed=seed, R=R,
               mean=float(row["peak_mean_m"]), var=float(row["peak_var_m2"]),
               stick_fraction=float(row["stick_fraction"]))
    if "x0" in wl:
        x0 = wl["x0"]
        out.update(err_mean=abs(out["mean"] / x0 - 1.0),
                   err_p05=abs(float(row["peak_p05_m"]) / x0 - 1.0),
                   err_p95=abs(float(row["peak_p95_m"]) / x0 - 1.0),
                   rel_sd=math.sqrt(max(out["var"], 0.0)) / x0)
    return out


def shown_command(res):
    return " ".join(["target/release/stickslip"] + res["cmd"][1:])


def parse_list(text, kind=int):
    return [kind(v) for v in text.split(",") if v.strip()]


def note_foreign(note, foreign):
    if foreign > 0.10:
        note += f"; DISTURBED: other processes took {foreign:.0%} of the cores"
    return note


# --------------------------------------------------------------------------
# Statistics for the noisy workload
# --------------------------------------------------------------------------


def path_stats(peaks):
    """Mean and (unbiased, all-peak) variance of the peaks [R, M], with standard
    errors from the spread between realisations: the peaks of one path are
    correlated from cycle to cycle, the paths are independent. SE(mean) uses
    the per-path means; SE(var) the per-path mean squared deviations."""
    R = peaks.shape[0]
    per_path = peaks.mean(axis=1)
    mean = float(per_path.mean())
    q = ((peaks - mean) ** 2).mean(axis=1)
    return dict(mean=mean, se_mean=float(per_path.std(ddof=1) / math.sqrt(R)),
                var=float(peaks.var(ddof=1)), se_var=float(q.std(ddof=1) / math.sqrt(R)), R=R)


def batch_stats(batches, M):
    """Pools K equal independent batches (stickslip runs with different seeds,
    each giving mean and unbiased variance of its peaks); the standard errors
    come from the spread between batches."""
    K = len(batches)
    n = batches[0]["R"] * M
    means = np.array([b["mean"] for b in batches])
    vars_ = np.array([b["var"] for b in batches])
    mean = float(means.mean())
    var = float(((n - 1) * vars_.sum() + n * ((means - mean) ** 2).sum()) / (K * n - 1))
    return dict(mean=mean, se_mean=float(means.std(ddof=1) / math.sqrt(K)),
                var=var, se_var=float(vars_.std(ddof=1) / math.sqrt(K)), R=K * batches[0]["R"])


def compare(cand, ref, z):
    """|mean difference| and |variance difference| each within z combined
    standard errors."""
    se_m = math.hypot(cand["se_mean"], ref["se_mean"])
    se_v = math.hypot(cand["se_var"], ref["se_var"])
    zm = (cand["mean"] - ref["mean"]) / se_m
    zv = (cand["var"] - ref["var"]) / se_v
    return dict(z_mean=zm, z_var=zv, ratio=cand["var"] / ref["var"], ratio_half=z * se_v / ref["var"],
                ok=abs(zm) <= z and abs(zv) <= z)


def describe(st, cmp, ref):
    return (f"mean {st['mean']:.6e} (SE {st['se_mean']:.1e}; {st['mean'] / ref['mean'] - 1:+.1e} = "
            f"{cmp['z_mean']:+.1f} SE)  var {st['var']:.4e} (ratio {cmp['ratio']:.3f}, "
            f"{cmp['z_var']:+.1f} SE)  {'PASS' if cmp['ok'] else 'fail'}")


def search_ladder(ladder, try_S, coarse_first=False):
    """The smallest S of the ladder for which try_S(S) -> (ok, record) passes.
    With coarse_first, the powers of two are tried first, then the ladder
    points between the last failing power of two and the first passing one
    (this finds the same S as a full scan wherever passing is monotone in S).
    Returns (S or None, {S: record})."""
    ladder = sorted(ladder)
    tried = {}

    def attempt(S):
        if S not in tried:
            tried[S] = try_S(S)
        return tried[S][0]

    if not coarse_first:
        for S in ladder:
            if attempt(S):
                return S, {s: r for s, (_, r) in tried.items()}
        return None, {s: r for s, (_, r) in tried.items()}
    coarse = [S for S in ladder if S & (S - 1) == 0] or ladder
    last_fail = 0
    for S in coarse:
        if attempt(S):
            for s in ladder:
                if last_fail < s < S and attempt(s):
                    return s, {t: r for t, (_, r) in tried.items()}
            return S, {t: r for t, (_, r) in tried.items()}
        last_fail = S
    return None, {t: r for t, (_, r) in tried.items()}


# --------------------------------------------------------------------------
# Workload 1: Den Hartog
# --------------------------------------------------------------------------


def den_hartog_section(args, ctx):
    wl = make_workload(args)
    R, W, M, x0 = args.realisations, args.warmup, args.cycles, wl["x0"]
    targets = parse_list(args.targets, float)
    work = R * (W + M)
    ncpu = ctx["ncpu"]
    tmp = ctx["tmp"]
    log(f"==== workload 1: Den Hartog, eta={args.eta}, f={wl['freq_hz']!r} Hz, zeta=0, no noise, "
        f"mu=a={wl['a']!r}, N0={wl['N0']} N, beta={wl['beta']:.6g} "
        f"(= {args.beta_fraction} x no-stop threshold {wl['beta_stop']:.6g}) ====")
    log(f"x(0)={wl['x_init']:.6e} m, v(0)=0 (frictionless steady state); exact amplitude x0={x0:.12e} m")
    log(f"R={R} realisations x ({W} warm-up + {M} measured) periods; "
        f"targets {', '.join(f'{t:g}' for t in targets)}; best of {args.repeats} timed runs")
    log("")

    # ---- stickslip GPU: accuracy search on the full workload -----------------
    log("-- stickslip GPU: accuracy search (full workload; error = |mean peak/x0 - 1|) --")
    gpu_runs = {}
    for S in parse_list(args.stickslip_steps):
        res = run_stickslip(args.binary, wl, "gpu", R, W, M, S, 1, os.path.join(tmp, f"dh-gpu{S}"))
        gpu_runs[S] = res
        log(f"  S={S:6d}: mean err {res['err_mean']:.2e}  (p05 {res['err_p05']:.1e}, p95 {res['err_p95']:.1e}, "
            f"sd/x0 {res['rel_sd']:.1e}, stick {res['stick_fraction']:g})  run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
        if res["err_mean"] <= min(targets):
            break
    adapter = next(iter(gpu_runs.values()))["adapter"]
    ctx["adapter"] = adapter
    log(f"  {adapter}")
    ss_S = {}
    for t in targets:
        ok = [S for S, r in gpu_runs.items() if r["err_mean"] <= t]
        if not ok:
            raise SystemExit(f"stickslip did not reach {t:g} at any steps/period tried")
        ss_S[t] = min(ok)
    for S in sorted(set(ss_S.values())):
        for _ in range(args.repeats - 1):
            res = run_stickslip(args.binary, wl, "gpu", R, W, M, S, 1, os.path.join(tmp, f"dh-gpu{S}r"))
            log(f"  repeat S={S}: mean err {res['err_mean']:.2e}, run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
            if res["run_s"] < gpu_runs[S]["run_s"]:
                gpu_runs[S] = res
        log("  command: " + shown_command(gpu_runs[S]))

    cpu_runs = {}
    if not args.skip_cpu:
        log("-- stickslip CPU reference (f64, rayon) at the same steps/period --")
        for S in sorted(set(ss_S.values())):
            for _ in range(args.repeats):
                res = run_stickslip(args.binary, wl, "cpu", R, W, M, S, 1, os.path.join(tmp, f"dh-cpu{S}"))
                log(f"  S={S}: mean err {res['err_mean']:.2e}  run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
                if S not in cpu_runs or res["run_s"] < cpu_runs[S]["run_s"]:
                    cpu_runs[S] = res
    log("")

    # ---- Numba event-locating: accuracy search on one realisation -----------
    log("-- Numba event-locating peer: accuracy search (one realisation -- without noise all are the same "
        "path -- full W + M; error = max over measured peaks) --")
    log(f"  JIT compile (excluded from every timing): {ctx['event_compile_s']:.2f} s")
    ev_search = {}
    for S in parse_list(args.event_steps):
        pk, _ = event_numba.simulate_events(*event_args(wl, 1, W, M, S))
        ev_search[S] = errors(pk, x0)
        log(f"  S={S:6d}: max err {ev_search[S][0]:.2e}  mean err {ev_search[S][1]:.2e}")
        if ev_search[S][0] <= min(targets):
            break
    ev_S = {}
    for t in targets:
        ok = [S for S, e in ev_search.items() if e[0] <= t]
        if not ok:
            raise SystemExit(f"the event-locating peer did not reach {t:g} at any steps/period tried")
        ev_S[t] = min(ok)
    event_runs = {}
    for S in sorted(set(ev_S.values())):
        Rt, (dt, (pk, st), foreign) = timed_scaled_R(
            lambda r: (lambda: event_numba.simulate_events(*event_args(wl, r, W, M, S))),
            R, args.budget_s, args.repeats, probe_R=R // 8, quantum=2 * ncpu)
        emax, emean = errors(pk, x0)
        scaled = dt * R / Rt
        note = "full workload" if Rt == R else f"timed R={Rt}, scaled x{R / Rt:.2f} to R={R}"
        log(f"  timed S={S}: R={Rt} in {dt:.2f} s -> {scaled:.2f} s for R={R} ({note}); "
            f"error max {emax:.2e}, mean {emean:.2e}; stuck {float(st.sum()):.3g} s")
        event_runs[S] = dict(time_s=scaled, err=emax, foreign=foreign,
                             note=note + f"; compile {ctx['event_compile_s']:.1f} s excluded")
    log("")

    # ---- Numba fixed-step: accuracy search on one realisation ----------------
    log("-- Numba fixed-step peer: accuracy search (one realisation, full W + M; error = max over measured peaks) --")
    log(f"  JIT compile (excluded from every timing): {ctx['fixed_compile_s']:.2f} s")
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
            raise SystemExit(f"the fixed-step peers did not reach {t:g} at any steps/period tried")
        peer_S[t] = min(ok)
    for S in sorted(set(peer_S.values())):
        pk, _ = simulate_numba(*peer_args(wl, 1, 0, 4 * W + M, S))
        e = np.abs(pk[0] / x0 - 1.0)
        log(f"  settling at S={S}: max err over periods [{W},{W + M}) {e[W:W + M].max():.2e}, "
            f"[{W // 2},{W // 2 + M}) {e[W // 2:W // 2 + M].max():.2e}, "
            f"[{4 * W},{4 * W + M}) {e[4 * W:].max():.2e}")

    numba_runs = {}
    for S in sorted(set(peer_S.values())):
        Rt, (dt, (pk, st), foreign) = timed_scaled_R(
            lambda r: (lambda: simulate_numba(*peer_args(wl, r, W, M, S))),
            R, args.budget_s, args.repeats, probe_R=max(2 * ncpu, min(R, int(2e6 / S))), quantum=ncpu)
        emax, emean = errors(pk, x0)
        scaled = dt * R / Rt
        note = "full workload" if Rt == R else f"timed R={Rt}, scaled x{R / Rt:.2f} to R={R}"
        log(f"  timed S={S}: R={Rt} in {dt:.2f} s -> {scaled:.2f} s for R={R} ({note}); "
            f"error max {emax:.2e}, mean {emean:.2e}; stuck steps {int(st.sum())}")
        numba_runs[S] = dict(time_s=scaled, err=emax, foreign=foreign,
                             note=note + f"; compile {ctx['fixed_compile_s']:.1f} s excluded")
    log("")

    # ---- NumPy: same algorithm (checked against Numba), then timed ------------
    log("-- NumPy fixed-step peer (at the Numba fixed-step peer's steps/period) --")
    S_chk = 256
    pk_np, _ = simulate_numpy(*peer_args(wl, 4, W, M, S_chk))
    pk_nb, _ = simulate_numba(*peer_args(wl, 4, W, M, S_chk))
    diff = float(np.max(np.abs(pk_np - pk_nb))) / x0
    log(f"  same paths as the Numba fixed-step peer? S={S_chk}, R=4, full run: max |peak diff|/x0 = {diff:.1e}")
    numpy_runs = {}
    for S in sorted(set(peer_S.values())):
        numpy_runs[S] = time_numpy(wl, R, W, M, S, args, err_if_prefix=numba_runs[S]["err"],
                                   err_fn=lambda pk: errors(pk, x0)[0])
    log("")

    # ---- JAX: same algorithm (checked against Numba), then timed -------------
    log("-- JAX fixed-step peer (vmap + lax.scan, at the Numba fixed-step peer's steps/period) --")
    run, _ = jax_peer.build(*peer_args(wl, 4, W, M, S_chk))
    pk_jx, _ = run()
    diff = float(np.max(np.abs(pk_jx - pk_nb))) / x0
    log(f"  same paths as the Numba fixed-step peer? S={S_chk}, R=4, full run: max |peak diff|/x0 = {diff:.1e}")
    jax_runs = {}
    for S in sorted(set(peer_S.values())):
        jx = time_jax(wl, R, W, M, S, args, ctx)
        emax, emean = errors(jx["peaks"], x0)
        log(f"  timed S={S}: R={jx['Rt']} in {jx['dt']:.2f} s -> {jx['time_s']:.2f} s for R={R} ({jx['note']}); "
            f"error max {emax:.2e}, mean {emean:.2e}; stuck steps {int(jx['stuck'].sum())}")
        jax_runs[S] = dict(time_s=jx["time_s"], err=emax, foreign=jx["foreign"], note=jx["note"] + jx["compile_note"])
    log("")

    # ---- table -----------------------------------------------------------------
    log(f"== Den Hartog results: R={R} realisations x {W}+{M} periods, eta={args.eta}, {ncpu} cores ==")
    hdr = (f"{'target':>7s}  {'implementation':34s} {'steps/period':>12s} {'error vs DH':>16s} "
           f"{'time s':>9s} {'real-steps/s':>12s} {'/GPU':>8s} {'/CPU':>8s}  note")
    log(hdr)
    log("-" * len(hdr))
    cells = {}
    for t in targets:
        g = gpu_runs[ss_S[t]]
        c = cpu_runs.get(ss_S[t])
        rows = [("stickslip GPU (wgpu, f32)", ss_S[t], g["err_mean"], "mean", g["run_s"],
                 f"run_s; process wall {g['wall_s']:.2f} s", g["foreign"])]
        if c:
            rows.append(("stickslip CPU (f64 reference)", ss_S[t], c["err_mean"], "mean", c["run_s"],
                         f"run_s; process wall {c['wall_s']:.2f} s", c["foreign"]))
        peers_here = [
            (PEER_EVENT, ev_S[t], event_runs[ev_S[t]]),
            (PEER_NUMBA, peer_S[t], numba_runs[peer_S[t]]),
            (PEER_NUMPY, peer_S[t], numpy_runs[peer_S[t]]),
            (PEER_JAX, peer_S[t], jax_runs[peer_S[t]]),
        ]
        for name, S, r in peers_here:
            rows.append((name, S, r["err"], "max", r["time_s"], r["note"], r["foreign"]))
        col = f"Den Hartog {t:.0e}"
        cells[col] = dict(gpu=(ss_S[t], g["run_s"]), cpu=(ss_S[t], c["run_s"]) if c else None,
                          peers={name: (S, r["time_s"]) for name, S, r in peers_here})
        for name, S, err, kind, secs, note, foreign in rows:
            rate = work * S / secs
            vs_cpu = f"{secs / c['run_s']:7.2f}x" if c else f"{'-':>8s}"
            log(f"{t:7.0e}  {name:34s} {S:12d} {err:11.2e} {kind:>4s} {secs:9.2f} {rate:12.3e} "
                f"{secs / g['run_s']:7.2f}x {vs_cpu}  {note_foreign(note, foreign)}")
        log("")
    log("/GPU, /CPU = that row's time / stickslip GPU (CPU) time (sweep.json run_s, start-up excluded); "
        "peers exclude their JIT compile.")
    log("errors: stickslip = |mean peak/x0 - 1| (every realisation is the same path; p05/p95/sd above); "
        "peers = max over all measured peaks of |peak/x0 - 1|.")
    log("event-locating peer error vs steps/period (max, mean): " +
        ", ".join(f"{S}: {e[0]:.1e}/{e[1]:.1e}" for S, e in ev_search.items()))
    log("fixed-step peers' error vs steps/period (max, mean): " +
        ", ".join(f"{S}: {e[0]:.1e}/{e[1]:.1e}" for S, e in search.items()))
    log("")
    return cells


def time_numpy(wl, R, W, M, S, args, err_if_prefix, err_fn):
    """Times the NumPy peer on all R realisations, on a prefix of its time
    steps when the full run is predicted to exceed the budget (each step costs
    the same), scaled linearly in steps."""
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
        err = err_fn(pk)
        note = "full workload"
        log(f"  timed S={S}: full workload in {dt:.2f} s")
    else:
        err = err_if_prefix
        note = f"timed {steps} of {total} steps (all R), scaled x{total / steps:.1f}; accuracy of the Numba fixed-step run"
        log(f"  timed S={S}: {steps}/{total} steps at R={R} in {dt:.2f} s -> {scaled:.1f} s for the full workload")
    return dict(time_s=scaled, err=err, foreign=foreign, note=note, peaks=pk)


def time_jax(wl, R, W, M, S, args, ctx):
    """Times the JAX peer (compiled ahead of time, compile excluded) on R
    realisations, or on fewer (scaled linearly in R) when a probe predicts more
    than the budget. At least 1024 realisations are timed where R allows, so
    that the vectorised loop's per-step overhead stays amortised."""
    builds = {}

    def prepare(r):
        run, cs = jax_peer.build(*peer_args(wl, r, W, M, S))
        builds[r] = cs
        return run

    quantum = ctx["jax_devices"] * 8
    Rt, (dt, (pk, st), foreign) = timed_scaled_R(prepare, R, args.budget_s, args.repeats,
                                                 probe_R=min(R, 1024), quantum=min(R, max(quantum, 1024)))
    note = "full workload" if Rt == R else f"timed R={Rt}, scaled x{R / Rt:.2f} to R={R}"
    return dict(Rt=Rt, dt=dt, time_s=dt * R / Rt, peaks=pk, stuck=st, foreign=foreign, note=note,
                compile_note=f"; compile {builds[Rt]:.1f} s excluded")


# --------------------------------------------------------------------------
# Workload 2: the noisy default
# --------------------------------------------------------------------------


def noisy_section(args, ctx):
    R, W, M = args.noisy_realisations, args.noisy_warmup, args.noisy_cycles
    f, N0, z, K = args.noisy_frequency, args.noisy_normal_force, args.z, args.reference_batches
    ncpu, tmp = ctx["ncpu"], ctx["tmp"]
    if R % K:
        raise SystemExit(f"--noisy-realisations ({R}) must be a multiple of --reference-batches ({K})")
    log(f"==== workload 2: the noisy default (stickslip's embedded model) at {f:g} Hz, {N0:g} N ====")
    log(f"R={R} realisations x ({W} warm-up + {M} measured) periods from the frictionless steady state")
    log(f"matched accuracy: |mean - ref mean| <= {z:g} SE and |var - ref var| <= {z:g} SE (combined standard "
        f"errors; SE from the spread between realisations' per-path means / mean squared deviations, since the "
        f"peaks of one path are correlated)")
    log("")

    # ---- the reference: stickslip's f64 CPU integrator, K independent seeds ----
    S_ref = args.reference_steps
    log(f"-- reference: stickslip CPU (f64) at S={S_ref}, {K} batches of R/{K}={R // K} realisations, "
        f"seeds {args.reference_seed}..{args.reference_seed + K - 1} (independent of every timed run's noise) --")
    blank = dict(freq_hz=f, N0=N0, sets=[])
    batches = []
    for i in range(K):
        seed = args.reference_seed + i
        b = run_stickslip(args.binary, blank, "cpu", R // K, W, M, S_ref, seed, os.path.join(tmp, f"nz-ref{i}"),
                          timing=False)
        batches.append(b)
    ref = batch_stats(batches, M)
    model = batches[0]["model"]
    wl = noisy_workload(model, f, N0)
    log(f"  mean {ref['mean']:.6e} m (SE {ref['se_mean']:.1e}), var {ref['var']:.4e} m^2 (SE {ref['se_var']:.1e}), "
        f"stick fraction {np.mean([b['stick_fraction'] for b in batches]):.4f} (untimed)")
    log(f"  model (from sweep.json): {json.dumps(model, sort_keys=True)}")
    log(f"  x(0)={wl['x_init']:.6e} m, v(0)={wl['v_init']:.6e} m/s (frictionless steady state)")
    log(f"  command: {shown_command(batches[0])}")
    log("")

    def ss_try(backend):
        def try_S(S):
            res = run_stickslip(args.binary, blank, backend, R, W, M, S, 1, os.path.join(tmp, f"nz-{backend}{S}"))
            # a single stickslip run gives no per-path data: its SE is taken as the
            # reference's (same model, same R and M)
            st = dict(mean=res["mean"], var=res["var"], se_mean=ref["se_mean"] * math.sqrt(ref["R"] / R),
                      se_var=ref["se_var"] * math.sqrt(ref["R"] / R), R=R)
            cmp = compare(st, ref, z)
            log(f"  S={S:6d}: {describe(st, cmp, ref)}  stick {res['stick_fraction']:.4f}  "
                f"run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
            return cmp["ok"], dict(res=res, st=st, cmp=cmp)
        return try_S

    def ss_section(backend, label):
        log(f"-- stickslip {label}: accuracy search (full workload, seed 1; SE taken as the reference's) --")
        S, tried = search_ladder(parse_list(args.noisy_stickslip_steps), ss_try(backend))
        if S is None:
            S = max(tried)
            log(f"  (no steps/period on the ladder matched; using S={S})")
        best = tried[S]["res"]
        for _ in range(args.repeats - 1):
            res = run_stickslip(args.binary, blank, backend, R, W, M, S, 1, os.path.join(tmp, f"nz-{backend}{S}r"))
            log(f"  repeat S={S}: run {res['run_s']:.2f} s, wall {res['wall_s']:.2f} s")
            if res["run_s"] < best["run_s"]:
                best = res
        log("  command: " + shown_command(best))
        if backend == "gpu":
            log(f"  {best['adapter']}")
            ctx.setdefault("adapter", best["adapter"])
        return dict(S=S, time_s=best["run_s"], wall_s=best["wall_s"], foreign=best["foreign"],
                    cmp=tried[S]["cmp"], st=tried[S]["st"], matched=tried[S]["cmp"]["ok"],
                    note=f"run_s; process wall {best['wall_s']:.2f} s")

    gpu = ss_section("gpu", "GPU (wgpu, f32)")
    cpu = None if args.skip_cpu else ss_section("cpu", "CPU (f64 reference)")
    log("")

    def peer_search(ladder, prepare, coarse_first, compile_s):
        """Each try runs the full workload under the timing guard; the passing
        run's time counts (best of it and repeats - 1 more if it is short).
        prepare(S) does the untimed set-up (JAX: compile) and returns the run,
        which returns (peaks, stick fraction)."""
        runs = {}

        def try_S(S):
            runs[S] = prepare(S)
            dt, (pk, st), foreign = timed(runs[S])
            stats = path_stats(pk)
            cmp = compare(stats, ref, z)
            log(f"  S={S:6d}: {describe(stats, cmp, ref)}  stick {st:.4f}  time {dt:.2f} s")
            return cmp["ok"], dict(dt=dt, foreign=foreign, st=stats, cmp=cmp)
        S, tried = search_ladder(ladder, try_S, coarse_first)
        if S is None:
            S = max(tried)
            log(f"  (no steps/period on the ladder matched; using S={S})")
        rec = tried[S]
        dt, foreign = rec["dt"], rec["foreign"]
        if dt <= args.budget_s:
            for _ in range(args.repeats - 1):
                d2, _, f2 = timed(runs[S])
                log(f"  repeat S={S}: {d2:.2f} s")
                if d2 < dt:
                    dt, foreign = d2, f2
        return dict(S=S, time_s=dt, foreign=foreign, cmp=rec["cmp"], st=rec["st"], matched=rec["cmp"]["ok"],
                    note=f"full workload; compile {compile_s(S):.1f} s excluded")

    T = 2.0 * math.pi / wl["omega"]
    # ---- Numba event-locating ---------------------------------------------------
    log("-- Numba event-locating peer: accuracy search (full workload, its own RNG) --")

    def run_event(S):
        pk, st = event_numba.simulate_events(*event_args(wl, R, W, M, S))
        return pk, float(st.sum()) / (R * M * T)
    ev = peer_search(parse_list(args.noisy_event_steps), lambda S: (lambda: run_event(S)), False,
                     lambda S: ctx["event_compile_s"])
    log("")

    # ---- Numba fixed-step ---------------------------------------------------------
    log("-- Numba fixed-step peer: accuracy search (full workload; powers of two first, then the point between) --")

    def run_fixed(S):
        pk, st = simulate_numba(*peer_args(wl, R, W, M, S))
        return pk, float(st.sum()) / (R * M * S)
    nb = peer_search(parse_list(args.noisy_peer_steps), lambda S: (lambda: run_fixed(S)), True,
                     lambda S: ctx["fixed_compile_s"])
    log("")

    # ---- NumPy and JAX: the same paths as the Numba fixed-step peer -------------------
    S = nb["S"]
    S_chk, R_chk = 256, 4
    pk_nb, _ = simulate_numba(*peer_args(wl, R_chk, W, M, S_chk))
    pk_np, _ = simulate_numpy(*peer_args(wl, R_chk, W, M, S_chk))
    run, _ = jax_peer.build(*peer_args(wl, R_chk, W, M, S_chk))
    pk_jx, _ = run()
    scale = ref["mean"]
    log(f"-- NumPy and JAX fixed-step peers at S={S}, the Numba fixed-step peer's: the same arithmetic and the "
        f"same noise, so the same paths --")
    log(f"  same paths as the Numba fixed-step peer? S={S_chk}, R={R_chk}, full run: max |peak diff|/mean peak = "
        f"NumPy {float(np.max(np.abs(pk_np - pk_nb))) / scale:.1e}, JAX {float(np.max(np.abs(pk_jx - pk_nb))) / scale:.1e}")

    def checked(peaks, label):
        st = path_stats(peaks)
        cmp = compare(st, ref, z)
        log(f"  {label}: {describe(st, cmp, ref)}")
        return st, cmp

    log("  NumPy:")
    npy = time_numpy(wl, R, W, M, S, args, err_if_prefix=None, err_fn=lambda pk: None)
    npy.update(S=S)
    if npy["note"] == "full workload":
        npy["st"], npy["cmp"] = checked(npy["peaks"], "statistics")
        npy["matched"] = npy["cmp"]["ok"]
    else:
        npy["matched"] = None
        npy["note"] = npy["note"].replace("accuracy of the Numba fixed-step run",
                                          "same paths as the Numba fixed-step run (checked above)")
    log("  JAX (vmap + lax.scan):")
    jx = time_jax(wl, R, W, M, S, args, ctx)
    log(f"  timed S={S}: R={jx['Rt']} in {jx['dt']:.2f} s -> {jx['time_s']:.2f} s for R={R} ({jx['note']})")
    jst, jcmp = checked(jx["peaks"], f"statistics of the R={jx['Rt']} realisations run")
    jax_row = dict(S=S, time_s=jx["time_s"], foreign=jx["foreign"], st=jst, cmp=jcmp, matched=jcmp["ok"],
                   note=jx["note"] + (f" (statistics of those R={jx['Rt']})" if jx["Rt"] != R else "")
                   + jx["compile_note"])
    log("")

    # ---- table ----------------------------------------------------------------------
    log(f"== noisy default results: R={R} x {W}+{M} periods at {f:g} Hz, {N0:g} N, {ncpu} cores ==")
    log(f"reference (stickslip CPU f64, S={S_ref}, seeds {args.reference_seed}+): mean {ref['mean']:.6e} m "
        f"(SE {ref['se_mean']:.1e}), var {ref['var']:.4e} m^2 (SE {ref['se_var']:.1e})")
    hdr = (f"{'implementation':34s} {'steps/period':>12s} {'dmean/SE':>9s} {'var ratio':>10s} {'dvar/SE':>8s} "
           f"{'match':>6s} {'time s':>9s} {'/GPU':>8s} {'/CPU':>8s}  note")
    log(hdr)
    log("-" * len(hdr))
    rows = [("stickslip GPU (wgpu, f32)", gpu)]
    if cpu:
        rows.append(("stickslip CPU (f64 reference)", cpu))
    rows += [(PEER_EVENT, ev), (PEER_NUMBA, nb), (PEER_NUMPY, npy), (PEER_JAX, jax_row)]
    for name, r in rows:
        if r.get("cmp"):
            c = r["cmp"]
            stats = f"{c['z_mean']:+9.1f} {c['ratio']:10.3f} {c['z_var']:+8.1f} {'yes' if c['ok'] else 'NO':>6s}"
        else:
            stats = f"{'-':>9s} {'-':>10s} {'-':>8s} {'?':>6s}"
        vs_cpu = f"{r['time_s'] / cpu['time_s']:7.2f}x" if cpu else f"{'-':>8s}"
        log(f"{name:34s} {r['S']:12d} {stats} {r['time_s']:9.2f} {r['time_s'] / gpu['time_s']:7.2f}x {vs_cpu}  "
            f"{note_foreign(r['note'], r['foreign'])}")
    log(f"match: |dmean| and |dvar| <= {z:g} combined SE, i.e. the variance ratio within 1 +- "
        f"{ev['cmp']['ratio_half']:.3f} for the event-locating peer (an F-type interval with the effective "
        f"degrees of freedom of correlated peaks).")
    log("stickslip runs give no per-path data; their SE is taken as the reference's (same model, R and M).")
    log("")
    peers_here = {name: (r["S"], r["time_s"]) for name, r in rows[-4:]}
    return {"noisy default": dict(gpu=(gpu["S"], gpu["time_s"]), cpu=(cpu["S"], cpu["time_s"]) if cpu else None,
                                  peers=peers_here)}


# --------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------

PEER_EVENT = "Numba prange, event-locating (f64)"
PEER_NUMBA = "Numba prange, fixed-step RK4 (f64)"
PEER_NUMPY = "NumPy vectorised, fixed-step RK4"
PEER_JAX = "JAX vmap+scan, fixed-step RK4"


def ratio_table(cells):
    cols = list(cells)
    log("== ratios: peer time / stickslip time, each at its own matched-accuracy steps/period (S) ==")
    w = 26
    log(f"{'':36s}" + "".join(f"{c:>{w}s}" for c in cols))
    log(f"{'':36s}" + "".join(f"{'S':>6s}{'vs GPU':>10s}{'vs CPU':>10s}" for _ in cols))
    for who in ("stickslip GPU", "stickslip CPU"):
        key = "gpu" if who.endswith("GPU") else "cpu"
        line = f"{who + ' (time, s)':36s}"
        for c in cols:
            v = cells[c][key]
            line += f"{v[0]:6d}{v[1]:10.2f}{'':>10s}" if v else f"{'-':>{w}s}"
        log(line)
    for name in (PEER_EVENT, PEER_NUMBA, PEER_NUMPY, PEER_JAX):
        line = f"{name:36s}"
        for c in cols:
            S, t = cells[c]["peers"][name]
            g = cells[c]["gpu"][1]
            cc = cells[c]["cpu"]
            line += f"{S:6d}{t / g:9.2f}x" + (f"{t / cc[1]:9.2f}x" if cc else f"{'-':>10s}")
        log(line)
    log("")
    for c in cols:
        g, cc, p = cells[c]["gpu"][1], cells[c]["cpu"], cells[c]["peers"]
        for who, t in (("GPU", g), ("CPU", cc[1] if cc else None)):
            if t is None:
                continue
            ev, jx = p[PEER_EVENT][1] / t, p[PEER_JAX][1] / t
            log(f"{c}: stickslip {who} is {ev:.2f}x the event-locating Numba peer (goal >= 3x: "
                f"{'MET' if ev >= 3 else 'NOT MET'}) and {jx:.2f}x the JAX peer (goal >= 10x: "
                f"{'MET' if jx >= 10 else 'NOT MET'})")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default="target/release/stickslip")
    ap.add_argument("--workloads", default="denhartog,noisy", help="comma list of denhartog, noisy")
    ap.add_argument("--quick", action="store_true",
                    help="a small smoke run for development (R=256, noisy 20+20 periods, 1 repeat, 10 s budget, "
                         "no waiting for idle cores); its timings mean little")
    g = ap.add_argument_group("Den Hartog workload")
    g.add_argument("--eta", type=float, default=0.8)
    g.add_argument("--beta-fraction", type=float, default=0.5)
    g.add_argument("--realisations", type=int, default=4096)
    g.add_argument("--warmup", type=int, default=200)
    g.add_argument("--cycles", type=int, default=50)
    g.add_argument("--targets", default="1e-4,1e-3",
                   help="relative errors vs Den Hartog every implementation must reach (the first is the headline)")
    g.add_argument("--stickslip-steps", default="16,24,32,48,64,96,128,192,256,384,512")
    g.add_argument("--event-steps", default="8,12,16,24,32,48,64,96,128,192,256,384,512",
                   help="ladder of the event-locating peer (it may go below stickslip's minimum of 16)")
    g.add_argument("--peer-steps", default="128,192,256,384,512,768,1024,1536,2048,3072,4096,6144,8192,"
                                           "12288,16384,24576,32768,49152,65536")
    g = ap.add_argument_group("noisy workload")
    g.add_argument("--noisy-frequency", type=float, default=7.0)
    g.add_argument("--noisy-normal-force", type=float, default=16.39)
    g.add_argument("--noisy-realisations", type=int, default=4096)
    g.add_argument("--noisy-warmup", type=int, default=100)
    g.add_argument("--noisy-cycles", type=int, default=100)
    g.add_argument("--reference-steps", type=int, default=256, help="steps/period of stickslip's f64 reference")
    g.add_argument("--reference-batches", type=int, default=16,
                   help="the reference runs as this many independent seeds (its SE comes from their spread)")
    g.add_argument("--reference-seed", type=int, default=1001)
    g.add_argument("--z", type=float, default=3.0, help="matched: mean and variance within z combined SE")
    g.add_argument("--noisy-stickslip-steps", default="16,24,32,48,64,96,128,192,256")
    g.add_argument("--noisy-event-steps", default="8,12,16,24,32,48,64,96,128,192,256")
    g.add_argument("--noisy-peer-steps", default="256,384,512,768,1024,1536,2048,3072,4096,6144,8192,"
                                                 "12288,16384,24576,32768")
    g = ap.add_argument_group("timing")
    g.add_argument("--repeats", type=int, default=2, help="timed runs per measurement; the best is reported")
    g.add_argument("--budget-s", type=float, default=40.0,
                   help="a peer run predicted to take longer than this is timed on a reduced workload "
                        "(Numba/JAX: fewer realisations; NumPy: a prefix of the time steps, all realisations) "
                        "and scaled linearly to the full workload; the noisy accuracy searches of the Numba "
                        "peers always run the full workload")
    g.add_argument("--wait-s", type=float, default=120.0,
                   help="longest wait for the shared machine's cores to go idle before each timing")
    g.add_argument("--jax-devices", type=int, default=0, help="JAX host devices (default: one per core)")
    g.add_argument("--skip-cpu", action="store_true", help="skip stickslip's CPU reference")
    args = ap.parse_args()
    if args.quick:
        for name, value in dict(realisations=256, noisy_realisations=256, noisy_warmup=20, noisy_cycles=20,
                                repeats=1, budget_s=10.0, wait_s=0.0, reference_batches=8).items():
            if getattr(args, name) == ap.get_default(name):
                setattr(args, name, value)
    QUIET["limit_s"] = args.wait_s
    workloads = [w.strip() for w in args.workloads.split(",") if w.strip()]
    if set(workloads) - {"denhartog", "noisy"}:
        raise SystemExit(f"--workloads: unknown {sorted(set(workloads) - {'denhartog', 'noisy'})}")

    ncpu, cpu_model = machine_info()
    jax_devices = args.jax_devices or ncpu
    jax = jax_peer.configure(jax_devices)
    import jaxlib
    log("== stickslip peer comparison ==" + ("  [--quick: smoke run, small workload; not a benchmark]"
                                              if args.quick else ""))
    log(f"machine: nproc={ncpu}, cpu='{cpu_model}', python {platform.python_version()}, "
        f"numpy {np.__version__}, numba {numba.__version__} ({numba.config.NUMBA_NUM_THREADS} threads), "
        f"jax {jax.__version__}/jaxlib {jaxlib.__version__} ({len(jax.devices())} CPU devices)")
    ctx = dict(ncpu=ncpu, tmp=tempfile.mkdtemp(prefix="stickslip-peers-"), jax_devices=len(jax.devices()))

    # JIT compilation, excluded from every timing
    t0 = time.perf_counter()
    simulate_numba(*peer_args(make_workload(args), 2, 1, 1, 16))
    ctx["fixed_compile_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    event_numba.simulate_events(*event_args(make_workload(args), 2, 1, 1, 16))
    ctx["event_compile_s"] = time.perf_counter() - t0
    log(f"Numba JIT compile (excluded from timings): fixed-step {ctx['fixed_compile_s']:.1f} s, "
        f"event-locating {ctx['event_compile_s']:.1f} s; JAX compiles ahead of each timed shape (excluded, "
        f"reported per row)")
    log("")

    cells = {}
    if "denhartog" in workloads:
        cells.update(den_hartog_section(args, ctx))
    if "noisy" in workloads:
        cells.update(noisy_section(args, ctx))

    log(f"== summary: {ncpu} cores ({cpu_model}); {ctx.get('adapter') or ''} ==")
    ratio_table(cells)
    log(f"shared-machine guard: waited {QUIET['waited_s']:.0f} s in all for idle cores; {QUIET['retried']} timings "
        f"retaken because other processes used > 10% of the cores; reported timings had at most "
        f"{QUIET['worst']:.0%} of the cores taken by other processes")


if __name__ == "__main__":
    main()
