#!/usr/bin/env python3
"""Independent reference for sagging cables: a sagged-equilibrium FE model of a whole
cable robot (numpy + scipy only; shares no code with the Rust crate).

Model
-----
Each cable is a chain of n corotational two-node truss elements of unstretched length
l0 = L0/n (L0 the cable's UNSTRETCHED length). Element axial force N = EA (l − l0)/l0 with
l the current element length; gravity acts as lumped nodal weights μ|g| l0/2 per element end
(equal to the consistent load of a linear truss under a uniform load) and m g on the
end-effector (a point mass where every cable ends). Anchors are fixed; the end-effector node
is free (or fixed with "end_fixed": a single cable between two supports).

Equilibrium R(x) = Σ_e N_e c_e (±) + f_ext = 0 is solved by Newton with the exact tangent
K_t = Σ_e [(EA/l0) c cᵀ + (N/l)(I − c cᵀ)] on [1 −1; −1 1] (scipy.sparse), a backtracking
line search, from a start on each cable's own elastic catenary (Irvine's closed form solved
here with scipy.optimize given the chord and L0). Element vectors are carried as
d_e = D_e + (u_j − u_i) (D_e from the start, u the nodal displacements) so that the
computed strain keeps full precision even for very stiff cables.

Results: the end-effector's equilibrium position, each cable's end forces (the discrete
chain's element forces are exactly the continuous tension vector at element midpoints, so
the end tension is |N c + (w l0/2) up| at the end-effector, |N c − (w l0/2) up| at the
anchor), the end-effector stiffness (Schur complement of K_t onto its 3 DOF), and the first
natural frequencies of K_t φ = ω² M φ with the consistent mass (μ l0/6)[2I I; I 2I] plus
the end-effector's mass (scipy.sparse.linalg.eigsh in shift-invert mode at σ = 0, or a
dense scipy.linalg.eigh for small models), with each mode's end-effector participation
m |φ_ee|² / (φᵀ M φ).

CLI: sag_reference.py [REQUEST.json] (or the request on stdin); the answer is JSON on
stdout. The request/answer schema is in `describe_schema()` (``--schema`` prints it).
"""

import json
import math
import sys
import time

import numpy as np
import scipy
import scipy.linalg
import scipy.optimize
import scipy.sparse
import scipy.sparse.linalg

# Default elements per cable (the brief's reference resolution).
DEFAULT_ELEMENTS = 160
# Newton stops when max |R| ≤ RESIDUAL_REL × the reference weight (end-effector weight, or
# the cables' weight with a fixed end) ...
RESIDUAL_REL = 1e-10
# ... or, for very stiff cables, ≤ ROUNDING_FLOOR_EPS · ε · max EA: an element force
# EA (l − l0)/l0 carries a rounding error of about ε EA (l measured to ε l), so no iterate
# can do better (only binds when EA exceeds ~1e-10/(16 ε) ≈ 3e4 times the weight).
ROUNDING_FLOOR_EPS = 16.0
# Newton iteration bound (quadratic convergence from the catenary start needs ~3-6).
NEWTON_MAX_ITER = 60
# Line-search halvings before a step is taken anyway (and the stall counter advances).
LINE_SEARCH_MAX = 40
# Largest model solved by the dense generalised eigensolver (otherwise sparse shift-invert).
DENSE_MAX_DOF = 600
# Horizontal span below which a cable is treated as vertical (relative to its length).
VERTICAL_REL = 1e-12


