"""Per-cycle arithmetic of the acceleration-residual FDIR on Python floats (compiled with mypyc).

What it does: the window residual of :mod:`flight_sw.fdir.residual_model` and the
hypothesis test of :mod:`flight_sw.fdir.rate_residual`, written out for their sizes (3
axes, n ≤ 16 thrusters, ~10 accelerometer samples, 2n hypotheses), where numpy's
per-call overhead was most of a cycle (~190 µs of the 16-thruster cycle's ~330 µs) and
its small products went through the CPU's BLAS kernel, whose summation order depends on
the CPU. Every sum here runs in one fixed order (index order), so the bits depend on IEEE
double arithmetic only.

- :func:`sample_terms`: what one accelerometer sample contributes to every window holding
  it (predicted specific force, residual variance, thrust-rate term), computed once per
  sample instead of once per window (a window holds ~50 samples and moves by 2);
- :func:`window_residual`: ``z``, the scaled regressors and the per-sample weights of one
  window (the equations of :mod:`flight_sw.fdir.residual_model`'s docstring);
- :func:`hypotheses`: per hypothesis (closed 0..n−1, open n..2n−1) the clipped least-
  squares amplitude β and the likelihood gain ``2β·hz − β²·hh`` (module docstring of
  :mod:`flight_sw.fdir.rate_residual`);
- :func:`signature`: one hypothesis's window signature (6 numbers), for the "explains
  the residual" test.

In and out: plain lists, matrices as lists of rows: ``ang`` [rad/s²] and ``lin`` [m/s²]
(3×n, per thruster at full thrust), rates [rad/s], specific forces [m/s²], times [s].
Assumptions: finite inputs, positive variances (the noise parameters are validated > 0).
Sources: those of :mod:`flight_sw.fdir.rate_residual` (Gertler 1998; Willsky & Jones 1976).
"""

from __future__ import annotations

import math

N_AXES = 3
Vector = list[float]
Matrix = list[list[float]]


def _dot3(m_row: Vector, v: Vector) -> float:
    return m_row[0] * v[0] + m_row[1] * v[1] + m_row[2] * v[2]


def _net_and_squares(row: Vector, x: Vector) -> tuple[float, float]:
    """``(Σ_k row_k x_k, Σ_k (row_k x_k)²)``: a net prediction and its per-thruster spread."""
    net = 0.0
    squares = 0.0
    for k in range(len(x)):
        t = row[k] * x[k]
        net += t
        squares += t * t
    return net, squares


def _angular(ang: Matrix, j: Matrix, j_inv: Matrix, tau_s: Vector, edges: Vector,
             w_a: Vector, w_b: Vector, span_s: float, noise: Vector
             ) -> tuple[Vector, Vector]:
    """(z_ang, σ_ang): the angular channel (residual_model docstring)."""
    gyro_noise, model_rel, thrust_rel, edge_s = noise[0], noise[1], noise[2], noise[3]
    n = len(tau_s)
    w_bar = [0.5 * (w_a[0] + w_b[0]), 0.5 * (w_a[1] + w_b[1]), 0.5 * (w_a[2] + w_b[2])]
    jw = [_dot3(j[0], w_bar), _dot3(j[1], w_bar), _dot3(j[2], w_bar)]
    c = [w_bar[1] * jw[2] - w_bar[2] * jw[1], w_bar[2] * jw[0] - w_bar[0] * jw[2],
         w_bar[0] * jw[1] - w_bar[1] * jw[0]]
    z = [0.0, 0.0, 0.0]
    sig = [0.0, 0.0, 0.0]
    for i in range(N_AXES):
        a_i = ang[i]
        pred, contrib_sq = _net_and_squares(a_i, tau_s)
        edge_sq = 0.0
        for k in range(n):
            edge_sq += a_i[k] * a_i[k] * edges[k]
        pred -= _dot3(j_inv[i], c) * span_s
        var = (2.0 * gyro_noise * gyro_noise + (model_rel * pred) ** 2
               + thrust_rel * thrust_rel * contrib_sq + edge_s * edge_s * edge_sq)
        sig[i] = math.sqrt(var)
        z[i] = ((w_b[i] - w_a[i]) - pred) / sig[i]
    return z, sig


