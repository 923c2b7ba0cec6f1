"""Independent non-linear 3-D finite-element reference for a line SECTION (the acceptance check for sections).

Self-contained: it reads the case's RAW inputs (the TOML with :mod:`tomllib`, a towers CSV with
:mod:`csv`) and implements the section model of docs/method.md ("Line sections") from its definitions,
sharing no code with ``linecheck`` (it imports nothing from it).  The only other helper it uses
is the closed-form inclined elastic catenary (Irvine 1981) in ``irvine_inclined.py``.

Model (global frame: x along the first span, y to its left, z up; SI units)
---------------------------------------------------------------------------
* Plan geometry: span i joins towers i and i+1, heading h_i = sum of the angles of towers 1..i,
  horizontal length L_i = station[i+1] - station[i]; plan positions P_1 = 0,
  P_{i+1} = P_i + L_i (cos h_i, sin h_i).  Still-air clamp C_j = (P_j, ground_j + height_j);
  a suspension insulator's fixed top T_j = C_j + (0, 0, v_j).
* Clipping-in: span i's unstretched length L_u,i is that of the inclined elastic catenary of
  horizontal tension H0 between C_i and C_{i+1} (Irvine 1981 ch. 2); the nodes start ON that
  catenary, at equal unstretched arc length.
* Conductor: ``n_el`` exact large-displacement elastic truss elements per span, unstretched length
  l0 = L_u,i / n_el, axial force N = EA (l/l0 - 1) with l the current length (no sag or
  small-strain approximation).  Consistent tangent (Crisfield 1991, "Non-linear Finite Element
  Analysis of Solids and Structures", Vol. 1, ch. 3): k = EA/l0 e e^T + N/l (I - e e^T),
  K_e = [[k, -k], [-k, k]].
* Strain clamps: the conductor node is pinned at C_j.  Suspension: a very stiff truss (penalty
  EA_ins = ``insulator_stiffness`` * EA, unstretched length v_j) from the fixed T_j to the
  conductor node; it carries no moment, so it swings freely (a rigid pendulum up to a stretch of
  ~1e-5 m, reported as ``insulator_length_error``).
* Loads per unit UNSTRETCHED length: weight W (-z); the mean wind at a node is the horizontal
  vector V = V(z) (sin d, cos d, 0), V(z) = v_ref (z_agl/z_ref)^alpha, z_agl = the node's
  still-air height above the ground interpolated linearly in station.  Drag (``drag_direction``):

  - ``"horizontal-normal"`` (default): 1/2 rho C_d D |V_n| V_n n_i with n_i = (-sin h_i, cos h_i, 0)
    the span's horizontal normal and V_n = V . n_i; a fixed (dead) load.
  - ``"cross-flow"``: the cross-flow (independence) principle, Hoerner 1965, "Fluid-Dynamic Drag",
    ch. 3: the drag on a yawed cylinder is that of the velocity component normal to its axis.
    On every element with CURRENT (deformed) unit axis e: V_perp = V - (V . e) e and the drag is
    1/2 rho C_d D |V_perp| V_perp, a follower load.  Its load stiffness -df/dx (derived in
    :meth:`_Model.crossflow`) is part of the (then non-symmetric) Newton tangent.

    ``crossflow_axes`` = ``"still-air"`` or ``"chord"`` freezes e at the still-air elements or
    at each span's chord C_i C_i+1 (dead loads, for comparison with models that do so).

  On a level span in wind normal to the line the two coincide on the still-air geometry
  (V . e = 0, :func:`still_air_drag`).  After the blow-out the elements away from mid-span
  have e_y != 0: the follower drag is smaller (by ~1.5 <e_y^2>) and has an upward part, both
  second order in the sag slope; with wind off the normal (V_x != 0) V . e changes to first
  order, |V_perp| drops near one end of each span and rises near the other.
  Nodal loads: consistent lumping of the linearly interpolated nodal intensities
  (l0 (2q_a + q_b)/6, l0 (q_a + 2 q_b)/6), exact for weight.
* Solution: full Newton-Raphson with step limiting (largest nodal move <= ``dmax``) on the weight
  from the clipped-in catenary (the still-air state), then the wind in adaptive load increments.
  Sparse direct solves.
* Reactions = force of the conductor system on each tower's fixed point (strain: the clamp,
  including the load lumped at the pinned node; suspension: the insulator top), global (R_x, R_y,
  R_z) with R_z DOWN, and in the tower frame: x along the mean heading psi_j of its two spans
  (end tower: its span's), y = x turned +90 deg, z down:
  R_x' = R_x cos psi + R_y sin psi, R_y' = -R_x sin psi + R_y cos psi, R_z' = R_z.
* Still-air small vibrations: K = the consistent tangent at the still-air equilibrium (material +
  geometric stiffness, the insulators' geometric stiffness N/l is their pendulum stiffness),
  lumped mass W/g per unit unstretched length (g = 9.81 m/s2, paper Eq. 8), insulators massless.
  The discrete chain converges to the continuum as O(1/n_el^2); :func:`still_air_frequencies`
  can Richardson-extrapolate two meshes.
"""