def describe_schema():
    return {
        "request": {
            "anchors_m": "list of [x, y, z] per cable (m)",
            "ee_position_m": "[x, y, z]: the end-effector pose (start of Newton) (m)",
            "ee_mass_kg": "point-mass end-effector (kg); 0 allowed with end_fixed",
            "gravity_m_s2": "[gx, gy, gz] (default [0, 0, -9.81])",
            "ea_n": "EA per cable (N): a number or a list",
            "mu_kg_m": "mass per unstretched length per cable (kg/m): number or list",
            "unstretched_lengths_m": "L0 per cable (m); or instead:",
            "end_tensions_n": "target end-effector-end tensions: L0 is chosen so the "
            "continuous catenaries balance the end-effector at the pose, nearest to "
            "these tensions (relative least squares)",
            "elements": "elements per cable (default 160)",
            "end_fixed": "true: the end node is a fixed support (single-cable checks)",
            "ee_weight_carried": "false: the end-effector's weight is not applied (its mass "
            "still is in the dynamics), as for a scene with weight_carried = false",
            "modes": "number of natural frequencies (default 10; 0 for none)",
            "convergence_levels": "optional list of element counts, e.g. [80, 160, 320]: "
            "solve each, report them and the Richardson extrapolation (order 2) of the "
            "two finest with the observed order from the last three",
            "dense_check": "true: also solve the eigenproblem densely and report the "
            "largest relative difference (small models)",
            "tangent_check": "true: compare K_t with central differences of R",
            "return_nodes": "true: include every node's equilibrium position",
        },
        "answer": {
            "elements, dof": "the (finest) model's size",
            "converged, newton_iterations, residual_history_n, residual_max_n, "
            "residual_tol_n": "Newton: max |R| over the free DOFs per iteration (N)",
            "tangent_asymmetry": "‖K_t − K_tᵀ‖_F / ‖K_t‖_F",
            "ee_position_m, ee_displacement_m": "equilibrium position, and its offset "
            "from the input pose",
            "ee_residual_n": "the end-effector node's residual force (N)",
            "catenary_ee_residual_n": "force balance at the INPUT pose of the continuous "
            "elastic catenaries with these L0 (0 when L0 is consistent with the pose)",
            "stiffness_matrix_n_m, stiffness_principal_n_m": "Schur complement of K_t "
            "onto the end-effector (N/m), its eigenvalues ascending",
            "frequencies_hz, ee_participation": "first `modes` natural frequencies and "
            "each mode's share of kinetic energy in the end-effector mass",
            "eigen": "eigensolver used, negative eigenvalue count, dense_max_rel_diff, "
            "plane_normal_share (single cable: each mode's kinetic energy share normal "
            "to the cable's plane)",
            "cables[i]": "unstretched_length_m, tension_ee_n (at s = L0), "
            "tension_anchor_n (s = 0), h_n (horizontal component), element_force_min_n, "
            "force_on_ee_n, slack, catenary_at_pose (the closed-form start: h_n, "
            "v_anchor_n, tension_ee_n, tension_anchor_n, force_on_ee_n)",
            "levels, richardson": "with convergence_levels: every level's answer; "
            "extrapolated / error_estimate / observed_order of ee_position_m, "
            "stiffness_principal_n_m, tension_ee_n, tension_anchor_n, h_n, "
            "frequencies_hz",
            "chosen": "with end_tensions_n: the unstretched_lengths_m chosen, the "
            "continuous catenaries' end_tensions_n and ee_residual_n at the pose",
            "time_s, wall_time_s, versions": "run times (s) and library versions",
            "error": "only on failure (exit status 2): the reason",
        },
    }


# ---------------------------------------------------------------------------------------
# Elastic catenary (Irvine), in the cable's vertical plane: x horizontal from the anchor
# toward the end, z up; s unstretched arclength from the anchor; V(s) = Va + w s.


def asinh_ratio(d):
    """asinh(d)/d, 1 at d = 0 (series below 1e-4)."""
    if abs(d) < 1e-4:
        return 1.0 - d * d / 6.0 + 3.0 * d**4 / 40.0
    return math.asinh(d) / d


def catenary_point(h, va, s, w, ea):
    """(x, z) at unstretched arclength s of the elastic catenary, cancellation-free."""
    ve = va + w * s
    ta = math.hypot(h, va)
    te = math.hypot(h, ve)
    if h == 0.0:
        x = 0.0
    elif va * ve >= 0.0:
        den = ve * ta + va * te
        q = s / h if den == 0.0 else s * (va + ve) / den
        x = h * s / ea + h * q * asinh_ratio(w * q)
    else:
        delta = (ve * ta - va * te) / (h * h)
        x = h * s / ea + (h / w) * math.asinh(delta)
    tsum = ta + te
    z = s * (va + ve) / (2.0 * ea) + (0.0 if tsum == 0.0 else s * (va + ve) / tsum)
    return x, z


def catenary_jacobian(h, va, s, w, ea):
    """∂(x, z)/∂(H, Va) at s (Irvine's flexibility; only steers Newton)."""
    ve = va + w * s
    ta = math.hypot(h, va)
    te = math.hypot(h, ve)
    x, _ = catenary_point(h, va, s, w, ea)
    dasinh = (x - h * s / ea) / h if h > 0 else 0.0  # = Δasinh / w
    if w > 0:
        dxdh = s / ea + dasinh - (ve / te - va / ta) / w
        dxdv = h * (1.0 / te - 1.0 / ta) / w
        dzdv = s / ea + (ve / te - va / ta) / w
    else:
        t = ta
        dxdh = s / ea + s / t - s * h * h / t**3
        dxdv = -s * h * va / t**3
        dzdv = s / ea + s / t - s * va * va / t**3
    return np.array([[dxdh, dxdv], [dxdv, dzdv]])


