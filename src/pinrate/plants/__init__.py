"""Plants: what the controller drives. :class:`~.abstract_plant.Plant` is the seam (reset, advance by
joint rates held for a duration, measure); :class:`~.kinematic_plant.KinematicPlant` follows the
rates exactly (pinrate's loops without a plant), :class:`~.mujoco_plant.MujocoPlant` is a
MuJoCo simulation of the same robot (``pip install "pinrate[mujoco]"``; MuJoCo is imported
only when one is built)."""

from .abstract_plant import Measurement, Plant
from .kinematic_plant import KinematicPlant
from .mujoco_plant import ACTUATORS, MujocoPlant

__all__ = ["ACTUATORS", "KinematicPlant", "Measurement", "MujocoPlant", "Plant"]
