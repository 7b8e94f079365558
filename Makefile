# airsim-mapper: the two user commands are `make demo` and `make test`; both set up what is missing.
SHELL := /bin/bash
PY := .venv/bin/python
DEMO_SECONDS ?= 30
SOAK_SECONDS ?= 600
SCREENSHOT ?= docs/rviz.png

.PHONY: setup check test lint demo bench soak screenshot clean

setup:
	@bash tools/setup.sh

# The fast inner loop: lint and every test that starts no process (no roscore, server or node).
check: setup
	@$(PY) -m ruff check .
	@$(PY) -m pytest -q -m "not live"

test: setup
	@$(PY) -m ruff check .
	@$(PY) -m pytest -q

lint: setup
	@$(PY) -m ruff check .
	@$(PY) -m ruff format --check .

demo: setup
	@DEMO_SECONDS=$(DEMO_SECONDS) $(PY) -m tools.demo

bench: setup
	@$(PY) -m tools.bench

soak: setup
	@SOAK_SECONDS=$(SOAK_SECONDS) $(PY) -m tools.soak

screenshot: setup
	@$(PY) -m tools.screenshot --out $(SCREENSHOT)

clean:
	rm -rf .venv .venv-ros2 devel build out tools/bench/results.json .pytest_cache .ruff_cache
