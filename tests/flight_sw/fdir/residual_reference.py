"""The residual FDIR's window residual and hypothesis test in numpy (the textbook form).

The reference :mod:`flight_sw.fdir.residual_kernel` is checked against: the array
expressions of :mod:`flight_sw.fdir.residual_model` and :mod:`flight_sw.fdir.rate_residual`
as they were before the float kernel (matrix products, broadcasting, one window at a
time, nothing cached per sample).
"""

from __future__ import annotations

import numpy as np


def window_residual(ang: np.ndarray, lin: np.ndarray, j: np.ndarray, tau_s: np.ndarray,
                    edges: np.ndarray, w_a: np.ndarray, w_b: np.ndarray, span_s: float,
                    fs: np.ndarray, frac: np.ndarray, rate: np.ndarray, bias: np.ndarray,
                    dt: float, noise: list[float]) -> dict[str, np.ndarray]:
    """z, h_ang, h_lin, u_s, w_lin, 1/σ², mean linear residual of one window."""
    gyro_noise, model_rel, thrust_rel, edge_s, accel_noise, accel_bias = noise
    n = tau_s.size
    w_bar = 0.5 * (w_a + w_b)
    dw_pred = ang @ tau_s - np.linalg.inv(j) @ np.cross(w_bar, j @ w_bar) * span_s
    var_ang = (2.0 * gyro_noise**2 + (model_rel * dw_pred) ** 2
               + thrust_rel**2 * ((ang * tau_s) ** 2).sum(axis=1) + edge_s**2 * (ang**2 @ edges))
    sig_ang = np.sqrt(var_ang)
    z = np.zeros(6)
    z[:3] = ((w_b - w_a) - dw_pred) / sig_ang
    out = {"h_ang": ang / sig_ang[:, None], "h_lin": np.zeros((3, n)), "u_s": np.zeros(n),
           "w_lin": np.zeros((0, 3)), "inv_var": np.zeros((0, 3)), "mean": None}
    s_count = fs.shape[0]
    if s_count >= 2:
        f_pred = frac @ lin.T
        r_s = (fs - bias) - f_pred
        var_s = (accel_noise**2 + accel_bias**2 + (model_rel * f_pred) ** 2
                 + thrust_rel**2 * ((frac**2) @ (lin.T**2)) + edge_s**2 * ((rate**2) @ (lin.T**2)))
        u_s = frac.sum(axis=0) * dt
        sig_lin = np.sqrt(s_count * (accel_noise * dt) ** 2 + (accel_bias * span_s) ** 2
                          + (model_rel * (lin @ u_s)) ** 2
                          + thrust_rel**2 * ((lin * u_s) ** 2).sum(axis=1)
                          + (edge_s * dt) ** 2 * ((rate @ lin.T) ** 2).sum(axis=0))
        z[3:] = r_s.sum(axis=0) * dt / sig_lin
        out.update(h_lin=lin / sig_lin[:, None], u_s=u_s, w_lin=r_s / var_s, inv_var=1.0 / var_s,
                   mean=fs.mean(axis=0) - f_pred.mean(axis=0))
    out["z"] = z
    return out


def hypotheses(z: np.ndarray, h_ang: np.ndarray, h_lin: np.ndarray, tau_cmd_s: np.ndarray,
               span_s: float, u_s: np.ndarray, frac: np.ndarray, stuck: np.ndarray,
               w_lin: np.ndarray, inv_var: np.ndarray, lin: np.ndarray, known: np.ndarray,
               beta_max: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(gain, β, window signatures 6×2n) per hypothesis: closed 0..n−1, open n..2n−1."""
    n = tau_cmd_s.size
    frac_cmd = frac.copy()
    frac_cmd[:, stuck] = 0.0
    wl = w_lin @ lin
    ivl = inv_var @ lin**2
    g_c = -h_ang * tau_cmd_s
    g_o = h_ang * np.maximum(span_s - tau_cmd_s, 0.0)
    hz = np.concatenate((z[:3] @ g_c - (wl * frac_cmd).sum(axis=0),
                         z[:3] @ g_o + (wl * (1.0 - frac_cmd)).sum(axis=0)))
    hh = np.concatenate(((g_c**2).sum(axis=0) + (ivl * frac_cmd**2).sum(axis=0),
                         (g_o**2).sum(axis=0) + (ivl * (1.0 - frac_cmd) ** 2).sum(axis=0)))
    beta = np.clip(np.divide(hz, hh, out=np.zeros_like(hz), where=hh > 0.0), 0.0, beta_max)
    gain = 2.0 * beta * hz - beta**2 * hh
    gain[np.concatenate((known, known))] = -np.inf
    sig = np.zeros((6, 2 * n))
    sig[:3, :n], sig[:3, n:] = g_c, g_o
    sig[3:, :n] = -h_lin * np.where(stuck, 0.0, u_s)
    sig[3:, n:] = h_lin * np.maximum(frac.shape[0] * dt - u_s, 0.0)
    return gain, beta, sig
