"""The names that left ``simulator``'s door for a namespace (issue 31): namespace -> the old
names, ``"old as new"`` where the namespace has another name for it. ``simulator.<old>`` keeps
working for one release, as the same object as ``simulator.<namespace>.<new>``, with an
:class:`~simulator.errors.EtorigamiDeprecationWarning` naming the new place (see
:func:`simulator._lazy.attach`); the documentation's migration table is made from this one.
Read only when a name is not found otherwise, so ``import simulator`` does not load it.

``RENAMED``: old name -> new name in the same place (the door and every namespace that
publishes the new name; issue 31: one spelling of the factories, ``make_<thing>``), with the
same warning."""

MOVED = {
    "materials": ("SU8", "SPR", "SUBSTRATE", "Fluid", "GOLD", "GOLD_FILM", "SILICON"),
    "model": ("sharp_model", "SharpHingeParameters", "SharpHingeMesh", "build_sharp_mesh",
              "STANDARD_GRAVITY", "REFERENCE_GRAVITY", "LayerStack", "STACKS", "get_stack",
              "stack_model", "central_panel", "unsupported_panels", "check_supported",
              "start_fold_angles", "plain_contact", "lumped_masses"),
    "thermal": ("ROOM_TEMPERATURE", "Layer", "SheetLayers", "HEAT_LOSS_MODELS", "CONDUCTIONS",
                "REFERENCE_BETA", "integrate_heat", "TransientHeatResult", "capacity_vector",
                "ThetaStepper", "theta_step", "REFERENCE_THETA", "DEFAULT_THETA",
                "TemperatureLimit", "TemperatureVerdict", "crease_limit_temperatures",
                "TG_FACTOR", "LIMIT_MEASURES", "crease_temperatures", "CREASE_MEASURES",
                "calibrate_environment", "CalibrationResult", "fixed_shape_temperatures",
                "FixedShapeTemperatures", "boundary_panel_plane"),
    "schedules": ("PowerSchedule", "StepPower", "Ramp", "SquareWave", "Sine", "PiecewiseLinear",
                  "Schedule", "StepSignal", "RampSignal", "SquareWaveSignal", "SineSignal",
                  "PiecewiseLinearSignal"),
    "steps": ("Step", "StepContext", "StepOutcome", "StepRecorder", "SimulationState",
              "initial_state", "Event", "EVENT_KINDS", "crossing_event", "StepResult"),
    "solvers": ("DynamicsResult", "MotionState", "TimeIntegrator", "integrate", "LoadPath",
                "mgdcm", "displacement_control as control_displacement", "ContinuationResult",
                "CriticalPoint", "Stability", "tangent_stability", "state_stability",
                "check_equilibrium", "EquilibriumCheck", "EQUILIBRIUM_RTOL"),
    "mechanics": ("fold_angles", "EquilibriumSystem", "ElementFamily", "FamilyValues",
                  "Configuration", "crease_crossings", "node_crossings"),
    "cases": ("describe_cases", "parameter_note", "miura_sheet_model", "miura_fold_signs",
              "single_fold_model"),
    "fold": ("read_fold", "write_fold", "fold_to_pattern", "pattern_to_fold", "read_model",
             "write_model", "fold_to_model", "model_to_fold", "write_fold_frames",
             "result_to_fold_frames", "parse_fold", "load_fold_json", "FoldGeometry"),
    "viewer": ("write_viewer", "viewer_html", "load_viewer_data"),
    "fe": ("fe_disk", "fe_sphere", "solve_fe3d", "solve_fe2d", "FEDiskResult", "FE3DResult",
           "FE2DResult"),
    "kernels": ("spring_kernel_backend", "kernel_cache_warm", "warm_kernel_cache"),
}

RENAMED = {"build_mesh": "make_mesh"}
