# The two commands a new machine needs (see README.md):
#   make demo   install what is missing, build, run the demo headless into out/
#   make test   install what is missing, build, run every test
# and `make build` to build alone.
.PHONY: deps build test test-cpp test-python test-blender demo bench clean

JOBS ?= $(shell nproc)
BUILD ?= build
VENV_PY := .venv/bin/python

deps:
	@scripts/install_deps.sh

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPENUMBRA_PYTHON=$(abspath $(VENV_PY))

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

test-cpp: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

test-python: build
	$(VENV_PY) -m pytest -q tests/python

test-blender: build
	$(VENV_PY) tests/blender/run_blender_tests.py

# Every suite runs even if an earlier one fails; the exit status is the worst.
test: build
	@status=0; \
	$(MAKE) --no-print-directory test-cpp || status=1; \
	$(MAKE) --no-print-directory test-python || status=1; \
	$(MAKE) --no-print-directory test-blender || status=1; \
	exit $$status

# Heavy measurements, separate from the tests; results go to docs/.
bench: build
	$(VENV_PY) bench/run_all.py $(BENCH)

demo: build
	$(VENV_PY) examples/demo.py --out out

clean:
	rm -rf $(BUILD) out
