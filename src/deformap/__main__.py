"""``python -m deformap``: the same command as the ``deformap`` console script."""

from deformap.cli import main

main()
