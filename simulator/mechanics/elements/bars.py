"""Bar element: Green-Lagrange strain, linear material (theory 3.2).

For a bar from node a to node b with reference vector ``dX = X_b - X_a``, current
vector ``dx``, stored reference length ``L0`` and axial stiffness ``EA``:

    eps = (|dx|^2 - |dX|^2) / (2 L0^2) = (2 dX . du + |du|^2) / (2 L0^2),
    U = EA L0 eps^2 / 2.

With ``L0 = |dX|`` (the usual case) this is the Green-Lagrange strain.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bar_kernel"]

_BLOCK = np.block([[np.eye(3), -np.eye(3)], [-np.eye(3), np.eye(3)]])


def bar_kernel(dX: np.ndarray, du: np.ndarray, L0: np.ndarray, EA: np.ndarray,
               hessian: bool = True):
    """Energy [J], gradient [N] (n, 6) and Hessian [N/m] (n, 6, 6) of all bars.

    Parameters
    ----------
    dX : (n, 3) reference end vector ``X_b - X_a`` [m]
    du : (n, 3) relative end displacement ``u_b - u_a`` [m]
    L0 : (n,) stored reference length [m]
    EA : (n,) axial stiffness [N]
    hessian : bool
        With False the third output is None.

    The strain ``eps = (2 dX . du + |du|^2) / (2 L0^2)`` is formed from displacements, not
    from current positions, so it keeps full precision for stiff bars (no cancellation).
    Derivatives are with respect to the end positions (a then b).
    """
    dx = dX + du
    eps = (2 * np.einsum("ij,ij->i", dX, du) + np.einsum("ij,ij->i", du, du)) / (2 * L0**2)
    g = np.concatenate([-dx, dx], axis=1) / (L0**2)[:, None]           # d eps / d x
    c = EA * L0
    energy = 0.5 * c * eps**2
    grad = (c * eps)[:, None] * g
    if not hessian:
        return energy, grad, None
    hess = c[:, None, None] * (g[:, :, None] * g[:, None, :]) \
        + (c * eps / L0**2)[:, None, None] * _BLOCK
    return energy, grad, hess
