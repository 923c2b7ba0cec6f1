"""Independent full non-linear dynamic reference of a line section, with OpenSeesPy.

Not a runtime dependency of linecheck: install the ``bench`` extra (``pip install -e '.[bench]'``).
OpenSeesPy's Linux wheel links the system BLAS/LAPACK (Debian ``libblas3``, ``liblapack3``);
:func:`load_opensees` says so in one line when they are missing.

Model (the same system as linecheck; docs/method.md for axes and signs)
--------------------------------------------------------------------------
* Conductor: ``n_el`` corotational truss elements per span (OpenSees ``corotTruss``, engineering
  strain, exact geometry at any rotation), all of unstretched length l_u = L_u / n_el with linecheck's
  L_u (``LineSystem.unstretched_length``) and axial stiffness EA: N = EA (l / l_u - 1).  The nodes
  start on the still-air parabola z = -4 S s (1 - s) (equal x spacing), and each element gets the
  initial strain that makes its unstretched length l_u (``InitStrainMaterial`` with
  E_e = E L0 / l_u, eps0 = 1 - l_u / L0, L0 the initial chord: exact for any L0); the still-air
  state is then *solved* under the weight.
* Strain towers: conductor node pinned at (x_j, 0, 0).  Suspension towers: a stiff corotational
  truss insulator from the fixed point (x_j, 0, v) to the attachment node, axial stiffness
  1e3 EA / (L_u / ne) (the penalty linecheck uses, ne = linecheck's elements per span); it swings
  freely as a pendulum.  The attachment node keeps its mass in every direction, so the insulator
  has an axial mode at ~235 Hz (omega dt ~ 74) that average-acceleration Newmark never damps and
  that would otherwise ring as a (-1)^n residue in the insulator force (89 N r.m.s. in R_y at the
  six-span tower at 40 m/s, against 15 N of genuine high-frequency response): it gets 50 % of
  critical damping by stiffness-proportional damping on the insulator elements alone
  (beta = 1 / omega_ax ~ 7e-4 s), which adds beta R_res / v ~ 1.4 N s/m to the pendulum swing,
  negligible against the aerodynamic damping (~33 N s/m per node at 40 m/s).  linecheck instead
  removes the attachment node's inertia along the insulator (docs/validation.md).
* Lumped mass W L_u / (n_el g) per element, half to each node, in x, y and z.
* Weight W per unit unstretched length (nodal, tributary).
* Drag at every conductor node i with the total wind relative to the conductor,

      F_i = 1/2 rho C_d D L_i |U_i| U_i,

  L_i the tributary unstretched length and U_i the relative velocity.  The wind is linecheck's,
  for the same case, seed and record, read from the file ``linecheck wind CASE --field OUT.npz``
  writes (:func:`read_field`; layout in docs/wind.md): the running-mean normal component V_n
  (``u_mean[..., 1]``) plus the normal component of the along-wind fluctuation
  (``u_turb[..., 1]`` = v V_n / |V|, as linecheck's Eq. 5 uses it; synoptic: V + v), blowing
  toward +y.  Three drag models:

  - ``"crossflow"`` (default): U = W_n y - P u', P = I - e e^T, e the current conductor tangent
    at the node: the relative velocity in every direction normal to the conductor axis (the
    cross-flow principle; its linearisation about u' = 0, 1/2 rho C_d D L V (P + y y^T P), is
    linecheck's ``"quasi-steady"`` damping wherever the conductor tangent is normal to y, and
    differs from it at second order in the tangent's y component elsewhere).
  - ``"transverse"``: U = (W_n - u'_y) y, i.e. F_y = 1/2 rho C_d D (V_m + v - u'_y)|V_m + v - u'_y| L_i
    and nothing else (its linearisation is the paper's Eq. 13, ``damping = "paper"``).
  - ``"crossflow-linear"`` (diagnostic): the crossflow drag linearised about the running mean
    U0 = V_n y, F = 1/2 rho C_d D L (|U0| U0 + |U0| dU + U0 (U0 . dU)/|U0|), dU = U - U0: linecheck's
    loads (Eqs 1, 5) and quasi-steady damping exactly, on the geometrically non-linear model.
    Its difference from linecheck is the structural linearisation; its difference from
    ``"crossflow"`` is the drag's non-linearity (v^2 term, relative velocity squared).

  The first two keep the v^2 term and the full non-linear dependence on the relative velocity;
  with u' = 0 they are exactly linecheck's load (Eq. 1 + Eq. 5) plus the v^2 term.  A load (and
  the weight) at a pinned node goes straight into its support.
* Optional structural damping: stiffness-proportional on the conductor elements,
  C_s = beta K_T (current tangent, OpenSees Rayleigh with ``-doRayleigh``), the same beta as
  linecheck's ``"quasi-steady"`` default (2 zeta_s / omega_1, zeta_s = 0.2 %).

Solution
--------
Static (Newton, ``BandGeneral``): the weight in one load step from the parabola, then the wind
at the first instant of the record (u' = 0) in load steps (10 by default, halved on failure).
Dynamic: Newmark average acceleration (``Newmark 0.5 0.25``) with full Newton iterations at every
step (``NormDispIncr`` 1e-9 m).  The drag is a nodal load re-applied at every step (the load
pattern is rebuilt): the wind part is that of the new instant t_{n+1}; the structural velocity
and the conductor tangent are those of the last converged step t_n (explicit in the velocity,
first order in dt).  For a harmonic motion at circular frequency w a lag of dt turns the damping
force c u' into c u' cos(w dt) plus a stiffness c w sin(w dt): the damping is changed by a
relative (w dt)^2 / 2: 0.2 % at 0.2 Hz, 1.2 % at 0.5 Hz for dt = 0.05 s.  ``substeps=2`` halves dt (the wind
interpolated linearly in time) to show it (bench_nonlinear.py).  The record starts from the
static equilibrium under the wind of its first instant, at rest: linecheck's quasi-static
start (u0 = K^-1 F0, u0' = 0).

Reactions: forces the conductor system exerts on the tower at its fixed point (R_x toward +x,
R_y toward +y, R_z downward), from the element axial forces (insulator at a suspension tower;
the adjacent conductor elements plus the load applied at the node at a strain tower).
Structural damping forces are not part of the reactions (as in linecheck, R = G u).
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from linecheck.core.case import GRAVITY, Case
from linecheck.core.system import LineSystem

INSULATOR_AXIAL_FACTOR = 1.0e3  # insulator axial stiffness / (EA / (L_u / ne)), as linecheck
DRAG_MODELS = ("crossflow", "transverse", "crossflow-linear")
SYSTEM_LIBS = ("libblas", "liblapack", "libgfortran", "cannot open shared object")
BLAS_HINT = ("OpenSeesPy cannot load the system BLAS/LAPACK it links (libblas.so.3, liblapack.so.3): "
             "install them first, e.g. `apt-get install libblas3 liblapack3` (Debian/Ubuntu)")


class OpenSeesUnavailable(RuntimeError):
    """openseespy cannot be imported; the message is one line saying why and what to do."""


def load_opensees():
    """Import ``openseespy.opensees``; raise :class:`OpenSeesUnavailable` with a one-line reason."""
    try:
        import openseespy  # noqa: F401
    except ModuleNotFoundError:
        raise OpenSeesUnavailable("openseespy is not installed: pip install -e '.[bench]' "
                                  "(or pip install openseespy)") from None
    try:
        import openseespy.opensees as ops
    except Exception as exc:
        detail = _root_cause(exc)
        if any(s in detail.lower() for s in SYSTEM_LIBS):
            raise OpenSeesUnavailable(f"{BLAS_HINT} [{detail}]") from None
        raise OpenSeesUnavailable(f"openseespy failed to import: {detail}") from None
    return ops


def _root_cause(exc: BaseException) -> str:
    """Message of the innermost exception of a chain; for the wrapped Linux loader, retry the
    inner module to get the dynamic linker's own message."""
    while exc.__cause__ is not None or exc.__context__ is not None:
        exc = exc.__cause__ or exc.__context__
    msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    if "Failed to import openseespy" in msg:
        try:
            import openseespylinux.opensees  # noqa: F401
        except Exception as inner:
            return _root_cause(inner)
    return msg


