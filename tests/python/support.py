"""Helpers shared by the Python tests: numpy when the run allows it, and
arrays read back as lists whichever kind they are."""

try:
    import numpy as np
except ImportError:  # run_tests.py --block-numpy, or no numpy installed
    np = None


def as_list(values):
    """numpy arrays and lists alike as (nested) lists."""
    return values.tolist() if hasattr(values, "tolist") else values


def flat(values):
    """A grid's values as one flat list, x fastest."""
    values = as_list(values)
    if values and isinstance(values[0], list):
        return [v for row in values for v in row]
    return list(values)
