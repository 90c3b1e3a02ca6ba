"""``python -m echocal``: the ``echocal`` command."""

from echocal.cli import main

if __name__ == "__main__":
    main()
