"""Executes a notebook top to bottom in its own folder (as Jupyter would) and fails on the first cell that raises.

    python scripts/run_notebook.py notebooks/lecture.ipynb [--write OUT.ipynb]
"""

import argparse
import pathlib
import sys
import time

import nbformat
from nbclient import NotebookClient


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("notebook", type=pathlib.Path)
    p.add_argument("--write", type=pathlib.Path, help="save the executed notebook (outputs included) here")
    p.add_argument("--timeout", type=int, default=900, help="seconds a cell may take")
    args = p.parse_args()
    nb = nbformat.read(args.notebook, as_version=4)
    t0 = time.monotonic()
    client = NotebookClient(nb, timeout=args.timeout, kernel_name="python3",
                            resources={"metadata": {"path": str(args.notebook.resolve().parent)}})
    client.execute()
    cells = sum(c.cell_type == "code" for c in nb.cells)
    print(f"{args.notebook}: {cells} code cells executed without error in {time.monotonic() - t0:.1f} s")
    if args.write:
        nbformat.write(nb, args.write)
    return 0


if __name__ == "__main__":
    sys.exit(main())
