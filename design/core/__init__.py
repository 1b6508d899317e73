"""The generic design core: design spaces, problems, evaluation logs, optimisers and
executors."""
