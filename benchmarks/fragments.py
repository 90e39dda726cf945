"""benchmarks/REPORT.md, assembled from one fragment per benchmark (benchmarks/fragments/).

Each benchmark writes only its own fragment (``write``), so no run can erase another's
section; the readings written by hand are fragments of their own, which no benchmark writes.
``assemble`` joins the fragments of ``ORDER``, then any others found (by name), under the
report's title. ``python -m benchmarks.fragments`` assembles (``make bench`` runs it last).
"""

import re
import textwrap
from pathlib import Path

HERE = Path(__file__).resolve().parent
FRAGMENTS = HERE / "fragments"
REPORT = HERE / "REPORT.md"
WIDTH = 100

# Written by: report.py (methods), by hand (node_group, *_reading), bench_lights (lights),
# bench_transfer (transfer, transfer_equal_error), bench_photo (photo), bench_sizes (sizes),
# bench_real_scene (real_scene), bench_world_edit (world_edit), bench_eevee_default
# (eevee_default), bench_compile (compile), bench_eevee_raytracing (eevee_raytracing), the
# commands' benchmark (commands), bench_near_field (near_field).
ORDER = (
    "methods",
    "node_group",
    "lights",
    "lights_reading",
    "transfer",
    "transfer_equal_error",
    "transfer_reading",
    "texel",
    "texel_reading",
    "eevee_raytracing",
    "eevee_raytracing_reading",
    "photo",
    "sizes",
    "sizes_reading",
    "real_scene",
    "real_scene_reading",
    "world_edit",
    "world_edit_reading",
    "eevee_default",
    "eevee_default_reading",
    "compile",
    "compile_reading",
    "commands",
    "near_field",
)

TITLE = """# Benchmarks: SH lighting against the standard methods

What each benchmark measured, on what machine and data, its table, and what it means. Each
section is a fragment of benchmarks/fragments/, written by the benchmark it names (the
readings by hand) and joined here by `python -m benchmarks.fragments`; rerunning a benchmark
rewrites its own section only.
"""


def wrap(text, width=WIDTH):
    """``text`` with its prose lines (paragraphs and list items) wrapped at ``width``; table
    rows, headings, images, indented and fenced blocks are left as they are."""
    out, fenced = [], False
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
        if fenced or len(line) <= width or re.match(r"\s*(\||#|!\[|<!--)", line) or (
                line.startswith("    ") and not re.match(r"\s*([-*]|\d+\.) ", line)):
            out.append(line)
            continue
        bullet = re.match(r"(\s*)([-*]|\d+\.) ", line)
        indent = " " * len(bullet.group(0)) if bullet else re.match(r"\s*", line).group(0)
        out.extend(textwrap.wrap(line, width, subsequent_indent=indent,
                                 break_long_words=False, break_on_hyphens=False))
    return "\n".join(out) + "\n"


def write(name, text):
    """Write fragment ``name`` (wrapped) and assemble REPORT.md again."""
    FRAGMENTS.mkdir(exist_ok=True)
    (FRAGMENTS / f"{name}.md").write_text(wrap(text.strip("\n")), encoding="utf-8")
    assemble()


def read(name):
    """The text of fragment ``name`` ("" when it was never written)."""
    path = FRAGMENTS / f"{name}.md"
    return path.read_text(encoding="utf-8") if path.exists() else ""


def names(folder=FRAGMENTS):
    """The fragments to include: those of ``ORDER`` that exist, then the others by name."""
    found = sorted(path.stem for path in folder.glob("*.md"))
    return [n for n in ORDER if n in found] + [n for n in found if n not in ORDER]


def assemble(folder=FRAGMENTS, report=REPORT):
    """REPORT.md from the title and the fragments in ``folder``; returns its text."""
    parts = [TITLE.strip("\n")]
    parts += [(folder / f"{name}.md").read_text(encoding="utf-8").strip("\n")
              for name in names(folder)]
    text = "\n\n".join(parts) + "\n"
    report.write_text(text, encoding="utf-8")
    return text


if __name__ == "__main__":
    assemble()
