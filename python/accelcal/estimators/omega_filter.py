"""The fused omega's per-sample step (float reference), in the scalar form a firmware port
follows: an iterated EKF on omega whose prediction integrates alpha (trapezoid) and whose
measurement is the concentrated likelihood ``q = m p(omega) + v`` (cov m) of
:func:`accelcal.model.centripetal_split`.

Per sample n, with the state (x, P) of sample n-1:

1. alpha[n] = lin_alpha[n] - leak_alpha p(w0) (its centripetal term at the first guess
   w0 = x + dt (alpha[n-1] + lin_alpha[n] - leak_alpha p(x)) / 2);
   prediction w = x + dt (alpha[n-1] + alpha[n]) / 2, P = F P F^T + Q with
   F = I - dt leak_alpha J(x) (an error in omega moves the alpha it integrates: where the
   layout's leak is large and |omega| high, the integration alone is unstable);
2. start: w, or the ML estimate with the sign nearer w where it lowers the posterior cost
   (w - x)^T P^-1 (w - x) + p^T m p - 2 q^T p by more than ``jump`` (chi^2 units: at rest the
   ML estimate of noise fits it by about chi^2(6), and a jump to it would be a jump to noise;
   a recording that starts turning, or a lost branch, gains orders of magnitude more; the
   prior is then centred on the ML estimate, its width kept);
3. ``iterations`` Gauss-Newton steps on that cost (H = P^-1 + J^T m J, J = dp/domega);
4. P = (P^-1 + J^T m J)^-1 at the result; alpha[n] again with the new omega.

A 3 x 3 symmetric matrix is kept as its six entries (00, 01, 02, 11, 12, 22).
"""
from __future__ import annotations

import numpy as np

__all__ = ["fuse", "JUMP_CHI2"]

#: what a start at the ML estimate must save over the prediction (chi^2 units; P(chi^2(6) > 50) ~ 1e-8)
JUMP_CHI2 = 50.0


def _inv(a):
    """Inverse of a symmetric 3 x 3 (six entries) by its adjugate."""
    a00, a01, a02, a11, a12, a22 = a
    c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
    det = a00 * c00 + a01 * c01 + a02 * c02
    return ((c00 / det, c01 / det, c02 / det, (a00 * a22 - a02 * a02) / det, (a01 * a02 - a00 * a12) / det,
             (a00 * a11 - a01 * a01) / det))


def _mul(a, v):
    """Symmetric 3 x 3 (six entries) times a 3-vector."""
    return (a[0] * v[0] + a[1] * v[1] + a[2] * v[2], a[1] * v[0] + a[3] * v[1] + a[4] * v[2],
            a[2] * v[0] + a[4] * v[1] + a[5] * v[2])


def _products(x):
    a, b, c = x
    return (a * a, b * b, c * c, a * b, b * c, c * a)


def _columns(x):
    """The three columns of J = dp/domega at x (each a 6-vector)."""
    a, b, c = x
    return ((2 * a, 0.0, 0.0, b, 0.0, c), (0.0, 2 * b, 0.0, a, c, 0.0), (0.0, 0.0, 2 * c, 0.0, b, a))


def _dot(u, v):
    """6-vectors."""
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2] + u[3] * v[3] + u[4] * v[4] + u[5] * v[5]


def _dot3(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _info(m, cols):
    """J^T m J (six entries) and m J's columns."""
    mj = [tuple(_dot(row, col) for row in m) for col in cols]
    return (_dot(cols[0], mj[0]), _dot(cols[0], mj[1]), _dot(cols[0], mj[2]), _dot(cols[1], mj[1]),
            _dot(cols[1], mj[2]), _dot(cols[2], mj[2]))


def _propagate(P, la, cols, dt, Qs):
    """F P F^T + Q (six entries) with F = I - dt leak_alpha J, J's columns ``cols``."""
    F = [[(1.0 if i == j else 0.0) - dt * _dot(la[i], cols[j]) for j in range(3)] for i in range(3)]
    FP = [_mul(P, F[i]) for i in range(3)]          # row i of F P (P symmetric)
    return tuple(_dot3(FP[i], F[j]) + Qs[k] for k, (i, j) in enumerate(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2),
                                                                     (2, 2))))


def _cost(x, w, lam, q, m):
    p = _products(x)
    d = (x[0] - w[0], x[1] - w[1], x[2] - w[2])
    mp = [_dot(row, p) for row in m]
    return _dot3(d, _mul(lam, d)) + _dot(p, [s - 2.0 * t for s, t in zip(mp, q)])


