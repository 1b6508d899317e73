"""Shared finite-difference harness for element kernels.

A kernel is a callable ``kernel(x) -> (energy, grad, hess)`` taking element
coordinates ``x`` of shape ``(n_el, k, 3)`` and returning energies ``(n_el,)``,
gradients ``(n_el, 3k)`` and Hessians ``(n_el, 3k, 3k)`` with node-major DOF
order (node 0 x, y, z, node 1 x, y, z, ...).
"""

from __future__ import annotations

import numpy as np


def _fd_gradient(fun, x, h):
    """Central differences of a per-element scalar (n_el,) -> (n_el, 3k)."""
    n_el, k, _ = x.shape
    out = np.empty((n_el, 3 * k))
    for a in range(3 * k):
        dx = np.zeros_like(x)
        dx[:, a // 3, a % 3] = h
        out[:, a] = (fun(x + dx) - fun(x - dx)) / (2 * h)
    return out


def _fd_hessian(grad_fun, x, h):
    n_el, k, _ = x.shape
    out = np.empty((n_el, 3 * k, 3 * k))
    for a in range(3 * k):
        dx = np.zeros_like(x)
        dx[:, a // 3, a % 3] = h
        out[:, :, a] = (grad_fun(x + dx) - grad_fun(x - dx)) / (2 * h)
    return out


def relative_error(approx, exact):
    """Max over elements of ||approx - exact|| / max(||exact||, tiny)."""
    approx = approx.reshape(len(approx), -1)
    exact = exact.reshape(len(exact), -1)
    num = np.linalg.norm(approx - exact, axis=1)
    den = np.maximum(np.linalg.norm(exact, axis=1), 1e-300)
    return float(np.max(num / den))


def check_kernel(kernel, x, h=None, rtol=1e-6, rigid=True):
    """Assert gradient, Hessian, symmetry and rigid-body invariance of a kernel.

    Parameters
    ----------
    kernel : callable
        ``kernel(x) -> (energy, grad, hess)``.
    x : ndarray, shape (n_el, k, 3)
        Non-degenerate element configurations.
    h : float, optional
        Finite-difference step; default 1e-6 times the configuration size.
    rtol : float
        Relative error bound for gradient and Hessian.
    rigid : bool
        Also check zero net force and torque and rotation invariance.

    Returns
    -------
    dict
        Measured relative errors.
    """
    scale = float(np.max(np.ptp(x.reshape(-1, 3), axis=0)))
    h = 1e-6 * scale if h is None else h
    energy, grad, hess = kernel(x)
    fd_g = _fd_gradient(lambda y: kernel(y)[0], x, h)
    fd_h = _fd_hessian(lambda y: kernel(y)[1], x, h)
    errs = {
        "gradient": relative_error(grad, fd_g),
        "hessian": relative_error(hess, fd_h),
        "symmetry": relative_error(hess, np.swapaxes(hess, 1, 2)),
    }
    assert errs["gradient"] < rtol, f"gradient vs finite differences: {errs}"
    assert errs["hessian"] < rtol, f"Hessian vs finite differences: {errs}"
    assert errs["symmetry"] < 1e-12, f"Hessian not symmetric: {errs}"
    if rigid:
        n_el, k, _ = x.shape
        f = grad.reshape(n_el, k, 3)
        gnorm = np.linalg.norm(grad, axis=1, keepdims=True) + 1e-300
        net_force = np.linalg.norm(f.sum(axis=1), axis=1) / gnorm[:, 0]
        centre = x.mean(axis=1, keepdims=True)
        torque = np.cross(x - centre, f).sum(axis=1)
        net_torque = np.linalg.norm(torque, axis=1) / (gnorm[:, 0] * scale)
        errs["net_force"] = float(net_force.max())
        errs["net_torque"] = float(net_torque.max())
        assert errs["net_force"] < 1e-9, f"net force not zero: {errs}"
        assert errs["net_torque"] < 1e-9, f"net torque not zero: {errs}"
        rot = _rotation(np.array([0.3, -0.5, 0.8]), 0.7)
        e_rot = kernel(centre + (x - centre) @ rot.T + 0.123 * scale)[0]
        errs["rotation_invariance"] = relative_error(e_rot[:, None], energy[:, None])
        assert np.allclose(e_rot, energy, rtol=1e-9, atol=1e-12 * np.max(np.abs(energy))), (
            f"energy changes under rigid motion: {errs}")
    return errs


def _rotation(axis, angle):
    axis = axis / np.linalg.norm(axis)
    kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx
