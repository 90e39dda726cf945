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

# Lint for real errors (undefined names, unused imports), then the whole suite.
test: $(STAMP)
	$(PY) -m ruff check --select F,E9 sh_lighting tests tools benchmarks
	$(PY) -m pytest

# The same suite on Blender 4.2 LTS (the oldest version the manifest promises).
test-lts: $(LTS_STAMP)
	$(LTS_VENV)/bin/python -m pytest

# The add-on in a real Blender window, driven by clicks and key presses (tests/gui): on this
# machine Debian's Blender 4.3 in ../shared/tools/blender-gui-root (needs root);
# `make test-gui BLENDER=/path/to/blender` runs that Blender (4.2+) on an Xvfb screen instead.
BLENDER ?=
test-gui: $(STAMP)
	SH_GUI_BLENDER=$(BLENDER) $(PY) -m pytest -m gui tests/gui

BENCH_STAMP := $(VENV)/.installed-bench
$(BENCH_STAMP): $(STAMP) requirements-bench.txt
	$(PY) -m pip install --quiet --disable-pip-version-check -r requirements-bench.txt
	touch $(BENCH_STAMP)

bench: $(BENCH_STAMP)
	$(PY) -m benchmarks.bench_prefilter
	$(PY) -m benchmarks.report

package: $(STAMP)
	$(PY) -m tools.package dist

clean:
	rm -rf build dist out .pytest_cache
