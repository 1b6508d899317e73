"""Shared fixtures of the study tests: each study's ``main`` runs in quick mode at most once per
test session, in a temporary folder (never in results/), and every test file reads that run."""

import importlib

import pandas as pd
import pytest


@pytest.fixture(scope="session")
def quick_study(tmp_path_factory):
    """``quick_study(name) -> (module, out, df)``: ``studies.<name>.main(["--quick", ...])`` run
    once per session into a temporary folder ``out``; ``df`` is its main CSV."""
    cache = {}

    def run(name: str):
        if name not in cache:
            module = importlib.import_module(f"studies.{name}")
            out = tmp_path_factory.mktemp(name)
            assert module.main(["--quick", "--out", str(out), "--no-progress"]) == out
            cache[name] = (module, out, pd.read_csv(out / f"{module.NAME}.csv"))
        return cache[name]

    return run
