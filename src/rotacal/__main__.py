"""``python -m rotacal`` is the ``rotacal`` command."""

from rotacal.cli import main

main()
