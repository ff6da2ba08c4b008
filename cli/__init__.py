"""Command-line apps (typer): parse arguments, call the libraries, print. No mathematics here."""
