"""The cone programs in Clarabel's standard form, assembled directly as sparse CSC matrices.

Clarabel solves  min ½ xᵀPx + qᵀx  s.t.  Ax + s = b,  s ∈ 𝒦.  One program's structure (which
fingers touch, which of them slide, which have a target, which table corners touch, and whether
the wrench equality has a slack) is a :class:`Layout`; for a fixed layout only the wrench rows of
A, the right-hand side b and the linear cost q change from frame to frame, so one solver per layout
is built once and then updated in place (``solver.update``, which requires presolve to be off
and structural zeros to be kept).

Variables, in order (eq. 5 and 7):
    nominal part of each contact: (f, g, h) for a static contact, f for a sliding one;
    internal part of each contact (decomposition and reconstruction only), the same way;
    slack σ (6) on the nominal wrench equality (least-violation programs only).
A static contact's force is f n + g t_x + h t_y (eq. 2); a sliding one's is f (n + μ s), with s
the unit sliding direction: its friction lies on the cone's surface (eq. 3 as an equality).

Rows, in order:
    zero cone: Σ_c W_c x_c^(n) + σ = w (6 rows, eq. 1 and 8); Σ_c W_c x_c^(i) = 0 (6 rows, eq. 8);
    second-order cones: (μ f, g, h) of each static contact's nominal part, then of each static
        contact's total force (nominal + internal);
    non-negative cone: f of each sliding or frictionless contact, nominal part then total.
"""

from __future__ import annotations

from dataclasses import dataclass

import clarabel
import numpy as np
import scipy.sparse as sp

from fsv.linalg import mm

#: Slots of a contact's column bank: the directions n, t_x, t_y and the kinetic direction n + μ s.
STATIC_SLOTS = (0, 1, 2)
SLIDING_SLOTS = (3,)

OK = (clarabel.SolverStatus.Solved, clarabel.SolverStatus.AlmostSolved)


@dataclass(frozen=True)
class Layout:
    """The structure of one frame's program.

    Attributes:
        kind: "nominal", "decomposition" or "reconstruction".
        fingers: Active finger indices.
        sliding: Per active finger, whether it slides.
        fitted: Per active finger, whether it has a target (measured or predicted normal force).
        corners: Active table corner indices (0..7).
        slack: Whether the nominal wrench equality has a (penalised) slack.
    """

    kind: str
    fingers: tuple
    sliding: tuple
    fitted: tuple
    corners: tuple
    slack: bool


@dataclass(frozen=True)
class Weights:
    """Coefficients of a program that are constant over a sequence.

    Attributes:
        finger_friction: μ between finger and object.
        table_friction: μ between object and table.
        table_weight: Weight of the table forces' squared norms in the cost.
        slack_weight: Weight ρ of ||σ||² in least-violation programs.
        regularization: Weight ε of the squared internal components that no target fixes.
        max_iter: Interior-point iteration limit.
    """

    finger_friction: float
    table_friction: float
    table_weight: float
    slack_weight: float
    regularization: float
    max_iter: int


