"""What the plot scripts of tools/paper share: matplotlib without a display, and the CSV reader."""
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402,F401  (re-exported to the plot scripts)


def read_csv(path):
    """The columns of a CSV with a header, as lists of floats (empty cells: NaN)."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    cols = {}
    for key in rows[0]:
        cols[key] = [float(r[key]) if r[key] != "" else float("nan") for r in rows]
    return cols