def sample_terms(f: Vector, frac: Vector, rate: Vector, lin: Matrix, noise: Vector
                 ) -> tuple[Vector, Vector]:
    """What one accelerometer sample contributes to every window holding it, computed once:
    ``([f_pred (3), 1/σ² (3), Σ_k rate_k lin_ik (3)], ivl)`` with ``ivl_k = Σ_i lin_ik²/σ_i²``.

    ``f``: the sample [m/s²]; ``frac``, ``rate``: the modelled thrust fraction F/T_max and
    |dF/dt|/T_max [1/s] per thruster at its time; σ_i² the variance of its residual.
    """
    model_rel, thrust_rel, edge_s = noise[1], noise[2], noise[3]
    accel_noise, accel_bias = noise[4], noise[5]
    n = len(frac)
    base_var = accel_noise * accel_noise + accel_bias * accel_bias
    terms = [0.0] * 9
    for i in range(N_AXES):
        l_i = lin[i]
        pred = 0.0
        frac_sq = 0.0
        rate_sq = 0.0
        rate_sum = 0.0
        for k in range(n):
            lk = l_i[k]
            lk_sq = lk * lk
            pred += frac[k] * lk
            frac_sq += frac[k] * frac[k] * lk_sq
            rate_sq += rate[k] * rate[k] * lk_sq
            rate_sum += rate[k] * lk
        var = (base_var + (model_rel * pred) ** 2 + thrust_rel * thrust_rel * frac_sq
               + edge_s * edge_s * rate_sq)
        terms[i] = pred
        terms[N_AXES + i] = 1.0 / var
        terms[2 * N_AXES + i] = rate_sum
    ivl = [terms[3] * (lin[0][k] * lin[0][k]) + terms[4] * (lin[1][k] * lin[1][k])
           + terms[5] * (lin[2][k] * lin[2][k]) for k in range(n)]
    return terms, ivl


def window_residual(ang: Matrix, lin: Matrix, j: Matrix, j_inv: Matrix, tau_s: Vector,
                    edges: Vector, w_a: Vector, w_b: Vector, span_s: float, f: Matrix,
                    terms: Matrix, frac: Matrix, bias: Vector, dt_s: float, noise: Vector
                    ) -> tuple[Vector, Matrix, Matrix, Vector, Matrix, Vector | None]:
    """``(z, h_ang, h_lin, u_s, w_lin, mean_linear_residual)`` of a window.

    ``f``, ``terms``, ``frac``: the accelerometer samples inside it (specific force, their
    :func:`sample_terms`, thrust fractions); fewer than two: no linear channel (zeros,
    and None for the mean residual). ``noise``: gyro σ [rad/s], model and thrust
    relative errors, edge timing σ [s], accelerometer noise and bias σ [m/s²].
    """
    n = len(tau_s)
    z_ang, sig_ang = _angular(ang, j, j_inv, tau_s, edges, w_a, w_b, span_s, noise)
    model_rel, thrust_rel, edge_s = noise[1], noise[2], noise[3]
    accel_noise, accel_bias = noise[4], noise[5]
    h_ang = [[ang[i][k] / sig_ang[i] for k in range(n)] for i in range(N_AXES)]
    s_count = len(f) if len(f) >= 2 else 0
    z = z_ang + [0.0, 0.0, 0.0]
    if s_count == 0:
        return (z, h_ang, [[0.0] * n for _ in range(N_AXES)], [0.0] * n, [], None)
    w_lin: Matrix = []
    r_sum = [0.0, 0.0, 0.0]
    f_sum = [0.0, 0.0, 0.0]
    pred_sum = [0.0, 0.0, 0.0]
    rate_lin_sq = [0.0, 0.0, 0.0]  # Σ_samples (Σ_k rate lin_ik)²
    for s in range(s_count):
        f_s, t_s = f[s], terms[s]
        w_row = [0.0, 0.0, 0.0]
        for i in range(N_AXES):
            pred = t_s[i]
            r = (f_s[i] - bias[i]) - pred
            w_row[i] = r * t_s[N_AXES + i]
            r_sum[i] += r
            f_sum[i] += f_s[i]
            pred_sum[i] += pred
            rate_sum = t_s[2 * N_AXES + i]
            rate_lin_sq[i] += rate_sum * rate_sum
        w_lin.append(w_row)
    u_s = [0.0] * n
    for k in range(n):  # thruster outer, sample inner: a float local, no list write per term
        acc = 0.0
        for fr in frac:
            acc += fr[k]
        u_s[k] = acc * dt_s
    h_lin: Matrix = []
    for i in range(N_AXES):
        l_i = lin[i]
        net, each_sq = _net_and_squares(l_i, u_s)
        sig = math.sqrt(s_count * (accel_noise * dt_s) ** 2 + (accel_bias * span_s) ** 2
                        + (model_rel * net) ** 2 + thrust_rel * thrust_rel * each_sq
                        + (edge_s * dt_s) ** 2 * rate_lin_sq[i])
        z[N_AXES + i] = r_sum[i] * dt_s / sig
        h_lin.append([l_i[k] / sig for k in range(n)])
    mean = [f_sum[i] / s_count - pred_sum[i] / s_count for i in range(N_AXES)]
    return z, h_ang, h_lin, u_s, w_lin, mean


