"""What pinrate draws besides the robot: frame triads, arrows along a frame's axes, and the
colours of a servo's path (green where ρ < 1, red where ρ >= 1)."""

from __future__ import annotations

import meshcat.geometry as g
import numpy as np

from ..errors import InputError

CONVERGING_COLOUR = 0x2CA02C  # ρ < 1
DIVERGING_COLOUR = 0xD62728  # ρ >= 1
TARGET_COLOUR = 0xFF7F0E


def triad(length: float = 0.1, width: float = 3.0, opacity: float = 1.0) -> tuple[g.LineSegments]:
    """A frame triad: x red, y green, z blue."""
    vertices = np.array([[0, length, 0, 0, 0, 0], [0, 0, 0, length, 0, 0], [0, 0, 0, 0, 0, length]], dtype=np.float32)
    colours = np.array([[1, 1, 0, 0, 0, 0], [0, 0.6, 1, 0.6, 0, 0.6], [0, 0, 0, 0, 1, 1]], dtype=np.float32)
    return (
        g.LineSegments(
            g.PointsGeometry(vertices, colours),
            g.LineBasicMaterial(vertexColors=True, linewidth=width, opacity=opacity),
        ),
    )


AXIS_COLOURS = (0xD62728, 0x2CA02C, 0x1F77B4)
"""x red, y green, z blue: the colours of every drawn frame's axes."""


def arrow_parts(axis: int, length: float, radius: float) -> list[tuple[str, g.Cylinder, np.ndarray]]:
    """(name, geometry, transform in the frame) of a shaft and a cone head along ``axis``
    (meshcat's cylinders stand along their own y axis, centred on their origin)."""
    turn = np.eye(4)
    if axis == 0:  # y -> x: a quarter turn about -z
        turn[:3, :3] = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]
    elif axis == 2:  # y -> z: a quarter turn about x
        turn[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]
    direction = np.zeros(3)
    direction[axis] = 1.0
    shaft_length, head_length = 0.78 * length, 0.22 * length
    shaft, head = turn.copy(), turn.copy()
    shaft[:3, 3] = direction * shaft_length / 2
    head[:3, 3] = direction * (shaft_length + head_length / 2)
    return [
        ("shaft", g.Cylinder(shaft_length, radius), shaft),
        ("head", g.Cylinder(head_length, radiusTop=0.0, radiusBottom=2.2 * radius), head),
    ]


def path_colours(spectral_radius: np.ndarray) -> np.ndarray:
    """RGB (3, N) per path point: green where ρ < 1, red where ρ >= 1 (or undefined)."""
    try:
        converging = np.asarray(spectral_radius, dtype=float).reshape(-1) < 1.0
    except (TypeError, ValueError):
        raise InputError("spectral_radius must be a sequence of numbers") from None
    green = np.array([0x2C, 0xA0, 0x2C]) / 255.0
    red = np.array([0xD6, 0x27, 0x28]) / 255.0
    return np.where(converging[None, :], green[:, None], red[:, None]).astype(np.float32)


__all__ = [
    "AXIS_COLOURS",
    "CONVERGING_COLOUR",
    "DIVERGING_COLOUR",
    "TARGET_COLOUR",
    "arrow_parts",
    "path_colours",
    "triad",
]
