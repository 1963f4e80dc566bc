#!/usr/bin/env python3
"""Reference LQG gains for tests/quad-sim/tests/control_reference_dare.rs.

Independent of the Rust code: the ZOH matrices come from scipy.linalg.expm of the augmented
continuous model (flight/flight-core/src/control/LQG.md §1), the gains from scipy.linalg.solve_discrete_are, each
refined by Newton-free fixed-point polishing and checked by its Riccati residual.
Run:  python3 dare_reference.py > dare_reference.json   (numpy + scipy)
"""
import json
import math

import numpy as np
from scipy.linalg import expm, solve_discrete_are


def zoh(ac, bc, ts):
    n = ac.shape[0]
    m = np.zeros((n + 1, n + 1))
    m[:n, :n] = ac
    m[:n, n] = bc
    e = expm(m * ts)
    return e[:n, :n], e[:n, n]


def estimator_model(b1, b2, tau, ts):
    # x = (omega, nu, bias); u enters as (u - bias)
    ac = np.array([[0.0, b1 - b2, -b2], [0.0, -1.0 / tau, -1.0 / tau], [0.0, 0.0, 0.0]])
    bc = np.array([b2, 1.0 / tau, 0.0])
    return zoh(ac, bc, ts)


def lqr_model(b1, b2, tau, ts):
    # x = (theta, omega, nu)
    ac = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, b1 - b2], [0.0, 0.0, -1.0 / tau]])
    bc = np.array([0.0, b2, 1.0 / tau])
    return zoh(ac, bc, ts)


def polish(a, b, q, r, x):
    """A few Riccati fixed-point sweeps from scipy's answer (converged, so they only remove
    round-off), then the relative residual."""
    for _ in range(3):
        s = r + b @ x @ b
        axb = a.T @ x @ b
        x = a.T @ x @ a - np.outer(axb, axb) / s + q
        x = 0.5 * (x + x.T)
    s = r + b @ x @ b
    axb = a.T @ x @ b
    res = np.linalg.norm(a.T @ x @ a - np.outer(axb, axb) / s + q - x) / np.linalg.norm(x)
    return x, res


def kalman(b1, b2, tau, ts, kf):
    a, _ = estimator_model(b1, b2, tau, ts)
    q = np.diag(kf[:3])
    r = kf[3]
    c = np.array([1.0, 0.0, 0.0])
    p = solve_discrete_are(a.T, c.reshape(3, 1), q, np.array([[r]]))
    p, res = polish(a.T, c, q, r, p)
    return list(p[:, 0] / (p[0, 0] + r)), res


def lqr(a, b, q):
    x = solve_discrete_are(a, b.reshape(-1, 1), q, np.array([[1.0]]))
    x, res = polish(a, b, q, 1.0, x)
    k = (b @ x @ a) / (1.0 + b @ x @ b)
    return list(k), res


def main():
    kf_sets = {"taulabs": [1.0, 1e-5, 1e-7, 1000.0], "dronin": [1.0, 3e-6, 1e-6, 25.0]}
    cost_sets = {  # (angle, rate, torque or None, q4 or None)
        "taulabs": (4.0, 0.04, 10000.0, None),
        "invariant": (0.05, 0.02, None, 0.05),
    }
    cases = []
    worst = 0.0
    for ln_b in [7.0, 8.5, 10.0, 11.0, 12.0]:
        for tau in [0.010, 0.020, 0.040, 0.080]:
            for ts in [1 / 400, 1 / 1000, 1 / 2000, 1 / 8000]:
                for ln_b2 in [None, 6.0]:
                    if ln_b2 is not None and (ln_b not in (7.0, 10.0)):
                        continue
                    # f32-representable inputs, as the Rust side takes f32 parameters
                    lb = float(np.float32(ln_b))
                    tf = float(np.float32(tau))
                    b1 = math.exp(lb)
                    b2 = 0.0 if ln_b2 is None else math.exp(float(np.float32(ln_b2)))
                    case = {"ln_beta1": ln_b, "ln_beta2": ln_b2, "tau": tau, "ts": ts, "kalman": {}, "rate": {}, "attitude": {}}
                    for name, kf in kf_sets.items():
                        k, res = kalman(b1, b2, tf, ts, kf)
                        worst = max(worst, res)
                        case["kalman"][name] = k
                    a, b = lqr_model(b1, b2, tf, ts)
                    for name, (qa, qr, qt, q4) in cost_sets.items():
                        q3 = qt if qt is not None else q4 * b1
                        k2, res2 = lqr(a[1:, 1:], b[1:], np.diag([qr, q3]))
                        k3, res3 = lqr(a, b, np.diag([qa, qr, q3]))
                        worst = max(worst, res2, res3)
                        case["rate"][name] = k2
                        case["attitude"][name] = k3
                    cases.append(case)
    out = {
        "generator": "tests/quad-sim/reference/dare_reference.py (scipy expm + solve_discrete_are)",
        "kf_sets": kf_sets,
        "cost_sets": {k: {"q_angle": v[0], "q_rate": v[1], "q_torque": v[2], "q4": v[3]} for k, v in cost_sets.items()},
        "worst_relative_residual": worst,
        "cases": cases,
    }
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
