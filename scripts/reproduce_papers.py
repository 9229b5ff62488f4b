"""Reproduce the papers' tables: the same as ``bushenv reproduce``.

python scripts/reproduce_papers.py --out runs/reproduce
"""

import sys

from bushenv.cli import main

if __name__ == "__main__":
    sys.exit(main(["reproduce", *sys.argv[1:]]))
