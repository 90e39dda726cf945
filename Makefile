# Two commands for a newcomer: `make demo` and `make test`. Each builds .venv on first use.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
LTS_VENV  := .venv-lts
LTS_STAMP := $(LTS_VENV)/.installed
HDRI ?=

.PHONY: demo test test-lts test-gui bench package clean

$(STAMP): requirements.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements.txt
	touch $(STAMP)

$(LTS_STAMP): requirements-lts.txt
	$(PYTHON) -m venv $(LTS_VENV)
	$(LTS_VENV)/bin/python -m pip install --quiet --disable-pip-version-check -r requirements-lts.txt
	touch $(LTS_STAMP)

demo: $(STAMP)
	$(PY) -m tools.demo $(HDRI)

# pytest-xdist workers for test and test-lts: one test file per worker at a time (module
# fixtures are built once); JOBS=0 runs everything in one process.
JOBS ?= 2
XDIST := -n $(JOBS) --dist loadfile --no-loadscope-reorder

# Lint for real errors (undefined names, unused imports), then the whole suite (slow tests
# included; the GUI session and the benchmarks are targets of their own).
test: $(STAMP)
	$(PY) -m ruff check --select F,E9 sh_lighting tests tools benchmarks
	$(PY) -m pytest $(XDIST)

# The tests whose outcome depends on the Blender version, on Blender 4.2 LTS (the oldest the
# manifest promises): tests/blender, tests/cli and tests/farm. tests/core and tests/interop need numpy
# only, the same numpy 1.26.4 in both environments, so `make test` has run them already.
test-lts: $(LTS_STAMP)
	$(LTS_VENV)/bin/python -m pytest $(XDIST) tests/blender tests/cli tests/farm

# The add-on in a real Blender window, driven by clicks and key presses (tests/gui). By
# default Debian's Blender in the root tools/blender_gui_root.sh builds (needs root; the root
# is made on first use, at BLENDER_GUI_ROOT, default /opt/blender-gui-root);
# `make test-gui BLENDER=/path/to/blender` runs that Blender (4.2+) on an Xvfb screen instead.
BLENDER ?=
test-gui: $(STAMP)
	SH_GUI_BLENDER=$(BLENDER) $(PY) -m pytest -m gui tests/gui

BENCH_STAMP := $(VENV)/.installed-bench
$(BENCH_STAMP): $(STAMP) requirements-bench.txt
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements-bench.txt
	touch $(BENCH_STAMP)

# The speed of prefiltering, the measurement tables that tests assert bounds on, then each
# benchmark's fragment of benchmarks/REPORT.md (benchmarks/fragments/) with its plots, and
# REPORT.md assembled from all the fragments (those of bench_lights and bench_transfer,
# which are not run here, included).
bench: $(BENCH_STAMP)
	$(PY) -m benchmarks.bench_prefilter
	$(PY) -m benchmarks.bench_tables
	$(PY) -m benchmarks.report
	$(PY) -m benchmarks.bench_real_scene
	$(PY) -m benchmarks.bench_world_edit
	$(PY) -m benchmarks.bench_eevee_default
	$(PY) -m benchmarks.bench_texel --eevee
	$(PY) -m benchmarks.bench_eevee_raytracing
	$(PY) -m benchmarks.bench_compile
	$(PY) -m benchmarks.bench_sizes
	$(PY) -m benchmarks.bench_photo
	$(PY) -m benchmarks.fragments

# The extension zip, with the standard library alone (no .venv); BLENDER=/path/to/blender
# also runs Blender's own `blender --command extension validate` on it.
package:
	$(PYTHON) -m tools.package dist $(if $(BLENDER),--check $(BLENDER))

clean:
	rm -rf build dist out .pytest_cache