class Program:
    """One layout's cone program and its Clarabel solver, re-used across frames by update."""

    def __init__(self, layout: Layout, weights: Weights, num_fingers: int):
        self.layout = layout
        self.num_fingers = K = num_fingers
        internal = layout.kind != "nominal"
        contacts = _Contacts.of(layout, weights, K)
        cols = _Columns.of(contacts, internal, layout.slack)
        zero_rows, soc, nonneg = _cone_rows(contacts, cols, internal)
        n, num_w = cols.n, cols.num_w
        m = zero_rows + 3 * len(soc) + len(nonneg)
        A, mask = _constraint_matrix(m, n, cols, zero_rows, soc, nonneg)
        cj, ri = np.nonzero(mask.T)  # column-major order = CSC order
        self._A_rows, self._A_cols = ri, cj
        self._A_data0 = A[ri, cj]
        indptr = np.searchsorted(cj, np.arange(n + 1))
        self._A_indices, self._A_indptr = ri.astype(np.int64), indptr.astype(np.int64)
        # The 6 wrench entries of each wrench column come first in that column.
        self._wpos = (indptr[:num_w, None] + np.arange(6)).ravel()
        self._gather = np.asarray(cols.gather, dtype=np.int64)
        self.cones = [clarabel.ZeroConeT(zero_rows)] + [clarabel.SecondOrderConeT(3)] * len(soc)
        if nonneg:
            self.cones.append(clarabel.NonnegativeConeT(len(nonneg)))
        self.m, self.n = m, n
        P, self._q_fit = _cost_matrix(layout, weights, contacts, cols, internal)
        self._P = sp.csc_matrix(np.triu(P))
        self._S = _unpacking(layout, cols, K)
        self._num_w = num_w
        self._q = np.zeros(n)
        self._settings = _settings(layout, weights, internal)
        self._solver = None

    def solve(self, bank: np.ndarray, wrench: np.ndarray, target: np.ndarray) -> tuple:
        """Solves the program for one frame.

        Args:
            bank: Direction columns of the frame, shape (K + 8, 4, 6): per contact and slot the
                wrench [d, p x d] of a unit force along direction d at the contact point p.
            wrench: Required wrench, object frame, shape (6,).
            target: Per finger the target normal force (decomposition: measured total; reconstruction:
                predicted internal), shape (K,); only the fitted fingers' entries are read.

        Returns:
            ``(forces, status, objective, iterations)``: forces shape (2K + 16, 3) stacking the
            nominal finger forces (K), the internal finger forces (K), the nominal table corner
            forces (8) and the internal ones (8), zero where absent; Clarabel's status; the cost
            with its constant term [N^2]; the number of interior-point iterations.
        """
        return self.run(self.assemble(bank[None], wrench[None], target[None])[0])

    def assemble(self, bank: np.ndarray, wrench: np.ndarray, target: np.ndarray) -> list:
        """The solver data of F frames at once (one NumPy pass for all of them).

        Args:
            bank: Direction columns per frame, shape (F, K + 8, 4, 6) (see :meth:`solve`).
            wrench: Required wrench per frame, object frame, shape (F, 6).
            target: Target normal force per frame and finger, shape (F, K) (see :meth:`solve`).

        Returns:
            Per frame the input of :meth:`run`: the values of A (CSC order), b and q (None when
            the program has no target) as Python lists, which Clarabel's update reads several
            times faster than arrays; the cost's constant term [N^2]; and the directions of the
            wrench columns, shape (num_w, 3).
        """
        F = bank.shape[0]
        cols = bank.reshape(F, -1, 6)[:, self._gather]  # (F, num_w, 6)
        data = np.repeat(self._A_data0[None], F, axis=0)
        data[:, self._wpos] = cols.reshape(F, -1)
        b = np.zeros((F, self.m))
        b[:, :6] = wrench
        q = np.zeros((F, self.n))
        const = np.zeros(F)
        for k, js in self._q_fit:
            q[:, js] = -2.0 * target[:, k, None]
            const += target[:, k] ** 2
        qs = q.tolist() if self._q_fit else [None] * F
        return list(zip(data.tolist(), b.tolist(), qs, const.tolist(), cols[:, :, :3]))

    def run(self, frame: tuple) -> tuple:
        """Solves the program for one frame assembled by :meth:`assemble`; returns as :meth:`solve`."""
        data, b, q, const, dirs = frame
        if self._solver is None:
            A = sp.csc_matrix((np.array(data), self._A_indices, self._A_indptr), shape=(self.m, self.n))
            q0 = self._q if q is None else np.array(q)
            self._solver = clarabel.DefaultSolver(self._P, q0, A, np.array(b), self.cones, self._settings)
        elif q is None:
            self._solver.update(A=data, b=b)
        else:
            self._solver.update(A=data, b=b, q=q)
        sol = self._solver.solve()
        x = np.array(sol.x[: self._num_w])
        forces = mm(self._S, x[:, None] * dirs)
        return forces, sol.status, sol.obj_val + const, sol.iterations


