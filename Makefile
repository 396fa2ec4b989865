# The commands the README names. Each target sets up what is missing first:
# an OpenCL platform (Debian's PoCL), the virtual environment, and the package with its test extras.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: setup opencl demo test bench clean

setup: opencl $(STAMP)

# An OpenCL platform is an ICD file in /etc/OpenCL/vendors; without one, install PoCL from Debian.
opencl:
	@if ls /etc/OpenCL/vendors/*.icd >/dev/null 2>&1; then :; \
	elif [ "$$(id -u)" = 0 ]; then \
		echo "No OpenCL platform found: installing Debian's pocl-opencl-icd"; \
		apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y pocl-opencl-icd; \
	else \
		echo "No OpenCL platform found. Install PoCL, then run make again:"; \
		echo "    sudo apt-get update && sudo apt-get install -y pocl-opencl-icd"; \
		exit 1; \
	fi

$(STAMP): pyproject.toml
	@[ -x $(PY) ] || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

# The main job: render a scene, run the whole machine, print its scores and write vmcl-demo/report.html.
demo: setup
	$(VENV)/bin/vmcl demo --out vmcl-demo

# The tests, after the linter and the type checker (the house's rules hold in CI, not only locally).
test: setup
	$(PY) -m ruff check vmcl hardware tests benchmarks
	$(PY) -m mypy
	$(PY) -m pytest -q

bench: setup
	$(PY) benchmarks/primitives.py
	$(PY) benchmarks/pipeline.py
	$(PY) benchmarks/readme.py

clean:
	rm -rf $(VENV) vmcl-demo build dist *.egg-info .pytest_cache .hypothesis
