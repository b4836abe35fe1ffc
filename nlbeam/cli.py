"""Alias of ``nlbeam.app.cli`` (the ``nlbeam`` command), kept for the name users import."""
import sys

from nlbeam.app.cli import main

__all__ = ["main"]

if __name__ == "__main__":
    sys.exit(main())
