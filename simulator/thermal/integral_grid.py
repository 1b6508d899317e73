"""The far field of the integral heat loss on a grid: an Ewald split of ``1/r`` (theory 4.7).

The fast path (:mod:`simulator.thermal.integral_fast`) applies the centroid rule ``sum_{j != i}
p_j / |c_i - c_j|`` of the single-layer matrix to a vector in every MINRES iteration. With the
fast multipole method that is 0.4-1.4 s per evaluation at 20,000 points on the 2-core machine,
and a solve needs some 50. :class:`GridFarField` applies it in tens of milliseconds, as in the
particle-mesh Ewald method, by splitting the kernel at a length ``sigma``,

    1/r = erf(r / sigma) / r  +  erfc(r / sigma) / r,

* the smooth part (finite at r = 0, 2 / (sigma sqrt(pi))) on a uniform grid of spacing
  ``h``: the charges spread to the grid by the transpose of tensor-product Lagrange
  interpolation of order :data:`ORDER` (``W^T p``, ``(ORDER + 1)^3`` nodes per point), the
  grid potential the aperiodic convolution with the sampled smooth kernel (zero-padded FFT),
  and interpolated back (``W``): ``W G W^T p``; its own value at each point's self pair is
  subtracted exactly (the centroid rule has no self term);
* the short-range part summed over the pairs closer than :data:`CUTOFF` ``sigma`` (a sparse
  matrix; erfc(4) = 1.5e-8).

Above an isothermal plane the image charges (``-p`` at the mirrored points) are the same
sums: the grid's frame has the plane normal as its third axis, so the image part is a
convolution in-plane and a correlation across it (the charge grid flipped), and the
short-range image pairs are sparse. The grid's frame is otherwise the point cloud's principal
axes (a flat sheet is a flat grid). The cost per evaluation is two sparse products of
``(ORDER + 1)^3 n`` entries, one FFT pair over the padded grid, and the short-range pairs;
the grid grows with the sheet's bounding box, which :data:`MAX_GRID` caps (the caller then
uses the FMM).
"""

from __future__ import annotations

import logging
import math

import numpy as np
import scipy.fft as sfft
import scipy.sparse as sp
from scipy.special import erf, erfc

__all__ = ["GridFarField", "ORDER", "CUTOFF", "SPACING", "SPLIT", "PRECORRECT", "MAX_GRID",
           "grid_size", "grid_pairs", "smooth_kernel"]

logger = logging.getLogger(__name__)

#: Lagrange interpolation order of the grid (ORDER + 1 nodes per axis and point).
ORDER = 3
#: Short-range pairs: closer than CUTOFF x sigma (erfc(4) = 1.5e-8 of 1/r).
CUTOFF = 4.0
#: Grid spacing h as a fraction of the split length sigma.
SPACING = 0.5
#: The split length sigma as a multiple of the square root of the mean sub-triangle area
#: (some 200 short-range pairs per point, about one grid node per point and layer).
SPLIT = 2.0
#: Pairs closer than PRECORRECT x sigma get the exact smooth kernel instead of the grid's
#: interpolated one (the grid's error is largest there).
PRECORRECT = 4.0
#: Largest padded grid (nodes) the far field is put on; beyond it the caller takes the FMM.
MAX_GRID = 16_000_000
#: Nodes per axis and point (``ORDER + 1``), node offsets a pair spans per axis
#: (``2 ORDER + 1``) and the first stencil node's offset below a point's floor node.
_K1, _WIDTH, _LO = ORDER + 1, 2 * ORDER + 1, (ORDER - 1) // 2


def _frame(points, plane):
    """Rotation (3, 3) whose rows are the grid's axes: the plane normal third when there is a
    plane, else the point cloud's principal axes (the thinnest third)."""
    if plane is not None:
        n = np.asarray(plane[1], float)
        n = n / np.linalg.norm(n)
        a = np.eye(3)[int(np.argmin(np.abs(n)))]
        e1 = np.cross(n, a)
        e1 /= np.linalg.norm(e1)
        return np.array([e1, np.cross(n, e1), n])
    c = points - points.mean(axis=0)
    _, vecs = np.linalg.eigh(c.T @ c)
    return vecs[:, ::-1].T.copy()


def _lagrange(u):
    """Weights (n, ORDER + 1) of the nodes -1, 0, .., ORDER - 1 (relative to the floor) at
    offsets ``u`` (n,) in [0, 1)."""
    nodes = np.arange(ORDER + 1) - (ORDER - 1) // 2
    out = np.ones((len(u), ORDER + 1))
    for a in range(ORDER + 1):
        for b in range(ORDER + 1):
            if a != b:
                out[:, a] *= (u - nodes[b]) / (nodes[a] - nodes[b])
    return out


