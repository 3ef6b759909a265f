"""Small non-linear least squares: Levenberg-Marquardt for smooth residual functions.

``levenberg_marquardt(fun, x0)`` minimises ``0.5 * sum(fun(x) ** 2)`` over a handful of unknowns
(the trilateration of Eq. 10, the planar pose of a marker). It is the trust-region form of the
Levenberg-Marquardt method (K. Levenberg, 1944; D. W. Marquardt, 1963) as MINPACK's ``lmder``
implements it (J. J. Moré, "The Levenberg-Marquardt algorithm: implementation and theory",
Numerical Analysis, Lecture Notes in Mathematics 630, 1978): a step solves the damped problem
``min |J p + f|^2 + par |D p|^2`` with ``par`` chosen so that the step stays within a trust radius
``|D p| <= delta`` (Moré's safeguarded Newton iteration on ``par``, ``lmpar``, with numpy's least
squares and QR in place of MINPACK's pivoted QR), and the radius grows or shrinks with the ratio
of the actual to the predicted reduction. The stopping tests, the update of the radius, the scaling
``D`` (the Jacobian's column norms, never decreasing) and the defaults (``ftol = xtol = gtol =
1e-8``, at most ``100 n`` evaluations) are MINPACK's, so the answers are those of SciPy's
``least_squares(method="lm")`` (which calls MINPACK) up to float rounding.

Unlike MINPACK, fewer residuals than unknowns are allowed: the damped step is still defined
(the Gauss-Newton step is the minimum-norm one), and the solver ends on one of the minimisers.
The Jacobian is numeric (forward differences with SciPy's step ``sqrt(eps) max(1, |x_j|)``, or
central differences) unless an analytic one is given.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

__all__ = ["LeastSquaresResult", "levenberg_marquardt"]

EPS = float(np.finfo(float).eps)
TINY = float(np.finfo(float).tiny)  # MINPACK's dwarf

Residuals = Callable[..., Any]  # fun(x, *args) -> (m,) residuals
Jacobian = Callable[..., Any]  # jac(x, *args) -> (m, n) d residuals / d x

STATUS_MESSAGES = {
    0: "the maximum number of function evaluations is exceeded",
    1: "gtol: the gradient is orthogonal to the residuals",
    2: "ftol: the relative reduction of the sum of squares is small",
    3: "xtol: the relative step is small",
    4: "ftol and xtol are both satisfied",
}


@dataclass(frozen=True)
class LeastSquaresResult:
    """The answer, with SciPy's field names: ``x``, the residuals ``fun`` at ``x``, ``cost`` =
    0.5 |fun|^2, the Jacobian ``jac`` at the last accepted iterate, the number of residual
    evaluations ``nfev`` (those for numeric Jacobians not counted, as MINPACK counts them) and of
    Jacobians ``njev``, and ``status`` (0: too many evaluations, 1: gtol, 2: ftol, 3: xtol, 4: ftol
    and xtol; as ``scipy.optimize.least_squares``)."""

    x: np.ndarray
    fun: np.ndarray
    cost: float
    jac: np.ndarray
    nfev: int
    njev: int
    status: int

    @property
    def success(self) -> bool:
        return self.status > 0

    @property
    def message(self) -> str:
        return STATUS_MESSAGES[self.status]


def _numeric_jacobian(
    fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray, f0: np.ndarray, method: str
) -> np.ndarray:
    """Finite-difference Jacobian with SciPy's steps: ``h_j = r sign(x_j) max(1, |x_j|)``, ``r`` =
    sqrt(eps) (forward) or eps^(1/3) (central), ``sign(0)`` = +1, and the step actually taken."""
    sign = np.where(x >= 0, 1.0, -1.0)
    rel = EPS**0.5 if method == "forward" else EPS ** (1.0 / 3.0)
    h = rel * sign * np.maximum(1.0, np.abs(x))
    jac = np.empty((f0.size, x.size))
    for j in range(x.size):
        up = x.copy()
        up[j] += h[j]
        dx = up[j] - x[j]
        if method == "forward":
            jac[:, j] = (fun(up) - f0) / dx
        else:
            down = x.copy()
            down[j] -= h[j]
            jac[:, j] = (fun(up) - fun(down)) / (up[j] - down[j])
    return jac


def _jacobian_function(
    jac: Jacobian | str, residuals: Callable[[np.ndarray], np.ndarray], args: tuple[Any, ...]
) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """``J(x, f(x))``: the analytic ``jac(x, *args)`` or finite differences of ``residuals``."""
    if callable(jac):
        analytic = jac
        return lambda v, fv: np.asarray(analytic(v, *args), dtype=float).reshape(fv.size, v.size)
    if jac not in ("forward", "central"):
        raise ValueError(f"jac must be callable, 'forward' or 'central', not {jac!r}")
    method = jac
    return lambda v, fv: _numeric_jacobian(residuals, v, fv, method)


def _damped_step(
    jac: np.ndarray, diag: np.ndarray, f: np.ndarray, delta: float, par: float
) -> tuple[np.ndarray, float]:
    """Moré's ``lmpar`` (MINPACK): ``par >= 0`` and the step ``p`` minimising
    ``|J p + f|^2 + par |D p|^2`` such that either ``par = 0`` and ``|D p| <= 1.1 delta`` (the
    Gauss-Newton step fits) or ``| |D p| - delta | <= 0.1 delta``, by a safeguarded Newton
    iteration on ``par`` from its last value (at most 10 steps). MINPACK's pivoted QR factors are
    replaced by numpy's least squares and QR; the Gauss-Newton step of a rank-deficient ``J`` is
    the minimum-norm one."""
    m, n = jac.shape
    x, _, rank, _ = np.linalg.lstsq(jac, f, rcond=None)  # the step is -x
    dx = diag * x
    dxnorm = float(np.linalg.norm(dx))
    fp = dxnorm - delta
    if fp <= 0.1 * delta:
        return -x, 0.0
    parl = 0.0  # a lower bound on par: the Newton step at par = 0
    if rank == n:
        r0 = np.linalg.qr(jac).R
        y = np.linalg.solve(r0.T, diag * (dx / dxnorm))
        parl = fp / delta / float(y @ y)
    gnorm = float(np.linalg.norm((jac.T @ f) / diag))
    paru = gnorm / delta  # an upper bound
    if paru == 0.0:
        paru = TINY / min(delta, 0.1)
    par = min(max(par, parl), paru)
    if par == 0.0:
        par = gnorm / dxnorm
    rhs = np.concatenate([f, np.zeros(n)])
    for it in range(1, 11):
        if par == 0.0:
            par = max(TINY, 0.001 * paru)
        q, r = np.linalg.qr(np.vstack([jac, math.sqrt(par) * np.diag(diag)]))
        x = np.linalg.solve(r, q.T @ rhs)
        dx = diag * x
        dxnorm = float(np.linalg.norm(dx))
        previous, fp = fp, dxnorm - delta
        if abs(fp) <= 0.1 * delta or (parl == 0.0 and previous < 0.0 and fp <= previous) or it == 10:
            break
        y = np.linalg.solve(r.T, diag * (dx / dxnorm))
        correction = fp / delta / float(y @ y)  # Newton's step on 1 / |D p(par)| = 1 / delta
        if fp > 0.0:
            parl = max(parl, par)
        elif fp < 0.0:
            paru = min(paru, par)
        par = max(parl, par + correction)
    return -x, par


def _max_cosine(jac: np.ndarray, f: np.ndarray, fnorm: float, col_norms: np.ndarray) -> float:
    """The largest |cosine| between the residual vector and a (non-zero) Jacobian column."""
    if fnorm == 0.0:
        return 0.0
    nonzero = col_norms > 0.0
    cosines = np.abs(jac.T @ f)[nonzero] / (fnorm * col_norms[nonzero])
    return float(cosines.max()) if cosines.size else 0.0


def _new_radius(
    ratio: float, actred: float, dirder: float, shrunk: bool, delta: float, pnorm: float, par: float
) -> tuple[float, float]:
    """MINPACK's update of the trust radius and of ``par`` from the reduction ``ratio``; ``shrunk``:
    the new norm of the residuals is at least 10 times the old one."""
    if ratio <= 0.25:
        temp = 0.5 if actred >= 0.0 else 0.5 * dirder / (dirder + 0.5 * actred)
        if shrunk or temp < 0.1:
            temp = 0.1
        return temp * min(delta, pnorm / 0.1), par / temp
    if par == 0.0 or ratio >= 0.75:
        return pnorm / 0.5, 0.5 * par
    return delta, par


def _reductions(
    jp: np.ndarray, fnorm: float, fnorm_trial: float, par: float, pnorm: float
) -> tuple[float, float, float]:
    """The actual and the predicted relative reductions of the sum of squares by the step ``p``
    (``jp`` = J p), and the directional derivative, as MINPACK scales them."""
    actred = 1.0 - (fnorm_trial / fnorm) ** 2 if 0.1 * fnorm_trial < fnorm else -1.0
    t1 = float(np.linalg.norm(jp)) / fnorm
    t2 = math.sqrt(par) * pnorm / fnorm
    return actred, t1 * t1 + t2 * t2 / 0.5, -(t1 * t1 + t2 * t2)


def _status(small_f: bool, small_x: bool, out_of_evaluations: bool) -> int:
    """The status after a trial step: 2 (ftol), 3 (xtol), 4 (both), 0 (out of evaluations), -1: go on."""
    if small_f or small_x:
        return 4 if small_f and small_x else 2 if small_f else 3
    return 0 if out_of_evaluations else -1


def _scaling(x_scale: np.ndarray | float | str, n: int) -> tuple[np.ndarray, bool]:
    """The initial ``D`` and whether it follows the Jacobian's column norms."""
    if isinstance(x_scale, str):
        if x_scale != "jac":
            raise ValueError(f"x_scale must be 'jac' or positive numbers, not {x_scale!r}")
        return np.ones(n), True
    return 1.0 / np.broadcast_to(np.asarray(x_scale, dtype=float), (n,)), False


