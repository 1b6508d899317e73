"""The monotone sheet conduction's exact derivative in the shape (theory 12.6).

The monotone conduction (:mod:`simulator.thermal.monotone`) is the P1 conduction of a fixed
triangulation of the mesh nodes and Steiner points ``q = x_a + f (x_b - x_a)`` on mesh edges,
condensed onto the mesh nodes: ``K_c = K_mm - K_ms K_ss^-1 K_sm``. With ``z = (dT, s)``,
``s = -K_ss^-1 K_sm dT`` the Steiner points' rises,

    d(K_c dT) = E^T (dK z),      E^T = [I, -K_ms K_ss^-1],

and ``dK z`` is the sum over the triangles of the derivative of their T3 products ``y_i =
k t (e_i . w) / (4 A)``, ``w = sum_j z_j e_j`` (``e_i`` the edge opposite corner i), in their
corners: ``dy_i / dP_k = k t / (4 A) ((d_{k,i+2} - d_{k,i+1}) w + (z_{k+1} - z_{k+2}) e_i) -
y_i (n x e_k) / (2 A)``; the Steiner points' positions are linear in the nodes'.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..linalg.ladder import factorize
from ..thermal.monotone import t3_matrices

__all__ = ["monotone_jacobian"]


def monotone_jacobian(mono, x, rise) -> sp.csr_matrix:
    """``d (K_c(x) dT) / dx`` [W/(K m)] of the monotone conduction ``mono``
    (:class:`~simulator.thermal.monotone.MonotoneConduction`) at node positions ``x`` (n, 3)
    [m] for the fixed rise ``dT`` = ``rise`` (n,) [K]: (n, 3n), node-major columns."""
    x = np.asarray(x, float)
    n, s = len(x), mono.n_steiner
    N = n + s
    P = mono.positions(x)
    C = mono.corners
    K = t3_matrices(P[C], mono.kt)                                        # (m', 3, 3)
    z = np.zeros(N)
    z[:n] = rise
    rows, cols = np.repeat(C, 3, axis=1).ravel(), np.tile(C, (1, 3)).ravel()
    Kf = sp.csr_matrix((K.ravel(), (rows, cols)), shape=(N, N))
    if s:
        lu = factorize(Kf[n:, n:].tocsc(), kind="spd")     # the Steiner block, SPD
        z[n:] = -lu.solve(Kf[n:, :n] @ rise)
    # the triangles' T3 products and their derivatives in the corners
    Pc = P[C]                                                             # (m', 3, 3)
    e = np.stack([Pc[:, 2] - Pc[:, 1], Pc[:, 0] - Pc[:, 2], Pc[:, 1] - Pc[:, 0]], axis=1)
    cross = np.cross(Pc[:, 1] - Pc[:, 0], Pc[:, 2] - Pc[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    normal = cross / (2 * area[:, None])
    zc = z[C]                                                             # (m', 3)
    w = np.einsum("tj,tjk->tk", zc, e)
    scale = mono.kt / (4 * area)
    y = scale[:, None] * np.einsum("tik,tk->ti", e, w)
    dA = 0.5 * np.cross(normal[:, None, :], e)                            # (m', 3 corners, 3)
    idx = np.arange(3)
    sel = (idx[None, :] == (idx[:, None] + 2) % 3).astype(float) \
        - (idx[None, :] == (idx[:, None] + 1) % 3).astype(float)         # (i, k)
    dz = zc[:, (idx + 1) % 3] - zc[:, (idx + 2) % 3]                      # (m', k)
    G = scale[:, None, None, None] * (sel[None, :, :, None] * w[:, None, None, :]
                                       + dz[:, None, :, None] * e[:, :, None, :]) \
        - (y / area[:, None])[:, :, None, None] * dA[:, None, :, :]       # (m', i, k, 3)
    g_rows = np.repeat(C, 9, axis=1).ravel()
    g_cols = np.tile((3 * C[:, :, None] + np.arange(3)).reshape(-1, 9), (1, 3)).ravel()
    Gs = sp.csr_matrix((G.ravel(), (g_rows, g_cols)), shape=(N, 3 * N))
    # the Steiner points' positions in the nodes'
    q_rows = [np.arange(3 * n)]
    q_cols = [np.arange(3 * n)]
    q_vals = [np.ones(3 * n)]
    if s:
        a, b = mono.steiner[:, 0].astype(np.int64), mono.steiner[:, 1].astype(np.int64)
        f = mono.steiner[:, 2]
        for end, weight in ((a, 1 - f), (b, f)):
            q_rows.append((3 * (n + np.arange(s))[:, None] + np.arange(3)).ravel())
            q_cols.append((3 * end[:, None] + np.arange(3)).ravel())
            q_vals.append(np.repeat(weight, 3))
    Q = sp.csr_matrix((np.concatenate(q_vals), (np.concatenate(q_rows), np.concatenate(q_cols))),
                      shape=(3 * N, 3 * n))
    GQ = (Gs @ Q).tocsr()
    out = GQ[:n]
    if s:                                  # E^T: the Steiner rows condensed onto the nodes
        X = lu.solve(GQ[n:].toarray())
        out = out - sp.csr_matrix(Kf[:n, n:] @ X)
    return out.tocsr()
