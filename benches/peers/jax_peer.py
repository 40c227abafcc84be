"""Peer 4: JAX on the CPU, float64 -- jax.vmap over realisations, jax.lax.scan
over the time steps, compiled once by XLA.

The algorithm is the fixed-step one of the Numba and NumPy peers in peers.py,
written per realisation and vectorised with vmap:

- fixed-step f64 RK4 with sgn(v) friction at every stage;
- when v changes sign in a step, a stick check: |k(u - x)| <= mu_s N holds the
  block with v = 0; breakaway in the direction of k(u - x);
- the peak is the largest sampled x of the period;
- noise held per interval: the interval of a step is that of its start
  (floor(t / tau)); (xi_mu, xi_N) of interval i comes from the peers' own
  counter-based generator (peer_rng.py), a pure function of (seed,
  realisation, interval), so the JAX peer draws the same noise as the Numba
  and NumPy peers; it is computed for a whole period's intervals at once.

Structure: an outer lax.scan over periods (each emits the period's peak) and
an inner lax.scan over the S steps of a period, with the base displacement
read from a per-period table, as in the other peers. The run is compiled ahead
of time (jit(...).lower(...).compile()), so the compile time is measured on
its own and excluded from the timing.

Cores: XLA's CPU backend runs one realisation-vectorised loop on one core. To
use every core, as the other peers do, the realisations are split over
`devices` host devices (XLA_FLAGS=--xla_force_host_platform_device_count, set
by configure() before jax is imported) with a sharded jit: each device runs
its share on its own core.
"""

import math
import os


def configure(devices):
    """Must run before jax is imported: float64, and `devices` CPU devices."""
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_force_host_platform_device_count" not in flags:
        os.environ["XLA_FLAGS"] = (flags + f" --xla_force_host_platform_device_count={devices}").strip()
    os.environ.setdefault("JAX_PLATFORMS", "cpu")
    import jax
    jax.config.update("jax_enable_x64", True)
    return jax


def build(R, W, M, S, m, k, c, U0, a, b, cs, d, N0, sig_mu, sig_N, tau_s, period_s, x_init, v_init,
          seed, unroll=1):
    """Compiles the run for these shapes and constants. Returns
    (run, compile_s) where run() returns (peaks[R, M], stuck_steps[R]) as
    NumPy arrays (the device arrays are ready when it returns)."""
    import time

    import jax
    import jax.numpy as jnp
    import numpy as np
    from jax.sharding import Mesh, NamedSharding, PartitionSpec

    import peer_rng

    h = period_s / S
    inv_m = 1.0 / m
    steps_per_tau = h / tau_s
    noisy = sig_mu != 0.0 or sig_N != 0.0
    # base displacement at each step's start, middle and end
    uh = U0 * np.cos(np.pi * np.arange(2 * S + 1) / S)
    u_start, u_mid, u_end = jnp.asarray(uh[0:2 * S:2]), jnp.asarray(uh[1:2 * S:2]), jnp.asarray(uh[2::2])
    # the most noise intervals one period can touch
    K = int(math.ceil(period_s / tau_s)) + 2

    def acc(x, v, u, sdir, nmu, N):
        s = jnp.where(v > 0.0, 1.0, jnp.where(v < 0.0, -1.0, sdir))
        mu = jnp.maximum(a + b / (1.0 + cs * jnp.abs(v)) + d * v * v + nmu, 0.0)
        return (k * (u - x) - c * v - mu * N * s) * inv_m

    def path(key, x, v):
        """One realisation (uint64 noise key): W + M periods from (x, v) at t = 0."""

        def period(carry, p):
            x, v, stuck, sdir, nst = carry
            step0 = p * S
            if noisy:
                # step n lies in noise interval floor(n h / tau), as in the other peers
                iv = jnp.floor((step0 + jnp.arange(S)) * steps_per_tau).astype(jnp.int64)
                first = iv[0]
                xi = jnp.stack(peer_rng.gaussian_pair_jax(jnp, key, first + jnp.arange(K, dtype=jnp.int64)), axis=1)
                slot = iv - first
            else:
                xi = jnp.zeros((K, 2))
                slot = jnp.zeros(S, jnp.int64)

            def step(st, inp):
                x, v, stuck, sdir, pk, ns = st
                u0, u1, u2, sl = inp
                nmu = sig_mu * xi[sl, 0]
                N = jnp.maximum(N0 + sig_N * xi[sl, 1], 0.0)
                mu_s_N = jnp.maximum(a + b + nmu, 0.0) * N
                # breakaway from stick
                fs = k * (u0 - x)
                brk = stuck & (jnp.abs(fs) > mu_s_N)
                sdir = jnp.where(brk, jnp.where(fs > 0.0, 1.0, -1.0), sdir)
                stuck = stuck & ~brk
                ns = ns + stuck.astype(jnp.int64)
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
                x = jnp.where(stuck, x, xn)
                vn = jnp.where(stuck, 0.0, vn)
                # velocity reversal during the step: stick or turn round
                rev = ~stuck & (vn * sdir <= 0.0)
                hold = rev & (jnp.abs(k * (u2 - x)) <= mu_s_N)
                vn = jnp.where(hold, 0.0, vn)
                stuck = stuck | hold
                sdir = jnp.where(rev & ~hold, -sdir, sdir)
                return (x, vn, stuck, sdir, jnp.maximum(pk, x), ns), None

            (x, v, stuck, sdir, pk, ns), _ = jax.lax.scan(
                step, (x, v, stuck, sdir, x, jnp.int64(0)), (u_start, u_mid, u_end, slot), unroll=unroll)
            # stuck steps are counted in the measured periods only
            return (x, v, stuck, sdir, nst + jnp.where(p >= W, ns, 0)), pk

        init = (x, v, v == 0.0, jnp.where(v >= 0.0, 1.0, -1.0), jnp.int64(0))
        (_, _, _, _, nst), pks = jax.lax.scan(period, init, jnp.arange(W + M, dtype=jnp.int64))
        return pks[W:], nst

    def run_all(keys, x, v):
        return jax.vmap(path)(keys, x, v)

    keys = jnp.asarray(peer_rng.path_keys_np(seed, R))
    devs = jax.devices()
    nd = len(devs)
    while nd > 1 and R % nd:
        nd -= 1
    mesh = Mesh(np.array(devs[:nd]), ("r",))
    shard = NamedSharding(mesh, PartitionSpec("r"))
    keys = jax.device_put(keys, shard)
    # every realisation gets its own initial state (all equal here), so that
    # XLA cannot fold noiseless realisations into one computation
    xs = jax.device_put(jnp.full(R, x_init), shard)
    vs = jax.device_put(jnp.full(R, v_init), shard)
    t0 = time.perf_counter()
    compiled = jax.jit(run_all, in_shardings=(shard, shard, shard),
                       out_shardings=(shard, shard)).lower(keys, xs, vs).compile()
    compile_s = time.perf_counter() - t0

    def run():
        peaks, nst = compiled(keys, xs, vs)
        peaks.block_until_ready()
        return np.asarray(peaks), np.asarray(nst)

    return run, compile_s
