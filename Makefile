# airsim-mapper: the two user commands are `make demo` and `make test`; both set up what is missing.
SHELL := /bin/bash
PY := .venv/bin/python
DEMO_SECONDS ?= 30
SOAK_SECONDS ?= 600
SCREENSHOT ?= docs/rviz.png

.PHONY: setup test lint demo bench soak screenshot clean

setup:
	@bash tools/setup.sh

test: setup
	@$(PY) -m ruff check .
	@$(PY) -m pytest -q

lint: setup
	@$(PY) -m ruff check .
	@$(PY) -m ruff format --check .

demo: setup
	@DEMO_SECONDS=$(DEMO_SECONDS) $(PY) -m airsim_mapper.demo

bench: setup
	@$(PY) -m airsim_mapper.bench

soak: setup
	@SOAK_SECONDS=$(SOAK_SECONDS) $(PY) -m airsim_mapper.soak

screenshot: setup
	@$(PY) -m airsim_mapper.screenshot --out $(SCREENSHOT)

clean:
	rm -rf .venv out bench/results.json .pytest_cache .ruff_cache
