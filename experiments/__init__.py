"""The runner of Section 3.6's procedure, results on disk, reports, figures, videos and benchmarks."""
import pathlib

#: The checkout (`python -m experiments` runs from there); for an installed wheel, the
#: folder that holds the packages.
ROOT = pathlib.Path(__file__).resolve().parent.parent
