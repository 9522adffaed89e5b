"""What the arm is: the robot model with its tip and sensor frames, the arm/wrist partition,
pose errors in the sensor frame. Everything here is Pinocchio kinematics; nothing solves
for joint rates."""

from .manipulator import Robot, RobotSpec
from .partition import Partition, PartitionIndex

__all__ = ["Partition", "PartitionIndex", "Robot", "RobotSpec"]
