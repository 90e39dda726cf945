"""The command line's progress lines: a line per long stage, the time left of a batch."""

from sh_lighting.cli import report


def test_a_stage_gets_a_line_only_when_it_is_long(capsys):
    report.stage_line("projection", 0.2)
    report.stage_line("decode", 3.456)
    assert capsys.readouterr().out == "  decode: 3.46 s\n"


def test_timed_stage_prints_its_time_and_nothing_when_it_fails(capsys, monkeypatch):
    monkeypatch.setattr(report, "STAGE_LINE_SECONDS", 0.0)
    with report.timed_stage("writing"):
        pass
    assert capsys.readouterr().out.startswith("  writing: 0.00 s")
    try:
        with report.timed_stage("writing"):
            raise ValueError("no")
    except ValueError:
        pass
    assert capsys.readouterr().out == ""


def test_the_time_left_is_the_mean_so_far_times_the_files_left():
    assert report.time_left(2, 10, 10.0) == "; about 40 s left"
    assert report.time_left(1, 100, 30.0) == "; about 50 min left"
    assert report.time_left(10, 10, 50.0) == ""  # nothing left
    assert report.time_left(3, 4, 0.3) == ""  # under a second


def test_a_step_expected_to_be_long_says_so_on_stderr_first(capsys):
    report.before_long("decoding big.exr (383 MB)", 1.9)
    assert capsys.readouterr() == ("", "")
    report.before_long("decoding big.exr (383 MB)", 3.8)
    assert capsys.readouterr() == ("", "sh_lighting: decoding big.exr (383 MB)...\n")
