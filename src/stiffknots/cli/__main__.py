"""``python -m stiffknots.cli``."""

from stiffknots.cli.main import main

main()
