"""The names that left ``design``'s door for a namespace (issue 31): namespace -> the old
names. ``design.<old>`` keeps working for one release, as the same object as
``design.<namespace>.<old>``, with an :class:`~simulator.errors.EtorigamiDeprecationWarning`
naming the new place (see :func:`simulator._lazy.attach`); the documentation's migration table
is made from this one. Read only when a name is not found otherwise.

``RENAMED``: old name -> new name in the same place (the door and every namespace that
publishes the new name; issue 31: one spelling of the factories, ``make_<thing>``), with the
same warning."""

MOVED = {
    "core": ("EVALUATION_STATUSES", "LoggedProblem", "executor_from_option"),
    "devices": ("GRIPPER_SPACE", "SU8_TG", "STAGE_STATUSES", "BASE_CREASES", "ARM_CREASES",
                "REFERENCE_NEWTON", "gripper_circuits", "MIURA_SPACE", "lift_per_power_table"),
    "analysis": ("with_residual_fold", "CREASE_GROUPS", "linear_allocation",
                 "ALLOCATION_STATUSES", "influence_matrices", "fold_sensitivity",
                 "limit_temperatures", "TEMPERATURE_MEASURES", "Distribution", "UncertainInput",
                 "FabricationScenario", "SCENARIOS", "residual_fold_per_crease",
                 "wilson_interval", "rank_correlations", "summarize_yield"),
}

RENAMED = {"gripper_model": "make_gripper_model", "miura_model": "make_miura_model"}
