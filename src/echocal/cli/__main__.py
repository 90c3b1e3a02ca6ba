"""``python -m echocal.cli``."""

from echocal.cli import main

main()
