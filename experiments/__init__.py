"""The protocol runner, results on disk, reports, figures, videos and benchmarks."""
