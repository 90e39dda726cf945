"""The bundles' own files, read without running a job: every parameter file names each
parameter once, and only parameters its template defines (the render
bundle listed ApplyMode twice; a farm takes one of the two and ignores the other)."""

from pathlib import Path

import pytest
import yaml

BUNDLES = Path(__file__).resolve().parents[2] / "farm" / "openjd"


@pytest.mark.parametrize("bundle", sorted(p.name for p in BUNDLES.iterdir() if p.is_dir()))
def test_a_parameter_file_names_each_template_parameter_once(bundle):
    values = yaml.safe_load((BUNDLES / bundle / "parameter_values.yaml").read_text())
    names = [p["name"] for p in values["parameterValues"]]
    template = yaml.safe_load((BUNDLES / bundle / "template.yaml").read_text())
    defined = {p["name"] for p in template["parameterDefinitions"]}
    assert sorted(names) == sorted(set(names)), f"{bundle}: a parameter listed twice: {names}"
    assert set(names) <= defined, f"{bundle}: {set(names) - defined} not in the template"


def test_the_render_bundles_apply_mode_is_the_command_lines():
    """ApplyMode offers apply --mode's choices, with its default (Edit World in Cycles)."""
    from sh_lighting.choices import APPLY_MODES

    template = yaml.safe_load((BUNDLES / "render" / "template.yaml").read_text())
    (mode,) = [p for p in template["parameterDefinitions"] if p["name"] == "ApplyMode"]
    assert mode["allowedValues"] == list(APPLY_MODES)
    assert mode["default"] == APPLY_MODES[0]
    values = yaml.safe_load((BUNDLES / "render" / "parameter_values.yaml").read_text())
    (given,) = [p["value"] for p in values["parameterValues"] if p["name"] == "ApplyMode"]
    assert given == APPLY_MODES[0]
