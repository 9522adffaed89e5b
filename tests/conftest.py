"""Shared fixtures and independent reference computations for the tests."""

from __future__ import annotations

import pytest

import pinrate
from support import DATA


@pytest.fixture(scope="session")
def ur5() -> pinrate.Robot:
    return pinrate.load("ur5")


@pytest.fixture(scope="session")
def panda() -> pinrate.Robot:
    return pinrate.load("panda")


@pytest.fixture(scope="session")
def mixed() -> pinrate.Robot:
    """Negative and non-z axes, a prismatic and a continuous joint; sensor mid-chain."""
    return pinrate.load(DATA / "mixed_joints.urdf", tip="tool", sensor="link2")
