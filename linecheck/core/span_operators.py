"""Span load operators of paper Appendix A: exact linear maps from the nodal load intensities
of a span (piecewise linear on ``ne`` equal elements of a unit span) to its end reactions,
shear at Gauss points and bending moments at the nodes, which step 1 (core/static.py) scales
by the span length.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

GAUSS_T, GAUSS_W = np.polynomial.legendre.leggauss(3)  # exact for degree 5


@dataclass(frozen=True)
class SpanOperators:
    """Linear maps from nodal load intensities g_k (piecewise linear on a unit span) to
    the beam quantities of paper Appendix A (simply supported span of length 1).

    a_left, a_right: (ne+1,) end reactions v_A = int g (1-s) ds, v_B = int g s ds.
    shear_gp: (n_gp, ne+1) shear Q(s) = v_A - int_0^s g at Gauss points; w_gp (n_gp,) weights.
    moment_nodes: (ne+1, ne+1) bending moment M(s_k) = int_0^s Q at the nodes.
    """

    a_left: np.ndarray
    a_right: np.ndarray
    shear_gp: np.ndarray
    w_gp: np.ndarray
    moment_nodes: np.ndarray


@lru_cache(maxsize=32)
def span_operators(ne: int) -> SpanOperators:
    """Exact integration operators for piecewise-linear loads on ``ne`` equal elements."""
    h = 1.0 / ne
    n = ne + 1
    eye = np.eye(n)
    # cumulative integral of g at the nodes: C_k = sum_{i<k} h (g_i + g_{i+1}) / 2 (trapezoid exact)
    cum_nodes = np.zeros((n, n))
    cum_nodes[1:] = np.cumsum(0.5 * h * (eye[:-1] + eye[1:]), axis=0)
    # end reactions for piecewise-linear g (exact): int_e g (1-s) ds and int_e g s ds per element
    t, w = GAUSS_T, GAUSS_W
    tt = 0.5 * (t + 1.0)  # local coordinate in [0, 1]
    ww = 0.5 * w * h
    s_gp = (np.arange(ne)[:, None] + tt[None, :]) * h  # (ne, 3)
    # g at gauss points: g_e (1-t) + g_{e+1} t  -> (ne, 3, n)
    g_gp = (1 - tt)[None, :, None] * eye[:-1][:, None, :] + tt[None, :, None] * eye[1:][:, None, :]
    a_left = np.einsum("eg,egk->k", ww[None, :] * (1.0 - s_gp), g_gp)
    a_right = np.einsum("eg,egk->k", ww[None, :] * s_gp, g_gp)
    # int_0^s g at gauss points: C_e + h (g_e t + (g_{e+1} - g_e) t^2 / 2)
    cum_gp = (
        cum_nodes[:-1][:, None, :]
        + h * (eye[:-1][:, None, :] * (tt - 0.5 * tt**2)[None, :, None] + eye[1:][:, None, :] * (0.5 * tt**2)[None, :, None])
    )
    shear_gp = (a_left[None, None, :] - cum_gp).reshape(ne * 3, n)
    w_gp = np.tile(ww, ne)
    # moment at nodes M(s_k) = int_0^{s_k} Q ds; Q is quadratic per element -> Simpson is exact
    q_nodes = a_left[None, :] - cum_nodes  # (n, n)
    cum_mid = cum_nodes[:-1] + h * (eye[:-1] * (0.5 - 0.125) + eye[1:] * 0.125)  # int_0^{s_e + h/2} g
    q_mid = a_left[None, :] - cum_mid
    incr = h / 6.0 * (q_nodes[:-1] + 4.0 * q_mid + q_nodes[1:])
    moment_nodes = np.zeros((n, n))
    moment_nodes[1:] = np.cumsum(incr, axis=0)
    return SpanOperators(a_left, a_right, shear_gp, w_gp, moment_nodes)
