"""``etorigami cases``: full summaries, allowed values and what a power is per
(simulator.cases.describe_cases, simulator.cases.parameter_note)."""

import inspect

from design.cli import main
from simulator.cases import describe_cases, parameter_note
from simulator.cases import CASES


def test_summaries_are_whole_first_paragraphs_without_issue_numbers():
    for name, doc, _ in describe_cases():
        first = CASES[name].__doc__.strip().split("\n\n")[0]
        assert doc == " ".join(first.split()), name
        assert "issue" not in doc.lower(), name
    miura = dict((n, d) for n, d, _ in describe_cases())["miura_lifter"]
    assert miura.endswith("cools the creases near it.")


def test_every_text_parameter_lists_its_values_and_every_power_says_per_what():
    for name, fn in CASES.items():
        for p in inspect.signature(fn).parameters.values():
            if isinstance(p.default, str):
                note = parameter_note(name, p.name)
                assert note.startswith("one of ") and repr(p.default) in note, (name, p.name)
            if p.name == "power_mW":
                assert parameter_note(name, p.name), name
    assert "q/2" in parameter_note("crane", "power_mW")
    assert parameter_note("single-fold", "gravity") == ""


def test_cases_prints_the_notes(capsys):
    assert main(["cases"]) == 0
    out = capsys.readouterr().out
    assert "variant = 'loss'  (one of 'within', 'loss')" in out
    assert "coupling = 'staggered'  (one of 'staggered', 'iterated', 'settled')" in out
    assert "cools the creases" in out and "issue 9" not in out