def fuse(q, lin_alpha, leak_alpha, Q, m, w_ml, dt: float, x0, P0, iterations: int = 2, jump: float = JUMP_CHI2,
         margins: list | None = None, state: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Run the step over every sample (or, with ``state``, over a chunk of them, carried on).

    Parameters
    ----------
    q : array_like (n, 6)
        The centripetal readings per sample.
    lin_alpha : array_like (n, 3)
        rad/s^2: alpha before its centripetal correction.
    leak_alpha : array_like (3, 6)
    Q : array_like (3, 3)
        (rad/s)^2 per step.
    m : array_like (6, 6)
    w_ml : array_like (n, 3)
        rad/s: the per-sample ML estimate (either sign).
    dt : float
        s.
    x0 : array_like (3,)
        rad/s at the first sample; ``P0`` (3, 3) its covariance.
    iterations : int
    jump : float
        The cost a start at the ML estimate must save (chi^2 units).
    margins : list, optional
        Appended per sample: cost(ML) - (cost(prediction) - jump), the jump test's margin
        (negative: the start moved to the ML estimate).
    state : dict, optional
        The filter's state after the last sample (x, P and the alpha it integrates), kept in it
        and taken from it: run on the next chunk of samples with the same dict, the step goes on
        from there (``x0``, ``P0`` then unused), the numbers those of one run over all of them.

    Returns
    -------
    w : ndarray (n, 3)
        rad/s.
    cov : ndarray (n, 3, 3)
        (rad/s)^2.
    """
    m = np.asarray(m, float).tolist()
    la = np.asarray(leak_alpha, float).tolist()
    Qs = np.asarray(Q, float)[[0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]].tolist()
    carried = state is not None and "x" in state
    if carried:
        x, P, a_prev = state["x"], state["P"], state["a"]
    else:
        P = tuple(np.asarray(P0, float)[[0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]].tolist())
        x = tuple(float(v) for v in x0)
    h = 0.5 * dt
    qs, als, mls = np.asarray(q, float).tolist(), np.asarray(lin_alpha, float).tolist(), np.asarray(w_ml, float).tolist()
    n = len(qs)
    w = np.empty((n, 3))
    cov = np.empty((n, 6))

    def alpha(k, x):
        p = _products(x)
        return [als[k][i] - _dot(la[i], p) for i in range(3)]

    if not carried:
        a_prev = alpha(0, x) if n else None
    for k in range(n):
        qk = qs[k]
        if k or carried:
            a = alpha(k, x)
            P = _propagate(P, la, _columns(x), dt, Qs)
            # alpha[n]'s centripetal term at the predicted omega[n] (at omega[n-1] it lags a step,
            # and the lag's error dt/2 leak dp adds up over a turn)
            a = alpha(k, tuple(x[i] + h * (a_prev[i] + a[i]) for i in range(3)))
            x = tuple(x[i] + h * (a_prev[i] + a[i]) for i in range(3))
        wp = x
        lam = _inv(P)
        c = mls[k]
        if _dot3(c, wp) < 0.0:
            c = (-c[0], -c[1], -c[2])
        margin = _cost(c, wp, lam, qk, m) - (_cost(wp, wp, lam, qk, m) - jump)
        if margins is not None:
            margins.append(margin)
        if margin < 0.0:
            x = wp = tuple(c)      # the prediction is refuted: its width kept, centred on the ML
        for _ in range(iterations):
            cols = _columns(x)
            info = _info(m, cols)
            p = _products(x)
            r = [t - _dot(row, p) for t, row in zip(qk, m)]
            g = _mul(lam, (wp[0] - x[0], wp[1] - x[1], wp[2] - x[2]))
            g = tuple(g[i] + _dot(cols[i], r) for i in range(3))
            step = _mul(_inv(tuple(lam[i] + info[i] for i in range(6))), g)
            x = (x[0] + step[0], x[1] + step[1], x[2] + step[2])
        info = _info(m, _columns(x))
        P = _inv(tuple(lam[i] + info[i] for i in range(6)))
        w[k] = x
        cov[k] = P
        a_prev = alpha(k, x)
    if state is not None and (carried or n):
        state.update(x=x, P=P, a=a_prev)
    full = cov[:, [0, 1, 2, 1, 3, 4, 2, 4, 5]].reshape(n, 3, 3)
    return w, full
