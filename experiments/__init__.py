"""The runner of Section 3.6's procedure, results on disk, reports, figures, videos and benchmarks."""
