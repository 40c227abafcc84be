"""Peer 3: the best CPU code a strong user could write without stickslip.

Numba, @njit(parallel=True), prange over realisations, f64, with the same
exact event location as stickslip's f64 CPU reference integrator (the `cpu`
module: Path::run_period, advance_segment, rk4_slip, locate_velocity_zero,
breakaway_time, earliest_entry), written directly rather than translated line
by line:

- a fixed grid of S steps per excitation period; a step is split wherever a
  noise-interval boundary (every tau seconds) falls inside it, so each random
  value holds exactly over its interval;
- slip: classical RK4 with the slip direction frozen (the ODE is smooth there);
- a velocity zero inside a step: the step length at which the RK4 map's
  velocity reaches zero is found by Illinois (modified regula falsi) root
  finding (stickslip's bracketing, tolerance and iteration limits), the block
  is put there at rest, and the stick-or-slip test decides;
- stick: the breakaway instant k (U0 cos(Omega t) - x) = +-mu_s N is solved in
  closed form (acos), since only the base moves;
- at most 64 events per segment, as stickslip;
- peak = the largest x of the period, including the event points.

The full baseline law: mu(v) = a + b/(1 + c|v|) + d v^2 + sigma_mu xi_mu,
clipped at 0; N = N0 + sigma_N xi_N, clipped at 0; breakaway at
mu_s = a + b + sigma_mu xi_mu (clipped at 0).

What a user tuning this would do, and this does: constants hoisted out of the
loops; the segment grid (step grid split at the noise boundaries) and the base
displacement at every segment's start, middle and end, which are the same for
every realisation, tabulated once per run, so that cos is only evaluated at
events; noise-dependent terms (friction offset, N, breakaway force) computed
once per interval; the full step's velocity reused as the root finder's upper
bracket; its own cheap counter-based RNG (peer_rng.py: SplitMix64 and
Box-Muller, one (xi_mu, xi_N) pair per interval from one log, one sqrt, one
cos and one sin). It does not reproduce stickslip's Philox noise bit for bit
(that is not needed: the comparison with stickslip under noise is
statistical), but like stickslip's its noise is a pure function of (seed,
realisation, interval), so it does not depend on the step size or the thread.
"""

import math

import numpy as np
from numba import njit, prange

from peer_rng import gaussian_pair, path_key

# Events handled inside one segment before progress is forced (guards against
# chattering at exactly balanced forces), as in stickslip's CPU reference.
MAX_EVENTS_PER_SEGMENT = 64

TAU = 2.0 * math.pi


@njit
def _acc(x, v, u, sgn, P, mu0, N):
    """Acceleration while slipping in direction sgn (frozen) at base position u.
    mu0 = a + sigma_mu xi_mu of the current interval, N its normal force."""
    k, c, inv_m, b, cs, d = P
    mu = mu0 + b / (1.0 + cs * (sgn * v)) + d * v * v
    if mu < 0.0:
        mu = 0.0
    return (k * (u - x) - c * v - sgn * mu * N) * inv_m


@njit
def _rk4(x, v, h, ua, um, ub, sgn, P, mu0, N):
    """One classical RK4 step of the slip ODE over h; ua, um, ub = base
    displacement at the start, middle and end of the step."""
    half = 0.5 * h
    k1x = v
    k1v = _acc(x, v, ua, sgn, P, mu0, N)
    k2x = v + half * k1v
    k2v = _acc(x + half * k1x, k2x, um, sgn, P, mu0, N)
    k3x = v + half * k2v
    k3v = _acc(x + half * k2x, k3x, um, sgn, P, mu0, N)
    k4x = v + h * k3v
    k4v = _acc(x + h * k3x, k4x, ub, sgn, P, mu0, N)
    return (x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v))


@njit
def _velocity_zero(ta, x, v, h, vh, ua, sgn, P, mu0, N, U0, omega, period):
    """Step length h* in (0, h] at which the RK4 map's velocity reaches zero,
    given vh = v_RK4(h) with sgn * vh <= 0: Illinois root finding on
    g(s) = sgn * v_RK4(s)."""
    lo = 0.0
    g_lo = sgn * v
    hi = h
    g_hi = sgn * vh
    if g_lo <= 0.0:
        # slip starting from rest: find a point where it is under way
        probe = 0.5 * h
        found = False
        for _ in range(60):
            _, vp = _rk4(x, v, probe, ua, U0 * math.cos(omega * (ta + 0.5 * probe)),
                         U0 * math.cos(omega * (ta + probe)), sgn, P, mu0, N)
            gp = sgn * vp
            if gp > 0.0:
                lo = probe
                g_lo = gp
                found = True
                break
            hi = probe
            g_hi = gp
            probe *= 0.5
        if not found:
            return hi
    tol = 1e-15 * max(h, period * 1e-6)
    side = 0
    for _ in range(100):
        if hi - lo <= tol:
            break
        mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo)
        if not (mid > lo and mid < hi):
            mid = 0.5 * (lo + hi)
        _, vm = _rk4(x, v, mid, ua, U0 * math.cos(omega * (ta + 0.5 * mid)),
                     U0 * math.cos(omega * (ta + mid)), sgn, P, mu0, N)
        gm = sgn * vm
        if gm > 0.0:
            lo = mid
            g_lo = gm
            if side == 1:
                g_hi *= 0.5
            side = 1
        else:
            hi = mid
            g_hi = gm
            if side == -1:
                g_lo *= 0.5
            side = -1
    return hi