from __future__ import annotations

import csv
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.linalg import eigh
from scipy.sparse.linalg import spsolve

from . import irvine_inclined
from .truss import load_stepping, truss_internal, truss_state

GRAVITY = 9.81  # [m/s2] paper Eq. 8


class FEConvergenceError(RuntimeError):
    """The reference Newton iteration did not converge."""


# ============================================================================ raw inputs
@dataclass(frozen=True)
class Tower:
    """One tower row as written in the case (SI; angle in degrees)."""

    name: str
    station: float
    ground: float
    height: float
    support: str
    angle: float
    insulator_length: float | None


@dataclass(frozen=True)
class Section:
    """The raw section inputs the reference needs.

    Attributes:
        W [N/m], D [m], EA [N], Cd [-], H0 [N], v_default [m] (line insulator_length),
        towers (tuple of :class:`Tower`), rho [kg/m3], v_ref [m/s], direction [deg],
        alpha [-] (profile_exponent), z_ref [m] (reference_height or the mean clamp height
        above ground).
    """

    W: float
    D: float
    EA: float
    Cd: float
    H0: float
    v_default: float
    towers: tuple[Tower, ...]
    rho: float = 1.25
    v_ref: float = 0.0
    direction: float = 0.0
    alpha: float = 0.0
    z_ref: float | None = None
    name: str = ""

    @property
    def reference_height(self) -> float:
        """[m] z_ref: as given, else the mean clamp height above ground."""
        if self.z_ref is not None:
            return self.z_ref
        return float(np.mean([t.height for t in self.towers]))


def _tower_from_row(row: dict, k: int) -> Tower:
    def num(key, default=None):
        v = row.get(key, default)
        if v is None or (isinstance(v, str) and v.strip() == ""):
            if default is None:
                raise ValueError(f"tower {k + 1}: missing {key}")
            return default
        return float(v)

    ins = row.get("insulator_length")
    ins = None if ins is None or (isinstance(ins, str) and ins.strip() == "") else float(ins)
    return Tower(
        name=str(row.get("name") or f"T{k + 1}"),
        station=num("station"),
        ground=num("ground", 0.0),
        height=num("height"),
        support=str(row.get("support", "")).strip(),
        angle=num("angle", 0.0),
        insulator_length=ins,
    )


def read_section(path: str | Path) -> Section:
    """Read a towers-form case (TOML + optional towers CSV) with the standard library only."""
    p = Path(path)
    data = tomllib.loads(p.read_text(encoding="utf-8"))
    line, wind = data["line"], data.get("wind", {})
    if "towers_file" in line:
        with open(p.parent / line["towers_file"], newline="", encoding="utf-8-sig") as fh:
            text = [ln for ln in fh if ln.strip() and not ln.lstrip().startswith("#")]  # comment lines
        rows = [{(k or "").strip(): (v or "").strip() for k, v in r.items()} for r in csv.DictReader(text)]
    else:
        rows = list(line["towers"])
    towers = tuple(_tower_from_row(r, k) for k, r in enumerate(rows))
    return Section(
        W=float(line["weight"]),
        D=float(line["diameter"]),
        EA=float(line["area"]) * float(line["elastic_modulus"]),
        Cd=float(line.get("drag_coefficient", 1.0)),
        H0=float(line["tension"]),
        v_default=float(line.get("insulator_length", 4.0)),
        towers=towers,
        rho=float(wind.get("air_density", 1.25)),
        v_ref=float(wind.get("v_ref", 0.0)),
        direction=float(wind.get("direction", 0.0)),
        alpha=float(wind.get("profile_exponent", 0.0)),
        z_ref=float(wind["reference_height"]) if "reference_height" in wind else None,
        name=str(data.get("name", p.stem)),
    )


