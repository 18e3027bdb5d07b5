"""Speed benchmarks: ratios against peers or the old code, run in the same process."""
