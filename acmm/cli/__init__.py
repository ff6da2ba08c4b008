"""The ``acmm`` command line (typer): parse arguments, call the stages, print."""
