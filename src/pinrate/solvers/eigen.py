"""Spectral radius of a real square matrix of size 0 to 3, in closed form: the one routine
behind every rho that pinrate computes in closed form, on Python floats (one matrix, the
servo's step) and on numpy arrays (a stack of matrices, the work-volume maps) alike.

The same source runs on both because every operation goes through an :class:`Ops`
namespace: :data:`FLOATS` (``math``; ``choose`` runs the one branch taken) or
:data:`ARRAYS` (numpy ufuncs; ``choose`` runs both branches and picks elementwise with
``np.where``). Since a branch may run where it is not taken, every argument of a square
root, a cube root, an arc cosine or a division is made safe first.

Accuracy: the characteristic polynomial is taken of the *shifted* matrix M - s I with
s = tr M / n (for 2x2: the discriminant ((a - d) / 2)^2 + b c), so a multiple eigenvalue
(c I) or a cluster costs no cancellation of the large terms; Cardano's formula takes the
cube root of the larger of -q/2 +- sqrt(D) and the other from their product -p/3. The
eigenvalues are then accurate to about eps * ||M|| where M's eigenvalues are
well-conditioned, the same order as LAPACK's; a double root of a normal matrix, whose
polynomial roots are ill-conditioned, loses up to sqrt(eps) of that.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

_SQRT3_HALF = math.sqrt(3.0) / 2.0
FLAT = 1e-200
"""Viète's cut: a 3x3 whose shifted p >= -FLAT has a triple root (rho is ``|tr M / 3|``); the
compiled core's ``FLAT`` must be the same (pinrate.compiled checks it at load)."""


@dataclass(frozen=True)
class Ops:
    """The elementary operations the routine needs, for one kind of number."""

    sqrt: Callable[[Any], Any]
    cbrt: Callable[[Any], Any]
    arccos: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    sin: Callable[[Any], Any]
    hypot: Callable[[Any, Any], Any]
    maximum: Callable[[Any, Any], Any]
    minimum: Callable[[Any, Any], Any]
    where: Callable[[Any, Any, Any], Any]
    absolute: Callable[[Any], Any]
    choose: Callable[[Any, Callable[[], Any], Callable[[], Any]], Any]
    """choose(condition, if_true, if_false): the value of the branch (a thunk) taken."""


def _float_cbrt(x: float) -> float:
    return math.copysign(abs(x) ** (1.0 / 3.0), x)


def _float_where(condition: bool, if_true: float, if_false: float) -> float:
    return if_true if condition else if_false


def _float_choose(condition: bool, if_true: Callable[[], float], if_false: Callable[[], float]) -> float:
    return if_true() if condition else if_false()


def _array_choose(condition: np.ndarray, if_true: Callable[[], Any], if_false: Callable[[], Any]) -> np.ndarray:
    return np.where(condition, if_true(), if_false())


FLOATS = Ops(
    math.sqrt, _float_cbrt, math.acos, math.cos, math.sin, math.hypot, max, min, _float_where, abs, _float_choose
)
"""Python floats: one matrix."""

ARRAYS = Ops(
    np.sqrt, np.cbrt, np.arccos, np.cos, np.sin, np.hypot, np.maximum, np.minimum, np.where, np.abs, _array_choose
)
"""numpy arrays: elementwise over a stack of matrices."""


def _spectral_radius_1(a: Any, ops: Ops) -> Any:
    """max ``|λ|`` of [[a]]."""
    return ops.absolute(a)


def spectral_radius_2(a: Any, b: Any, c: Any, d: Any, ops: Ops) -> Any:
    """max ``|λ|`` of [[a, b], [c, d]]: λ = (a + d)/2 ± sqrt(D), D = ((a - d)/2)^2 + b c.

    Real roots (D >= 0): ``|(a + d)/2|`` + sqrt(D); a complex pair: ``|λ|^2`` = det = a d - b c.
    """
    half_difference = (a - d) * 0.5
    discriminant = half_difference * half_difference + b * c
    real = ops.absolute((a + d) * 0.5) + ops.sqrt(ops.maximum(discriminant, 0.0))
    complex_pair = ops.sqrt(ops.maximum(a * d - b * c, 0.0))
    return ops.where(discriminant >= 0.0, real, complex_pair)


def spectral_radius_3(m: tuple[Any, ...], ops: Ops) -> Any:
    """max ``|λ|`` of the 3x3 matrix with row-major entries ``m`` (nine numbers or arrays).

    With s = tr M / 3 and S = M - s I (trace 0), λ = t + s where t³ + p t + q = 0,
    p = the sum of S's principal 2x2 minors and q = -det S. One real root and a complex
    pair when D = (q/2)² + (p/3)³ > 0 (Cardano), three real roots otherwise (Viète).
    """
    a, b, c, d, e, f, g, h, i = m
    shift = (a + e + i) * (1.0 / 3.0)
    a, e, i = a - shift, e - shift, i - shift
    minor_ei, minor_fh = e * i, f * h
    p = (a * e - b * d) + (a * i - c * g) + (minor_ei - minor_fh)
    q = -(a * (minor_ei - minor_fh) - b * (d * i - f * g) + c * (d * h - e * g))
    half_q = 0.5 * q
    third_p = p * (1.0 / 3.0)
    discriminant = half_q * half_q + third_p * third_p * third_p
    one_real = discriminant > 0.0

    def cardano() -> Any:
        # u = cbrt(-q/2 - sign(q) sqrt(D)) has no cancellation; v = -p / (3 u).
        root = ops.sqrt(ops.maximum(discriminant, 0.0))
        u = ops.cbrt(ops.where(half_q >= 0.0, -half_q - root, -half_q + root))
        v = -third_p / ops.where(u == 0.0, 1.0, u)  # u = 0 only where D <= 0 (not taken)
        real_part = -(u + v) * 0.5 + shift
        imaginary_part = _SQRT3_HALF * (u - v)
        return ops.maximum(ops.absolute(u + v + shift), ops.hypot(real_part, imaginary_part))

    def viete() -> Any:
        # p <= 0 here; p = 0 only with q = 0, a triple root t = 0 (and a |p| below FLAT
        # spreads the roots by less than 1e-100: rho is |s| to every digit).
        flat = p >= -FLAT
        safe_p = ops.where(one_real | flat, -1.0, p)
        radius = 2.0 * ops.sqrt(-safe_p * (1.0 / 3.0))
        angle = ops.arccos(ops.maximum(-1.0, ops.minimum(1.0, 3.0 * q / (safe_p * radius)))) * (1.0 / 3.0)
        # Roots radius cos(angle - 2 pi k / 3) + shift: k = 0 is the largest (cos in [1/2, 1]),
        # k = 2 the smallest (cos(angle + 2 pi / 3), by the angle sum); the middle one lies
        # between them, so it is never the largest in magnitude and is not computed.
        cosine, sine = ops.cos(angle), ops.sin(angle)
        largest = radius * cosine + shift
        smallest = -radius * (0.5 * cosine + _SQRT3_HALF * sine) + shift
        return ops.where(flat, ops.absolute(shift), ops.maximum(ops.absolute(largest), ops.absolute(smallest)))

    return ops.choose(one_real, cardano, viete)
