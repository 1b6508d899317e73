"""The classic crease patterns of ``pattern_robustness`` (studies/_classic_patterns.py, issue 28):
plain FOLD crease patterns that are drawn right (Kawasaki-flat vertices, Maekawa's M - V = +-2
where the pattern is flat-foldable, counter-clockwise faces) and that ``etorigami check``
accepts; the committed files are what the generator writes."""

import json
import pathlib

import numpy as np
import pytest

from design.cli import main
from studies._classic_patterns import PATTERNS, POWERS_MW, kawasaki_defects

PATTERN_DIR = pathlib.Path(__file__).resolve().parents[2] / "studies" / "patterns"


def _maekawa(fold):
    """M - V count at every interior vertex."""
    outline = {v for e, s in zip(fold["edges_vertices"], fold["edges_assignment"]) if s == "B"
               for v in e}
    count = {}
    for (a, b), s in zip(fold["edges_vertices"], fold["edges_assignment"]):
        for v in (a, b):
            if s in "MV" and v not in outline:
                count[v] = count.get(v, 0) + (1 if s == "M" else -1)
    return count


@pytest.mark.parametrize("name", sorted(PATTERNS))
def test_pattern_is_a_plain_crease_pattern_in_mm_with_ccw_faces(name):
    fold = PATTERNS[name]()
    assert fold["frame_classes"] == ["creasePattern"] and fold["frame_unit"] == "mm"
    assert not any("etorigami" in k for k in fold)
    assert set(fold["edges_assignment"]) <= {"M", "V", "F", "B"}
    xy = np.asarray(fold["vertices_coords"])
    for face in fold["faces_vertices"]:
        p = xy[face]
        area = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
        assert area > 0
    assert max(abs(d) for d in kawasaki_defects(fold).values()) < 1e-8
    maekawa = set(_maekawa(fold).values())          # the 8-crease waterbomb folds in 3-D only
    assert maekawa == {0} if name == "waterbomb_base" else maekawa <= {2, -2} and maekawa
    assert 1.0 <= np.ptp(xy, axis=0).max() <= 10.0


@pytest.mark.parametrize("name", sorted(PATTERNS))
def test_committed_file_is_the_generators_and_check_accepts_it(name, capsys):
    path = PATTERN_DIR / f"{name}.fold"
    assert json.loads(path.read_text()) == json.loads(json.dumps(PATTERNS[name]()))
    assert main(["check", str(path)]) == 0
    assert "Traceback" not in "".join(capsys.readouterr())


def test_every_pattern_has_three_increasing_powers():
    assert set(POWERS_MW) == set(PATTERNS)
    for powers in POWERS_MW.values():
        assert len(powers) == 3 and list(powers) == sorted(powers) and powers[0] > 0
