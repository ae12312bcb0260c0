"""The Python FMUs: build, embedding library, packaging, checks and the fmpy runtime."""
