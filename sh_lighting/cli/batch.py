"""``batch HDRI_DIR OUT_DIR``: one preset per HDRI of a folder, resumable, one line per file;
``--files A-B`` is one task of a farm job."""

import fnmatch
import time
from pathlib import Path

from ..formats.atomic import leftovers
from . import interrupts
from .options import add_nonfinite, positive, whole_range
from .paths import file_in_way, kind, remove_own_leftovers
from .report import CommandError, error_line, say, time_left

HELP = "one preset per HDRI of a folder; resumable"
DEFAULT_PATTERNS = "*.exr,*.hdr"


def add_arguments(p, prog):
    p.description = (
        "Write OUT_DIR/<stem>.json for every HDRI of HDRI_DIR matching --pattern, with a "
        "progress line per file and a total. Existing presets are kept (an interrupted batch "
        "resumes) unless --force; a file that fails is reported and the others are still "
        "processed; the exit status is 1 if any failed.")
    p.epilog = f"example:\n  {prog} batch ~/hdris presets/ --pattern '*.exr,*.hdr'"
    p.add_argument("hdri_dir", metavar="HDRI_DIR", help="folder of equirectangular HDRIs")
    p.add_argument("out_dir", metavar="OUT_DIR", help="folder of the presets (created)")
    p.add_argument("--force", action="store_true", help="recompute presets that exist")
    p.add_argument("--files", type=whole_range, metavar="A-B",
                   help="only the A-th to B-th matching files, counted from 1 in the order "
                   "listed (names, any case): one task of a farm job")
    p.add_argument("--expect-files", type=positive, metavar="N",
                   help="fail before any work unless the folder holds exactly N matching "
                   "files (the count a farm job was split for)")
    p.add_argument("--pattern", default=DEFAULT_PATTERNS, metavar="GLOBS",
                   help=f"comma-separated file name patterns, any case (default: "
                   f"{DEFAULT_PATTERNS})")
    add_nonfinite(p)


def run(args):
    folder, out_dir = batch_folders(args)
    files = hdri_files(folder, args.pattern)
    if not files:
        raise CommandError(f"no file matching {args.pattern} in '{folder}'")
    if args.expect_files is not None and len(files) != args.expect_files:
        raise CommandError(
            f"'{folder}' holds {len(files)} file(s) matching {args.pattern}, not the "
            f"{args.expect_files} expected: nothing done (submit the job again for this folder)"
        )
    first, last = (1, len(files)) if args.files is None else args.files
    if not 1 <= first <= last <= len(files):
        raise CommandError(f"--files {first}-{last}: '{folder}' holds files 1-{len(files)} "
                           f"matching {args.pattern}")
    create_folder(out_dir)  # only now: a batch refused above leaves no folder behind
    if args.files is None:
        remove_batch_leftovers(out_dir)
    else:  # one task of a farm job: other tasks may be writing their presets right now
        for path in files[first - 1:last]:
            remove_own_leftovers(out_dir / f"{path.stem}.json")
    inputs = file_ids(files)
    counts = {"ok": 0, "skipped": 0, "failed": 0}
    failed, claimed = [], {}
    for path in files[:first - 1]:  # names taken before the selection, as in a whole batch
        claimed.setdefault(f"{path.stem}.json", path.name)
    start = time.perf_counter()
    for index, path in enumerate(files[first - 1:last], start=first):
        t0 = time.perf_counter()
        out = out_dir / f"{path.stem}.json"
        prefix = f"[{index}/{len(files)}] {path.name}"
        try:
            if out.name in claimed:
                raise CommandError(f"its preset name {out.name} is taken by {claimed[out.name]}")
            claimed[out.name] = path.name
            outcome = batch_one(path, out, args, inputs)
        except (CommandError, OSError, ValueError) as error:
            counts["failed"] += 1
            failed.append(path.name)
            say(f"{prefix}: FAILED ({time.perf_counter() - t0:.2f} s"
                f"{time_left(index - first + 1, last - first + 1, time.perf_counter() - start)})")
            error_line(f"{path.name}: {error}")
            continue
        counts[outcome] += 1
        if outcome == "skipped":
            say(f"{prefix}: skipped ({out.name} exists; --force to redo)")
        else:
            say(f"{prefix}: ok ({time.perf_counter() - t0:.2f} s"
                f"{time_left(index - first + 1, last - first + 1, time.perf_counter() - start)})")
    say(f"{last - first + 1} file(s): {counts['ok']} ok, {counts['skipped']} skipped, "
        f"{counts['failed']} failed in {time.perf_counter() - start:.2f} s")
    if failed:
        raise CommandError(f"{len(failed)} file(s) failed: {', '.join(failed)}")
    return 0