# ============================================================================ geometry
@dataclass(frozen=True)
class Geometry:
    """Plan and elevation geometry of the section (section model definitions).

    Attributes (n = n_towers, n - 1 = n_spans):
        heading: [rad] h_i per span, (n-1,).  length: [m] L_i, (n-1,).
        plan: [m] P_j, (n, 2).  clamp: [m] still-air clamp C_j, (n, 3).
        top: [m] fixed insulator top T_j (= C_j at strain towers), (n, 3).
        v: [m] insulator length per tower (0 at strain towers), (n,).
        suspension: (n,) bool.  psi: [rad] tower-frame heading, (n,).
        catenary: the clipped-in :class:`irvine_inclined.InclinedCatenary` per span.
    """

    heading: np.ndarray
    length: np.ndarray
    plan: np.ndarray
    clamp: np.ndarray
    top: np.ndarray
    v: np.ndarray
    suspension: np.ndarray
    psi: np.ndarray
    catenary: tuple


def geometry(sec: Section) -> Geometry:
    t = sec.towers
    n = len(t)
    station = np.array([x.station for x in t])
    angle = np.radians([x.angle for x in t])
    L = np.diff(station)
    heading = np.cumsum(angle)[:-1]  # h_i = sum of the angles of towers 1..i
    plan = np.zeros((n, 2))
    for i in range(n - 1):
        plan[i + 1] = plan[i] + L[i] * np.array([math.cos(heading[i]), math.sin(heading[i])])
    z = np.array([x.ground + x.height for x in t])
    clamp = np.column_stack([plan, z])
    sus = np.array([x.support == "suspension" for x in t])
    v = np.array([(x.insulator_length if x.insulator_length is not None else sec.v_default) if s else 0.0
                  for x, s in zip(t, sus, strict=True)])
    top = clamp + np.column_stack([np.zeros((n, 2)), v])
    psi = np.empty(n)
    psi[0], psi[-1] = heading[0], heading[-1]
    psi[1:-1] = 0.5 * (heading[:-1] + heading[1:])
    cats = tuple(irvine_inclined.from_tension(L[i], z[i + 1] - z[i], sec.W, sec.EA, sec.H0) for i in range(n - 1))
    return Geometry(heading, L, plan, clamp, top, v, sus, psi, cats)


