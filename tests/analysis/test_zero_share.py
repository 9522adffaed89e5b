"""analyze explains a 0 % share (issue 10): which block is singular everywhere, and why."""

from __future__ import annotations

import pinrate
from pinrate.analysis import analyze

# Two pitch joints and a roll joint: with the roll as the wrist serving the angular y row, W
# (1 x 1) is the roll axis' y component, 0 everywhere.
URDF = """<?xml version="1.0"?>
<robot name="pitch_pitch_roll">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="tool0"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit effort="1" velocity="1" lower="-2" upper="2"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.4"/>
    <axis xyz="0 1 0"/><limit effort="1" velocity="1" lower="-2" upper="2"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 0.3"/>
    <axis xyz="1 0 0"/><limit effort="1" velocity="1" lower="-2" upper="2"/></joint>
  <joint name="tool" type="fixed"><parent link="l3"/><child link="tool0"/><origin xyz="0 0 0.1"/></joint>
</robot>
"""


def test_a_zero_share_names_the_singular_block_and_its_rank(tmp_path) -> None:
    path = tmp_path / "pitch_pitch_roll.urdf"
    path.write_text(URDF, encoding="utf-8")
    robot = pinrate.load(path)
    partition = pinrate.Partition(["j1", "j2"], ["j3"], linear="xz", angular="y")
    report = analyze(robot, samples=500, partition=partition, points=11, tcp_samples=50)
    assert report.sample.fraction == 0.0
    text = report.markdown()
    assert "**Why ρ < 1 nowhere:**" in text
    assert "W (1x1) has rank 0 at every configuration examined" in text and "j3" in text


def test_a_share_above_zero_gets_no_explanation() -> None:
    report = analyze(pinrate.load("ur5"), samples=500, points=11, tcp_samples=50)
    assert report.sample.fraction > 0 and "Why ρ < 1 nowhere" not in report.markdown()
