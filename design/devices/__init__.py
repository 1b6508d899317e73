"""Devices: the parametrised gripper and Miura lifter and their power searches.

The public names (``from design.devices import GRIPPER_SPACE``): each device's design, model
(the gripper's with its heat model), evaluation, problem and design space, with its
constants (the gripper's crease groups and stage statuses, the SU-8 glass transition). :func:`design.gripper_drive`, the gripper's
electrical drive, is at ``design``'s door (``design.devices.gripper_drive`` is its module).
"""

from simulator._lazy import attach as _attach

__getattr__, __dir__ = _attach(__name__, {
    ".gripper": ("ARM_CREASES", "BASE_CREASES", "REFERENCE_NEWTON", "STAGE_STATUSES",
                 "GripperDesign", "GripperResult", "StageResult", "evaluate_gripper",
                 "make_gripper_model"),
    ".gripper_heat": ("GripperHeatModel",),
    ".gripper_problem": ("GRIPPER_SPACE", "GripperProblem"),
    ".gripper_drive": ("GripperDrive", "gripper_circuits"),
    ".limits": ("SU8_TG",),
    ".fold_target": ("FoldTargetProblem",),
    ".fold_shape": ("FoldShapeProblem",),
    ".gripper_inverse": ("GripperInverseProblem",),
    ".miura": ("MIURA_SPACE", "LiftPowerResult", "MiuraDesign", "MiuraProblem",
               "heated_creases", "lift_per_power_table", "lift_power", "make_miura_model"),
}, renamed="design._moved")

__all__ = [
    # gripper
    "GripperDesign", "GripperHeatModel", "make_gripper_model", "evaluate_gripper", "GripperResult", "StageResult",
    "STAGE_STATUSES", "GripperProblem", "GRIPPER_SPACE", "BASE_CREASES", "ARM_CREASES",
    "REFERENCE_NEWTON", "GripperDrive", "gripper_circuits", "SU8_TG",
    # Miura lifter
    "MiuraDesign", "make_miura_model", "heated_creases", "lift_power", "LiftPowerResult",
    "lift_per_power_table", "MiuraProblem", "MIURA_SPACE",
    # heater powers for target fold angles (with gradients)
    "FoldTargetProblem", "FoldShapeProblem", "GripperInverseProblem",
]
