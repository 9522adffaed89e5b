"""What the console shows its pages: the scene, the hello a page gets when it connects, the frames.

A frame (:meth:`Readout.frame`) is the page's whole picture at one render tick: the status in
words and colour (:func:`~.display.describe`), the joints, the tip's pose in the world, the
console's state and, when something moved, every link's pose from the viewer's own
``pin.Data``. It is computed on the render thread, never the control loop's.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin

from ..control.singularity import STRATEGIES, WRIST_STRATEGIES
from ..viewer import Viewer
from .display import describe, joint_gauges, joint_values
from .mapping import KEYS
from .pacing import LoopStats
from .session import FRAMES, MODES, Teleop


class Readout:
    """What the pages see of a :class:`~.session.Teleop`: its scene, its joints, the hello
    and the render thread's frames (with a ``pin.Data`` of their own for the tip's pose, and
    the viewer's for the links').

    Attributes:
        viewer: the console's viewer (offline: a scene kept in-process), at the Teleop's q.
        scene: the viewer's scene encoded once (meshcat's packed commands), shared by every
            page and by the recordings' HTML replays.
        gauges: the joints on the page (:func:`~.display.joint_gauges`).
        jog_gauges: the joints a jog button may move, by name.
    """

    def __init__(self, teleop: Teleop, stats: LoopStats) -> None:
        self.teleop = teleop
        self.robot = teleop.robot
        self.stats = stats
        self.viewer = Viewer(self.robot, offline=True)
        self.viewer.draw_hand_axes()
        self.viewer.frame(teleop.q)
        self.viewer.show(teleop.q, record=False)
        self.scene: list[bytes] = self.viewer.scene.packed()  # type: ignore[union-attr]  # the offline scene
        partition = teleop.controller.partition
        self.gauges = joint_gauges(self.robot, (*partition.arm, *partition.wrist))
        joggable = set(teleop.controller.joggable)
        self.jog_gauges = {gauge.name: gauge for gauge in self.gauges if gauge.name in joggable}
        self.data = self.robot.model.createData()

    def hello(
        self, *, client: int, rate: float, scheduling: str, freeze_limit: float, jog_share: float
    ) -> dict[str, Any]:
        """The first message to a page: the robot, its joints, what the keys and controls
        do, the loop's rate and scheduling, the dead man's limits, the strategies and modes
        to choose from."""
        teleop, robot = self.teleop, self.robot
        options = teleop.options
        return {
            "type": "hello",
            "client": client,
            "robot": robot.name,
            "tip": robot.tip,
            "sensor": robot.sensor,
            "joints": [gauge.__dict__ for gauge in self.gauges],
            "keys": sorted(KEYS),
            "rate": rate,
            "scheduling": scheduling,
            "timeout": teleop.timeout,
            "freeze_limit": freeze_limit,
            "max_linear_speed": teleop.max_linear_speed,
            "max_angular_speed": teleop.max_angular_speed,
            "algorithm": teleop.controller.algorithm,
            "singularity": options.get("singularity", teleop.controller.singularity),
            "wrist": options.get("wrist", teleop.controller.wrist),
            "singularities": list(STRATEGIES),
            "wrists": list(WRIST_STRATEGIES),
            "frames": list(FRAMES),
            "frame": teleop.frame,
            "modes": list(MODES),
            "wrist_joints": list(teleop.controller.partition.wrist),
            "joggable": sorted(self.jog_gauges),
            "jog_share": jog_share,
            "controls": [("vx", "vy", "vz", "wx", "wy", "wz")[row] for row in teleop.controller.index.rows],
        }

    def frame(self, *, poses: bool, mode: str, input_seq: int) -> dict[str, Any]:
        """One frame for the pages: the status (``status``, ``colour``, ``detail``,
        ``conditions``; ``dead_man``: why the dead man stopped the robot while the status
        says so, or None), the joints (``q``: each joint's value in velocity order;
        ``configuration``: q itself), the tip's pose in the world (``tip``: :meth:`tip`), the
        console's state (``halted``, ``reversing``, ``recording``, ``frame``, ``mode``, the
        strategies, the loop's rate), the last input applied (``input_seq``), the last step's
        numbers and, when ``poses``, every link's pose."""
        teleop = self.teleop
        q, step = teleop.q.copy(), teleop.last
        # The dead man is set from another thread: the step read before it may still move,
        # and then the frame says "moving" and no dead man until the still step is read.
        said = describe(
            step, halted=teleop.halted, reversing=teleop.reversing, dead_man=teleop.dead_man, fault=teleop.plant_fault
        )
        frame: dict[str, Any] = {
            "type": "frame",
            "input_seq": input_seq,
            "dead_man": said.dead_man or None,
            "status": said.word,
            "colour": said.colour,
            "detail": said.detail,
            "conditions": list(said.conditions),
            "frozen": list(step.frozen) if step is not None else [],
            "moving": bool(step is not None and step.joint_rates.any()),
            "q": joint_values(self.robot, q),
            "configuration": q.tolist(),
            "tip": self.tip(q),
            "halted": teleop.halted,
            "reversing": teleop.reversing,
            "recording": teleop.recording,
            "frame": teleop.frame,
            "mode": mode,
            "singularity": teleop.controller.singularity,
            "wrist": teleop.controller.wrist,
            "loop": self.stats.summary(),
        }
        if step is not None:
            observation = step.observation
            rho = observation.spectral_radius
            conditioning = teleop.controller.observed_conditioning(observation)
            frame["rho"] = rho if math.isfinite(rho) else None
            frame["conditioning"] = {"value": conditioning.value, "block": conditioning.block}
            frame["twist"] = [float(value) for value in step.twist]
        if poses:
            frame["poses"] = {
                path: transform.T.reshape(-1).tolist() for path, transform in self.viewer.node_transforms(q).items()
            }
        return frame

    def tip(self, q: np.ndarray) -> dict[str, Any]:
        """The tip's pose in the world (base) frame at q, for the page: ``position`` (m) and
        ``rpy`` (rad: roll, pitch, yaw with world_R_tip = Rz(yaw) Ry(pitch) Rx(roll),
        Pinocchio's ``matrixToRpy``), from the render thread's own ``pin.Data``."""
        model, data = self.robot.model, self.data
        pin.framesForwardKinematics(model, data, q)
        world_T_tip = data.oMf[self.robot.tip_id]
        return {
            "name": self.robot.tip,
            "position": [float(value) for value in world_T_tip.translation],
            "rpy": [float(value) for value in pin.rpy.matrixToRpy(world_T_tip.rotation)],
        }


__all__ = ["Readout"]