def grid_size(points, sigma: float, plane=None) -> int:
    """Nodes of the padded grid :class:`GridFarField` would use, at most (to compare with
    :data:`MAX_GRID` before building it)."""
    y = np.asarray(points, float) @ _frame(points, plane).T
    n = np.ceil(np.ptp(y, axis=0) / (SPACING * sigma)).astype(int) + ORDER - _LO + 1
    return int(np.prod([sfft.next_fast_len(2 * k) for k in n]))


def smooth_kernel(r, sigma: float) -> np.ndarray:
    """``erf(r / sigma) / r`` [1/m] (its limit 2 / (sigma sqrt(pi)) at r = 0)."""
    r = np.asarray(r, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = erf(r / sigma) / r
    return np.where(r > 1e-12 * sigma, out, 2 / (sigma * math.sqrt(math.pi)))


class GridFarField:
    """``sum_{j != i} p_j / |c_i - c_j|`` (minus ``sum_j p_j / |c_i - c_j*|`` above a plane,
    ``c*`` the mirror images) at every point ``c_i``, applied in ``O(n + N log N)``.

    Parameters
    ----------
    points : (n, 3) array
        The points (sub-triangle centroids) [m].
    sigma : float
        Split length [m] (the grid spacing is :data:`SPACING` of it).
    plane : (origin (3,), unit normal (3,)), optional
        Isothermal plane (image charges of opposite sign).
    """

    def __init__(self, points, sigma: float, plane=None):
        from scipy.spatial import cKDTree

        self.points = c = np.ascontiguousarray(points, float)
        self.n, self.sigma = len(c), float(sigma)
        self.h = h = SPACING * self.sigma
        self.plane = plane
        Q = _frame(c, plane)
        y = c @ Q.T
        lo = y.min(axis=0) - h * (ORDER // 2 + 1)
        t = (y - lo) / h
        base = np.floor(t).astype(np.int64)
        # the grid from the first node a point's stencil uses to the last (a shift by whole
        # cells: the same offsets t - base; a flat sheet's grid 4 nodes thick, not 6)
        first = base.min(axis=0) - _LO
        base -= first
        lo = lo + first * h
        self.shape = tuple(int(k) for k in base.max(axis=0) + ORDER - _LO + 1)
        u = t - (base + first)
        self.W = self._weights(u, base)
        self._base, self._u = base, u
        shift = None
        if plane is not None:
            zp = (np.asarray(plane[0], float) @ Q.T)[2]
            shift = 2 * (lo[2] - zp)
        self._fft_shape = tuple(sfft.next_fast_len(2 * k) for k in self.shape)
        g = self._kernel(None)
        self._G = sfft.rfftn(g, workers=-1)
        self.self_value = self._self_values(g)
        tree = cKDTree(c)
        self.short = self._short_range(tree, c, c, g, image=False)
        self._Gi = None
        if shift is not None:
            from ._single_layer import mirror

            gi = self._kernel(shift)
            self._Gi = sfft.rfftn(gi, workers=-1)
            self.short = self.short - self._short_range(tree, c, mirror(c, plane), gi,
                                                        image=True)

    @property
    def grid_nodes(self) -> int:
        """Nodes of the padded grid (the FFT's size)."""
        return int(np.prod(self._fft_shape))

    def _weights(self, u, base) -> sp.csr_matrix:
        """``W`` (n, N): tensor-product Lagrange weights of each point's grid nodes."""
        wx, wy, wz = (_lagrange(u[:, k]) for k in range(3))
        off = np.arange(ORDER + 1) - (ORDER - 1) // 2
        nx, ny, nz = self.shape
        ix = base[:, 0, None] + off[None]
        iy = base[:, 1, None] + off[None]
        iz = base[:, 2, None] + off[None]
        idx = ((ix[:, :, None, None] * ny + iy[:, None, :, None]) * nz
               + iz[:, None, None, :]).reshape(self.n, -1)
        val = (wx[:, :, None, None] * wy[:, None, :, None] * wz[:, None, None, :]).reshape(
            self.n, -1)
        rows = np.repeat(np.arange(self.n), idx.shape[1])
        return sp.csr_matrix((val.ravel(), (rows, idx.ravel())), shape=(self.n, nx * ny * nz))

    def _kernel(self, shift):
        """The smooth kernel on the padded grid's offsets (negative offsets wrapped; with
        ``shift``: the image kernel, third offset ``(k + nz - 1) h + shift`` for the
        z-flipped charge grid)."""
        h, (nx, ny, nz) = self.h, self.shape
        fx, fy, fz = self._fft_shape
        ax = [np.concatenate([np.arange(n), np.arange(-(f - n), 0)]) * h
              for n, f in zip((nx, ny, nz), (fx, fy, fz))]
        ax[0][nx:fx - nx + 1] = np.inf            # offsets no pair of nodes has
        ax[1][ny:fy - ny + 1] = np.inf
        z = ax[2].copy()
        z[nz:fz - nz + 1] = np.inf
        if shift is not None:
            z = z + (nz - 1) * h + shift
        r = np.sqrt(ax[0][:, None, None] ** 2 + ax[1][None, :, None] ** 2
                    + z[None, None, :] ** 2)
        return np.where(np.isfinite(r), smooth_kernel(np.where(np.isfinite(r), r, 1.0),
                                                      self.sigma), 0.0)

    def _self_values(self, g) -> np.ndarray:
        """The grid's value of each point's self pair, ``w_i^T G w_i`` (n,), ``g`` the grid
        kernel."""
        own = np.arange(self.n)
        return grid_pairs(self._base, self._u, own, own, g, self.shape[2])

    def _short_range(self, tree, c, sources, g, image: bool) -> sp.csr_matrix:
        """Sparse entries of the target-source pairs closer than :data:`CUTOFF` sigma (self
        pairs left out, not image ones): ``erfc(r / sigma) / r``, plus, within
        :data:`PRECORRECT` sigma, the smooth kernel's exact value less the grid's (``g`` the
        grid kernel, the image one with ``image``), so that these pairs are exact. The
        entries are symmetric (the kernel and the grid's values depend on ``c_i - c_j``, and
        through the plane on the mirrored pair as well): without ``image`` each pair is
        evaluated once (``i < j``) and mirrored."""
        from scipy.spatial import cKDTree

        if image:
            D = tree.sparse_distance_matrix(cKDTree(sources), CUTOFF * self.sigma,
                                            output_type="coo_matrix")
            rows, cols = D.row.astype(np.int64), D.col.astype(np.int64)
        else:
            rows, cols = tree.query_pairs(CUTOFF * self.sigma, output_type="ndarray").T
            rows, cols = np.ascontiguousarray(rows, np.int64), np.ascontiguousarray(cols, np.int64)
        r = np.linalg.norm(c[rows] - sources[cols], axis=1)     # (0 on the plane: kept)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = np.where(r > 0, erfc(r / self.sigma) / np.where(r > 0, r, 1.0), 0.0)
        near = np.flatnonzero(r < PRECORRECT * self.sigma)
        v[near] += smooth_kernel(r[near], self.sigma) - grid_pairs(
            self._base, self._u, rows[near], cols[near], g, self.shape[2], image)
        if not image:
            rows, cols, v = np.concatenate([rows, cols]), np.concatenate([cols, rows]), \
                np.concatenate([v, v])
        return sp.csr_matrix((v, (rows, cols)), shape=(self.n, self.n))

    def _convolve(self, rho, G):
        F = sfft.rfftn(rho, s=self._fft_shape, workers=-1)
        out = sfft.irfftn(F * G, s=self._fft_shape, workers=-1)
        nx, ny, nz = self.shape
        return out[:nx, :ny, :nz]

    def potential(self, p) -> np.ndarray:
        """``sum_{j != i} p_j / |c_i - c_j|`` (images subtracted) (n,) [1/m x p]."""
        p = np.asarray(p, float)
        rho = (self.W.T @ p).reshape(self.shape)
        phi = self._convolve(rho, self._G)
        if self._Gi is not None:
            phi = phi - self._convolve(rho[:, :, ::-1], self._Gi)
        return self.W @ phi.ravel() - self.self_value * p + self.short @ p


def _pair_coefficients(wa, wb, image: bool):
    """Per axis, the weights (p, 2 ORDER + 1) of the node offsets ``k``: sum of ``wa[a]
    wb[b]`` over ``a - b = k - ORDER`` (``a + b = k`` for the image axis)."""
    k = ORDER + 1
    out = np.zeros((len(wa), 2 * ORDER + 1))
    for a in range(k):
        for b in range(k):
            out[:, b + a if image else a - b + ORDER] += wa[:, a] * wb[:, b]
    return out


def grid_pairs(base, u, rows, cols, g, nz: int, image: bool = False, compiled=None):
    """The grid's value of the smooth kernel for the pairs ``(rows, cols)``, (p,): ``sum_ab
    w_i(a) w_j(b) g(node_a - node_b)`` (for ``image`` the third axis pairs the flipped grid,
    ``g(node_a + node_b - (nz - 1))``); ``base`` (n, 3) the points' floor nodes, ``u`` (n, 3)
    their offsets in cells, ``g`` the kernel on the padded grid's offsets. Compiled when
    ``compiled`` (default: when the numba backend is selected), numpy otherwise (the
    reference)."""
    from . import _single_layer_jit

    if compiled is None:
        compiled = _single_layer_jit.use_compiled()
    if compiled:
        kernel = _pairs_kernel()
        if kernel is not None:
            out = np.empty(len(rows))
            kernel(np.ascontiguousarray(base, np.int64), np.ascontiguousarray(u, float),
                   np.ascontiguousarray(rows, np.int64), np.ascontiguousarray(cols, np.int64),
                   np.ascontiguousarray(g, float), int(nz), bool(image), out)
            return out
    out = np.empty(len(rows))
    fx, fy, fz = g.shape
    lo = (ORDER - 1) // 2
    for s in range(0, len(rows), 4096):
        i, j = rows[s:s + 4096], cols[s:s + 4096]
        c = [_pair_coefficients(_lagrange(u[i, d]), _lagrange(u[j, d]), image and d == 2)
             for d in range(3)]
        dx = base[i, 0] - base[j, 0] - ORDER
        dy = base[i, 1] - base[j, 1] - ORDER
        dz = (base[i, 2] + base[j, 2] - 2 * lo - (nz - 1)) if image else \
            (base[i, 2] - base[j, 2] - ORDER)
        k = np.arange(2 * ORDER + 1)
        ix = (dx[:, None] + k) % fx
        iy = (dy[:, None] + k) % fy
        iz = (dz[:, None] + k) % fz
        vals = g[ix[:, :, None, None], iy[:, None, :, None], iz[:, None, None, :]]
        out[s:s + 4096] = np.einsum("pa,pb,pc,pabc->p", c[0], c[1], c[2], vals)
    return out


_compiled_pairs = None


def _pairs_kernel():
    """The compiled :func:`grid_pairs` (numba, parallel over the pairs), or None."""
    global _compiled_pairs
    if _compiled_pairs is None:
        from .._jit import compile_kernel

        _compiled_pairs = compile_kernel("grid pair kernel", _build_pairs, "using numpy") \
            or False
    return _compiled_pairs or None


def _lagrange_into(t, out):
    """:func:`_lagrange` at one offset ``t`` into ``out`` (ORDER + 1,) (compiled helper)."""
    for a in range(_K1):
        w = 1.0
        for b in range(_K1):
            if a != b:
                w *= (t - (b - _LO)) / (a - b)
        out[a] = w


def _pairs_loop(base, u, rows, cols, g, nz, image, out):
    """The compiled :func:`grid_pairs` (module-level with module constants, so that numba's
    cache finds it again: as a closure it was compiled anew in every process, some 7 s of
    CPU on the idle machine)."""
    fx, fy, fz = g.shape
    for p in _prange(rows.shape[0]):
        i, j = rows[p], cols[p]
        wa = np.empty(_K1)
        wb = np.empty(_K1)
        c = np.zeros((3, _WIDTH))
        for d in range(3):
            _lagrange_into(u[i, d], wa)
            _lagrange_into(u[j, d], wb)
            for a in range(_K1):
                for b in range(_K1):
                    if image and d == 2:
                        c[d, a + b] += wa[a] * wb[b]
                    else:
                        c[d, a - b + ORDER] += wa[a] * wb[b]
        dx = base[i, 0] - base[j, 0] - ORDER
        dy = base[i, 1] - base[j, 1] - ORDER
        if image:
            dz = base[i, 2] + base[j, 2] - 2 * _LO - (nz - 1)
        else:
            dz = base[i, 2] - base[j, 2] - ORDER
        iz = np.empty(_WIDTH, np.int64)
        for e in range(_WIDTH):
            iz[e] = (dz + e) % fz
        acc = 0.0
        for a in range(_WIDTH):
            ix = (dx + a) % fx
            for b in range(_WIDTH):
                iy = (dy + b) % fy
                row = 0.0
                for e in range(_WIDTH):
                    row += c[2, e] * g[ix, iy, iz[e]]
                acc += c[0, a] * c[1, b] * row
        out[p] = acc


_prange = range                        # numba's prange once compiled (:func:`_build_pairs`)
#: base, u, rows, cols, g, nz, image, out
_PAIRS_SIGNATURE = "void(i8[:, ::1], f8[:, ::1], i8[::1], i8[::1], f8[:, :, ::1], i8, b1, f8[::1])"


def _build_pairs():
    global _prange, _lagrange_into
    from numba import njit, prange

    _prange = prange
    if not hasattr(_lagrange_into, "py_func"):
        _lagrange_into = njit(cache=True, inline="always")(_lagrange_into)
    return njit(_PAIRS_SIGNATURE, parallel=True, cache=True)(_pairs_loop)
