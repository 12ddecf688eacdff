"""`python -m afford ...` runs the command line, as the `afford` script does."""

from afford import _main

_main()
