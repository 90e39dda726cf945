"""Node.js and the clients' pinned packages for tests/interop (see package.json).

On first use the packages of package-lock.json are installed with ``npm ci`` into
``out/interop-node/<hash of package-lock.json>/`` (beside the node scripts copied there, so
that their imports resolve), under a file lock so that parallel test runs install once.
Without node (≥ 18) or npm the tests are skipped with a message, unless the environment
variable ``CI`` is set (``.ci/run`` sets it): then they fail, so CI always runs them.
"""

import fcntl
import hashlib
import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
SCRIPTS = ("glsl.mjs", "png.mjs", "three.mjs", "babylon.mjs", "validate.mjs",
           "ext_lights_image_based.schema.json", "package.json", "package-lock.json")
MIN_NODE = 18
NPM_TIMEOUT = 600


def _unavailable(message):
    if os.environ.get("CI"):
        pytest.fail(f"tests/interop need Node.js: {message} (CI is set, so this fails)")
    pytest.skip(f"tests/interop skipped: {message}; install Node.js >= {MIN_NODE} and npm")


def _node_version(node):
    out = subprocess.run([node, "--version"], capture_output=True, text=True, timeout=30)
    return int(out.stdout.strip().lstrip("v").split(".")[0])


def _install(folder):
    """``npm ci`` into ``folder`` once (a stamp file marks a finished install)."""
    folder.mkdir(parents=True, exist_ok=True)
    stamp = folder / ".installed"
    with open(folder.parent / f".{folder.name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        for name in SCRIPTS:
            shutil.copyfile(HERE / name, folder / name)
        if not stamp.exists():
            run = subprocess.run(
                ["npm", "ci", "--no-audit", "--no-fund", "--loglevel=error"],
                cwd=folder, capture_output=True, text=True, timeout=NPM_TIMEOUT,
            )
            if run.returncode != 0:
                return f"npm ci failed in {folder}: {run.stderr.strip()[-500:]}"
            stamp.write_text("ok\n")
    return None


@pytest.fixture(scope="session")
def node_dir():
    """The folder holding the node scripts and their installed packages."""
    node = shutil.which("node")
    if node is None or shutil.which("npm") is None:
        _unavailable("node or npm is not on PATH")
    version = _node_version(node)
    if version < MIN_NODE:
        _unavailable(f"node {version} is older than {MIN_NODE}")
    lock_hash = hashlib.sha256((HERE / "package-lock.json").read_bytes()).hexdigest()[:12]
    folder = ROOT / "out" / "interop-node" / lock_hash
    problem = _install(folder)
    if problem:
        _unavailable(problem)
    return folder


@pytest.fixture(scope="session")
def run_node(node_dir, tmp_path_factory):
    """run_node(script, job) → the JSON the script writes (``job["output"]`` is set here)."""
    counter = iter(range(1_000_000))

    def run(script, job):
        work = tmp_path_factory.mktemp("node")
        job = dict(job, output=str(work / f"out{next(counter)}.json"))
        job_file = work / "job.json"
        job_file.write_text(json.dumps(job))
        done = subprocess.run(["node", script, str(job_file)], cwd=node_dir,
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, f"node {script} failed:\n{done.stderr[-2000:]}"
        return json.loads(Path(job["output"]).read_text())

    return run