TOL_GAP_REL = 1e-12
"""Relative duality-gap tolerance: off in effect. The programs stop on the absolute gap only: the
cost is strongly convex with modulus >= 1 in the forces (N^2), so a gap below Clarabel's default
1e-8 N^2 puts the forces within 1e-4 N of the optimum; a relative gap would loosen that bound with
the grip's magnitude."""

INTERNAL_TOL_GAP_ABS = 1e-11
"""Absolute duality-gap tolerance of the decomposition and reconstruction programs [N^2]: the
internal components that only the small regularisation fixes have a flat cost, and a gap of g moves
them by about sqrt(g / regularization), so their gap is closed further."""

INTERNAL_TOL_FEAS = 1e-10
"""Feasibility tolerance of the decomposition and reconstruction programs (Clarabel's default 1e-8)."""


@dataclass(frozen=True)
class _Contacts:
    """A layout's contacts, fingers first, then table corners: bank rows (finger k -> k, corner j
    -> K + j), sliding flags, friction coefficients and cost weights."""

    rows: list
    slides: list
    mus: list
    wts: list

    @staticmethod
    def of(layout: Layout, weights: Weights, K: int) -> "_Contacts":
        return _Contacts(rows=[k for k in layout.fingers] + [K + j for j in layout.corners],
                         slides=list(layout.sliding) + [False] * len(layout.corners),
                         mus=[weights.finger_friction] * len(layout.fingers) + [weights.table_friction] * len(layout.corners),
                         wts=[1.0] * len(layout.fingers) + [weights.table_weight] * len(layout.corners))


@dataclass(frozen=True)
class _Columns:
    """The program's variables: per contact its nominal (``nominal``) and internal (``internal``)
    column indices; per wrench column its flat bank index (``gather``) and its contact (``owner``,
    ``-1 - contact`` for an internal part); the slack's columns; ``num_w`` wrench columns of ``n``."""

    nominal: list
    internal: list
    gather: list
    owner: list
    slack: list
    num_w: int
    n: int

    @staticmethod
    def of(contacts: _Contacts, internal: bool, slack: bool) -> "_Columns":
        cols_n, cols_i, gather, owner = [], [], [], []
        n = 0
        for c, (r, sl) in enumerate(zip(contacts.rows, contacts.slides)):
            slots = SLIDING_SLOTS if sl else STATIC_SLOTS
            cols_n.append(list(range(n, n + len(slots))))
            gather += [4 * r + s for s in slots]
            owner += [c] * len(slots)
            n += len(slots)
        if internal:
            for c, sl in enumerate(contacts.slides):
                slots = SLIDING_SLOTS if sl else STATIC_SLOTS
                cols_i.append(list(range(n, n + len(slots))))
                gather += [4 * contacts.rows[c] + s for s in slots]
                owner += [-1 - c] * len(slots)
                n += len(slots)
        num_w = n
        slack_cols = list(range(n, n + 6)) if slack else []
        return _Columns(cols_n, cols_i, gather, owner, slack_cols, num_w, n + len(slack_cols))


def _cone_rows(contacts: _Contacts, cols: _Columns, internal: bool) -> tuple:
    """``(zero rows, second-order cone blocks, non-negative rows)``; each row a list of (column, coefficient)."""
    slides, mus = contacts.slides, contacts.mus
    zero_rows = 12 if internal else 6
    soc, nonneg = [], []
    for c, cn in enumerate(cols.nominal):
        if not slides[c]:
            f, g, h = cn
            soc.append([[(f, -mus[c])], [(g, -1.0)], [(h, -1.0)]])
    if internal:
        for c, ci in enumerate(cols.internal):
            if not slides[c]:
                (fn, gn, hn), (fi, gi, hi) = cols.nominal[c], ci
                soc.append([[(fn, -mus[c]), (fi, -mus[c])], [(gn, -1.0), (gi, -1.0)], [(hn, -1.0), (hi, -1.0)]])
    for c, cn in enumerate(cols.nominal):
        if slides[c] or mus[c] == 0:
            nonneg.append([(cn[0], -1.0)])
    if internal:
        for c, ci in enumerate(cols.internal):
            if slides[c] or mus[c] == 0:
                nonneg.append([(cols.nominal[c][0], -1.0), (ci[0], -1.0)])
    return zero_rows, soc, nonneg


