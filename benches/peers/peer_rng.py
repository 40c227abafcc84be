"""The peers' own noise: a cheap counter-based generator, the kind a user
writes instead of porting stickslip's Philox.

(xi_mu, xi_N) of interval i of realisation r is a pure function of
(seed, r, i): SplitMix64 of the path key plus counters 2i+1 and 2i+2 of the
key's Weyl sequence, then Box-Muller (one log, one sqrt, one cos, one sin for
the pair). So it does not depend on the step size, the thread or the
implementation: the four peers (Numba event-locating and fixed-step, NumPy,
JAX) draw the same noise for the same realisation, up to the rounding of
log/cos/sin in each library. It is not stickslip's noise: the peers are
compared with stickslip statistically.

Three spellings of the same arithmetic: Numba (scalar), NumPy (arrays of
keys) and JAX (traced).
"""

import math

import numpy as np
from numba import njit

GOLDEN = 0x9E3779B97F4A7C15
MIX1 = 0xBF58476D1CE4E5B9
MIX2 = 0x94D049BB133111EB
INV_2_53 = 1.0 / 9007199254740992.0
TAU = 2.0 * math.pi

_G = np.uint64(GOLDEN)
_M1 = np.uint64(MIX1)
_M2 = np.uint64(MIX2)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_ONE = np.uint64(1)
_TWO = np.uint64(2)


# ---- Numba -------------------------------------------------------------------

@njit
def splitmix(z):
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit
def path_key(seed, r):
    """The key of realisation r."""
    return splitmix(splitmix(np.uint64(seed) * _G + _ONE) + np.uint64(r) * _M1)


@njit
def gaussian_pair(key, interval):
    """(xi_mu, xi_N) of one noise interval of the path with this key."""
    c = key + (np.uint64(interval) * _TWO + _ONE) * _G
    w1 = splitmix(c)
    w2 = splitmix(c + _G)
    u1 = (float(w1 >> _S11) + 1.0) * INV_2_53     # (0, 1]
    u2 = float(w2 >> _S11) * INV_2_53             # [0, 1)
    rad = math.sqrt(-2.0 * math.log(u1))
    return rad * math.cos(TAU * u2), rad * math.sin(TAU * u2)


# ---- NumPy -------------------------------------------------------------------

def path_keys_np(seed, R):
    """Keys of realisations 0..R-1 (uint64 array)."""
    with np.errstate(over="ignore"):
        return _splitmix_np(_splitmix_np(np.uint64(seed) * _G + _ONE) + np.arange(R, dtype=np.uint64) * _M1)


def _splitmix_np(z):
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


def gaussian_pair_np(keys, interval):
    """(xi_mu, xi_N) arrays of one interval for an array of path keys."""
    with np.errstate(over="ignore"):
        c = keys + (np.uint64(interval) * _TWO + _ONE) * _G
        w1 = _splitmix_np(c)
        w2 = _splitmix_np(c + _G)
    u1 = ((w1 >> _S11).astype(np.float64) + 1.0) * INV_2_53
    u2 = (w2 >> _S11).astype(np.float64) * INV_2_53
    rad = np.sqrt(-2.0 * np.log(u1))
    return rad * np.cos(TAU * u2), rad * np.sin(TAU * u2)


# ---- JAX ---------------------------------------------------------------------

def gaussian_pair_jax(jnp, key, interval):
    """(xi_mu, xi_N) for a uint64 path key and int64 interval index (traced;
    works elementwise on arrays)."""
    u64 = jnp.uint64

    def mix(z):
        z = (z ^ (z >> u64(30))) * u64(MIX1)
        z = (z ^ (z >> u64(27))) * u64(MIX2)
        return z ^ (z >> u64(31))

    c = key + (interval.astype(jnp.uint64) * u64(2) + u64(1)) * u64(GOLDEN)
    w1 = mix(c)
    w2 = mix(c + u64(GOLDEN))
    u1 = ((w1 >> u64(11)).astype(jnp.float64) + 1.0) * INV_2_53
    u2 = (w2 >> u64(11)).astype(jnp.float64) * INV_2_53
    rad = jnp.sqrt(-2.0 * jnp.log(u1))
    return rad * jnp.cos(TAU * u2), rad * jnp.sin(TAU * u2)
