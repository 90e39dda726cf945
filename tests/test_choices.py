"""The Apply modes' Default by render engine (``choices.resolve_mode``), as measured:
Edit World in Cycles, Keep BSDF with Shadows in EEVEE (benchmarks/bench_eevee_default.py,
bench_texel.py), Keep BSDF elsewhere."""

import pytest

from sh_lighting.choices import APPLY_MODES, resolve_mode


@pytest.mark.parametrize("engine, mode", [
    ("CYCLES", "WORLD"),
    ("BLENDER_EEVEE", "TRANSFER"),  # 5.0
    ("BLENDER_EEVEE_NEXT", "TRANSFER"),  # 4.2-4.5
    ("BLENDER_WORKBENCH", "KEEP_BSDF"),
])
def test_the_default_by_engine(engine, mode):
    assert resolve_mode("AUTO", engine) == mode


@pytest.mark.parametrize("mode", APPLY_MODES[1:])
def test_a_named_mode_is_itself_in_every_engine(mode):
    for engine in ("CYCLES", "BLENDER_EEVEE", "BLENDER_WORKBENCH"):
        assert resolve_mode(mode, engine) == mode
