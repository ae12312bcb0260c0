"""The Python FMUs: build, export library, packaging, checks and the fmpy runtime."""