def to_tower_frame(R: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Global (R_x, R_y, R_z-down) -> tower frame, shape (n, 3) (section model definitions)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.column_stack([R[:, 0] * c + R[:, 1] * s, -R[:, 0] * s + R[:, 1] * c, R[:, 2]])


# ============================================================================ the FE model
class _Model:
    """Points (conductor nodes, then insulator tops), elements, loads and the sparse tangent."""

    def __init__(self, sec: Section, geo: Geometry, n_el: int, insulator_stiffness: float) -> None:
        ns = geo.length.size
        nt = ns + 1
        n = int(n_el)
        nc = ns * n + 1
        self.sec, self.geo, self.n, self.ns, self.nt, self.nc = sec, geo, n, ns, nt, nc
        self.tower_node = np.arange(nt) * n
        self.sus_idx = np.flatnonzero(geo.suspension)
        nsus = self.sus_idx.size
        self.nn = nc + nsus

        # still-air start: the clipped-in catenaries, nodes at equal unstretched arc length
        X = np.zeros((self.nn, 3))
        l0c = np.empty(ns * n)
        for i, cat in enumerate(geo.catenary):
            s = np.linspace(0.0, cat.Lu, n + 1)
            x, zz = cat.shape(s)
            x[-1], zz[-1] = cat.L, cat.h  # exact end points
            d = np.array([math.cos(geo.heading[i]), math.sin(geo.heading[i])])
            sl = slice(i * n, (i + 1) * n + 1)
            X[sl, :2] = geo.plan[i] + x[:, None] * d
            X[sl, 2] = geo.clamp[i, 2] + zz
            l0c[i * n:(i + 1) * n] = cat.Lu / n
        X[self.tower_node] = geo.clamp  # exactly on the clamps
        X[nc:] = geo.top[self.sus_idx]
        self.X0 = X

        # elements: conductor chain, then insulators (top -> conductor node)
        self.a = np.concatenate([np.arange(ns * n), nc + np.arange(nsus)])
        self.b = np.concatenate([np.arange(1, ns * n + 1), self.tower_node[self.sus_idx]])
        self.n_cond = ns * n
        self.span_of_el = np.repeat(np.arange(ns), n)
        self.l0 = np.concatenate([l0c, geo.v[self.sus_idx]])
        self.EA = np.concatenate([np.full(ns * n, sec.EA), np.full(nsus, insulator_stiffness * sec.EA)])
        self.dX0 = X[self.b] - X[self.a]
        self.c0 = np.einsum("ij,ij->i", self.dX0, self.dX0) - self.l0**2

        # free dofs: conductor nodes except strain clamps; insulator tops fixed
        free = np.zeros((self.nn, 3), dtype=bool)
        free[:nc] = True
        free[self.tower_node[~geo.suspension]] = False
        self.free = free.reshape(-1)
        self.free_idx = np.flatnonzero(self.free)
        gmap = np.full(3 * self.nn, -1)
        gmap[self.free_idx] = np.arange(self.free_idx.size)
        dofs = np.concatenate([3 * self.a[:, None] + np.arange(3), 3 * self.b[:, None] + np.arange(3)], axis=1)
        rows = np.repeat(dofs[:, :, None], 6, axis=2)
        cols = np.repeat(dofs[:, None, :], 6, axis=1)
        self._keep = (gmap[rows] >= 0) & (gmap[cols] >= 0)
        self._r = gmap[rows][self._keep]
        self._c = gmap[cols][self._keep]
        kc = self._keep[: ns * n]  # the conductor elements' entries (cross-flow load stiffness)
        self._rows_cond = gmap[rows[: ns * n]][kc]
        self._cols_cond = gmap[cols[: ns * n]][kc]
        self.nf = self.free_idx.size

        # weight: W l0 / 2 to each end of every conductor element (exact for a uniform load)
        fw = np.zeros((self.nn, 3))
        half = 0.5 * sec.W * l0c
        np.add.at(fw[:, 2], self.a[: self.n_cond], -half)
        np.add.at(fw[:, 2], self.b[: self.n_cond], -half)
        self.fw = fw.reshape(-1)
        self.fq = np.zeros(3 * self.nn)
        self.mass_node = np.zeros(self.nn)
        np.add.at(self.mass_node, self.a[: self.n_cond], 0.5 * sec.W * l0c / GRAVITY)
        np.add.at(self.mass_node, self.b[: self.n_cond], 0.5 * sec.W * l0c / GRAVITY)

    # ---------------------------------------------------------------- element state
    def state(self, U: np.ndarray):
        """Axial forces [N], unit vectors, current lengths [m] of all elements at displacements
        U (nn, 3) from X0.  Total Lagrangian in U so that round-off does not grow with the
        absolute coordinates: l - l0 = (c0 + 2 dX0.dU + dU.dU) / (l + l0), c0 = |dX0|^2 - l0^2."""
        return truss_state(U, self.a, self.b, self.dX0, self.c0, self.l0, self.EA)

    def internal(self, U: np.ndarray) -> np.ndarray:
        """Internal nodal forces [N], (3 nn,): node a gets -N e, node b +N e."""
        N, e, _ = self.state(U)
        return truss_internal(N, e, self.a, self.b, self.nn)

    def tangent(self, U: np.ndarray) -> sp.csc_matrix:
        """Consistent tangent on the free dofs (Crisfield 1991 Vol. 1 ch. 3)."""
        N, e, ell = self.state(U)
        ee = e[:, :, None] * e[:, None, :]
        k = (self.EA / self.l0 - N / ell)[:, None, None] * ee + (N / ell)[:, None, None] * np.eye(3)
        Ke = np.block([[k, -k], [-k, k]])
        return sp.coo_matrix((Ke[self._keep], (self._r, self._c)), shape=(self.nf, self.nf)).tocsc()

    # ---------------------------------------------------------------- wind
    def set_wind(self, X_still: np.ndarray) -> None:
        """Wind vectors at the element ends and the horizontal-normal drag (section model).

        Sets ``Va``, ``Vb`` [m/s] (n_cond, 3): the horizontal mean wind V(z) (sin d, cos d, 0) at
        each conductor element's ends from their still-air heights, and ``fq`` [N] (3 nn,): the
        nodal horizontal-normal drag 1/2 rho C_d D |V_n| V_n n_i (consistent lumping)."""
        sec, geo = self.sec, self.geo
        ne = self.n_cond
        self.Va = np.zeros((ne, 3))
        self.Vb = np.zeros((ne, 3))
        if sec.v_ref == 0.0:
            self.fq = np.zeros(3 * self.nn)
            return
        d = math.radians(sec.direction)
        vdir = np.array([math.sin(d), math.cos(d), 0.0])
        z_ref = sec.reference_height
        station = np.array([t.station for t in sec.towers])
        ground = np.array([t.ground for t in sec.towers])
        fq = np.zeros((self.nn, 3))
        i = self.span_of_el
        h = geo.heading[i]
        t = np.column_stack([np.cos(h), np.sin(h)])
        nrm = np.column_stack([-np.sin(h), np.cos(h), np.zeros_like(h)])
        for end, nodes in (("a", self.a[:ne]), ("b", self.b[:ne])):
            P = X_still[nodes]
            st = station[i] + np.clip(np.einsum("ij,ij->i", P[:, :2] - geo.plan[i], t), 0.0, geo.length[i])
            zg = np.interp(st, station, ground)
            z_agl = P[:, 2] - zg
            if np.any(z_agl <= 0):
                raise ValueError("conductor below ground in still air")
            V = sec.v_ref * (z_agl / z_ref) ** sec.alpha if sec.alpha != 0.0 else np.full(z_agl.size, sec.v_ref)
            Vn = V * (nrm @ vdir)
            q = (0.5 * sec.rho * sec.Cd * sec.D * np.abs(Vn) * Vn)[:, None] * nrm  # [N/m] along n_i
            if end == "a":
                qa, self.Va = q, V[:, None] * vdir
            else:
                qb, self.Vb = q, V[:, None] * vdir
        l0 = self.l0[:ne, None]
        np.add.at(fq, self.a[:ne], l0 * (2.0 * qa + qb) / 6.0)
        np.add.at(fq, self.b[:ne], l0 * (qa + 2.0 * qb) / 6.0)
        self.fq = fq.reshape(-1)

    def crossflow(self, U: np.ndarray, stiffness: bool = True):
        """Cross-flow drag at displacements U: nodal loads [N] (3 nn,) and, if ``stiffness``, the
        load stiffness K_L = -df/dx [N/m] on the free dofs (sparse, non-symmetric), else None.

        Per element (ends a, b; current length l, unit axis e; c = 1/2 rho C_d D [kg/m2]):
        u_k = V_k - (V_k . e) e, q_k = c |u_k| u_k [N/m] (Hoerner 1965 ch. 3), nodal loads
        f_a = l0 (2 q_a + q_b)/6, f_b = l0 (q_a + 2 q_b)/6.  Derivatives: d(|u|u)/du = |u| I +
        u u^T/|u| (0 at u = 0); du_k/de = -(e V_k^T + (V_k . e) I); de/dx_b = -de/dx_a = (I - e e^T)/l
        (Crisfield 1991 Vol. 1 ch. 3).  With G_k = dq_k/dx_b, A = l0 (2 G_a + G_b)/6,
        B = l0 (G_a + 2 G_b)/6: df/dx = [[-A, A], [-B, B]] on (a, b), so K_L = [[A, -A], [B, -B]]."""
        sec, ne = self.sec, self.n_cond
        c = 0.5 * sec.rho * sec.Cd * sec.D
        _, e, ell = self.state(U)
        e, ell = e[:ne], ell[:ne]
        l0 = self.l0[:ne, None]
        q, G = [], []
        P = np.eye(3) - e[:, :, None] * e[:, None, :]
        for V in (self.Va, self.Vb):
            Ve = np.einsum("ij,ij->i", V, e)
            u = V - Ve[:, None] * e
            un = np.sqrt(np.einsum("ij,ij->i", u, u))
            q.append(c * un[:, None] * u)
            if stiffness:
                inv = np.divide(1.0, un, out=np.zeros_like(un), where=un > 0.0)
                dq_du = c * (un[:, None, None] * np.eye(3) + (u * inv[:, None])[:, :, None] * u[:, None, :])
                du_de = -(e[:, :, None] * V[:, None, :] + Ve[:, None, None] * np.eye(3))
                G.append(np.einsum("nij,njk,nkl->nil", dq_du, du_de, P) / ell[:, None, None])
        qa, qb = q
        f = np.zeros((self.nn, 3))
        np.add.at(f, self.a[:ne], l0 * (2.0 * qa + qb) / 6.0)
        np.add.at(f, self.b[:ne], l0 * (qa + 2.0 * qb) / 6.0)
        if not stiffness:
            return f.reshape(-1), None
        A = l0[:, :, None] * (2.0 * G[0] + G[1]) / 6.0
        B = l0[:, :, None] * (G[0] + 2.0 * G[1]) / 6.0
        Ke = np.block([[A, -A], [B, -B]])
        K = sp.coo_matrix((Ke[self._keep[:ne]], (self._rows_cond, self._cols_cond)), shape=(self.nf, self.nf))
        return f.reshape(-1), K.tocsc()


def _newton(m: _Model, U: np.ndarray, fext, tol: float, max_iter: int, dmax: float):
    """Full Newton-Raphson with step limiting; returns (U, iterations, residual [N]).

    ``fext``: the external nodal loads [N] (3 nn,), or for a follower load a callable
    ``fext(U) -> (loads, K_L)`` with K_L = -d loads/dU on the free dofs (sparse) added to the
    tangent, or None (then the iteration uses the structural tangent alone and converges
    linearly to the same residual tolerance)."""
    res = np.inf
    for it in range(max_iter + 1):
        f, KL = fext(U) if callable(fext) else (fext, None)
        r = (f - m.internal(U))[m.free_idx]
        res = float(np.max(np.abs(r)))
        if not np.isfinite(res):
            raise FEConvergenceError("non-finite residual")
        if res <= tol:
            return U, it, res
        if it == max_iter:
            break
        K = m.tangent(U) if KL is None else m.tangent(U) + KL
        du = spsolve(K, r)
        big = float(np.max(np.abs(du)))
        if not np.isfinite(big):
            raise FEConvergenceError("singular tangent")
        alpha = min(1.0, dmax / big) if big > 0 else 1.0
        step = np.zeros(3 * m.nn)
        step[m.free_idx] = alpha * du
        U = U + step.reshape(-1, 3)
    raise FEConvergenceError(f"no convergence in {max_iter} iterations (residual {res:.3g} N)")


# ============================================================================ results
@dataclass(frozen=True)
class State:
    """One converged equilibrium.

    Attributes:
        reactions: [N] global (R_x, R_y, R_z-down) force on each tower's fixed point, (n_towers, 3).
        reactions_tower: [N] the same in each tower's frame, (n_towers, 3).
        clamp_displacement: [m] conductor clamp position minus its still-air clamp point C_j,
            global frame, (n_towers, 3) (zero at strain towers).
        tension: [N] horizontal tension per span (mean over the span's elements of the axial
            force's horizontal component along the span heading), (n_spans,).
        nodes: [m] conductor node positions, (n_spans n_el + 1, 3).
        insulator_length_error: [m] largest |l_ins - v| (penalty stretch).
        residual: [N] largest out-of-balance force at a free dof.  iterations, load_steps.
    """

    reactions: np.ndarray
    reactions_tower: np.ndarray
    clamp_displacement: np.ndarray
    tension: np.ndarray
    nodes: np.ndarray
    insulator_length_error: float
    residual: float
    iterations: int
    load_steps: int


@dataclass(frozen=True)
class Solution:
    """Still-air and wind states of a section (``wind`` is None when v_ref = 0); unstretched_length
    [m] per span; drag_direction, crossflow_axes: the drag model of the wind state (:func:`solve`)."""

    section: Section
    geometry: Geometry
    n_el: int
    still: State
    wind: State | None
    unstretched_length: np.ndarray = field(default_factory=lambda: np.zeros(0))
    drag_direction: str = "horizontal-normal"
    crossflow_axes: str = "current"


def _state(m: _Model, U: np.ndarray, fext: np.ndarray, res: float, its: int, steps: int) -> State:
    geo = m.geo
    F = (fext - m.internal(U)).reshape(-1, 3)  # at fixed points: the force on the support
    R = np.zeros((m.nt, 3))
    strain = np.flatnonzero(~geo.suspension)
    R[strain] = F[m.tower_node[strain]]
    R[m.sus_idx] = F[m.nc + np.arange(m.sus_idx.size)]
    R[:, 2] *= -1.0  # R_z downward positive
    N, e, ell = m.state(U)
    nce = m.n_cond
    h = geo.heading[m.span_of_el]
    Hx = N[:nce] * (e[:nce, 0] * np.cos(h) + e[:nce, 1] * np.sin(h))
    H = Hx.reshape(m.ns, m.n).mean(axis=1)
    X = m.X0 + U
    disp = X[m.tower_node] - geo.clamp
    ins_err = float(np.max(np.abs(ell[nce:] - m.l0[nce:]))) if m.sus_idx.size else 0.0
    return State(R, to_tower_frame(R, geo.psi), disp, H, X[: m.nc].copy(), ins_err, res, its, steps)


def _build(source: Section | str | Path, n_el: int, insulator_stiffness: float):
    sec = source if isinstance(source, Section) else read_section(source)
    geo = geometry(sec)
    return sec, geo, _Model(sec, geo, n_el, insulator_stiffness)


def _still(m: _Model, tol: float, max_iter: int, dmax: float):
    return _newton(m, np.zeros_like(m.X0), m.fw, tol, max_iter, dmax)


def still_air_drag(source: Section | str | Path, *, n_el: int = 100, drag_direction: str = "horizontal-normal",
                   insulator_stiffness: float = 1e3, tol: float = 1e-5) -> np.ndarray:
    """[N] nodal drag loads of ``drag_direction`` evaluated on the still-air equilibrium (the first
    wind increment's load), conductor nodes only, shape (n_spans n_el + 1, 3), global frame."""
    _sec, geo, m = _build(source, n_el, insulator_stiffness)
    U, _, _ = _still(m, tol, 50, 0.1 * float(np.min(geo.length)))
    m.set_wind(m.X0 + U)
    f = m.fq if drag_direction == "horizontal-normal" else m.crossflow(U, False)[0]
    return f.reshape(-1, 3)[: m.nc].copy()


DRAG_DIRECTIONS = ("horizontal-normal", "cross-flow")
CROSSFLOW_AXES = ("current", "still-air", "chord")


def _chord_displacements(m: _Model) -> np.ndarray:
    """[m] displacements (nn, 3) that put every span's conductor nodes on the straight line between
    its still-air clamps C_i, C_i+1 (the span's chord), at equal spacing."""
    X = m.X0.copy()
    t = np.linspace(0.0, 1.0, m.n + 1)[:, None]
    for i in range(m.ns):
        X[i * m.n:(i + 1) * m.n + 1] = m.geo.clamp[i] + t * (m.geo.clamp[i + 1] - m.geo.clamp[i])
    return X - m.X0


def solve(source: Section | str | Path, *, n_el: int = 100, insulator_stiffness: float = 1e3,
          tol: float = 1e-5, max_iter: int = 50, wind: bool = True, wind_steps: int = 4,
          drag_direction: str = "horizontal-normal", crossflow_axes: str = "current",
          load_stiffness: bool = True) -> Solution:
    """Still-air equilibrium and (if v_ref > 0 and ``wind``) the mean-wind equilibrium.

    Args:
        source: a :class:`Section` or the path of a towers-form case file.
        n_el: conductor elements per span.
        insulator_stiffness: [-] EA_ins / EA of the penalty insulator truss.
        tol: [N] force residual at every free dof (the insulator penalty's round-off floor,
            EA_ins/v times the spacing of doubles near |dX| ~ 4 m, is ~1e-6 N).
        wind_steps: initial number of wind increments (halved on failure, doubled after easy steps).
        drag_direction: ``"horizontal-normal"`` (the drag along each span's horizontal normal, a
            dead load) or ``"cross-flow"`` (the wind component normal to each element's axis);
            see the module docstring.  Any value is accepted in still air.
        crossflow_axes: the axes e of the cross-flow drag: ``"current"`` (each element's deformed
            axis, a follower load: the cross-flow principle on the conductor as it stands; default),
            ``"still-air"`` (each element's axis in the still-air equilibrium, a dead load) or
            ``"chord"`` (every element of span i on the straight line C_i C_i+1, a dead load).  The
            two dead forms show how much of the difference to "horizontal-normal" is the follower
            effect; "chord" is the form of a model that loads each span with one drag per unit length.
        load_stiffness: cross-flow on current axes only: include the load stiffness -df/dx in the
            Newton tangent (quadratic convergence; default) or iterate with the structural tangent
            alone (the same equilibrium to ``tol``, more iterations).
    """
    if drag_direction not in DRAG_DIRECTIONS:
        raise ValueError(f"drag_direction {drag_direction!r}: expected one of {DRAG_DIRECTIONS}")
    if crossflow_axes not in CROSSFLOW_AXES:
        raise ValueError(f"crossflow_axes {crossflow_axes!r}: expected one of {CROSSFLOW_AXES}")
    sec, geo, m = _build(source, n_el, insulator_stiffness)
    dmax = 0.1 * float(np.min(geo.length))
    U, its, res = _still(m, tol, max_iter, dmax)
    still = _state(m, U, m.fw, res, its, 1)
    wstate = None
    if wind and sec.v_ref > 0.0:
        m.set_wind(m.X0 + U)
        follower = drag_direction == "cross-flow" and crossflow_axes == "current"
        if not follower:
            if drag_direction == "horizontal-normal":
                fq = m.fq
            else:  # cross-flow on fixed axes: one evaluation, a dead load
                fq = m.crossflow(U if crossflow_axes == "still-air" else _chord_displacements(m), False)[0]
            U, res, total, steps = load_stepping(lambda U0, f: _newton(m, U0, f, tol, max_iter, dmax), U, m.fw,
                                                 fq, wind_steps, 6, FEConvergenceError)
            fext = m.fw + fq
        else:
            def load(lam: float):  # the load at wind factor lam (0..1): weight + lam * cross-flow drag
                def f(U1: np.ndarray):
                    fq, KL = m.crossflow(U1, load_stiffness)
                    return m.fw + lam * fq, (None if KL is None else lam * KL)
                return f

            # load_stepping hands the increment f0 + lam df to its solver: with f0 = 0, df = 1 that is lam
            U, res, total, steps = load_stepping(lambda U0, lam: _newton(m, U0, load(lam), tol, max_iter, dmax), U,
                                                 0.0, 1.0, wind_steps, 6, FEConvergenceError)
            fext = m.fw + m.crossflow(U, False)[0]
        wstate = _state(m, U, fext, res, total, steps)
    return Solution(sec, geo, n_el, still, wstate, np.array([c.Lu for c in geo.catenary]), drag_direction,
                    crossflow_axes)


# ============================================================================ vibrations
@dataclass(frozen=True)
class Modes:
    """Still-air natural modes.

    Attributes:
        frequencies_hz: [Hz] ascending, (n_modes,).
        out_of_plane: [-] share of each mode's kinetic energy along the span's horizontal normal
            n_i (the rest is in the conductor's vertical plane), (n_modes,).
        dominant: dominant global axis per mode, "x", "y" or "z" (as linecheck's ``direction``).
    """

    frequencies_hz: np.ndarray
    out_of_plane: np.ndarray
    dominant: tuple[str, ...]

    def in_plane(self, k: int) -> np.ndarray:
        """[Hz] the lowest ``k`` in-plane frequencies."""
        return self.frequencies_hz[self.out_of_plane < 0.5][:k]

    def out_plane(self, k: int) -> np.ndarray:
        """[Hz] the lowest ``k`` out-of-plane frequencies."""
        return self.frequencies_hz[self.out_of_plane >= 0.5][:k]


def _modes_of(m: _Model, U: np.ndarray, n_modes: int) -> Modes:
    K = m.tangent(U).toarray()
    mass = np.repeat(m.mass_node, 3)[m.free_idx]
    keep = mass > 0  # massless dofs (none for the conductor; insulator tops are fixed)
    s = 1.0 / np.sqrt(mass[keep])
    A = K[np.ix_(keep, keep)] * s[:, None] * s[None, :]
    w2, psi = eigh(A, subset_by_index=[0, min(n_modes, A.shape[0]) - 1])
    phi = np.zeros((m.nf, w2.size))
    phi[keep] = psi * s[:, None]
    full = np.zeros((3 * m.nn, w2.size))
    full[m.free_idx] = phi
    shp = full.reshape(m.nn, 3, -1)[: m.nc]  # conductor nodes
    # horizontal normal of each node's span (a tower node: its left span's, right for tower 1)
    span = np.clip((np.arange(m.nc) - 1) // m.n, 0, m.ns - 1)
    h = m.geo.heading[span]
    nrm = np.column_stack([-np.sin(h), np.cos(h), np.zeros_like(h)])
    mn = m.mass_node[: m.nc]
    e_out = np.einsum("n,nk->k", mn, np.einsum("nj,njk->nk", nrm, shp) ** 2)
    e_all = np.einsum("n,njk->k", mn, shp**2)
    dom = tuple("xyz"[i] for i in np.argmax(np.einsum("n,njk->jk", mn, shp**2), axis=0))
    return Modes(np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi), e_out / e_all, dom)


def still_air_modes(source: Section | str | Path, *, n_el: int = 200, n_modes: int = 12,
                    insulator_stiffness: float = 1e3, tol: float = 1e-5) -> Modes:
    """Still-air natural modes on a mesh of ``n_el`` elements per span."""
    _sec, geo, m = _build(source, n_el, insulator_stiffness)
    U, _, _ = _still(m, tol, 50, 0.1 * float(np.min(geo.length)))
    return _modes_of(m, U, n_modes)


def refined_frequencies(source: Section | str | Path, *, n_el: int = 200, k: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``k`` (in-plane, out-of-plane) still-air frequencies [Hz], Richardson-extrapolated
    from ``n_el`` and 2 ``n_el`` elements per span (lumped-mass chain error O(1/n^2))."""
    a = still_air_modes(source, n_el=n_el, n_modes=4 * k)
    b = still_air_modes(source, n_el=2 * n_el, n_modes=4 * k)
    ip = (4.0 * b.in_plane(k) - a.in_plane(k)) / 3.0
    op = (4.0 * b.out_plane(k) - a.out_plane(k)) / 3.0
    return ip, op
