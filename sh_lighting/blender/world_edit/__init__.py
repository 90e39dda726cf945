"""World Edit: in Cycles the designed lighting reaches the picture as the world itself,
L'(ω) = max(0, L_world(ω) + Σ (L_lm − L⁰_lm) Y_lm(ω)) (``nodes``), path traced with every
shadow, bounce and reflection; ``edit`` puts it into the world and takes it out again
(docs/blender.md, "Edit World")."""

from .edit import (  # noqa: F401
    WorldEditError,
    applied_message,
    clamping_note,
    clamping_of,
    edit_world,
    group_of,
    is_edited,
    own_coefficients,
    refresh,
    remove,
    status_lines,
)
