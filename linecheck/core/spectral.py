"""Frequency-domain check of synoptic cases: estimate 1, exact linear random vibration.

Exact linear random vibration of the same linearised model as the time domain (step-1
mean state K, lumped M, the case's damping C):

    S_r(n) = S_v(n) * w(n)^H Coh(n) w(n),   w_i = t_i(n) a_i,

with a_i = rho C_d D L_i V_i the load per unit turbulence at node i (paper Eq. 5),
S_v the von Karman spectrum, Coh_ij = exp(-C n |x_i - x_j| / V) (Davenport 1961) and
t_i(n) the reaction per unit load at node i:

    t_F(n) = G H(w) P + D,  H(w) = (K - w^2 M + i w C)^-1   (total fluctuating)
    t_B    = G K^-1 P + D                                   (quasi-static background)
    t_R    = t_F - t_B                                       (resonant, R = F - B)

(G, D: reaction maps of :mod:`linecheck.core.model`; P: y-DOF loading), evaluated by
complex modal superposition (:class:`ModalTransfer`, over the modes of
:mod:`linecheck.core.complex_modes`) or, for large systems and as the cross-check, by direct
block-tridiagonal solves (:func:`dynamic_solve`).  The variances integrate S_r over the band
that the time-domain synthesis contains (1/T_record .. 1/(2 dt)), on a logarithmic grid refined
around every lightly damped complex pole (tan-spaced points, exact for Lorentzian peaks).
Expected peaks use Davenport's (1964) peak factor g = sqrt(2 ln nu T) + 0.5772 / sqrt(2 ln nu T),
nu = sqrt(m2/m0) from the spectral moments of the response.

Estimate 2, the closed-form Davenport / Castanheta gust response factor, is
:mod:`linecheck.core.gust_factor`; this module re-exports it, the spectrum, the peak factor
and the complex modes for its callers.  Formulas and sources are collected in docs/method.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack, solve_banded

from .complex_modes import LARGE_SYSTEM_DOF as LARGE_SYSTEM_DOF
from .complex_modes import ComplexModes as ComplexModes
from .complex_modes import StateEigen as StateEigen
from .complex_modes import complex_modes as complex_modes
from .errors import NumericalError
from .gust_factor import EULER_GAMMA as EULER_GAMMA
from .gust_factor import DavenportEstimate as DavenportEstimate
from .gust_factor import davenport_gust_factor as davenport_gust_factor
from .gust_factor import joint_acceptance_uniform as joint_acceptance_uniform
from .gust_factor import peak_factor as peak_factor
from .gust_factor import von_karman as von_karman
from .model import BANDWIDTH, LinearModel, band_blocks, blocks_to_band, reaction_matrix_direct
from .wind.turbulence import von_karman_cumulative

GRID_SIGNIFICANCE = 1e-3  # direct path: refine poles whose single-mode r.m.s. exceeds this x the background's
EXCLUSION_RATIO = 1e3  # a coarse point may over-count an unrefined pole by at most this x its own variance


def frequency_grid(f_lo: float, f_hi: float, modes: ComplexModes, *, n_log: int = 300, n_peak: int = 17,
                   n_tail: int = 12, zeta_resolved: float = 0.05, refine: np.ndarray | None = None) -> np.ndarray:
    """Integration grid [Hz]: log-spaced plus points around every lightly damped pole.

    Around a pole of half-power half-width b = zeta f: the core f + b tan(theta), theta
    uniform in (-1.45, 1.45) (the tan substitution makes a Lorentzian peak constant in
    theta), and geometric tails f +- b 10^(1 .. 4).  Without the tails the trapezoid rule
    bridges a very narrow peak's flanks with one chord and overestimates them badly (the
    paper-damping modes have b ~ 1e-8 f, far below the log grid's 3 % spacing).

    ``refine`` (bool per mode, default all): poles left unrefined (modes that do not matter
    at the tower of interest, :func:`modal_contributions`) get an exclusion zone instead: a
    grid point at kappa half-widths from a Lorentzian peak of width b, on a panel of width
    Delta, over-counts that mode's variance by about Delta / (pi b kappa^2), so points closer
    than kappa = sqrt(Delta / (pi b) / EXCLUSION_RATIO) half-widths are dropped (the
    trapezoid then bridges the peak and under-counts an insignificant mode instead).
    """
    parts = [np.geomspace(f_lo, f_hi, n_log)]
    spacing = (f_hi / f_lo) ** (1.0 / (n_log - 1)) - 1.0  # relative spacing of the log grid
    core = np.tan(np.linspace(-1.45, 1.45, n_peak))  # |tan| <= 8.2
    tail = np.geomspace(10.0, 1e4, n_tail)
    offsets = np.concatenate([-tail[::-1], core, tail])
    excluded = []
    for k, (f, z) in enumerate(zip(modes.frequencies_hz, modes.damping_ratio)):
        if f_lo < f < f_hi and z < zeta_resolved:
            b = max(z * f, 1e-12 * f)
            if refine is None or refine[k]:
                parts.append(f + b * offsets)
            else:
                ratio = spacing * f / (np.pi * b)
                if ratio > EXCLUSION_RATIO:
                    excluded.append((f, b * np.sqrt(ratio / EXCLUSION_RATIO)))
    grid = np.unique(np.concatenate(parts))
    for f, r in excluded:
        grid = grid[np.abs(grid - f) >= r]
    return grid[(grid >= f_lo) & (grid <= f_hi)]


def _general_band(ab_upper: np.ndarray) -> np.ndarray:
    """Symmetric upper band storage (u+1, n) -> general band storage (2u+1, n) for solve_banded."""
    u, n = ab_upper.shape[0] - 1, ab_upper.shape[1]
    out = np.zeros((2 * u + 1, n), dtype=ab_upper.dtype)
    out[: u + 1] = ab_upper
    for k in range(1, u + 1):
        # lower diagonal k: A[j+k, j] = A[j, j+k] = ab_upper[u - k, j + k]
        out[u + k, : n - k] = ab_upper[u - k, k:]
    return out


def _quad_kms(w: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """w^H Coh w for Coh_ij = rho^|i-j| (equally spaced nodes), O(N) per frequency.

    Args: w (n_f, ..., N) complex; rho (n_f,) in [0, 1), or per gap (n_f, N-1) for unequally
        spaced points (Markov coherence Coh_ij = prod of the gaps' rho between i and j,
        the section form).  Returns (n_f, ...) real.
    """
    gap = rho.ndim == 2
    shape = (-1,) + (1,) * (w.ndim - 2)
    r = rho.reshape(shape) if not gap else None
    h = np.zeros(w.shape[:-1], dtype=complex)
    total = np.sum(np.abs(w) ** 2, axis=-1)
    cross = np.zeros(w.shape[:-1])
    for j in range(1, w.shape[-1]):
        rj = r if not gap else rho[:, j - 1].reshape(shape)
        h = rj * (h + w[..., j - 1])  # h_j = sum_{i<j} rho^(j-i) w_i
        cross += np.real(np.conj(w[..., j]) * h)
    return total + 2.0 * cross


def markov_rho(system, f: np.ndarray, coherence_decay: float, v_mean: float) -> np.ndarray:
    """Davenport coherence of neighbouring FE nodes, exp(-C f dx / V) (Davenport 1961).

    Equally spaced nodes (the equal-span form): shape (n_f,) with dx the element length
    (Kac-Murdock-Szego coherence).  A section: per gap, shape (n_f, n_nodes - 1), dx the plan
    distance between neighbouring still-air nodes (:attr:`LineSystem.node_gaps`); the
    coherence of non-neighbours is then the product along the line (Markov), as in the
    turbulence synthesis (docs/wind.md, "Sections")."""
    if not system.is_section:
        dx = system.uniform_element_length
        return np.exp(-coherence_decay * f * dx / v_mean)
    return np.exp(-coherence_decay * f[:, None] * system.node_gaps[None, :] / v_mean)


def tower_rows(model: LinearModel, A: np.ndarray, tower: int) -> np.ndarray:
    """The three reaction rows of ``tower`` of A (3 n_towers, ...) in the tower's own frame
    (x along its mean heading, y turned +90 deg, z down; a straight line: as is)."""
    rows = A[3 * tower:3 * tower + 3]
    system = model.system
    if system.straight_in_plan:
        return rows
    psi = system.tower_headings[tower]
    Q = np.array([[np.cos(psi), np.sin(psi), 0.0], [-np.sin(psi), np.cos(psi), 0.0], [0.0, 0.0, 1.0]])
    return np.tensordot(Q, rows, axes=1)


def load_rows(model: LinearModel, A: np.ndarray) -> np.ndarray:
    """Rows of a DOF array A (n_dof, ...) taken along every free node's transverse load
    direction -> (n_free, ...): the y rows on a straight line, sum_c b_c A[3i + c] on a section."""
    free = model.dofs.free_nodes
    ydof = model.dofs.node_dof[free] + 1
    system = model.system
    dirs = model.load_directions  # the cross-flow form's directions, else the node normals
    if dirs is None and system.straight_in_plan:
        return A[ydof]
    b = (system.node_normals if dirs is None else dirs)[free]
    first = model.dofs.node_dof[free]
    return sum(b[:, c].reshape((-1,) + (1,) * (A.ndim - 1)) * A[first + c] for c in range(3))


MODAL_CONDITION_LIMIT = 1e8  # eigenvalue condition number above which the modal sum is not trusted
MODAL_CHECK_RTOL = 1e-7  # modal vs direct transfer at the check frequencies


class ModalTransfer:
    """Reaction transfer functions by complex modal superposition (exact with all modes).

    With the state form of :func:`modal_contributions`, the reactions at one tower per unit
    y-load at free node i are

        T(w) = sum_k A_k / (i w - lambda_k),   A_k = (G S psi_k^u)(chi_k^v,H M*^-1 S^T e_y,i) / (chi_k^H psi_k),

    summed over all 2 n_t eigenvalues (Veletsos & Ventura 1986; Tisseur & Meerbergen
    2001).  A real system's eigenpairs come in conjugate pairs, so each pair contributes

        (i w 2 Re A_k - 2 Re(A_k conj(lambda_k))) / (|lambda_k|^2 - w^2 - 2 i w Re lambda_k),

    and the whole sum is two real matrix products per block of frequencies -- far cheaper
    than solving the dynamic stiffness at every frequency of the pole-refined grid.

    The state form lives in the condensed coordinates (u = S t), which miss the static
    response of the insulator-axial directions to their own load: a load along a rigid
    insulator goes straight into the tower.  That feed-through is frequency independent,
    so it is the difference between the exact static transfer G K^-1 P and the modal sum
    at w = 0, added at every frequency.
    """

    def __init__(self, model: LinearModel, modes: ComplexModes, tower: int, static: np.ndarray):
        """``static``: [-] exact quasi-static transfer G K^-1 P at the free nodes, (3, n_free_nodes)."""
        ex, S = modes.expansion, modes.S
        n_t = S.shape[1]
        free = model.dofs.free_nodes
        G = tower_rows(model, model.G, tower)
        r = G @ (S @ ex.right[:n_t])  # (3, n_e)
        c = ex.left[n_t:].conj().T @ (load_rows(model, S).T / modes.mass[:, None])  # (n_e, n_free)
        A = r.T[:, :, None] * (c / ex.norm[:, None])[:, None, :]  # (n_e, 3, n_free)
        lam = ex.poles
        pair = lam.imag > 0.0
        self.lam_pair, self.lam_real = lam[pair], lam[~pair].real
        Ap = A[pair]
        self.P = (2.0 * Ap.real).reshape(Ap.shape[0], -1)  # (n_p, 3 n_free)
        self.Q = (2.0 * (Ap * lam[pair].conj()[:, None, None]).real).reshape(Ap.shape[0], -1)
        self.R = A[~pair].real.reshape(-1, self.P.shape[1])  # real poles: A_k real
        self.PQT = np.ascontiguousarray(np.concatenate([self.P, self.Q], axis=1).T)  # (2 m, n_p)
        self.shape = (3, free.size)
        self.feedthrough = np.zeros(self.shape)
        self.feedthrough = static - self(np.zeros(1))[..., 0].real

    def __call__(self, omega: np.ndarray) -> np.ndarray:
        """Transfer functions at [rad/s] ``omega`` (n_f,), shape (3, n_free_nodes, n_f)."""
        w = omega[None, :]
        lam = self.lam_pair[:, None]
        a = np.abs(lam) ** 2 - w**2  # D = a + i c = |lambda|^2 - w^2 - 2 i w Re(lambda)
        c = -2.0 * w * lam.real
        den = a * a + c * c
        Yr = self.PQT @ (a / den)  # (2 m, n_f): rows P then Q; 1/D = (a - i c)/den
        Yi = self.PQT @ (-c / den)
        m = self.P.shape[1]
        out = np.empty((m, omega.size), dtype=complex)
        # T = i w (U P) - U Q
        out.real = -w * Yi[:m] - Yr[m:] + self.feedthrough.reshape(-1, 1)
        out.imag = w * Yr[:m] - Yi[m:]
        if self.R.size:
            out += self.R.T @ (1.0 / (1j * w - self.lam_real[:, None]))
        return out.reshape(self.shape + (omega.size,))


def _inv3(A: np.ndarray) -> np.ndarray:
    """Inverses of 3x3 matrices by the adjugate (Cramer), frequency last: shape (3, 3, n)."""
    a = A
    out = np.empty_like(A)
    out[0, 0] = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    out[1, 0] = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    out[2, 0] = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    out[0, 1] = a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]
    out[1, 1] = a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]
    out[2, 1] = a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]
    out[0, 2] = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    out[1, 2] = a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]
    out[2, 2] = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    det = a[0, 0] * out[0, 0] + a[0, 1] * out[1, 0] + a[0, 2] * out[2, 0]
    out /= det
    return out


def _mm(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Products of small matrices stored frequency last: (p, q, n) @ (q, r, n) -> (p, r, n)."""
    out = A[:, 0, None, :] * B[None, 0, :, :]
    for j in range(1, A.shape[1]):
        out += A[:, j, None, :] * B[None, j, :, :]
    return out


