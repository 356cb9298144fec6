"""Kinematic structures of the seeds wired from the controller blocks (element numbers as instance names)."""

from virtual_machine.structures.axis import AxisTuning, ServoAxis
from virtual_machine.structures.mechatronic import CncState, MechatronicS4, S4Tuning

__all__ = ["AxisTuning", "CncState", "MechatronicS4", "S4Tuning", "ServoAxis"]
