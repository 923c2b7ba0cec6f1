"""The compiled loops of the wind: the synthesis' phasors and coherence recursion, the
fluctuating drag loads, the analytic downburst field and the frequency-domain check's coherence
quadrature (Numba functions at module level, re-exported by :mod:`linecheck.core._loops`; what
they compute and how they are checked: :mod:`linecheck.core.kernel`)."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["coherent_spectrum", "drag_loads", "field_radius", "field_velocity", "mix_wires", "phasors", "quad_kms"]

@numba.njit(cache=True, nogil=True)
def phasors(phases, xr, xi):  # pragma: no cover - compiled
    """The unit phasors exp(i phi) = cos phi + i sin phi of the wind synthesis (glibc's cexp at a
    zero real part, as numpy's complex exp): xr = cos, xi = sin, each (n_nodes, n_freq)."""
    n_nodes, n_freq = phases.shape
    for j in range(n_nodes):
        for k in range(n_freq):
            p = phases[j, k]
            xr[j, k] = np.cos(p)
            xi[j, k] = np.sin(p)


@numba.njit(cache=True, nogil=True)
def coherent_spectrum(xr_, xi_, rho_rows, s_rows, row_of_gap, amp, scale, spec):  # pragma: no cover - compiled
    """The wind synthesis' spectrum of ordered nodes in one pass: from the unit phasors
    xi = exp(i phi) (:func:`phasors`: xr_ + i xi_), the Markov (equal gaps: KMS) recursion
    y_0 = xi_0, y_j = rho y_(j-1) + s xi_j along the nodes with the coefficient row of gap j - 1,
    and spec[j, k + 1] = scale (amp_k y_jk), as numpy's form (turbulence.synthesize): a real
    times a complex as numpy forms it (the real cast to complex: (a x_r - 0 x_i, a x_i + 0 x_r)).
    xr_, xi_ (n_nodes, n_freq); rho_rows, s_rows (n_rows, n_freq); row_of_gap (n_nodes - 1,);
    amp (n_freq,); spec (n_nodes, >= n_freq + 1) complex, zero outside columns 1 .. n_freq."""
    n_nodes, n_freq = xr_.shape
    pr = np.empty(n_freq)
    pi = np.empty(n_freq)
    for j in range(n_nodes):
        g = row_of_gap[j - 1] if j > 0 else 0
        for k in range(n_freq):
            xr = xr_[j, k]
            xi = xi_[j, k]
            if j == 0:
                yr = xr
                yi = xi
            else:
                r = rho_rows[g, k]
                w = s_rows[g, k]
                yr = (r * pr[k] - 0.0 * pi[k]) + (w * xr - 0.0 * xi)
                yi = (r * pi[k] + 0.0 * pr[k]) + (w * xi + 0.0 * xr)
            pr[k] = yr
            pi[k] = yi
            a = amp[k]
            zr = a * yr - 0.0 * yi
            zi = a * yi + 0.0 * yr
            spec[j, k + 1] = complex(scale * zr - 0.0 * zi, scale * zi + 0.0 * zr)


@numba.njit(cache=True, nogil=True)
def mix_wires(spec, low, k0):  # pragma: no cover - compiled
    """The many-wire synthesis' mixing across wires (wires.mix_wires_numpy), in place and in one
    pass over the spectra: spec (n_p, n_nodes, n_bins) complex, the points' single-wire spectra;
    low (n_p, n_p, n_freq) the lower factor L_w per frequency; for bins k0 .. k0 + n_freq - 1 and
    every point p >= 1, spec[p] = sum_(q <= p) L_w[p, q] spec[q] of the raw spectra, the real and
    imaginary parts each summed from 0 over q in order, every product rounded by itself (no fused
    multiply-add), as the numpy form's acc += L_w[p, q] spec[q]."""
    n_p, n_nodes = spec.shape[0], spec.shape[1]
    n_freq = low.shape[2]
    vr = np.empty(n_p)
    vi = np.empty(n_p)
    for j in range(n_nodes):
        for k in range(n_freq):
            for q in range(n_p):
                z = spec[q, j, k0 + k]
                vr[q] = z.real
                vi[q] = z.imag
            for p in range(1, n_p):
                ar = 0.0
                ai = 0.0
                for q in range(p + 1):
                    c = low[p, q, k]
                    ar += c * vr[q]
                    ai += c * vi[q]
                spec[p, j, k0 + k] = complex(ar, ai)


@numba.njit(cache=True, nogil=True)
def drag_loads(pv, pq, s2, v, s0, quad, loads):  # pragma: no cover - compiled
    """The fluctuating drag on the free nodes (service.fluctuating_loads), as the numpy form:
    loads[t, i, f] = pv[t, f] v[i, t, s0 + f] (paper Eq. 5), plus ((v^2 - s2) pq) with the
    quadratic drag, each product and sum rounded by itself.  pv, pq, s2 (n_steps,
    n_free); v (n_real, n_steps, n_nodes), the free nodes s0 .. s0 + n_free - 1; loads
    (n_steps, n_real, n_free)."""
    n_real, n_steps = v.shape[0], v.shape[1]
    n_free = loads.shape[2]
    for t in range(n_steps):
        for i in range(n_real):
            for f in range(n_free):
                x = v[i, t, s0 + f]
                val = pv[t, f] * x
                if quad:
                    val = val + ((x * x - s2[t, f]) * pq[t, f])
                loads[t, i, f] = val


@numba.njit(cache=True, nogil=True)
def field_radius(x, cx, cy, r_max, decay, r, z):  # pragma: no cover - compiled
    """First pass of DownburstField.velocity (Holmes & Oliver 2000): per instant
    t and line point x, r = hypot(x - cx, 0 - cy) and the Gaussian's exponent
    z = -(((r - r_max)/decay)^2) (numpy then takes exp(z) on the whole array, as it does now).
    x (n_x,); cx, cy (n_t,); r, z (n_t, n_x)."""
    for t in range(cx.size):
        dy = 0.0 - cy[t]
        for i in range(x.size):
            dx = x[i] - cx[t]
            rr = np.hypot(dx, dy)
            r[t, i] = rr
            q = (rr - r_max) / decay
            z[t, i] = -(q * q)


@numba.njit(cache=True, nogil=True)
def field_velocity(x, cx, cy, r, e, r_max, fz, pi, v_max, tx, ty, vx, vy):  # pragma: no cover - compiled
    """Second pass: f_r = r/r_max inside r_max else e (= exp(z)), speed = v_max ((f_r f_z) Pi(t)),
    v = speed d/r + translation (0 + translation at r = 0)."""
    for t in range(cx.size):
        dy = 0.0 - cy[t]
        p = pi[t]
        for i in range(x.size):
            rr = r[t, i]
            fr = rr / r_max if rr <= r_max else e[t, i]
            speed = v_max * ((fr * fz) * p)
            if rr > 0.0:
                dx = x[i] - cx[t]
                vx[t, i] = (speed * dx) / rr + tx
                vy[t, i] = (speed * dy) / rr + ty
            else:
                vx[t, i] = 0.0 + tx
                vy[t, i] = 0.0 + ty


@numba.njit(cache=True, nogil=True)
def quad_kms(w, rho, gap, out):  # pragma: no cover - compiled
    """spectral._quad_kms_nodes in one pass: w (K, N, F) complex, rho (F,) (``gap`` False)
    or per gap (N - 1, F); out (K, F) = sum_i |w_i|^2 (summed over the nodes one after the other,
    as numpy reduces a non-contiguous axis) + 2 sum_j Re(conj(w_j) h_j), h_j = (h_{j-1} + w_{j-1})
    rho_j, the complex-times-real product written as numpy forms it, (a c - b 0, a 0 + b c)."""
    K, N, F = w.shape
    hr = np.empty(F)
    hi = np.empty(F)
    cr = np.empty(F)
    for k in range(K):
        for f in range(F):
            x = w[k, 0, f]
            out[k, f] = x.real * x.real + x.imag * x.imag
        for j in range(1, N):
            for f in range(F):
                x = w[k, j, f]
                out[k, f] += x.real * x.real + x.imag * x.imag
        hr[:] = 0.0
        hi[:] = 0.0
        cr[:] = 0.0
        for j in range(1, N):
            g = j - 1 if gap else 0
            for f in range(F):
                y = w[k, j - 1, f]
                a = hr[f] + y.real
                b = hi[f] + y.imag
                c = rho[g, f]
                hr[f] = a * c - b * 0.0
                hi[f] = a * 0.0 + b * c
                x = w[k, j, f]
                cr[f] += x.real * hr[f] + x.imag * hi[f]
        for f in range(F):
            out[k, f] = out[k, f] + 2.0 * cr[f]
