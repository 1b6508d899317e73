"""Devices: the parametrised gripper and Miura lifter and their power searches."""
