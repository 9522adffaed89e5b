"""The operator's two 3-axis controllers from a keyboard or a gamepad (Barker 1983: one
controller for the hand's translational velocity, one for its rotational velocity).

Keys are physical keys (the browser's ``KeyboardEvent.code``), so the layout is the same on
every keyboard layout. Each key deflects one axis fully; opposite keys cancel.

==========  =====================  ==========  ======================
key         axis (deflection)      key         axis (deflection)
==========  =====================  ==========  ======================
KeyW/KeyS   linear x +1 / -1       KeyI/KeyK   angular x +1 / -1
KeyA/KeyD   linear y +1 / -1       KeyJ/KeyL   angular y +1 / -1
KeyE/KeyQ   linear z +1 / -1       KeyO/KeyU   angular z +1 / -1
==========  =====================  ==========  ======================

A gamepad in the browser's standard layout: the left stick is the translational controller
in the plane (up: +x, left: +y), the triggers its third axis (right: +z, left: -z); the right
stick is the rotational controller (up: +x, left: +y), the bumpers its third axis (right:
+z, left: -z). A stick's deflection inside ``dead_zone`` (radial) reads as zero and the rest
of its travel is rescaled to [0, 1], so the output is continuous; triggers the same, alone.

A 3Dconnexion SpaceMouse (read by the page through WebHID) is both controllers in one cap:
its translation is the translational controller, its rotation the rotational one, in the
hand axes like the keys: pushing the cap away from the operator is +x, to the left +y,
lifting it +z, and the rotations are right-handed about the same axes (turning it
counter-clockwise seen from above: about +z; tilting its top away from the operator: about
+y; to the right: about +x). The device reports counts in
±:data:`SPACEMOUSE_FULL_SCALE` on its own axes (HID usages X, Y, Z, Rx, Ry, Rz: x to the
right, y towards the operator, z down, rotations right-handed about them, as spacenavd reads
them); each triple has a radial dead zone of :data:`SPACEMOUSE_DEAD_ZONE` of full scale.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

KEYS: dict[str, tuple[int, float]] = {
    "KeyW": (0, 1.0),
    "KeyS": (0, -1.0),
    "KeyA": (1, 1.0),
    "KeyD": (1, -1.0),
    "KeyE": (2, 1.0),
    "KeyQ": (2, -1.0),
    "KeyI": (3, 1.0),
    "KeyK": (3, -1.0),
    "KeyJ": (4, 1.0),
    "KeyL": (4, -1.0),
    "KeyO": (5, 1.0),
    "KeyU": (5, -1.0),
}
"""``KeyboardEvent.code`` -> (axis of [vx vy vz wx wy wz], deflection)."""

DEAD_ZONE = 0.15
"""Share of a stick's or trigger's travel that reads as zero."""

SPACEMOUSE_FULL_SCALE = 350.0
"""A SpaceMouse's counts at full deflection (its HID logical range is -350..350)."""

SPACEMOUSE_DEAD_ZONE = 0.1
"""Share of a SpaceMouse's translation or rotation (radial, per triple) that reads as zero:
the cap's rest noise is a few counts, a hand resting on it some tens."""

# Standard gamepad layout (https://w3c.github.io/gamepad/#remapping).
LEFT_X, LEFT_Y, RIGHT_X, RIGHT_Y = 0, 1, 2, 3
LEFT_BUMPER, RIGHT_BUMPER, LEFT_TRIGGER, RIGHT_TRIGGER = 4, 5, 6, 7


def keyboard(codes: Iterable[str]) -> np.ndarray:
    """Deflections (6,) in [-1, 1] from the physical keys held (unknown codes ignored)."""
    deflection = np.zeros(6)
    for code in set(codes):
        if code in KEYS:
            axis, sign = KEYS[code]
            deflection[axis] += sign
    return deflection


def _number(values: Sequence[object], index: int) -> float:
    """values[index] as a finite float in [-1, 1]; 0 when missing or not a number."""
    if index >= len(values):
        return 0.0
    value = values[index]
    if isinstance(value, dict):  # a GamepadButton: {"value": ..., "pressed": ...}
        value = value.get("value", 0.0)
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return 0.0
    return min(max(number, -1.0), 1.0) if math.isfinite(number) else 0.0