def inextensible_guess(span, rise, l0, w):
    """(H, Va) of the inextensible catenary through (span, rise) of length l0, or None."""
    chord2 = l0 * l0 - rise * rise
    if span <= 0 or chord2 <= span * span or w <= 0:
        return None
    target = math.sqrt(chord2)
    g = lambda a: 2 * a * math.sinh(span / (2 * a)) - target
    lo, hi = span / 1000.0, span
    while g(lo) <= 0 or not math.isfinite(g(lo)):
        lo *= 2.0
        if lo >= hi:
            return None
    while g(hi) > 0:
        hi *= 2.0
    a = scipy.optimize.brentq(g, lo, hi, xtol=1e-14 * span, rtol=1e-14)
    mid = math.asinh(rise / (2 * a * math.sinh(span / (2 * a))))
    u1 = mid - span / (2 * a)
    hh = w * a
    return hh, hh * math.sinh(u1)


def solve_catenary(span, rise, l0, w, ea):
    """(H, Va) of the elastic catenary from the anchor to (span, rise) with length l0."""
    chord = math.hypot(span, rise)
    if span <= VERTICAL_REL * max(chord, l0):
        # Vertical: z(L0) = L0 + (Va L0 + w L0²/2)/EA for a taut hanging cable.
        va = ((abs(rise) - l0) * ea / l0 - w * l0 / 2.0) * math.copysign(1.0, rise)
        return 0.0, va
    scale = max(w * l0, ea * abs(chord / l0 - 1.0), 1e-9 * ea)
    guesses = []
    t_taut = ea * (chord / l0 - 1.0)
    if t_taut > 0:
        guesses.append((t_taut * span / chord, t_taut * rise / chord - w * l0 / 2.0))
    ig = inextensible_guess(span, rise, l0, w)
    if ig is not None:
        guesses.append(ig)
    guesses.append((scale, rise / chord * scale - w * l0 / 2.0))
    best = None
    for h0, v0 in guesses:
        sol = _newton_catenary(span, rise, l0, w, ea, h0, v0, scale)
        if sol is not None and (best is None or sol[2] < best[2]):
            best = sol
        if best is not None and best[2] <= 1e-13 * chord:
            break
    if best is None:
        raise RuntimeError(f"catenary: no solution (span {span}, rise {rise}, L0 {l0})")
    return best[0], best[1]


def _newton_catenary(span, rise, l0, w, ea, h, va, scale):
    """Damped Newton on (H, Va); returns (H, Va, |residual|) or None."""
    def res(hh, vv):
        x, z = catenary_point(hh, vv, l0, w, ea)
        return np.array([x - span, z - rise])

    h = max(h, 1e-12 * scale)
    r = res(h, va)
    for _ in range(200):
        nr = np.linalg.norm(r)
        if nr <= 1e-14 * max(span, abs(rise)):
            break
        try:
            step = np.linalg.solve(catenary_jacobian(h, va, l0, w, ea), -r)
        except np.linalg.LinAlgError:
            return None
        alpha = 1.0
        while alpha > 1e-12:
            hn, vn = h + alpha * step[0], va + alpha * step[1]
            if hn > 0:
                rn = res(hn, vn)
                if np.linalg.norm(rn) < nr:
                    break
            alpha *= 0.5
        else:
            break
        h, va, r = hn, vn, rn
    return h, va, float(np.linalg.norm(r))


def catenary_for_end_tension(span, rise, t_end, w, ea, l0_guess):
    """(H, Va, L0) of the elastic catenary to (span, rise) whose end tension is t_end."""
    phi0 = math.atan2(rise, span) + 0.5 * w * l0_guess * math.cos(math.atan2(rise, span)) / t_end

    def res(p):
        phi, l0 = p[0], p[1] * l0_guess
        h, ve = t_end * math.cos(phi), t_end * math.sin(phi)
        x, z = catenary_point(h, ve - w * l0, l0, w, ea)
        return [(x - span) / l0_guess, (z - rise) / l0_guess]

    sol = scipy.optimize.root(res, [phi0, 1.0], method="hybr", options={"xtol": 1e-15})
    phi, l0 = sol.x[0], sol.x[1] * l0_guess
    if np.max(np.abs(res(sol.x))) > 1e-12:
        raise RuntimeError(f"catenary for end tension {t_end} N did not converge")
    h, ve = t_end * math.cos(phi), t_end * math.sin(phi)
    return h, ve - w * l0, l0