# --------------------------------------------------------------------------- the wind record
@dataclass(frozen=True)
class WindRecord:
    """Wind of one record at linecheck's global FE nodes (still-air x).

    Attributes:
        time: [s] record instants (burn-in included), shape (n_steps,).
        normal: [m/s] total wind normal to the line W_n = V_n + v V_n/|V|, (n_steps, n_nodes).
        mean_normal: [m/s] running-mean normal component V_n, (n_steps, n_nodes).
        keep: analysed steps (after the burn-in), bool (n_steps,).
    """

    time: np.ndarray
    normal: np.ndarray
    mean_normal: np.ndarray
    keep: np.ndarray


def read_field(path) -> WindRecord:
    """The wind of one record from a ``linecheck wind CASE --field OUT.npz`` file (public layout,
    docs/wind.md): the total normal wind W_n = u_mean_y + u_turb_y and the running mean u_mean_y
    at every conductor node and instant (burn-in included, marked by ``burn_in``).  Only the
    file is read: nothing of linecheck's internals is called, so any wind in that layout (from
    linecheck or elsewhere) can be fed to this reference."""
    with np.load(path, allow_pickle=False) as z:
        t = np.asarray(z["t"], dtype=float)
        burn = float(z["burn_in"])
        u_mean = np.asarray(z["u_mean"], dtype=float)
        u_turb = np.asarray(z["u_turb"], dtype=float)
    keep = t >= t[0] + burn - 1e-9
    return WindRecord(t, u_mean[:, :, 1] + u_turb[:, :, 1], u_mean[:, :, 1].copy(), keep)


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class NonlinearResult:
    """Non-linear dynamic response of one record.

    Attributes:
        time: [s] (n_steps,) as the wind record.
        reactions: [N] total reactions at every tower, (n_steps, n_towers, 3) (R_z downward).
        still_air: [N] reactions under the weight alone, (n_towers, 3).
        keep: analysed steps (bool, n_steps).
        wall: [s] wall time of the analysis (model, statics and time stepping).
        solver_wall: [s] the part spent inside OpenSees' ``analyze`` of the time steps (the rest is
            the Python coupling: reading the state, the drag, re-applying the loads, reactions).
        iterations: Newton iterations per step (n_steps,) (0 for the start).
    """

    time: np.ndarray
    reactions: np.ndarray
    still_air: np.ndarray
    keep: np.ndarray
    wall: float
    solver_wall: float
    iterations: np.ndarray

    @property
    def wind_induced(self) -> np.ndarray:
        """[N] total - still air, (n_steps, n_towers, 3)."""
        return self.reactions - self.still_air[None]


