# Shortcuts for the scripts; the build itself is CMake (see README.md).
.PHONY: demo test bench bench-quick
demo:
	scripts/demo.sh
test:
	scripts/test.sh
bench:        # installs the peers, builds, runs every benchmark, writes bench/results/
	scripts/bench.sh
bench-quick:
	scripts/bench.sh --quick