# ---------------------------------------------------------------------------------------
# The robot and its FE model


def per_cable(value, m, name):
    if isinstance(value, (int, float)):
        return np.full(m, float(value))
    arr = np.asarray(value, dtype=float)
    if arr.shape != (m,):
        raise ValueError(f"{name}: expected a number or {m} values")
    return arr


class Robot:
    """The request, validated: anchors, pose, masses, cables."""

    def __init__(self, req):
        self.anchors = np.asarray(req["anchors_m"], dtype=float).reshape(-1, 3)
        self.m = len(self.anchors)
        self.ee = np.asarray(req["ee_position_m"], dtype=float).reshape(3)
        self.mass = float(req.get("ee_mass_kg", 0.0))
        self.g = np.asarray(req.get("gravity_m_s2", [0.0, 0.0, -9.81]), dtype=float)
        self.gnorm = float(np.linalg.norm(self.g))
        self.up = -self.g / self.gnorm
        self.ea = per_cable(req["ea_n"], self.m, "ea_n")
        self.mu = per_cable(req["mu_kg_m"], self.m, "mu_kg_m")
        self.end_fixed = bool(req.get("end_fixed", False))
        self.weight_carried = bool(req.get("ee_weight_carried", True))
        if "unstretched_lengths_m" in req:
            self.l0 = per_cable(req["unstretched_lengths_m"], self.m, "unstretched_lengths_m")
        else:
            self.l0 = None
        for name, arr in (("ea_n", self.ea), ("mu_kg_m", self.mu)):
            if not np.all(np.isfinite(arr)) or np.any(arr < 0) or (name == "ea_n" and np.any(arr <= 0)):
                raise ValueError(f"{name}: must be finite and positive")
        if self.l0 is not None and (not np.all(np.isfinite(self.l0)) or np.any(self.l0 <= 0)):
            raise ValueError("unstretched_lengths_m: must be finite and positive")
        if not (np.all(np.isfinite(self.anchors)) and np.all(np.isfinite(self.ee))):
            raise ValueError("anchors_m, ee_position_m: must be finite")
        if not (math.isfinite(self.gnorm) and self.gnorm > 0):
            raise ValueError("gravity_m_s2: must be finite and non-zero")
        if not math.isfinite(self.mass) or self.mass < 0:
            raise ValueError("ee_mass_kg: must be finite and ≥ 0")
        if not self.end_fixed and self.mass <= 0:
            raise ValueError("ee_mass_kg must be > 0 with a free end-effector")

    def plane(self, i):
        """(horizontal unit h, span, rise) of cable i's vertical plane at the pose."""
        chord = self.ee - self.anchors[i]
        rise = float(chord @ self.up)
        horiz = chord - rise * self.up
        span = float(np.linalg.norm(horiz))
        if span > VERTICAL_REL * np.linalg.norm(chord):
            return horiz / span, span, rise
        basis = np.eye(3)[np.argmin(np.abs(self.up))]
        h = basis - (basis @ self.up) * self.up
        return h / np.linalg.norm(h), 0.0, rise

    def weight_ref(self):
        """Residual scale: the end-effector's weight, or the cables' weight (fixed end)."""
        if not self.end_fixed:
            return self.mass * self.gnorm
        return float(np.sum(self.mu * self.l0)) * self.gnorm


def choose_l0(robot, targets):
    """L0 per cable so the continuous catenaries balance the end-effector at the pose, with
    end tensions nearest to `targets` in relative least squares (Gauss-Newton on the KKT
    system of min Σ((T_i − T*_i)/T*_i)² subject to Σ f_i(T) + m g = 0)."""
    m = robot.m
    w = robot.mu * robot.gnorm
    targets = np.asarray(targets, dtype=float)
    planes = [robot.plane(i) for i in range(m)]
    l0_guess = np.array([math.hypot(p[1], p[2]) for p in planes])

    def force(i, t):
        """Force of cable i on the end-effector with end tension t, and its L0."""
        h, span, rise = planes[i]
        hh, va, l0 = catenary_for_end_tension(span, rise, t, w[i], robot.ea[i], l0_guess[i])
        return -(hh * h + (va + w[i] * l0) * robot.up), l0

    t = targets.copy()
    weight = robot.mass * robot.g if robot.weight_carried else np.zeros(3)
    wt2 = targets**2
    for _ in range(50):
        fl = [force(i, t[i]) for i in range(m)]
        r = sum(f for f, _ in fl) + weight
        l0s = np.array([l0 for _, l0 in fl])
        if np.max(np.abs(r)) <= 1e-12 * robot.mass * robot.gnorm:
            return l0s, t, r
        a = np.zeros((3, m))
        for i in range(m):
            dt = 1e-6 * t[i]
            a[:, i] = (force(i, t[i] + dt)[0] - force(i, t[i] - dt)[0]) / (2 * dt)
        lam = np.linalg.solve((a * wt2) @ a.T, -r - a @ (targets - t))
        t = targets + wt2 * (a.T @ lam)
    raise RuntimeError(f"choose_l0: no balance, residual {np.max(np.abs(r))} N")


