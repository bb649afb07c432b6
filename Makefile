# Front door: `make demo` runs the closed-loop demo, `make test` the test suite.
# Both create .venv and install what they need by themselves (idempotent).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp

.PHONY: install test test-integration test-all demo lint format bench clean

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	@# torch first, pinned: on these machines 2.13.0 is a local CPU wheel; any other
	@# spec pulls a multi-GB CUDA build. The rl extra then accepts the installed torch.
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e '.[rl,dev,fast,zoo,video,cluster]'
	@touch $(STAMP)

install: $(STAMP)

test: install
	$(PY) -m pytest -q
	$(MAKE) test-integration

# Signals to a real training run, rl_zoo3 on configs/ppo.yaml, and the wheel installed into a
# fresh venv outside the repo (a few minutes; CI runs them through `make test`).
test-integration: install
	$(PY) -m pytest -q -m integration

test-all: install
	$(PY) -m pytest -q -m ''

demo: install
	$(VENV)/bin/lrp-gym demo

bench: install
	$(VENV)/bin/lrp-gym bench

lint: install
	$(VENV)/bin/ruff check lrp_gym agents tests
	$(VENV)/bin/ruff format --check lrp_gym agents tests
	$(VENV)/bin/mypy

format: install
	$(VENV)/bin/ruff format lrp_gym agents tests
	$(VENV)/bin/ruff check --fix lrp_gym agents tests

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache
