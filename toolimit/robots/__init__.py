"""Robot models by name (Pinocchio), each carrying a tool frame, on a planar mobile base."""

from toolimit.robots.model import BASE_COORDINATES, ArmDescription, RobotModel
from toolimit.robots.registry import ROBOTS, make_robot, register_robot

__all__ = ["BASE_COORDINATES", "ROBOTS", "ArmDescription", "RobotModel", "make_robot", "register_robot"]