@njit
def _entry(best_t, best_s, sgn, phase_a, x, reach, U0, omega, tb):
    """Entering cos(theta) >= C+ happens at theta = 2 pi n - acos(C+), entering
    cos(theta) <= C- at 2 pi n + acos(C-); keeps (best_t, best_s) unless this
    direction's entry is earlier (and within tb)."""
    level = (x + sgn * reach) / U0
    if level < -1.0 or level > 1.0:
        return best_t, best_s
    base = -sgn * math.acos(level)
    n = math.ceil((phase_a - base) / TAU)
    t = (base + n * TAU) / omega
    if t <= tb and t < best_t:
        return t, sgn
    return best_t, best_s


@njit
def _breakaway(ta, tb, x, ua, F_s, k, U0, omega):
    """Earliest time in [ta, tb] at which the stuck block breaks away, and the
    direction (0.0 if it stays stuck): k (U0 cos(Omega t) - x) = +-F_s."""
    f = k * (ua - x)
    if f > F_s:
        return ta, 1.0
    if f < -F_s:
        return ta, -1.0
    if U0 == 0.0:
        return math.inf, 0.0
    phase_a = omega * ta
    reach = F_s / k
    t, s = _entry(math.inf, 0.0, 1.0, phase_a, x, reach, U0, omega, tb)
    t, s = _entry(t, s, -1.0, phase_a, x, reach, U0, omega, tb)
    if s == 0.0:
        return math.inf, 0.0
    return max(t, ta), s


@njit
def _stick_or_slip(x, u, F_s, k):
    f = k * (u - x)
    if abs(f) <= F_s:
        return 0.0
    return 1.0 if f > 0.0 else -1.0


@njit
def _advance(ta, tb, ua, um, ub, x, v, mode, pk, P, mu0, N, F_s, U0, omega, period):
    """From ta to tb (local times in the period) with the noise held, through
    any stick/slip events. ua, um, ub: base displacement at ta, the middle and
    tb. Returns (x, v, mode, pk, time stuck)."""
    k = P[0]
    stuck_s = 0.0
    events = 0
    t = ta
    while t < tb:
        if mode == 0.0:
            if events < MAX_EVENTS_PER_SEGMENT:
                u_t = ua if t == ta else U0 * math.cos(omega * t)
                t_end, s = _breakaway(t, tb, x, u_t, F_s, k, U0, omega)
            else:
                t_end, s = math.inf, 0.0
            if s == 0.0:
                stuck_s += tb - t
                t = tb
            else:
                stuck_s += t_end - t
                t = t_end
                mode = s
            events += 1
        else:
            h = tb - t
            if t == ta:
                u0, u1 = ua, um
            else:
                u0 = U0 * math.cos(omega * t)
                u1 = U0 * math.cos(omega * (t + 0.5 * h))
            x1, v1 = _rk4(x, v, h, u0, u1, ub, mode, P, mu0, N)
            if mode * v1 > 0.0:
                x = x1
                v = v1
                if x1 > pk:
                    pk = x1
                t = tb
            else:
                hz = _velocity_zero(t, x, v, h, v1, u0, mode, P, mu0, N, U0, omega, period)
                xz, _ = _rk4(x, v, hz, u0, U0 * math.cos(omega * (t + 0.5 * hz)),
                             U0 * math.cos(omega * (t + hz)), mode, P, mu0, N)
                x = xz
                v = 0.0
                if xz > pk:
                    pk = xz
                t += hz
                if events < MAX_EVENTS_PER_SEGMENT:
                    mode = _stick_or_slip(x, U0 * math.cos(omega * t), F_s, k)
                else:
                    mode = 0.0
                events += 1
    return x, v, mode, pk, stuck_s


@njit
def _noise(key, interval, noisy, a, b, sig_mu, N0, sig_N):
    """(mu0 = a + sigma_mu xi_mu, N, breakaway force F_s) of one interval."""
    if noisy:
        z_mu, z_n = gaussian_pair(key, interval)
    else:
        z_mu, z_n = 0.0, 0.0
    nmu = sig_mu * z_mu
    N = max(N0 + sig_N * z_n, 0.0)
    return a + nmu, N, max(a + b + nmu, 0.0) * N