# --------------------------------------------------------------------------- the model
class NonlinearLine:
    """OpenSeesPy model of a line section (one at a time: OpenSees has one global domain).

    Args:
        case: linecheck case (geometry, conductor, air, C_d, D).
        n_el: conductor elements per span (default linecheck's ``elements_per_span``).
        drag: ``"crossflow"`` or ``"transverse"`` (module docstring).
        structural_beta: [s] stiffness-proportional damping factor on the conductor elements.
        insulator_damping: [-] damping ratio of the insulator's axial mode (stiffness-proportional
            on the insulator elements, beta = 2 zeta / omega_ax, omega_ax = sqrt(k_ax / m_node));
            0 leaves that mode undamped.
        tol: [m] Newton tolerance on the displacement increment (``NormDispIncr``).
    """

    def __init__(self, case: Case, *, n_el: int | None = None, drag: str = "crossflow",
                 structural_beta: float = 0.0, insulator_damping: float = 0.5, tol: float = 1e-9) -> None:
        if drag not in DRAG_MODELS:
            raise ValueError(f"drag must be one of {DRAG_MODELS}, got {drag!r}")
        self.ops = load_opensees()
        self.case = case
        self.system = LineSystem(case.line)
        self.n_el = int(n_el or self.system.ne)
        self.drag = drag
        self.beta = float(structural_beta)
        self.tol = float(tol)
        line, sys_ = case.line, self.system
        k_ax = INSULATOR_AXIAL_FACTOR * line.ea / (sys_.unstretched_length / sys_.ne)
        m_node = line.weight * sys_.unstretched_length / (int(n_el or sys_.ne) * GRAVITY)
        self.beta_ins = 2.0 * float(insulator_damping) / np.sqrt(k_ax / m_node)
        self.coef = 0.5 * case.wind.air_density * line.drag_coefficient * line.diameter  # 1/2 rho C_d D
        n, ns = self.n_el, sys_.n_spans
        self.nc = ns * n + 1  # conductor nodes (global chain, tower nodes shared)
        self.tower_node = np.arange(sys_.n_towers) * n
        self.sus = sys_.suspension.copy()
        self.lu_el = sys_.unstretched_length / n
        trib = np.zeros(self.nc)
        trib[:-1] += 0.5 * self.lu_el
        trib[1:] += 0.5 * self.lu_el
        self.trib = trib
        pinned = np.zeros(self.nc, dtype=bool)
        pinned[self.tower_node[~self.sus]] = True
        self.pinned = pinned
        self.free = np.flatnonzero(~pinned)
        # still-air x of the nodes and the interpolation from linecheck's nodes (wind)
        L = line.span_length
        s = np.linspace(0.0, 1.0, n + 1)
        x = np.concatenate([k * L + s[:-1] * L for k in range(ns)] + [np.array([ns * L])])
        self.x0 = x
        xl = sys_.node_x0
        eye = np.eye(xl.size)
        self.interp = np.stack([np.interp(x, xl, eye[:, k]) for k in range(xl.size)], axis=1)  # (nc, n_lc)

    # ------------------------------------------------------------------ build
    def _build(self) -> None:
        ops = self.ops
        line, sys_ = self.case.line, self.system
        L, S, v = line.span_length, line.sag, line.insulator_length
        n, ns = self.n_el, sys_.n_spans
        ops.wipe()
        ops.model("basic", "-ndm", 3, "-ndf", 3)
        s = (self.x0 - np.floor(self.x0 / L + 1e-12) * L) / L
        s[-1] = 1.0
        z = -4.0 * S * s * (1.0 - s)
        z[self.tower_node] = 0.0
        self.X0 = np.column_stack([self.x0, np.zeros(self.nc), z])
        for i in range(self.nc):
            ops.node(i + 1, *self.X0[i])
            m = line.weight * self.trib[i] / GRAVITY
            if not self.pinned[i]:
                ops.mass(i + 1, m, m, m)
            else:
                ops.fix(i + 1, 1, 1, 1)
        E = line.elastic_modulus
        A = line.area
        self.n_cond = ns * n
        for e in range(self.n_cond):
            L0 = float(np.linalg.norm(self.X0[e + 1] - self.X0[e]))
            ops.uniaxialMaterial("Elastic", 2 * e + 1, E * L0 / self.lu_el)
            ops.uniaxialMaterial("InitStrainMaterial", 2 * e + 2, 2 * e + 1, 1.0 - self.lu_el / L0)
            ops.element("corotTruss", e + 1, e + 1, e + 2, A, 2 * e + 2, "-doRayleigh", 1 if self.beta > 0 else 0)
        if self.beta > 0:
            ops.region(1, "-eleRange", 1, self.n_cond, "-rayleigh", 0.0, self.beta, 0.0, 0.0)
        # insulators: fixed point (x_j, 0, v) -> attachment node
        k_ax = INSULATOR_AXIAL_FACTOR * line.ea / (sys_.unstretched_length / sys_.ne)
        mat = 2 * self.n_cond + 1
        ops.uniaxialMaterial("Elastic", mat, k_ax * v)  # A = 1: EA_ins / v = k_ax
        self.ins_ele = {}
        self.fixed_node = {}
        for j in np.flatnonzero(self.sus):
            tag = int(self.nc + 1 + j)
            ops.node(tag, float(sys_.tower_x[j]), 0.0, v)
            ops.fix(tag, 1, 1, 1)
            et = int(self.n_cond + 1 + j)
            ops.element("corotTruss", et, tag, int(self.tower_node[j]) + 1, 1.0, mat,
                        "-doRayleigh", 1 if self.beta_ins > 0 else 0)
            self.ins_ele[j] = et
            self.fixed_node[j] = np.array([sys_.tower_x[j], 0.0, v])
        if self.beta_ins > 0 and self.ins_ele:
            tags = [int(t) for t in self.ins_ele.values()]
            ops.region(2, "-ele", *tags, "-rayleigh", 0.0, self.beta_ins, 0.0, 0.0)
        # weight: a constant pattern
        ops.timeSeries("Linear", 1)
        ops.pattern("Plain", 1, 1)
        for i in self.free:
            ops.load(int(i) + 1, 0.0, 0.0, -line.weight * self.trib[i])
        ops.system("BandGeneral")
        ops.numberer("RCM")
        ops.constraints("Plain")

    def _static(self, steps: int) -> int:
        """LoadControl in ``steps`` increments of the active Linear patterns (halved on failure)."""
        ops = self.ops
        ops.test("NormDispIncr", self.tol, 100)
        ops.algorithm("Newton")
        lam, dl, its = 0.0, 1.0 / steps, 0
        while lam < 1.0 - 1e-12:
            d = min(dl, 1.0 - lam)
            ops.integrator("LoadControl", d)
            ops.analysis("Static")
            if ops.analyze(1) == 0:
                lam += d
                its += ops.testIter()
                continue
            dl = d / 2
            if dl < 1e-4:
                raise RuntimeError(f"OpenSees static analysis failed at load factor {lam:.4f}")
        return its

    # ------------------------------------------------------------------ state access
    def _state(self) -> tuple[np.ndarray, np.ndarray]:
        ops = self.ops
        D = np.array([ops.nodeDisp(i + 1) for i in range(self.nc)])
        V = np.array([ops.nodeVel(i + 1) for i in range(self.nc)])
        return self.X0 + D, V

    def _drag(self, w: np.ndarray, X: np.ndarray | None, V: np.ndarray | None,
              w_mean: np.ndarray | None = None) -> np.ndarray:
        """Nodal drag forces [N], (nc, 3), for the normal wind w (nc,) and the structural state
        (``w_mean``: the running mean, for ``"crossflow-linear"``)."""
        U = np.zeros((self.nc, 3))
        U[:, 1] = w
        if V is not None:
            if self.drag == "transverse":
                U[:, 1] -= V[:, 1]
            else:
                seg = np.diff(X, axis=0)
                seg /= np.linalg.norm(seg, axis=1)[:, None]
                e = np.zeros_like(X)
                e[:-1] += seg
                e[1:] += seg
                e /= np.linalg.norm(e, axis=1)[:, None]
                U -= V - np.einsum("ij,ij->i", V, e)[:, None] * e
        if self.drag == "crossflow-linear" and w_mean is not None:
            a = np.abs(w_mean)
            dU = U.copy()
            dU[:, 1] -= w_mean
            F = a[:, None] * dU
            F[:, 1] += a * w_mean + a * dU[:, 1]  # |U0| U0 + U0 (U0 . dU)/|U0| (U0 along y)
            return (self.coef * self.trib)[:, None] * F
        return (self.coef * self.trib * np.linalg.norm(U, axis=1))[:, None] * U

    def _set_drag(self, F: np.ndarray, series: int) -> None:
        ops = self.ops
        ops.remove("loadPattern", 2)
        ops.pattern("Plain", 2, series)
        for i in self.free:
            ops.load(int(i) + 1, *F[i])

    def _reactions(self, F: np.ndarray) -> np.ndarray:
        """[N] (n_towers, 3) forces on the towers' fixed points (R_z downward)."""
        ops = self.ops
        nt = self.system.n_towers
        R = np.zeros((nt, 3))
        for j in range(nt):
            node = int(self.tower_node[j])
            xj = self.X0[node] + np.array(ops.nodeDisp(node + 1))
            if self.sus[j]:
                N = ops.eleResponse(self.ins_ele[j], "axialForce")[0]
                d = xj - self.fixed_node[j]
                R[j] = N * d / np.linalg.norm(d)  # the insulator pulls its fixed point toward the node
            else:
                for e, other in ((node - 1, node - 1), (node, node + 1)):
                    if 0 <= e < self.n_cond:
                        N = ops.eleResponse(e + 1, "axialForce")[0]
                        xo = self.X0[other] + np.array(ops.nodeDisp(other + 1))
                        d = xo - xj
                        R[j] += N * d / np.linalg.norm(d)
                R[j] += F[node]  # a load at a pinned node goes straight into its support
                R[j, 2] -= self.case.line.weight * self.trib[node]  # and so does its weight
        R[:, 2] *= -1.0
        return R

    # ------------------------------------------------------------------ analyses
    def still_air(self) -> np.ndarray:
        """[N] reactions under the weight alone, (n_towers, 3)."""
        self._build()
        self._static(1)
        return self._reactions(np.zeros((self.nc, 3)))

    def mean_states(self, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Static equilibria under the mean wind, one per row of ``normal`` [m/s] (n_k, n_lc nodes),
        each warm-started from the previous.  Returns (reactions (n_k, n_towers, 3), still air)."""
        ops = self.ops
        self._build()
        self._static(1)
        still = self._reactions(np.zeros((self.nc, 3)))
        ops.loadConst("-time", 0.0)
        ops.timeSeries("Constant", 2)
        ops.pattern("Plain", 2, 2)  # placeholder, replaced below
        out = np.empty((normal.shape[0], self.system.n_towers, 3))
        ops.integrator("LoadControl", 0.0)  # the Constant pattern holds the whole load
        ops.test("NormDispIncr", self.tol, 100)
        ops.analysis("Static")
        for k in range(normal.shape[0]):
            F = self._drag(self.interp @ normal[k], None, None)
            self._set_drag(F, 2)  # Newton from the previous state (the mean changes slowly)
            ops.algorithm("Newton")
            if ops.analyze(1) != 0:
                ops.algorithm("NewtonLineSearch")
                if ops.analyze(1) != 0:
                    raise RuntimeError(f"OpenSees mean state {k} did not converge")
            out[k] = self._reactions(F)
        return out, still

    def run(self, wind: WindRecord, *, substeps: int = 1, static_steps: int = 10,
            progress: Callable[[int, int], None] | None = None) -> NonlinearResult:
        """Statics (weight, then the wind of the first instant) and the record, Newmark + Newton."""
        ops = self.ops
        t_start = _time.perf_counter()
        t = wind.time
        Wn = wind.normal @ self.interp.T  # (n_steps, nc)
        Wm = wind.mean_normal @ self.interp.T
        self._build()
        self._static(1)
        still = self._reactions(np.zeros((self.nc, 3)))
        ops.loadConst("-time", 0.0)
        # the wind of the first instant, at rest (the quasi-static start), in load steps
        F = self._drag(Wn[0], None, None, Wm[0])
        ops.timeSeries("Linear", 3)
        ops.pattern("Plain", 2, 3)
        for i in self.free:
            ops.load(int(i) + 1, *F[i])
        self._static(static_steps)
        ops.loadConst("-time", 0.0)
        n_steps = t.size
        R = np.empty((n_steps, self.system.n_towers, 3))
        R[0] = self._reactions(F)
        iters = np.zeros(n_steps, dtype=int)
        # dynamics
        ops.wipeAnalysis()
        ops.timeSeries("Constant", 4)
        ops.system("BandGeneral")
        ops.numberer("RCM")
        ops.constraints("Plain")
        ops.test("NormDispIncr", self.tol, 50)
        ops.algorithm("Newton")
        ops.integrator("Newmark", 0.5, 0.25)
        ops.analysis("Transient")
        dt = float(t[1] - t[0])
        h = dt / substeps
        report = max(1, n_steps // 50)
        solver = 0.0
        clock = _time.perf_counter
        for n in range(1, n_steps):
            for k in range(1, substeps + 1):
                a = k / substeps
                w = (1 - a) * Wn[n - 1] + a * Wn[n]
                wm = (1 - a) * Wm[n - 1] + a * Wm[n]
                X, V = self._state()
                F = self._drag(w, X, V, wm)
                self._set_drag(F, 4)
                c0 = clock()
                ok = ops.analyze(1, h)
                solver += clock() - c0
                its = ops.testIter()
                if ok != 0:  # fallback: the same load in four sub-steps
                    ok = ops.analyze(4, h / 4)
                    its = ops.testIter()
                    if ok != 0:
                        raise RuntimeError(f"OpenSees Newmark step failed at t = {t[n]:.3f} s")
                iters[n] += its
            R[n] = self._reactions(F)
            if progress is not None and n % report == 0:
                progress(n, n_steps)
        ops.wipe()
        return NonlinearResult(t, R, still, wind.keep, _time.perf_counter() - t_start, solver, iters)
