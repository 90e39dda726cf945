"""REPORT.md assembled from the benchmarks' fragments: no run erases another's section."""

from benchmarks import fragments


def test_fragments_in_their_order_then_the_others_by_name(tmp_path):
    for name in ("zeta", "sizes", "methods", "alpha", "lights_reading"):
        (tmp_path / f"{name}.md").write_text(f"## {name}\n\ntext of {name}\n")
    report = tmp_path.parent / f"{tmp_path.name}_REPORT.md"
    text = fragments.assemble(tmp_path, report)
    assert report.read_text() == text
    assert text.startswith(fragments.TITLE.strip("\n"))
    order = [line[3:] for line in text.splitlines() if line.startswith("## ")]
    assert order == ["methods", "lights_reading", "sizes", "alpha", "zeta"]


def test_a_fragment_rewritten_leaves_the_others(tmp_path):
    folder, report = tmp_path / "fragments", tmp_path / "REPORT.md"
    folder.mkdir()
    (folder / "lights.md").write_text("## lights\n\nfirst run\n")
    (folder / "node_group.md").write_text("## node group\n\nby hand\n")
    fragments.assemble(folder, report)
    (folder / "lights.md").write_text("## lights\n\nsecond run\n")
    text = fragments.assemble(folder, report)
    assert "by hand" in text and "second run" in text and "first run" not in text


def test_prose_is_wrapped_tables_and_code_are_not():
    long = "word " * 60
    row = "| " + " | ".join(["cell"] * 60) + " |"
    code = "    " + "x = 1; " * 40
    text = fragments.wrap(f"{long}\n\n- {long}\n\n{row}\n\n```\n{long}\n```\n\n{code}\n")
    lines = text.splitlines()
    assert row in lines and code in lines and long.rstrip() in [x.rstrip() for x in lines]
    prose = [x for x in lines if x.startswith(("word", "- word", "  word"))
             and x.rstrip() != long.rstrip()]
    assert len(prose) > 4 and all(len(x) <= fragments.WIDTH for x in prose)
    bullet = next(i for i, x in enumerate(lines) if x.startswith("- word"))
    assert lines[bullet + 1].startswith("  word")  # a list item's lines stay in the item


def test_the_committed_report_is_its_fragments_assembled():
    names = fragments.names()
    assert names[: len(fragments.ORDER)] == [n for n in fragments.ORDER if n in names]
    assert {"methods", "node_group", "lights", "transfer"} <= set(names)
    expected = "\n\n".join([fragments.TITLE.strip("\n")] + [
        fragments.read(name).strip("\n") for name in names]) + "\n"
    assert fragments.REPORT.read_text(encoding="utf-8") == expected
    assert max(len(line) for line in expected.splitlines()
               if not line.startswith("|")) <= 200
