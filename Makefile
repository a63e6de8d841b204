# The two commands a new machine needs (see README.md):
#   make demo   install what is missing, build, run the demo headless into out/
#   make test   install what is missing, build, package, run every test
# and `make build` to build alone, `make package` for the installable zips.
.PHONY: deps build package test test-cpp test-python test-blender demo bench clean

JOBS ?= $(shell nproc)
BUILD ?= build
VENV_PY := .venv/bin/python
# The module is built for every Python a supported Blender runs (3.11, 3.13, 3.10).
PYTHONS := $(abspath .venv/bin/python);$(abspath .venv313/bin/python);$(abspath .venv310/bin/python)

deps:
	@scripts/install_deps.sh

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release "-DPENUMBRA_PYTHONS=$(PYTHONS)" \
	  -Dpybind11_DIR="$$($(VENV_PY) -m pybind11 --cmakedir)"

build: deps $(BUILD)/CMakeCache.txt
	cmake --build $(BUILD) -j $(JOBS)

# dist/penumbra-<version>-linux_x64.zip (extension) and -legacy.zip (3.x).
package: build
	$(VENV_PY) scripts/package.py --build $(BUILD)

test-cpp: build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

test-python: build
	$(VENV_PY) -m pytest -q tests/python

test-blender: package
	$(VENV_PY) tests/blender/run_blender_tests.py

# Every suite runs even if an earlier one fails; the exit status is the worst.
test: build package
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
	rm -rf $(BUILD) out dist