def dead_zone(x: float, y: float, size: float = DEAD_ZONE) -> tuple[float, float]:
    """A stick's (x, y) with a radial dead zone: zero inside ``size``, the rest rescaled so
    that the edge of the zone maps to 0 and full travel to 1 (direction kept)."""
    radius = math.hypot(x, y)
    if radius <= size:
        return 0.0, 0.0
    scale = min(radius, 1.0)
    scale = (scale - size) / (1.0 - size) / radius
    return x * scale, y * scale


def _trigger(value: float, size: float) -> float:
    return 0.0 if value <= size else (value - size) / (1.0 - size)


def gamepad(axes: Sequence[object], buttons: Sequence[object], size: float = DEAD_ZONE) -> np.ndarray:
    """Deflections (6,) in [-1, 1] from a standard-layout gamepad's ``axes`` (numbers) and
    ``buttons`` (numbers or ``{"value": …}``); missing or malformed entries read as zero."""
    left_x, left_y = dead_zone(_number(axes, LEFT_X), _number(axes, LEFT_Y), size)
    right_x, right_y = dead_zone(_number(axes, RIGHT_X), _number(axes, RIGHT_Y), size)
    lift = _trigger(_number(buttons, RIGHT_TRIGGER), size) - _trigger(_number(buttons, LEFT_TRIGGER), size)
    twist = _trigger(_number(buttons, RIGHT_BUMPER), size) - _trigger(_number(buttons, LEFT_BUMPER), size)
    # Stick y grows downward and x rightward: up is +x, left is +y (a right-handed hand frame seen from above).
    return np.array([-left_y, -left_x, lift, -right_y, -right_x, twist])


def _radial(triple: np.ndarray, size: float) -> np.ndarray:
    """A 3-vector with a radial dead zone: zero inside ``size``, the rest of its length
    rescaled so that the zone's edge maps to 0 and 1 to 1 (direction kept, length <= 1)."""
    length = float(np.linalg.norm(triple))
    if length <= size:
        return np.zeros(3)
    return triple * ((min(length, 1.0) - size) / (1.0 - size) / length)


def spacemouse(counts: Sequence[object], size: float = SPACEMOUSE_DEAD_ZONE) -> np.ndarray:
    """Deflections (6,) in [-1, 1] from a SpaceMouse's raw counts ``(tx, ty, tz, rx, ry,
    rz)`` (the device's axes, see the module; missing or malformed entries read as zero):
    each scaled by :data:`SPACEMOUSE_FULL_SCALE`, each triple through a radial dead zone of
    ``size``, then turned into the hand axes (forward = -y, left = -x, up = -z: a proper
    rotation, so the rotation triple turns the same way)."""
    raw = np.clip([_count(counts, i) / SPACEMOUSE_FULL_SCALE for i in range(6)], -1.0, 1.0)
    translation, rotation = _radial(raw[:3], size), _radial(raw[3:], size)
    device_to_hand = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    return np.concatenate([device_to_hand @ translation, device_to_hand @ rotation])


def _count(values: Sequence[object], index: int) -> float:
    """values[index] as a finite float; 0 when missing or not a number."""
    if index >= len(values):
        return 0.0
    value = values[index]
    if isinstance(value, bool):
        return 0.0
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return 0.0
    return number if math.isfinite(number) else 0.0


def deflections(
    keys: Iterable[str] = (),
    axes: Sequence[object] = (),
    buttons: Sequence[object] = (),
    counts: Sequence[object] = (),
) -> np.ndarray:
    """Keyboard, gamepad and SpaceMouse (``counts``, see :func:`spacemouse`) together (6,),
    each axis clipped to [-1, 1]."""
    total = keyboard(keys) + gamepad(axes, buttons)
    if len(counts):
        total += spacemouse(counts)
    return np.clip(total, -1.0, 1.0)


__all__ = [
    "DEAD_ZONE",
    "KEYS",
    "SPACEMOUSE_DEAD_ZONE",
    "SPACEMOUSE_FULL_SCALE",
    "dead_zone",
    "deflections",
    "gamepad",
    "keyboard",
    "spacemouse",
]
