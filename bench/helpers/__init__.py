"""What the benchmarks share with each other and with the tests (imported as
`bench.helpers.<module>`, the repository root on sys.path): none of these is a
benchmark, and none runs anything when imported."""
