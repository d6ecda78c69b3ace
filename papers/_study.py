"""What every reproduction in papers/ does from the command line: --out, --quick, its checks' exit code."""

from __future__ import annotations

import argparse
from pathlib import Path


def study_cli(main, doc: str, quick_help: str, argv=None) -> int:
    """Parse ``--out`` (default papers/figures) and ``--quick``, run ``main(out, quick=...)`` and return
    0 when every check it returns ({name: (ok, detail)}) holds, 1 otherwise."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "figures")
    parser.add_argument("--quick", action="store_true", help=quick_help)
    args = parser.parse_args(argv)
    checks = main(args.out, quick=args.quick)
    return 0 if all(ok for ok, _ in checks.values()) else 1