def hdri_files(folder, patterns):
    """The entries of ``folder`` matching ``patterns`` (any case), sorted by name."""
    wanted = [p.strip().lower() for p in patterns.split(",") if p.strip()]
    if not wanted:
        raise CommandError(f"--pattern {patterns!r} holds no pattern")
    return sorted(
        (p for p in folder.iterdir()
         if any(fnmatch.fnmatchcase(p.name.lower(), w) for w in wanted)),
        key=lambda p: p.name.lower(),
    )


def batch_folders(args):
    """(HDRI folder, output folder), or a CommandError saying why they cannot be used (the
    output folder is created later, by ``create_folder``, once the batch is not refused)."""
    folder, out_dir = Path(args.hdri_dir), Path(args.out_dir)
    if not folder.is_dir():
        what = "is a file, not a folder" if folder.exists() else "does not exist"
        raise CommandError(f"HDRI folder '{folder}' {what}: give the folder of the HDRIs")
    if out_dir.exists() and not out_dir.is_dir():
        raise CommandError(f"OUT_DIR '{out_dir}' is a file, not a folder: give a folder")
    if file_in_way(out_dir):
        raise CommandError(f"cannot create OUT_DIR '{out_dir}': a file is in the way")
    return folder, out_dir


def create_folder(out_dir):
    """Create ``out_dir`` and its parents, or a CommandError saying why not."""
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        in_way = " (a file is in the way)" if file_in_way(out_dir) else ""
        raise CommandError(
            f"cannot create OUT_DIR '{out_dir}': {error.strerror}{in_way}"
        ) from None


def remove_batch_leftovers(out_dir):
    """Remove the temporary preset files a killed batch left in ``out_dir``; say so."""
    removed = []
    for path in leftovers(out_dir):
        if path.name.endswith(".tmp") and ".json." in path.name:
            try:
                path.unlink()
            except OSError as error:
                say(f"could not remove {path.name}, left by an interrupted run: {error}")
                continue
            removed.append(path.name)
    if removed:
        say(f"removed {len(removed)} temporary file(s) left in {out_dir} by an interrupted "
            f"run: {', '.join(removed)}")


def file_ids(paths):
    """{(device, inode): path} of the existing files among ``paths`` (links followed)."""
    ids = {}
    for path in paths:
        try:
            info = path.stat()
        except OSError:
            continue
        ids[info.st_dev, info.st_ino] = path
    return ids


def batch_one(path, out, args, inputs):
    """Write the preset of HDRI ``path`` to ``out``: "ok" or "skipped"; raises on failure.

    ``inputs``: ``file_ids`` of every file the batch reads (a preset never replaces one).
    """
    from .. import api
    from ..api import hdri_metadata
    from .compute import read_hdri_file

    if not path.is_file():
        raise CommandError(kind(path))
    try:
        info = out.stat()
        clash = inputs.get((info.st_dev, info.st_ino))
    except OSError:
        clash = None
    if clash is not None:
        raise CommandError(f"its preset {out.name} would replace the input {clash.name}")
    if out.exists() and not args.force:
        return "skipped"
    hdri = read_hdri_file(path, args.nonfinite)
    interrupts.check()
    api.export_coefficients(hdri.coefficients, out, "sh_lighting", True, hdri_metadata(hdri))
    return "ok"
