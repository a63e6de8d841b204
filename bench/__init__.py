"""The benchmarks (`make bench`): entry points `bench/<tool>[_aspect]_benchmark.py`,
the parts they share with the tests in `bench.helpers`, the scripts they run
inside Blender in `bench/blender_scripts/`, the C++ benchmarks in `bench/cpp/`.
A package so that tests and scripts import the helpers as `bench.helpers.<name>`
with the repository root on sys.path."""