@njit
def segment_table(W, M, S, U0, omega, tau_s, noisy):
    """The integration segments of the whole run, the same for every
    realisation: the step grid (S steps per period) split at every noise
    boundary (every tau_s). Returns (start, ta, tb, ua, um, ub, boundary):
    period p's segments are start[p]:start[p+1]; each runs from local time ta
    to tb with base displacement ua, um, ub at its start, middle and end;
    boundary marks a segment that ends on a noise boundary."""
    period = TAU / omega
    h = period / S
    # base displacement at the step grid's starts, middles and ends
    uh = np.empty(2 * S + 1)
    for i in range(2 * S + 1):
        uh[i] = U0 * math.cos(math.pi * i / S)
    q = tau_s / period                     # noise interval in periods
    P = W + M
    cap = P * S + (int(P / q) + 2 if noisy else 0)
    start = np.empty(P + 1, np.int64)
    ta_ = np.empty(cap)
    tb_ = np.empty(cap)
    ua_ = np.empty(cap)
    um_ = np.empty(cap)
    ub_ = np.empty(cap)
    boundary = np.zeros(cap, np.bool_)
    n = 0
    interval = 0
    for p in range(P):
        start[p] = n
        # local time of the next noise boundary (>= period when none this period)
        t_nb = ((interval + 1) * q - p) * period if noisy else math.inf
        for j in range(S):
            ta = j * h
            tb = period if j == S - 1 else (j + 1) * h
            if t_nb >= tb:
                # a whole step
                ta_[n], tb_[n] = ta, tb
                ua_[n], um_[n], ub_[n] = uh[2 * j], uh[2 * j + 1], uh[2 * j + 2]
                if t_nb == tb:
                    boundary[n] = True
                    interval += 1
                    t_nb = ((interval + 1) * q - p) * period
                n += 1
            else:
                # split at each boundary inside the step
                t = ta
                u_t = uh[2 * j]
                while t < tb:
                    t1 = t_nb if t_nb < tb else tb
                    if t1 < t:
                        t1 = t
                    u_1 = uh[2 * j + 2] if t1 == tb else U0 * math.cos(omega * t1)
                    ta_[n], tb_[n] = t, t1
                    ua_[n], um_[n], ub_[n] = u_t, U0 * math.cos(omega * 0.5 * (t + t1)), u_1
                    if t_nb <= t1:
                        boundary[n] = True
                        interval += 1
                        t_nb = ((interval + 1) * q - p) * period
                    n += 1
                    t = t1
                    u_t = u_1
    start[P] = n
    return start, ta_[:n], tb_[:n], ua_[:n], um_[:n], ub_[:n], boundary[:n]


@njit(parallel=True, fastmath=False)
def simulate_events(R, W, M, S, m, k, c, U0, omega, a, b, cs, d, N0, sig_mu, sig_N,
                    tau_s, x_init, v_init, seed):
    """R realisations x (W warm-up + M measured) periods at S steps/period.
    Returns (peaks[R, M], stuck time in the measured periods [R] in s)."""
    period = TAU / omega
    P = (k, c, 1.0 / m, b, cs, d)
    noisy = sig_mu != 0.0 or sig_N != 0.0
    # the segment grid and the base displacement on it are the same for every
    # realisation: computed once, so that no cos is evaluated between events
    start, ta_, tb_, ua_, um_, ub_, boundary = segment_table(W, M, S, U0, omega, tau_s, noisy)
    peaks = np.empty((R, M))
    stuck_time = np.zeros(R)
    for r in prange(R):
        key = path_key(seed, r)
        interval = 0
        mu0, N, F_s = _noise(key, 0, noisy, a, b, sig_mu, N0, sig_N)
        x = x_init
        v = v_init
        if v > 0.0:
            mode = 1.0
        elif v < 0.0:
            mode = -1.0
        else:
            mode = _stick_or_slip(x, U0, F_s, k)
        st = 0.0
        for p in range(W + M):
            pk = x
            measuring = p >= W
            for i in range(start[p], start[p + 1]):
                x, v, mode, pk, s = _advance(ta_[i], tb_[i], ua_[i], um_[i], ub_[i],
                                             x, v, mode, pk, P, mu0, N, F_s, U0, omega, period)
                if measuring:
                    st += s
                if boundary[i]:
                    interval += 1
                    mu0, N, F_s = _noise(key, interval, noisy, a, b, sig_mu, N0, sig_N)
            if measuring:
                peaks[r, p - W] = pk
        stuck_time[r] = st
    return peaks, stuck_time