def _constraint_matrix(m: int, n: int, cols: _Columns, zero_rows: int, soc: list, nonneg: list) -> tuple:
    """A's constant entries (m, n) and its structure (every entry kept, the wrench rows included)."""
    A = np.zeros((m, n))
    mask = np.zeros((m, n), bool)
    for j in range(cols.num_w):
        r0 = 0 if cols.owner[j] >= 0 else 6
        mask[r0 : r0 + 6, j] = True
    for i, j in enumerate(cols.slack):
        A[i, j] = 1.0
        mask[i, j] = True
    row = zero_rows
    for block in soc:
        for entries in block:
            for j, v in entries:
                A[row, j] = v
                mask[row, j] = True
            row += 1
    for entries in nonneg:
        for j, v in entries:
            A[row, j] = v
            mask[row, j] = True
        row += 1
    return A, mask


def _cost_matrix(layout: Layout, weights: Weights, contacts: _Contacts, cols: _Columns, internal: bool) -> tuple:
    """The cost's P (n, n): Σ w_c ||F_c^(n)||² for the nominal parts, the targets' squares and the
    regularisation; and per fitted finger ``(finger index, columns that carry -2 * target)``."""
    n = cols.n
    P = np.zeros((n, n))
    for c, cn in enumerate(cols.nominal):
        scale = 1.0 + contacts.mus[c] ** 2 if contacts.slides[c] else 1.0
        for j in cn:
            P[j, j] += 2.0 * contacts.wts[c] * scale
    q_fit = []
    if internal:
        eps = weights.regularization
        nf = len(layout.fingers)
        for c, ci in enumerate(cols.internal):
            fn, fi = cols.nominal[c][0], ci[0]
            for j in ci[1:]:
                P[j, j] += 2.0 * eps
            if c >= nf:  # a table corner: spreading the reaction over the corners is cheap
                P[fi, fi] += 2.0 * eps * weights.table_weight
            elif not layout.fitted[c]:
                P[fi, fi] += 2.0 * eps
            elif layout.kind == "decomposition":  # (f_n + f_i - target)^2
                P[fn, fn] += 2.0
                P[fi, fi] += 2.0
                P[fn, fi] += 2.0
                P[fi, fn] += 2.0
                q_fit.append((layout.fingers[c], [fn, fi]))
            else:  # reconstruction: (f_i - target)^2
                P[fi, fi] += 2.0
                q_fit.append((layout.fingers[c], [fi]))
    for j in cols.slack:
        P[j, j] = 2.0 * weights.slack_weight
    return P, q_fit


def _unpacking(layout: Layout, cols: _Columns, K: int) -> np.ndarray:
    """The matrix (2K + 16, wrench columns) that maps x * direction (per wrench column) to the K
    nominal and the K internal finger forces, then the 8 nominal and the 8 internal table corner forces."""
    S = np.zeros((2 * K + 16, cols.num_w))
    nf = len(layout.fingers)
    for j, o in enumerate(cols.owner):
        c, part = (o, 0) if o >= 0 else (-1 - o, 1)
        if c < nf:
            S[part * K + layout.fingers[c], j] = 1.0
        else:
            S[2 * K + part * 8 + layout.corners[c - nf], j] = 1.0
    return S


def _settings(layout: Layout, weights: Weights, internal: bool):
    """Clarabel's settings for a layout: presolve off and structural zeros kept (``solver.update``)."""
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.presolve_enable = False
    settings.input_sparse_dropzeros = False
    settings.max_iter = int(weights.max_iter)
    # Iterative refinement costs a fifth of a solve and buys digits the exact programs do not
    # need (their Newton–Euler residual stays near 1e-9 N); the heavily weighted slack of the
    # least-violation programs makes their KKT systems worse conditioned, so they keep it.
    settings.iterative_refinement_enable = bool(layout.slack) or internal
    settings.tol_gap_rel = TOL_GAP_REL
    if internal:
        settings.tol_gap_abs = INTERNAL_TOL_GAP_ABS
        settings.tol_feas = INTERNAL_TOL_FEAS
    return settings