class Model:
    """The assembled chain model: nodes (0 = end-effector, then per cable its anchor and
    interior nodes), elements anchor → end-effector, the free DOFs (interior first, the
    end-effector's 3 last unless fixed)."""

    def __init__(self, robot, n):
        self.robot, self.n = robot, n
        m = robot.m
        w = robot.mu * robot.gnorm
        nodes = [robot.ee.copy()]
        fixed = [robot.end_fixed]
        elems, self.cable_elems, self.guess, self.node_ids = [], [], [], []
        for i in range(m):
            h, span, rise = robot.plane(i)
            hh, va = solve_catenary(span, rise, robot.l0[i], w[i], robot.ea[i])
            self.guess.append((hh, va))
            ids = [len(nodes)]
            nodes.append(robot.anchors[i].copy())
            fixed.append(True)
            for j in range(1, n):
                x, z = catenary_point(hh, va, robot.l0[i] * j / n, w[i], robot.ea[i])
                ids.append(len(nodes))
                nodes.append(robot.anchors[i] + x * h + z * robot.up)
                fixed.append(False)
            ids.append(0)
            self.node_ids.append(np.array(ids))
            first = len(elems)
            elems += [(ids[j], ids[j + 1], i) for j in range(n)]
            self.cable_elems.append((first, len(elems) - 1))
        self.x0 = np.array(nodes)
        self.fixed = np.array(fixed)
        el = np.array(elems)
        self.a, self.b, self.cab = el[:, 0], el[:, 1], el[:, 2]
        self.ea = robot.ea[self.cab]
        self.l0 = robot.l0[self.cab] / n
        self.mu = robot.mu[self.cab]
        self.d0 = self.x0[self.b] - self.x0[self.a]
        # DOF numbering: interior nodes first, the end-effector last.
        nn = len(nodes)
        self.dof = -np.ones(nn, dtype=int)
        order = [k for k in range(1, nn) if not fixed[k]] + ([] if robot.end_fixed else [0])
        self.dof[order] = 3 * np.arange(len(order))
        self.ndof = 3 * len(order)
        # Lumped nodal weights μ|g| l0/2 per element end, plus the end-effector's m g.
        self.f_ext = np.zeros((nn, 3))
        half = (self.mu * self.l0 / 2.0)[:, None] * robot.g
        np.add.at(self.f_ext, self.a, half)
        np.add.at(self.f_ext, self.b, half)
        if robot.weight_carried:
            self.f_ext[0] += robot.mass * robot.g
        self.u = np.zeros((nn, 3))

    def element_state(self, u):
        d = self.d0 + u[self.b] - u[self.a]
        l = np.linalg.norm(d, axis=1)
        c = d / l[:, None]
        nf = self.ea * (l - self.l0) / self.l0
        return l, c, nf

    def nodal_residual(self, u):
        """R per node: element forces on the nodes plus the external loads, N."""
        _, c, nf = self.element_state(u)
        fc = nf[:, None] * c
        r = self.f_ext.copy()
        np.add.at(r, self.a, fc)
        np.add.at(r, self.b, -fc)
        return r

    def residual(self, u):
        r = self.nodal_residual(u)
        out = np.zeros(self.ndof)
        free = self.dof >= 0
        idx = self.dof[free][:, None] + np.arange(3)
        out[idx.ravel()] = r[free].ravel()
        return out

    def _assemble(self, blocks, diag_extra=None):
        """Sparse matrix from per-element 3 × 3 blocks B on [1 −1; −1 1] (sign = +1
        off-diagonal for mass: pass (diag, off) pairs)."""
        bd, bo = blocks
        rows, cols, vals = [], [], []
        for (p, q, blk) in ((self.a, self.a, bd), (self.b, self.b, bd), (self.a, self.b, bo), (self.b, self.a, bo)):
            dp, dq = self.dof[p], self.dof[q]
            keep = (dp >= 0) & (dq >= 0)
            ii = dp[keep][:, None, None] + np.arange(3)[None, :, None]
            jj = dq[keep][:, None, None] + np.arange(3)[None, None, :]
            rows.append(np.broadcast_to(ii, (keep.sum(), 3, 3)).ravel())
            cols.append(np.broadcast_to(jj, (keep.sum(), 3, 3)).ravel())
            vals.append(blk[keep].ravel())
        if diag_extra is not None:
            rows.append(diag_extra[0])
            cols.append(diag_extra[0])
            vals.append(diag_extra[1])
        mat = scipy.sparse.coo_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.ndof, self.ndof),
        )
        return mat.tocsc()

    def tangent(self, u):
        l, c, nf = self.element_state(u)
        cc = c[:, :, None] * c[:, None, :]
        k = (self.ea / self.l0)[:, None, None] * cc + (nf / l)[:, None, None] * (np.eye(3) - cc)
        return self._assemble((k, -k))

    def mass(self):
        eye = np.eye(3)[None]
        mm = (self.mu * self.l0 / 6.0)[:, None, None] * eye
        extra = None
        if not self.robot.end_fixed:
            e = self.dof[0] + np.arange(3)
            extra = (e, np.full(3, self.robot.mass))
        return self._assemble((2.0 * mm, mm), extra)

    def free_vector(self, du):
        """Nodal (nn × 3) displacement from a free-DOF vector."""
        out = np.zeros_like(self.u)
        free = self.dof >= 0
        out[free] = du[(self.dof[free][:, None] + np.arange(3))]
        return out

    def tolerance(self):
        """Newton's stopping residual, N (RESIDUAL_REL, or the rounding floor)."""
        floor = ROUNDING_FLOOR_EPS * np.finfo(float).eps * float(np.max(self.ea))
        return max(RESIDUAL_REL * self.robot.weight_ref(), floor)

    def solve(self):
        """Newton with backtracking; returns (converged, iterations, max|R| history)."""
        tol = self.tolerance()
        r = self.residual(self.u)
        hist = [float(np.max(np.abs(r)))]
        for it in range(NEWTON_MAX_ITER):
            if hist[-1] <= tol:
                return True, it, hist
            kt = self.tangent(self.u)
            du = self.free_vector(scipy.sparse.linalg.spsolve(kt, r))
            nr = np.linalg.norm(r)
            alpha, improved = 1.0, False
            for _ in range(LINE_SEARCH_MAX):
                rn = self.residual(self.u + alpha * du)
                if np.linalg.norm(rn) < nr:
                    improved = True
                    break
                alpha *= 0.5
            if not improved:  # the rounding floor: no step reduces ‖R‖
                return hist[-1] <= tol, it, hist
            self.u = self.u + alpha * du
            r = rn
            hist.append(float(np.max(np.abs(r))))
        return hist[-1] <= tol, NEWTON_MAX_ITER, hist


