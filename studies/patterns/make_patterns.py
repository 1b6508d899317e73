"""Write the classic crease patterns of the study ``pattern_robustness`` as FOLD files here.

Run from the repository root: ``python studies/patterns/make_patterns.py``. The drawings are in
``studies/_classic_patterns.py`` (plain FOLD 1.1, millimetres, crease patterns); each file is
written with the generator's defaults and is the input of ``etorigami check`` / ``run``.
"""

from __future__ import annotations

import json
import pathlib
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from studies._classic_patterns import PATTERNS  # noqa: E402


def main():
    for name, draw in PATTERNS.items():
        (HERE / f"{name}.fold").write_text(json.dumps(draw(), indent=1) + "\n")
        print(f"wrote {HERE.name}/{name}.fold")


if __name__ == "__main__":
    main()
