"""``python -m carom``: the carom command."""

from carom.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