# ---------------------------------------------------------------------------------------
# Results


def cable_results(model):
    """Per cable: end forces from the end elements (exact continuous tension vectors at the
    element midpoints ± the half-element weight), H, and the catenary start's values."""
    robot = model.robot
    l, c, nf = model.element_state(model.u)
    w = robot.mu * robot.gnorm
    out = []
    for i, (first, last) in enumerate(model.cable_elems):
        half = w[i] * robot.l0[i] / model.n / 2.0 * robot.up
        f_end = nf[last] * c[last] + half  # tension vector at s = L0, toward increasing s
        f_anchor = nf[first] * c[first] - half  # tension vector at s = 0
        h_vec = f_end - (f_end @ robot.up) * robot.up
        hh, va = model.guess[i]
        ve = va + w[i] * robot.l0[i]
        hunit, _, _ = robot.plane(i)
        out.append({
            "unstretched_length_m": float(robot.l0[i]),
            "tension_ee_n": float(np.linalg.norm(f_end)),
            "tension_anchor_n": float(np.linalg.norm(f_anchor)),
            "element_force_min_n": float(np.min(nf[first:last + 1])),
            "h_n": float(np.linalg.norm(h_vec)),
            "force_on_ee_n": (-f_end).tolist(),
            "slack": bool(np.min(nf[first:last + 1]) <= 0.0),
            "catenary_at_pose": {
                "h_n": hh,
                "v_anchor_n": va,
                "tension_ee_n": math.hypot(hh, ve),
                "tension_anchor_n": math.hypot(hh, va),
                "force_on_ee_n": (-(hh * hunit + ve * robot.up)).tolist(),
            },
        })
    return out


