"""Readable Python references of compiled kernels, which tests and benchmarks compare the kernels against; no run
loop uses them (:mod:`.px4_tree`: PX4-Avoidance's look-ahead tree)."""
