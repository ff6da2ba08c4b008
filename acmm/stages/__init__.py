"""The stages: config in, results file out (the glue between the library and its files)."""