def ee_stiffness(model, kt):
    """Schur complement of K_t onto the end-effector's 3 DOF, N/m."""
    nd = model.ndof
    kii = kt[: nd - 3, : nd - 3].tocsc()
    kie = kt[: nd - 3, nd - 3:].toarray()
    kee = kt[nd - 3:, nd - 3:].toarray()
    s = kee - kie.T @ scipy.sparse.linalg.splu(kii).solve(kie)
    return 0.5 * (s + s.T)


def natural_modes(model, kt, k, dense_check):
    """First k eigenpairs of K_t φ = λ M φ: frequencies, end-effector participations."""
    mm = model.mass()
    k = min(k, model.ndof - 1)
    info = {}
    if model.ndof <= DENSE_MAX_DOF:
        lam, vec = scipy.linalg.eigh(kt.toarray(), mm.toarray(), subset_by_index=[0, k - 1])
        info["eigensolver"] = "dense eigh"
    else:
        lam, vec = scipy.sparse.linalg.eigsh(kt, k=k, M=mm, sigma=0.0, which="LM", tol=0.0)
        order = np.argsort(lam)
        lam, vec = lam[order], vec[:, order]
        info["eigensolver"] = "eigsh shift-invert sigma=0"
        if dense_check:
            ld = scipy.linalg.eigh(kt.toarray(), mm.toarray(), eigvals_only=True, subset_by_index=[0, k - 1])
            info["dense_max_rel_diff"] = float(np.max(np.abs(lam - ld) / np.abs(ld)))
    part, normal = [], []
    robot = model.robot
    hunit, _, _ = robot.plane(0)
    nunit = np.cross(hunit, robot.up)
    for j in range(len(lam)):
        phi = vec[:, j]
        norm = phi @ (mm @ phi)
        part.append(0.0 if robot.end_fixed else float(robot.mass * np.sum(phi[-3:] ** 2) / norm))
        # M acts alike on x, y, z: the kinetic energy splits exactly by direction.
        pn = (phi.reshape(-1, 3) @ nunit)[:, None] * nunit
        normal.append(float(pn.ravel() @ (mm @ pn.ravel()) / norm))
    freqs = np.sqrt(np.maximum(lam, 0.0)) / (2 * math.pi)
    info["negative_eigenvalues"] = int(np.sum(lam < 0))
    if robot.m == 1:
        info["plane_normal_share"] = normal
    return freqs.tolist(), part, info


def tangent_check(model, kt):
    """Largest relative difference of K_t v and central differences of R along a random v."""
    rng = np.random.default_rng(1)
    v = rng.standard_normal(model.ndof)
    h = 1e-6 * max(1e-3, float(np.max(np.abs(model.d0)))) / max(1.0, float(np.linalg.norm(v, np.inf)))
    vn = model.free_vector(v)
    fd = -(model.residual(model.u + h * vn) - model.residual(model.u - h * vn)) / (2 * h)
    kv = kt @ v
    return float(np.max(np.abs(fd - kv)) / np.max(np.abs(kv)))


def solve_level(robot, n, req):
    t0 = time.perf_counter()
    model = Model(robot, n)
    t1 = time.perf_counter()
    converged, iters, hist = model.solve()
    t2 = time.perf_counter()
    kt = model.tangent(model.u)
    asym = scipy.sparse.linalg.norm(kt - kt.T) / scipy.sparse.linalg.norm(kt)
    res_nodes = model.nodal_residual(model.u)
    ans = {
        "elements": n,
        "dof": model.ndof,
        "converged": bool(converged),
        "newton_iterations": iters,
        "residual_history_n": hist,
        "residual_max_n": hist[-1],
        "residual_tol_n": model.tolerance(),
        "tangent_asymmetry": float(asym),
        "cables": cable_results(model),
    }
    if not robot.end_fixed:
        ee = model.x0[0] + model.u[0]
        ans["ee_position_m"] = ee.tolist()
        ans["ee_displacement_m"] = (ee - robot.ee).tolist()
        ans["ee_residual_n"] = res_nodes[0].tolist()
        s = ee_stiffness(model, kt)
        ans["stiffness_matrix_n_m"] = s.tolist()
        ans["stiffness_principal_n_m"] = np.linalg.eigvalsh(s).tolist()
        cat = sum(np.array(c["catenary_at_pose"]["force_on_ee_n"]) for c in ans["cables"])
        weight = robot.mass * robot.g if robot.weight_carried else np.zeros(3)
        ans["catenary_ee_residual_n"] = (cat + weight).tolist()
    t3 = time.perf_counter()
    k = int(req.get("modes", 10))
    if k > 0:
        f, p, info = natural_modes(model, kt, k, bool(req.get("dense_check", False)))
        ans["frequencies_hz"], ans["ee_participation"] = f, p
        ans["eigen"] = info
    t4 = time.perf_counter()
    if req.get("tangent_check", False):
        ans["tangent_fd_rel_diff"] = tangent_check(model, kt)
    if req.get("return_nodes", False):
        ans["nodes_m"] = [(model.x0[ids] + model.u[ids]).tolist() for ids in model.node_ids]
    ans["time_s"] = {"build": t1 - t0, "newton": t2 - t1, "stiffness": t3 - t2, "modes": t4 - t3, "total": t4 - t0}
    return ans