BACKWARD_ERROR_TOL = 1e-11  # normwise backward error above which a frequency is re-solved with pivoting


def dynamic_solve(blocks, omega: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """x = (K - w^2 M + i w C)^-1 b at many circular frequencies at once.

    The dynamic stiffness is complex symmetric and block tridiagonal (3x3 node blocks), so
    block Gaussian elimination (the block Thomas algorithm; Golub & Van Loan 2013, section
    4.5.1) runs node by node, vectorised over the frequencies.  It does not pivot between
    nodes, so every solution is checked by its normwise backward error
    ||Z x - b|| / (||Z|| ||x|| + ||b||) (infinity norms; Higham 2002, Thm 7.1); a frequency
    above :data:`BACKWARD_ERROR_TOL` is solved again by LAPACK zgbsv (partial pivoting).

    Args:
        blocks: ``band_blocks`` (D, E) of K [N/m], C [N s/m] and M [kg], in that order.
        omega: [rad/s] circular frequencies, shape (n_f,).
        rhs: right-hand sides by node, shape (n_nodes, 3, n_rhs).

    Returns:
        x, shape (n_nodes, 3, n_rhs, n_f) (frequency last).
    """
    (DK, EK), (DC, EC), (DM, EM) = blocks
    iw, w2 = 1j * omega, omega**2
    n_nodes = DK.shape[0]
    nf = omega.size
    n_rhs = rhs.shape[-1]
    # blocks of Z = K - w^2 M + i w C, frequency last: D_i (3, 3, n_f), E_i = Z[node i, node i+1]
    Dz = DK[..., None] + DC[..., None] * iw - DM[..., None] * w2  # (n_nodes, 3, 3, n_f)
    Ez = EK[..., None] + EC[..., None] * iw - EM[..., None] * w2  # (n_nodes - 1, 3, 3, n_f)
    Et = Ez.transpose(0, 2, 1, 3)
    b = rhs.astype(complex)[..., None]  # (n_nodes, 3, n_rhs, 1)
    Wz = np.empty((n_nodes, 3, 3 + n_rhs, nf), dtype=complex)  # [S_i^-1 E_i | S_i^-1 y_i]
    S, y = Dz[0], np.broadcast_to(b[0], (3, n_rhs, nf))
    for i in range(n_nodes):
        Si = _inv3(S)
        if i + 1 < n_nodes:
            Wz[i] = _mm(Si, np.concatenate([Ez[i], y], axis=1))
            P = _mm(Et[i], Wz[i])
            S = Dz[i + 1] - P[:, :3]
            y = b[i + 1] - P[:, 3:]
        else:
            Wz[i, :, 3:] = _mm(Si, y)
    x = np.empty((n_nodes, 3, n_rhs, nf), dtype=complex)
    x[-1] = Wz[-1, :, 3:]
    for i in range(n_nodes - 2, -1, -1):
        x[i] = Wz[i, :, 3:] - _mm(Wz[i, :, :3], x[i + 1])
    # normwise backward error of one combination of the right-hand sides (cheaper than all)
    c = np.linspace(1.0, 2.0, n_rhs)
    xc = np.einsum("nark,r->nak", x, c)[:, :, None, :]  # (n_nodes, 3, 1, n_f)
    r = np.einsum("narj,r->naj", b, c)[:, :, None, :] - _mm4(Dz, xc)
    r[:-1] -= _mm4(Ez, xc[1:])
    r[1:] -= _mm4(Et, xc[:-1])
    row = np.abs(Dz).sum(axis=2)  # (n_nodes, 3, n_f) row sums of |Z|
    row[:-1] += np.abs(Ez).sum(axis=2)
    row[1:] += np.abs(Et).sum(axis=2)
    eta = np.abs(r).max(axis=(0, 1, 2)) / (row.max(axis=(0, 1)) * np.abs(xc).max(axis=(0, 1, 2))
                                            + np.abs(rhs @ c).max())
    bad = np.flatnonzero(~(eta <= BACKWARD_ERROR_TOL))
    if bad.size:
        x[..., bad] = _banded_solve(blocks, omega[bad], rhs).transpose(1, 2, 3, 0)
    return x


def _mm4(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """:func:`_mm` over a leading node axis: (n, p, q, f) @ (n, q, r, f) -> (n, p, r, f)."""
    out = A[:, :, 0, None, :] * B[:, None, 0, :, :]
    for j in range(1, A.shape[2]):
        out += A[:, :, j, None, :] * B[:, None, j, :, :]
    return out


def _banded_solve(blocks, omega: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """LAPACK zgbsv (partial pivoting) at each frequency: the fallback of :func:`dynamic_solve`."""
    (DK, EK), (DC, EC), (DM, EM) = blocks
    kl = BANDWIDTH
    n_dof = 3 * DK.shape[0]
    parts = []
    for D, E in ((DK, EK), (DC, EC), (DM, EM)):
        g = np.zeros((2 * kl + 1 + kl, n_dof), dtype=complex)
        g[kl:] = _general_band(blocks_to_band(D, E))
        parts.append(g)
    base, cbase, mbase = parts
    b = np.asfortranarray(rhs.reshape(n_dof, -1).astype(complex))
    out = np.empty((omega.size,) + rhs.shape, dtype=complex)
    for k, w in enumerate(omega):
        _, _, x, info = lapack.zgbsv(kl, kl, base + (1j * w) * cbase - w**2 * mbase, b)
        if info != 0:
            raise NumericalError(f"dynamic stiffness singular at {w / (2 * np.pi):.6g} Hz (LAPACK zgbsv info {info})")
        out[k] = x.reshape(rhs.shape)
    return out


def _quad_kms_nodes(w: np.ndarray, rho: np.ndarray, compiled: bool = True) -> np.ndarray:
    """:func:`_quad_kms` with the node axis second to last and frequency last:
    w (..., N, n_f) complex, rho (n_f,) or per gap (N-1, n_f) -> (..., n_f) real (one compiled
    pass with the kernel's piece ``quad``, ``kernel.quad_kms``)."""
    if compiled and w.ndim == 3 and w.shape[1] > 0:
        from . import kernel

        fast = kernel.quad_kms(w, rho)
        if fast is not None:
            return fast
    h = np.zeros(w.shape[:-2] + w.shape[-1:], dtype=complex)
    total = np.sum(w.real**2 + w.imag**2, axis=-2)
    cross = np.zeros(total.shape)
    gap = rho.ndim == 2
    for j in range(1, w.shape[-2]):
        h += w[..., j - 1, :]
        h *= rho if not gap else rho[j - 1]  # h_j = sum_{i<j} rho^(j-i) w_i
        cross += w[..., j, :].real * h.real + w[..., j, :].imag * h.imag
    return total + 2.0 * cross


@dataclass(frozen=True)
class SpectralEstimate:
    """Frequency-domain statistics of the reactions at the tower of interest.

    Every statistic has shape (3,) for (R_x, R_y, R_z); forces [N], frequencies [Hz].
    GF_* are NaN where the mean vanishes (as in the time domain).  The spectra of the
    background and total fluctuating reactions on the integration grid are kept (e.g. to
    simulate Gaussian records with them).
    """

    mean: np.ndarray
    rms_background: np.ndarray
    rms_resonant: np.ndarray
    rms_fluctuating: np.ndarray
    nu_background: np.ndarray
    nu_fluctuating: np.ndarray
    peak_quasi_static: np.ndarray
    peak_dynamic: np.ndarray
    GF_Dy: np.ndarray
    GF_QS: np.ndarray
    Cont_R: np.ndarray
    duration: float
    band: tuple[float, float]
    n_frequencies: int
    method: str = "direct"  # "modal" (complex modal superposition) or "direct" (solves)
    frequencies: np.ndarray | None = None  # [Hz] the integration grid, (n_f,)
    psd_background: np.ndarray | None = None  # [N^2/Hz] one-sided spectra on the grid, (n_f, 3)
    psd_fluctuating: np.ndarray | None = None  # [N^2/Hz] (n_f, 3)


def _background_transfer(model: LinearModel, Gt: np.ndarray, Dt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quasi-static transfer t_B = G K^-1 P + D at one tower (K symmetric: solved with G^T).

    Args: Gt [N/m] the tower's rows of G (3, n_dof); Dt [-] its rows of D (3, n_nodes).
    Returns: x_B = K^-1 G^T [m/N] (n_dof, 3) and t_B [-] (3, n_nodes) complex.
    """
    K_gen = _general_band(model.K_band)
    xB = solve_banded((BANDWIDTH, BANDWIDTH), K_gen, Gt.T)  # (n_dof, 3)
    tB = Dt.astype(complex).copy()
    tB[:, model.dofs.free_nodes] += load_rows(model, xB).T
    return xB, tB


def _direct_transfer(model: LinearModel, damping: np.ndarray, Gt: np.ndarray):
    """Reaction transfer by direct solves: ``omega`` [rad/s] (n_f,) -> (3, n_free_nodes, n_f) complex,
    the tower's reactions per unit load along every free node's load direction."""
    system = model.system
    free = model.dofs.free_nodes
    blocks = [band_blocks(m) for m in (model.K_band, damping, model.M_band)]
    rhs = Gt.T.reshape(-1, 3, 3)  # (n_free_nodes, 3 dofs, 3 reactions): K symmetric, solve with G^T

    def direct(omega: np.ndarray) -> np.ndarray:  # (3, n_free, n_f)
        X = dynamic_solve(blocks, omega, rhs)  # (n_free, 3 dofs, 3 reactions, n_f)
        dirs = model.load_directions  # the cross-flow form's directions, else the node normals
        if dirs is None and system.straight_in_plan:
            return X[:, 1].transpose(1, 0, 2)  # y DOF of every free node
        b = (system.node_normals if dirs is None else dirs)[free]  # along every node's load direction
        return np.einsum("ncrf,nc->rnf", X, b)

    return direct


def _reaction_spectra(model: LinearModel, transfer, Dt: np.ndarray, tB: np.ndarray, load_per_v: np.ndarray,
                      f: np.ndarray, Sv: np.ndarray, rho: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One-sided spectra [N^2/Hz] of the background, total fluctuating and resonant reactions,
    S_r = S_v w^H Coh w with w_i = t_i a_i (module docstring), each (n_f, 3), in blocks of frequencies.

    Args: transfer: omega [rad/s] -> (3, n_free_nodes, n_f); Dt, tB [-] (3, n_nodes); load_per_v
        [N s/m] (n_nodes,); f [Hz] (n_f,); Sv [m^2/s^2/Hz] (n_f,); rho: neighbour coherence (n_f,)
        or per gap (n_f, n_nodes - 1).
    """
    system = model.system
    free = model.dofs.free_nodes
    SB = np.empty((f.size, 3))
    SF = np.empty((f.size, 3))
    SR = np.empty((f.size, 3))
    aT = load_per_v[None, :, None]
    tBaT = (tB * load_per_v[None, :])[..., None]
    chunk = max(64, 60_000 // max(system.n_nodes, 1))  # frequencies per block: memory, cache
    for c0 in range(0, f.size, chunk):
        fc = f[c0:c0 + chunk]
        tF = np.empty((3, system.n_nodes, fc.size), dtype=complex)  # reaction, node, frequency
        tF[:] = Dt[..., None]
        tF[:, free] += transfer(2 * np.pi * fc)
        sl = slice(c0, c0 + fc.size)
        tFa = tF * aT
        q = _quad_kms_nodes(np.concatenate([np.broadcast_to(tBaT, tF.shape), tFa, tFa - tBaT]), rho[sl].T if rho.ndim == 2 else rho[sl])
        SB[sl], SF[sl], SR[sl] = (Sv[sl, None] * q[3 * i:3 * i + 3].T for i in range(3))
    return SB, SF, SR


def _estimate(f: np.ndarray, SB: np.ndarray, SF: np.ndarray, SR: np.ndarray, mean_reaction: np.ndarray,
              duration: float, band: tuple[float, float], zero_mean_tol: float, method: str) -> SpectralEstimate:
    """Spectral moments, Davenport (1964) expected peaks and gust factors from the reaction spectra
    (n_f, 3) on the grid f [Hz] (module docstring); mean_reaction [N] (3,), duration [s]."""

    def integ(y: np.ndarray) -> np.ndarray:
        return np.trapezoid(y, f, axis=0)

    m0B, m0F, m0R = integ(SB), integ(SF), integ(SR)
    nuB = np.sqrt(integ(SB * f[:, None] ** 2) / np.maximum(m0B, 1e-300))
    nuF = np.sqrt(integ(SF * f[:, None] ** 2) / np.maximum(m0F, 1e-300))
    sB, sF, sR = np.sqrt(m0B), np.sqrt(m0F), np.sqrt(m0R)
    mabs = np.abs(mean_reaction)
    pk_qs = mabs + peak_factor(nuB, duration) * sB
    pk_dy = mabs + peak_factor(nuF, duration) * sF
    defined = mabs > zero_mean_tol
    with np.errstate(divide="ignore", invalid="ignore"):
        gf_dy = np.where(defined, pk_dy / mabs, np.nan)
        gf_qs = np.where(defined, pk_qs / mabs, np.nan)
        # Cont_R undefined (NaN, shown "**") where the peak is zero, e.g. turbulence_intensity = 0
        cont_r = np.where(pk_dy > 0, (pk_dy - pk_qs) / np.where(pk_dy > 0, pk_dy, 1.0), np.nan)
    return SpectralEstimate(
        mean=np.asarray(mean_reaction, dtype=float), rms_background=sB, rms_resonant=sR, rms_fluctuating=sF,
        nu_background=nuB, nu_fluctuating=nuF, peak_quasi_static=pk_qs, peak_dynamic=pk_dy,
        GF_Dy=gf_dy, GF_QS=gf_qs, Cont_R=cont_r, duration=duration, band=band, n_frequencies=int(f.size),
        method=method, frequencies=f, psd_background=SB, psd_fluctuating=SF,
    )


def random_vibration(
    model: LinearModel,
    damping: np.ndarray,
    load_per_v: np.ndarray,
    mean_reaction: np.ndarray,
    tower: int,
    *,
    sigma: float,
    length_scale: float,
    v_mean: float,
    coherence_decay: float,
    duration: float,
    band: tuple[float, float],
    zero_mean_tol: float,
    modes: ComplexModes | None = None,
) -> SpectralEstimate:
    """Estimate 1: exact linear random vibration of ``model`` (see module docstring).

    Args:
        model: linear model of the (synoptic) mean state.
        damping: [N s/m] damping matrix in upper band storage, shape (BANDWIDTH + 1, n_dof).
        load_per_v: [N s/m] a_i = rho C_d D L_i V_i at every global node, shape (n_nodes,).
        mean_reaction: [N] wind-induced mean reactions at ``tower``, shape (3,).
        tower: 0-based tower index.
        sigma, length_scale, v_mean, coherence_decay: turbulence (sigma = I V) [m/s], L_u [m],
            V [m/s], C [-].
        duration: [s] record length T for the peak factor.
        band: [Hz] integration band (f_lo, f_hi).
        zero_mean_tol: [N] a mean below this has no gust factor.
        modes: complex modes of the same model and damping (computed if not given); they
            place the refined frequency points.
    """
    system = model.system
    Gt = tower_rows(model, model.G, tower)  # (3, n_dof), in the tower's frame
    Dt = tower_rows(model, reaction_matrix_direct(system, model.load_directions), tower)  # (3, n_nodes)
    xB, tB = _background_transfer(model, Gt, Dt)
    if modes is None:
        modes = complex_modes(model, damping, max_hz=band[1] * 1.5)
    modal_ok = modes.expansion is not None and modes.expansion.condition.max() < MODAL_CONDITION_LIMIT
    refine = None
    if not modal_ok and modes.right is not None:
        # direct solves cost per frequency: refine only the poles that matter at this tower
        mc = modal_contributions(model, modes, load_per_v, tower, sigma=sigma, length_scale=length_scale,
                                 v_mean=v_mean, coherence_decay=coherence_decay, max_hz=np.inf)
        refine = mc.significant(GRID_SIGNIFICANCE)
    f = frequency_grid(band[0], band[1], modes, refine=refine)
    # the synthesis scales the spectrum to unit variance below its top frequency
    # (linecheck.core.wind.turbulence.spectral_grid); do the same here
    Sv = von_karman(f, sigma, length_scale, v_mean) / float(von_karman_cumulative(band[1], length_scale, v_mean))
    rho = markov_rho(system, f, coherence_decay, v_mean)  # Davenport coherence between neighbours
    direct = _direct_transfer(model, damping, Gt)
    transfer, method = direct, "direct"
    if modal_ok:
        modal = ModalTransfer(model, modes, tower, load_rows(model, xB).T)
        check = 2 * np.pi * f[:: max(1, f.size // 40)]
        ref = direct(check)
        if np.abs(modal(check) - ref).max() <= MODAL_CHECK_RTOL * np.abs(ref).max():
            transfer, method = modal, "modal"
    SB, SF, SR = _reaction_spectra(model, transfer, Dt, tB, load_per_v, f, Sv, rho)
    return _estimate(f, SB, SF, SR, mean_reaction, duration, band, zero_mean_tol, method)


# --------------------------------------------------------------------------- modal significance
@dataclass(frozen=True)
class ModalContribution:
    """Resonant contribution of every damped (complex) mode to the reactions at one tower.

    Attributes:
        frequencies_hz: [Hz] |lambda_k| / 2 pi, (n_modes,); damping_ratio: [-] -Re(lambda)/|lambda|;
        decay_rate: [1/s] -Re(lambda_k) (a transient decays as exp(-rate t));
        rms: [N] single-mode resonant r.m.s. contribution to (R_x, R_y, R_z), shape (n_modes, 3);
        rms_background: [N] background r.m.s. of (R_x, R_y, R_z), shape (3,).
    """

    frequencies_hz: np.ndarray
    damping_ratio: np.ndarray
    decay_rate: np.ndarray
    rms: np.ndarray
    rms_background: np.ndarray

    def significant(self, fraction: float = 0.01) -> np.ndarray:
        """Modes whose contribution exceeds ``fraction`` of the largest background r.m.s., (n_modes,) bool."""
        scale = float(np.max(self.rms_background))
        return self.rms.max(axis=1) > fraction * scale


def modal_contributions(
    model: LinearModel,
    modes: ComplexModes,
    load_per_v: np.ndarray,
    tower: int,
    *,
    sigma: float,
    length_scale: float,
    v_mean: float,
    coherence_decay: float,
    max_hz: float = 2.0,
) -> ModalContribution:
    """Single-mode estimate of every complex mode's stationary resonant contribution.

    State form x' = A x + b, x = (u, u'), A = [[0, I], [-M^-1 K, -M^-1 C]], b = (0, M^-1 f).
    With right/left eigenvectors psi_k, chi_k the response is
    x(w) = sum_k psi_k chi_k^H b / ((chi_k^H psi_k)(i w - lambda_k)); treating the load
    spectrum as locally white, int_0^inf df / |i 2 pi f - lambda|^2 = 1/(2 |Re lambda|), so

        sigma_r,k^2 = |G psi_k^u|^2 S_v(f_k) (c_k^H Coh c_k) / (|chi_k^H psi_k|^2 2 |Re lambda_k|),
        c_k,i = conj(chi_k^(M^-1 f_y,i)) a_i.

    A mode that neither moves transversely nor is damped transversely is still finite
    (its excitation and its damping vanish together), which is why near-degenerate,
    almost undamped modes can matter however small their damping.

    Args:
        modes: complex modes of ``model`` with its damping, computed with ``vectors=True``.
    """
    if modes.right is None or modes.left is None or modes.S is None or modes.norm is None:
        raise ValueError("modal_contributions needs complex modes computed with vectors=True")
    system = model.system
    S = modes.S
    sel = modes.frequencies_hz <= max_hz
    lam, vl, vr = modes.poles[sel], modes.left[:, sel], modes.right[:, sel]
    f = modes.frequencies_hz[sel]
    free = model.dofs.free_nodes
    Gt = tower_rows(model, model.G, tower)  # in the tower's frame
    norm = np.abs(modes.norm[sel])  # |chi^H psi|
    r = (Gt @ S) @ vr  # (3, n_modes) reaction per unit modal amplitude
    L = load_rows(model, S).T / modes.mass[:, None]  # M*^-1 S^T maps a y-load at free node i to b
    cvec = np.zeros((lam.size, system.n_nodes), dtype=complex)
    cvec[:, free] = (vl.conj().T @ L) * load_per_v[free][None, :]
    rho = markov_rho(system, f, coherence_decay, v_mean)
    SQ = von_karman(f, sigma, length_scale, v_mean) * _quad_kms(cvec, rho)
    rate = -lam.real
    with np.errstate(divide="ignore", invalid="ignore"):
        var = np.where(rate > 0, SQ / (norm**2 * 2 * rate), np.inf)
    rms = np.abs(r.T) * np.sqrt(var)[:, None]
    # background r.m.s. by the quasi-static transfer, integrated over the spectrum
    K_gen = _general_band(model.K_band)
    xB = solve_banded((BANDWIDTH, BANDWIDTH), K_gen, Gt.T)
    tB = tower_rows(model, reaction_matrix_direct(system, model.load_directions), tower).astype(float).copy()
    tB[:, free] += load_rows(model, xB).T
    fb = np.geomspace(1e-5, 10.0, 600)
    rhob = markov_rho(system, fb, coherence_decay, v_mean)
    wb = np.broadcast_to((tB * load_per_v[None, :])[None], (fb.size, 3, system.n_nodes)).astype(complex)
    SB = von_karman(fb, sigma, length_scale, v_mean)[:, None] * _quad_kms(wb, rhob)
    rms_b = np.sqrt(np.trapezoid(SB, fb, axis=0))
    return ModalContribution(f, rate / np.abs(lam), rate, rms, rms_b)


# ---- the compiled kernel's piece ``quad`` (linecheck.core.kernel): its load check

def _quad_check(fns) -> float:
    """The compiled coherence quadrature (``fns.quad_kms``) against :func:`_quad_kms_nodes` (one
    coherence for all gaps and one per gap); the largest relative difference."""
    from . import kernel

    rng = np.random.default_rng(27)
    w = rng.standard_normal((9, 13, 37)) + 1j * rng.standard_normal((9, 13, 37))
    w[:, 3] = 0.0  # a node without load
    pairs = []
    for rho in (rng.random(37), rng.random((12, 37))):
        ref = _quad_kms_nodes(w, rho, compiled=False)
        got = np.empty(ref.shape)
        fns.quad_kms(w, np.ascontiguousarray(np.atleast_2d(rho)), rho.ndim == 2, got)
        pairs.append((ref, got))
    return kernel.worst_difference(pairs)


def _register_kernel_check() -> None:
    from . import kernel

    kernel.register_check("quad", _quad_check)


_register_kernel_check()
