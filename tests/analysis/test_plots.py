"""The PNGs of pinrate.analysis.plots that take a run: a kinematic run has no plant to draw."""

from __future__ import annotations

import pytest

import pinrate
from pinrate.analysis.plots import plant_tracking_png


def test_a_run_without_a_plant_is_refused_by_name(ur5, tmp_path):
    target = ur5.pose(ur5.home())
    target[:3, 3] += 0.02
    trajectory = pinrate.servo(ur5, ur5.home(), target, max_steps=5)
    with pytest.raises(pinrate.InputError, match="not run on a plant"):
        plant_tracking_png(trajectory, ur5.joint_names, tmp_path / "rates.png")
    assert not (tmp_path / "rates.png").exists()
