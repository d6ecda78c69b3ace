"""What every validation study does with its report: print it and write it (Markdown) to its path."""

from __future__ import annotations

from pathlib import Path


def publish(text: str, path: Path) -> None:
    """Print ``text`` and write it to ``path`` (its directory created)."""
    print(text)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