def levenberg_marquardt(
    fun: Residuals,
    x0: np.ndarray,
    jac: Jacobian | Literal["forward", "central"] = "forward",
    *,
    args: tuple[Any, ...] = (),
    ftol: float = 1e-8,
    xtol: float = 1e-8,
    gtol: float = 1e-8,
    max_nfev: int | None = None,
    x_scale: np.ndarray | float | Literal["jac"] = "jac",
    factor: float = 100.0,
) -> LeastSquaresResult:
    """Minimise ``0.5 * sum(fun(x, *args) ** 2)`` from ``x0`` (Levenberg-Marquardt, MINPACK's
    ``lmder``; see the module docstring).

    ``jac``: a callable ``jac(x, *args) -> (m, n)``, or ``"forward"`` / ``"central"`` differences.
    Stops when the predicted and the actual relative reductions of the sum of squares are at most
    ``ftol`` (status 2), when the trust radius is at most ``xtol`` times the scaled norm of ``x``
    (status 3; 4 for both), when the cosine between the residuals and every Jacobian column is at
    most ``gtol`` (status 1), or after ``max_nfev`` evaluations of ``fun`` (status 0; default
    ``100 n``, as SciPy's ``least_squares(method="lm")``). Tolerances below the machine epsilon
    act as the machine epsilon. ``x_scale``: the characteristic scale of each unknown, or ``"jac"``
    for the Jacobian's column norms (MINPACK's ``mode = 1``, SciPy's default for ``"lm"``);
    ``factor``: the initial trust radius is ``factor |x0 / x_scale|`` (or ``factor`` if that is 0).
    """
    x = np.array(x0, dtype=float).reshape(-1)
    n = x.size
    ftol, xtol, gtol = max(ftol, EPS), max(xtol, EPS), max(gtol, EPS)

    def residuals(v: np.ndarray) -> np.ndarray:
        return np.atleast_1d(np.asarray(fun(v, *args), dtype=float))

    jacobian = _jacobian_function(jac, residuals, args)
    f = residuals(x)
    if not np.all(np.isfinite(f)):
        raise ValueError("the residuals are not finite at x0")
    max_nfev = 100 * n if max_nfev is None else max_nfev
    nfev, njev = 1, 0
    fnorm = float(np.linalg.norm(f))
    diag, scale_by_jac = _scaling(x_scale, n)
    par, delta, xnorm = 0.0, 0.0, 0.0
    first = True
    status = -1
    while status < 0:
        j = jacobian(x, f)
        njev += 1
        col_norms = np.linalg.norm(j, axis=0)
        if first:
            if scale_by_jac:
                diag = np.where(col_norms == 0.0, 1.0, col_norms)
            xnorm = float(np.linalg.norm(diag * x))
            delta = factor * xnorm if xnorm > 0.0 else factor
        if _max_cosine(j, f, fnorm, col_norms) <= gtol:
            status = 1
            break
        if scale_by_jac:
            diag = np.maximum(diag, col_norms)
        while True:  # until a step reduces the sum of squares enough (or a stopping test)
            p, par = _damped_step(j, diag, f, delta, par)
            pnorm = float(np.linalg.norm(diag * p))
            if first:
                delta = min(delta, pnorm)
            f_trial = residuals(x + p)
            nfev += 1
            fnorm_trial = float(np.linalg.norm(f_trial)) if np.all(np.isfinite(f_trial)) else math.inf
            actred, prered, dirder = _reductions(j @ p, fnorm, fnorm_trial, par, pnorm)
            ratio = actred / prered if prered != 0.0 else 0.0
            shrunk = 0.1 * fnorm_trial >= fnorm
            delta, par = _new_radius(ratio, actred, dirder, shrunk, delta, pnorm, par)
            accepted = ratio >= 1e-4
            if accepted:
                x, f, fnorm = x + p, f_trial, fnorm_trial
                xnorm = float(np.linalg.norm(diag * x))
                first = False
            small_f = abs(actred) <= ftol and prered <= ftol and 0.5 * ratio <= 1.0
            status = _status(small_f, delta <= xtol * xnorm, nfev >= max_nfev)
            if status >= 0 or accepted:
                break
    j = jacobian(x, f)
    njev += 1
    return LeastSquaresResult(x, f, 0.5 * float(f @ f), j, nfev, njev, status)