def richardson(levels):
    """Order-2 extrapolation of the two finest levels, observed order from the last three."""
    def numbers(ans):
        out = {}
        if "ee_position_m" in ans:
            out["ee_position_m"] = ans["ee_position_m"]
            out["stiffness_principal_n_m"] = ans["stiffness_principal_n_m"]
        out["tension_ee_n"] = [c["tension_ee_n"] for c in ans["cables"]]
        out["tension_anchor_n"] = [c["tension_anchor_n"] for c in ans["cables"]]
        out["h_n"] = [c["h_n"] for c in ans["cables"]]
        if "frequencies_hz" in ans:
            out["frequencies_hz"] = ans["frequencies_hz"]
        return {k: np.asarray(v, dtype=float) for k, v in out.items()}

    nums = [numbers(a) for a in levels]
    ns = [a["elements"] for a in levels]
    fine, coarse = nums[-1], nums[-2]
    ratio = ns[-1] / ns[-2]
    out = {"extrapolated": {}, "error_estimate": {}, "observed_order": {}}
    for key in fine:
        m = min(len(fine[key]), len(coarse[key]))
        f, c = fine[key][:m], coarse[key][:m]
        ext = f + (f - c) / (ratio**2 - 1)
        out["extrapolated"][key] = ext.tolist()
        out["error_estimate"][key] = np.abs(ext - f).tolist()
        if len(nums) >= 3:
            cc = nums[-3][key][:m]
            with np.errstate(divide="ignore", invalid="ignore"):
                p = np.log(np.abs((c - cc) / (f - c))) / math.log(ratio)
            out["observed_order"][key] = [float(x) if np.isfinite(x) else None for x in p]
    return out


def solve(req):
    robot = Robot(req)
    t0 = time.perf_counter()
    extra = {}
    if robot.l0 is None:
        if "end_tensions_n" not in req:
            raise ValueError("give unstretched_lengths_m or end_tensions_n")
        l0, t, r = choose_l0(robot, per_cable(req["end_tensions_n"], robot.m, "end_tensions_n"))
        robot.l0 = l0
        extra["chosen"] = {"unstretched_lengths_m": l0.tolist(), "end_tensions_n": t.tolist(), "ee_residual_n": r.tolist()}
    levels = req.get("convergence_levels")
    n = int(req.get("elements", DEFAULT_ELEMENTS))
    if levels:
        answers = [solve_level(robot, int(k), req) for k in levels]
        ans = dict(answers[-1])
        ans["levels"] = answers
        ans["richardson"] = richardson(answers)
    else:
        ans = solve_level(robot, n, req)
    ans.update(extra)
    ans["versions"] = {"numpy": np.__version__, "scipy": scipy.__version__, "python": sys.version.split()[0]}
    ans["wall_time_s"] = time.perf_counter() - t0
    return ans


def main(argv):
    if len(argv) > 1 and argv[1] == "--schema":
        json.dump(describe_schema(), sys.stdout, indent=1)
        return 0
    text = open(argv[1]).read() if len(argv) > 1 and argv[1] != "-" else sys.stdin.read()
    req = json.loads(text)
    batch = isinstance(req, list)
    try:
        out = [solve(r) for r in req] if batch else solve(req)
    except (ValueError, RuntimeError, KeyError) as e:
        json.dump({"error": f"{type(e).__name__}: {e}"}, sys.stdout)
        sys.stdout.write("\n")
        return 2
    json.dump(out, sys.stdout)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
