"""Keyboard and gamepad -> the operator's two 3-axis controllers (pinrate.teleop.mapping)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pinrate.teleop import mapping


def test_each_key_deflects_one_axis_fully():
    expected = {
        "KeyW": [1, 0, 0, 0, 0, 0], "KeyS": [-1, 0, 0, 0, 0, 0], "KeyA": [0, 1, 0, 0, 0, 0],
        "KeyD": [0, -1, 0, 0, 0, 0], "KeyE": [0, 0, 1, 0, 0, 0], "KeyQ": [0, 0, -1, 0, 0, 0],
        "KeyI": [0, 0, 0, 1, 0, 0], "KeyK": [0, 0, 0, -1, 0, 0], "KeyJ": [0, 0, 0, 0, 1, 0],
        "KeyL": [0, 0, 0, 0, -1, 0], "KeyO": [0, 0, 0, 0, 0, 1], "KeyU": [0, 0, 0, 0, 0, -1],
    }  # fmt: skip
    for code, deflection in expected.items():
        np.testing.assert_array_equal(mapping.keyboard([code]), deflection)


def test_opposite_keys_cancel_and_unknown_keys_are_ignored():
    np.testing.assert_array_equal(mapping.keyboard(["KeyW", "KeyS", "KeyZ", "Space"]), np.zeros(6))
    np.testing.assert_array_equal(mapping.keyboard(["KeyW", "KeyW"]), [1, 0, 0, 0, 0, 0])


def test_dead_zone_is_zero_inside_and_continuous_at_its_edge():
    assert mapping.dead_zone(0.1, 0.05, 0.15) == (0.0, 0.0)
    x, y = mapping.dead_zone(0.1500001, 0.0, 0.15)
    assert 0 < x < 1e-6 and y == 0
    x, y = mapping.dead_zone(0.6, 0.8, 0.15)  # radius 1: full travel, direction kept
    assert math.hypot(x, y) == pytest.approx(1.0)
    assert x / y == pytest.approx(0.75)
    x, _ = mapping.dead_zone(0.575, 0.0, 0.15)  # halfway between the edge and full travel
    assert x == pytest.approx(0.5)


def test_standard_gamepad_layout():
    up_left = mapping.gamepad([0, -1, 0, 0], [])
    np.testing.assert_allclose(up_left, [1, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(mapping.gamepad([-1, 0, 0, 0], []), [0, 1, 0, 0, 0, 0])
    buttons = [0, 0, 0, 0, 0, 0, 0, {"value": 1.0, "pressed": True}]
    np.testing.assert_allclose(mapping.gamepad([], buttons), [0, 0, 1, 0, 0, 0])
    np.testing.assert_allclose(mapping.gamepad([0, 0, 0, -1], []), [0, 0, 0, 1, 0, 0])
    np.testing.assert_allclose(mapping.gamepad([0, 0, -1, 0], []), [0, 0, 0, 0, 1, 0])
    np.testing.assert_allclose(mapping.gamepad([], [0, 0, 0, 0, 1, 0]), [0, 0, 0, 0, 0, -1])
    np.testing.assert_allclose(mapping.gamepad([], [0, 0, 0, 0, 0, 1]), [0, 0, 0, 0, 0, 1])


def test_a_resting_pad_reads_zero_and_malformed_entries_read_zero():
    np.testing.assert_array_equal(mapping.gamepad([0.05, -0.1, 0.12, 0.0], [0.1] * 17), np.zeros(6))
    np.testing.assert_array_equal(mapping.gamepad(["x", None, math.nan, math.inf], [{"no": 1}, "b"]), np.zeros(6))
    np.testing.assert_array_equal(mapping.gamepad([], []), np.zeros(6))


def test_keyboard_and_pad_add_and_clip():
    np.testing.assert_array_equal(mapping.deflections(["KeyW"], [0, -1, 0, 0], []), [1, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(mapping.deflections(["KeyS"], [0, -1, 0, 0], []), np.zeros(6), atol=1e-15)


# A SpaceMouse's own axes (HID): x to the operator's right, y towards the operator, z down.
# In the hand axes: forward is +x, left +y, up +z (like W, A, E).
@pytest.mark.parametrize(
    ("counts", "expected"),
    [
        ([0, -350, 0, 0, 0, 0], [1, 0, 0, 0, 0, 0]),  # pushed away from the operator
        ([-350, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0]),  # to the left
        ([0, 0, -350, 0, 0, 0], [0, 0, 1, 0, 0, 0]),  # lifted
        ([0, 0, 0, 0, -350, 0], [0, 0, 0, 1, 0, 0]),  # about the device's -y: the hand's +x
        ([0, 0, 0, -350, 0, 0], [0, 0, 0, 0, 1, 0]),
        ([0, 0, 0, 0, 0, -350], [0, 0, 0, 0, 0, 1]),  # about up: counter-clockwise seen from above
        ([0, -1000, 0, 0, 0, 0], [1, 0, 0, 0, 0, 0]),  # beyond full scale: clipped
    ],
)
def test_a_spacemouse_at_full_scale_deflects_one_hand_axis(counts, expected):
    np.testing.assert_allclose(mapping.spacemouse(counts), expected, atol=1e-15)


def test_the_spacemouse_map_is_a_rotation_and_its_dead_zone_is_radial():
    # the device's axes (right, back, down) and the hand's (forward, left, up) are both right-handed:
    # the translation and rotation triples turn alike, and a right-handed turn stays right-handed
    full = mapping.SPACEMOUSE_FULL_SCALE
    rng = np.random.default_rng(3)
    for _ in range(20):
        a, b = rng.uniform(-0.5, 0.5, 3), rng.uniform(-0.5, 0.5, 3)
        ta, tb = (mapping.spacemouse([*(v * full), 0, 0, 0], size=0.0)[:3] for v in (a, b))
        tc = mapping.spacemouse([*(np.cross(a, b) * full), 0, 0, 0], size=0.0)[:3]
        np.testing.assert_allclose(np.cross(ta, tb), tc, atol=1e-12)
    size = mapping.SPACEMOUSE_DEAD_ZONE
    inside = [0.6 * size * full, -0.6 * size * full, 0.3 * size * full]  # each axis under, the length too
    np.testing.assert_array_equal(mapping.spacemouse([*inside, *inside]), np.zeros(6))
    edge = mapping.spacemouse([0, -1.0001 * size * full, 0, 0, 0, 0])
    assert 0 < edge[0] < 1e-3  # continuous at the zone's edge
    half = mapping.spacemouse([0, -0.5 * full, 0, 0, 0, 0])[0]
    assert half == pytest.approx((0.5 - size) / (1 - size))
    np.testing.assert_array_equal(mapping.spacemouse(["x", None, math.nan, True]), np.zeros(6))
    np.testing.assert_allclose(mapping.deflections(["KeyW"], counts=[0, -full, 0, 0, 0, 0]), [1, 0, 0, 0, 0, 0])