def hypotheses(z: Vector, h_ang: Matrix, tau_cmd_s: Vector, span_s: float, frac: Matrix,
               stuck: list[bool], w_lin: Matrix, ivl: Matrix, lin: Matrix,
               known: list[bool], beta_max: float) -> tuple[Vector, Vector]:
    """(gain, β) per hypothesis: closed 0..n−1, open n..2n−1 (known failures: −inf);
    ``ivl``: the samples' :func:`sample_terms` second part."""
    n = len(tau_cmd_s)
    hz = [0.0] * (2 * n)  # angular window part, then the samples' part added as one sum
    hh = [0.0] * (2 * n)
    for k in range(n):
        closed = -tau_cmd_s[k]
        opened = span_s - tau_cmd_s[k]
        if opened < 0.0:
            opened = 0.0
        for i in range(N_AXES):
            gc = h_ang[i][k] * closed
            go = h_ang[i][k] * opened
            hz[k] += z[i] * gc
            hz[n + k] += z[i] * go
            hh[k] += gc * gc
            hh[n + k] += go * go
    samples = len(frac)
    for k in range(n):  # thruster outer, sample inner: float locals, no list write per term
        l0, l1, l2 = lin[0][k], lin[1][k], lin[2][k]
        is_stuck = stuck[k]
        szc = szo = shc = sho = 0.0
        for s in range(samples):
            wl_s = w_lin[s]
            wl = wl_s[0] * l0 + wl_s[1] * l1 + wl_s[2] * l2
            ivl_sk = ivl[s][k]
            fc = 0.0 if is_stuck else frac[s][k]
            fo = 1.0 - fc
            szc += wl * fc
            szo += wl * fo
            shc += ivl_sk * (fc * fc)
            sho += ivl_sk * (fo * fo)
        hz[k] -= szc
        hz[n + k] += szo
        hh[k] += shc
        hh[n + k] += sho
    gain = [0.0] * (2 * n)
    beta = [0.0] * (2 * n)
    for h in range(2 * n):
        b = hz[h] / hh[h] if hh[h] > 0.0 else 0.0
        b = min(max(b, 0.0), beta_max)
        beta[h] = b
        gain[h] = -math.inf if known[h % n] else 2.0 * b * hz[h] - b * b * hh[h]
    return gain, beta


def signature(h: int, h_ang: Matrix, h_lin: Matrix, tau_cmd_s: Vector, span_s: float,
              u_s: Vector, stuck: list[bool], s_count: int, dt_s: float) -> Vector:
    """Hypothesis ``h``'s window signature: the change of z per unit β (6 numbers)."""
    n = len(tau_cmd_s)
    k = h % n
    if h < n:
        a = -tau_cmd_s[k]
        b = -(0.0 if stuck[k] else u_s[k])
    else:
        a = max(span_s - tau_cmd_s[k], 0.0)
        b = max(s_count * dt_s - u_s[k], 0.0)
    return [h_ang[0][k] * a, h_ang[1][k] * a, h_ang[2][k] * a,
            h_lin[0][k] * b, h_lin[1][k] * b, h_lin[2][k] * b]
